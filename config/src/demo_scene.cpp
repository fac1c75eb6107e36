#include "flowsteer/config/demo_scene.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include <yaml-cpp/yaml.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/config/controller_reader.hpp"
#include "flowsteer/config/field_bounds.hpp"

namespace flowsteer::config {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

void read_camera(const base::YamlReader& r, const YAML::Node& node, servo::AnalyticScene& scene) {
  r.only_keys(node, "camera", {"resolution", "hfov_deg", "height_m", "pitch_deg"});
  int width = scene.intrinsics.width_px;
  int height = scene.intrinsics.height_px;
  if (const YAML::Node res = node["resolution"]) {
    const base::Bound& bound = base::bound_of(r.bounds(), "camera.resolution");
    if (res.IsSequence() && res.size() == 2) {
      width = r.within_integer(res[0], "camera.resolution[0]", bound);
      height = r.within_integer(res[1], "camera.resolution[1]", bound);
    } else {
      width = height = r.within_integer(res, "camera.resolution", bound);
    }
  }
  const double hfov_deg = r.bounded(node, "camera", "hfov_deg", 90.0);
  scene.intrinsics = base::CameraIntrinsics::from_horizontal_fov(width, height, hfov_deg * kDeg);
  scene.mount.height_m = r.bounded(node, "camera", "height_m", scene.mount.height_m);
  scene.mount.pitch_rad = r.bounded(node, "camera", "pitch_deg", 0.0) * kDeg;
}

servo::SceneObject read_object(const base::YamlReader& r, const YAML::Node& node,
                               const std::string& field, std::int32_t default_id) {
  r.only_keys(node, field, {"shape", "id", "position", "size", "radius_m", "height_m", "velocity"});
  servo::SceneObject o;
  o.shape = r.word(node, field, "shape", {"box", "cylinder"}, "box") == "box"
                ? servo::SceneObject::Shape::box
                : servo::SceneObject::Shape::cylinder;
  o.id = node["id"] ? r.integer(node["id"], field + ".id", 0) : default_id;
  if (!node["position"]) {
    r.fail(node, field + ".position", "missing: where is the object?");
  }
  o.position_m = r.bounded_pair(node, field, "position", {0.0, 0.0});
  o.velocity_mps = r.bounded_pair(node, field, "velocity", {0.0, 0.0});
  o.height_m = r.bounded(node, field, "height_m", 1.8);
  if (o.shape == servo::SceneObject::Shape::box) {
    if (node["radius_m"]) {
      r.fail(node["radius_m"], field + ".radius_m",
             "a box has a size [length, width], not a radius");
    }
    const Eigen::Vector2d size = r.bounded_pair(node, field, "size", {1.0, 1.0});
    o.length_m = size.x();
    o.width_m = size.y();
  } else {
    if (node["size"]) {
      r.fail(node["size"], field + ".size", "a cylinder has radius_m, not a size");
    }
    o.radius_m = r.bounded(node, field, "radius_m", 0.3);
  }
  return o;
}

// The controller settings every file shares, and the demo's own: preferred speed (goal
// reaching) and the leader's object id (following). Following weighs its terms alike (CGF
// Eq. 18: beta 1) unless told otherwise.
void read_controller(const base::YamlReader& r, const YAML::Node& node, DemoScene& d) {
  r.only_keys(node, "controller",
              {"kind", "law", "alpha", "beta", "gamma", "delta", "braking", "anticipation",
               "follow_gap_m", "preferred_speed_mps", "lambda", "max_accel_mps2", "max_turn_rate",
               "max_speed_ratio", "use_depth", "clearance_margin_m", "leader"});
  const bool following = r.word(node, "controller", "kind", {"goal_reaching", "following"},
                                "goal_reaching") == "following";
  if (following) {
    for (const char* key : {"delta", "preferred_speed_mps"}) {
      if (node[key]) {
        r.fail(node[key], std::string("controller.") + key,
               "only a goal_reaching controller has it");
      }
    }
    if (!node["leader"]) {
      r.fail(node, "controller.leader", "missing: a following controller needs the leader's id");
    }
    d.leader_id = r.integer(node["leader"], "controller.leader", 0);
  } else if (node["leader"]) {
    r.fail(node["leader"], "controller.leader", "only a following controller has a leader");
  }
  d.controller = config::read_controller(r, node, "controller", d.controller);
  d.preferred_speed_mps =
      r.bounded(node, "controller", "preferred_speed_mps", d.preferred_speed_mps);
}

}  // namespace

