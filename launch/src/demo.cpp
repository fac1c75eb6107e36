#include "flowsteer/launch/demo.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "flowsteer/servo/servo.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::launch {

namespace {

std::string fixed(double value, int decimals = 3) {
  if (std::isnan(value)) {
    return "-";
  }
  if (std::isinf(value)) {
    return value > 0 ? "inf" : "-inf";
  }
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

std::string column(const std::string& text, int width) {
  return text.size() >= static_cast<std::size_t>(width)
             ? text + " "
             : std::string(static_cast<std::size_t>(width) - text.size(), ' ') + text;
}

}  // namespace

void run_demo(const config::DemoScene& demo, std::ostream& out) {
  const servo::AnalyticScene& scene = demo.scene;
  servo::SceneRender render = servo::render_scene(scene);
  servo::derotate(render.flow,
                  servo::camera_angular_velocity(scene.agent_turn_rate, scene.mount.pitch_rad));
  std::vector<std::uint8_t> ground(render.flow.size(), 0);
  const servo::GroundRemovalResult ground_result =
      servo::mark_ground(render.flow, scene.mount, scene.agent_speed_mps, {}, ground);
  servo::Segmentation segmentation;
  servo::segment_by_ids(render.ids, render.flow.width(), render.flow.height(), ground,
                        segmentation);
  servo::FeatureExtractor extractor;
  const auto objects = extractor.extract(render.flow, segmentation);

  servo::Percept percept{objects, {}, {}, demo.leader_id};
  if (demo.goal_m) {
    // Body y points left; a bearing is positive to the right.
    percept.goal_bearing_rad = -std::atan2(demo.goal_m->y(), demo.goal_m->x());
    percept.goal_distance_m = demo.goal_m->norm();
  }
  servo::Controller controller =
      servo::make_controller(demo.controller, demo.agent_width_m, demo.preferred_speed_mps);
  const servo::ControlOutput command = controller.step(percept, {scene.agent_speed_mps});

  const double deg = 180.0 / std::numbers::pi;
  out << "flowsteer demo: " << scene.intrinsics.width_px << "x" << scene.intrinsics.height_px
      << " px, hfov "
      << fixed(2.0 * std::atan(0.5 * scene.intrinsics.width_px / scene.intrinsics.fx_px) * deg, 1)
      << " deg, camera " << fixed(scene.mount.height_m, 2) << " m pitched "
      << fixed(scene.mount.pitch_rad * deg, 1) << " deg; agent at "
      << fixed(scene.agent_speed_mps, 2) << " m/s turning " << fixed(scene.agent_turn_rate, 2)
      << " rad/s\n";
  out << "ground removed: " << ground_result.ground_pixels << " px ("
      << (ground_result.test == servo::GroundTest::depth  ? "depth test"
          : ground_result.test == servo::GroundTest::flow ? "flow test"
                                                          : "skipped: no motion")
      << ")\n\n";

  out << "objects: measured from the flow | truth from the geometry (TTC at the footprint "
         "centre)\n";
  const int widths[] = {4, 8, 12, 7, 8, 7, 8, 8, 8, 8, 8, 2, 8, 8};
  const char* headers[] = {"id",    "kind",  "status",  "px",   "g_x", "w",     "foe_x",
                           "foe_y", "ttc_s", "ttc_eq5", "inl%", "|",   "foe_x", "ttc_s"};
  for (std::size_t i = 0; i < std::size(headers); ++i) {
    out << column(headers[i], widths[i]);
  }
  out << "\n";
  for (const servo::ObjectFeatures& f : objects) {
    std::string truth_foe = "-";
    std::string truth_ttc = "-";
    for (const servo::SceneObject& o : scene.objects) {
      if (o.id == f.source_id) {
        const servo::ObjectTruth truth = servo::object_truth(scene, o);
        truth_foe = fixed(truth.foe.x());
        truth_ttc = fixed(truth.ttc_s, 2);
      }
    }
    const std::string cells[] = {std::to_string(f.source_id),
                                 servo::to_string(f.kind),
                                 servo::to_string(f.status),
                                 std::to_string(f.pixel_count),
                                 fixed(f.centre.x()),
                                 fixed(f.width),
                                 fixed(f.foe.x()),
                                 fixed(f.foe.y()),
                                 fixed(f.ttc_s, 2),
                                 fixed(f.ttc_eq5_s, 2),
                                 fixed(100.0 * f.fit.inlier_fraction, 1),
                                 "|",
                                 truth_foe,
                                 truth_ttc};
    for (std::size_t i = 0; i < std::size(cells); ++i) {
      out << column(cells[i], widths[i]);
    }
    out << "\n";
  }
  if (objects.empty()) {
    out << "  (no object in view)\n";
  }

  out << "\ncost terms (L, dL'/da_c, dL'/dw):\n";
  for (const servo::TermEvaluation& t : command.terms) {
    out << "  " << t.name << std::string(t.name.size() < 12 ? 12 - t.name.size() : 1, ' ')
        << "weight " << fixed(t.weight, 2) << "  L " << column(fixed(t.gradient.cost, 4), 9)
        << " dL'/da_c " << column(fixed(t.gradient.per_accel, 4), 9) << " dL'/dw "
        << column(fixed(t.gradient.per_turn, 4), 9) << "\n";
  }
  const double w = command.command.turn_rate;
  out << "\ncommand: a_c = " << fixed(command.command.accel_mps2) << " m/s^2, w = " << fixed(w)
      << " rad/s ("
      << (w > 0.0   ? "turns right"
          : w < 0.0 ? "turns left"
                    : "straight")
      << ")";
  if (command.command.turn_rate != command.unclamped.turn_rate ||
      command.command.accel_mps2 != command.unclamped.accel_mps2) {
    out << ", clamped from a_c = " << fixed(command.unclamped.accel_mps2)
        << ", w = " << fixed(command.unclamped.turn_rate);
  }
  out << "\n";
}

}  // namespace flowsteer::launch