DemoScene default_demo_scene() {
  DemoScene d;
  servo::AnalyticScene& s = d.scene;
  s.intrinsics = base::CameraIntrinsics::from_horizontal_fov(160, 120, 90.0 * kDeg);
  s.mount = {1.6, 0.0};
  s.agent_speed_mps = 1.0;
  servo::SceneObject post;
  post.id = 1;
  post.shape = servo::SceneObject::Shape::cylinder;
  post.radius_m = 0.25;
  post.height_m = 2.5;
  post.position_m = {5.0, -0.4};
  servo::SceneObject pedestrian;
  pedestrian.id = 2;
  pedestrian.shape = servo::SceneObject::Shape::cylinder;
  pedestrian.radius_m = 0.3;
  pedestrian.position_m = {9.0, 1.5};
  pedestrian.velocity_mps = {-1.2, 0.0};
  servo::SceneObject car;
  car.id = 3;
  car.length_m = 4.2;
  car.width_m = 1.8;
  car.height_m = 1.5;
  car.position_m = {14.0, 9.0};
  car.velocity_mps = {0.0, -4.0};
  s.objects = {post, pedestrian, car};
  d.goal_m = Eigen::Vector2d(20.0, -1.0);
  return d;
}

DemoScene parse_demo_scene(const std::string& yaml_text, const std::string& source_name) {
  const base::YamlReader r(source_name, demo_scene_bounds());
  const YAML::Node root = base::load_yaml_map(yaml_text, source_name, "camera, agent, objects",
                                              {"camera", "agent", "goal", "controller", "objects"});

  DemoScene d;
  servo::AnalyticScene& s = d.scene;
  s.intrinsics = base::CameraIntrinsics::from_horizontal_fov(160, 120, 90.0 * kDeg);
  s.mount = {1.6, 0.0};
  if (const YAML::Node camera = root["camera"]) {
    read_camera(r, camera, s);
  }
  if (const YAML::Node agent = root["agent"]) {
    r.only_keys(agent, "agent", {"speed_mps", "turn_rate", "width_m"});
    s.agent_speed_mps = r.bounded(agent, "agent", "speed_mps", 1.0);
    s.agent_turn_rate = r.bounded(agent, "agent", "turn_rate", 0.0);
    d.agent_width_m = r.bounded(agent, "agent", "width_m", 0.5);
  }
  if (const YAML::Node goal = root["goal"]) {
    d.goal_m = r.bounded_pair(root, "", "goal", {0.0, 0.0});
    if (d.goal_m->x() <= 0.0) {
      r.fail(goal, "goal", "must be ahead of the agent (x > 0) for the demo's single frame");
    }
  }
  if (const YAML::Node controller = root["controller"]) {
    read_controller(r, controller, d);
  }
  if (const YAML::Node objects = root["objects"]) {
    if (!objects.IsSequence()) {
      r.fail(objects, "objects", "expected a list of objects");
    }
    std::set<std::int32_t> ids;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string field = "objects[" + std::to_string(i) + "]";
      s.objects.push_back(read_object(r, objects[i], field, static_cast<std::int32_t>(i + 1)));
      if (!ids.insert(s.objects.back().id).second) {
        r.fail(objects[i], field + ".id",
               "id " + std::to_string(s.objects.back().id) + " is used twice");
      }
    }
  }
  const auto is_leader = [&](const servo::SceneObject& o) { return o.id == *d.leader_id; };
  if (d.leader_id && std::none_of(s.objects.begin(), s.objects.end(), is_leader)) {
    r.fail(root["controller"]["leader"], "controller.leader",
           "no object has id " + std::to_string(*d.leader_id));
  }
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw base::ConfigError(source_name, e.what());
  }
  return d;
}

DemoScene load_demo_scene(const std::filesystem::path& path) {
  return parse_demo_scene(base::read_text_file(path.string(), "scene file"), path.string());
}

}  // namespace flowsteer::config
