#include "flowsteer/sim/outputs.hpp"

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/pipeline/overlay.hpp"
#include "flowsteer/report/page.hpp"

namespace flowsteer::sim {

namespace {

namespace fox = recording::foxglove;

fox::Color scene_color(const cv::Scalar& bgr) {
  return {bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, 1.0};
}

// A solid standing on the ground: its centre half its height up, turned by its yaw.
fox::Solid scene_solid(const sim_camera::Solid& s, const fox::Color& color) {
  fox::Solid out;
  out.pose.position = {s.centre_m.x(), s.centre_m.y(), 0.5 * s.height_m};
  out.pose.orientation = recording::ros2::Quaternion::from_yaw(s.yaw_rad);
  out.size = s.shape == sim_camera::Solid::Shape::box
                 ? recording::ros2::Vector3{s.size_m.x(), s.size_m.y(), s.height_m}
                 : recording::ros2::Vector3{2.0 * s.radius_m, 2.0 * s.radius_m, s.height_m};
  out.color = color;
  return out;
}

fox::SceneEntity in_world(const char* id) {
  fox::SceneEntity entity;
  entity.id = id;
  entity.frame_id = "world";
  return entity;
}

void add_solid(fox::SceneEntity& entity, const sim_camera::Solid& s, const fox::Color& color) {
  auto& list = s.shape == sim_camera::Solid::Shape::box ? entity.cubes : entity.cylinders;
  list.push_back(scene_solid(s, color));
}

}  // namespace

cv::Scalar agent_color(std::size_t agent) {
  const report::Rgb c = report::agent_color(agent);
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

std::vector<fox::SceneEntity> static_scene_entities(const sim_camera::World& world) {
  const sim_camera::WorldSpec& spec = world.spec();
  std::vector<fox::SceneEntity> entities = {in_world("obstacles"), in_world("goals")};
  fox::SceneEntity& obstacles = entities[0];
  for (const sim_camera::Solid& o : spec.obstacles) {
    add_solid(obstacles, o, {0.6, 0.6, 0.6, 1.0});
  }
  fox::SceneEntity& goals = entities[1];
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    for (const Eigen::Vector2d& g : spec.agents[i].goals) {
      fox::Color color = scene_color(agent_color(i));
      color.a = 0.35;
      const double d = 2.0 * spec.agents[i].goal_radius_m;
      goals.cylinders.push_back({{{g.x(), g.y(), 0.01}, {}}, {d, d, 0.02}, color});
    }
  }
  return entities;
}

std::vector<fox::SceneEntity> moving_scene_entities(const sim_camera::World& world) {
  const sim_camera::WorldSpec& spec = world.spec();
  std::vector<fox::SceneEntity> entities = {in_world("agents"), in_world("moving")};
  fox::SceneEntity& agents = entities[0];
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    if (!world.present(i)) {
      continue;
    }
    const sim_camera::AgentSpec& a = spec.agents[i];
    const sim_camera::AgentState& s = world.agents()[i];
    sim_camera::Solid body;
    body.shape = sim_camera::Solid::Shape::cylinder;
    body.centre_m = s.position_m;
    body.radius_m = a.radius_m;
    body.height_m = a.height_m;
    add_solid(agents, body, scene_color(agent_color(i)));
    agents.texts.push_back({{{s.position_m.x(), s.position_m.y(), a.height_m + 0.2}, {}},
                            a.name,
                            14.0,
                            scene_color(agent_color(i))});
  }
  fox::SceneEntity& moving = entities[1];
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    add_solid(moving, world.moving_now(k), {0.43, 0.43, 0.43, 1.0});
  }
  return entities;
}

void write_image(const std::filesystem::path& path, const cv::Mat& image) {
  std::vector<std::uint8_t> encoded;
  bool ok = false;
  try {
    ok = cv::imencode(path.extension().string(), image, encoded);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot write " + path.string() + ": " + e.what());
  }
  if (!ok) {
    throw std::runtime_error("cannot write " + path.string() + ": cannot encode the image as " +
                             path.extension().string());
  }
  base::write_bytes(path, encoded.data(), encoded.size());
}

void write_summary_json(const std::filesystem::path& path, const SimResult& result) {
  std::ostringstream out;
  out << "{\n  \"scenario\": " << base::json_string(result.scenario)
      << ",\n  \"arrival\": " << base::json_string(std::string(to_string(result.arrival)))
      << ",\n  \"steps\": " << result.steps
      << ",\n  \"duration_s\": " << base::json_number(result.duration_s) << ",\n  \"agents\": [\n";
  for (std::size_t i = 0; i < result.agents.size(); ++i) {
    const AgentResult& a = result.agents[i];
    out << "    {\"name\": " << base::json_string(a.name)
        << ", \"reached_goal\": " << (a.reached_goal ? "true" : "false") << ", \"time_to_goal_s\": "
        << (a.reached_goal ? base::json_number(a.time_to_goal_s) : "null")
        << ", \"path_length_m\": " << base::json_number(a.path_length_m)
        << ", \"min_clearance_m\": " << base::json_number(a.min_clearance_m)
        << ", \"collisions\": " << a.collisions
        << ", \"spinning_s\": " << base::json_number(a.spinning_s);
    if (a.final_distance_to_leader_m >= 0.0) {
      out << ", \"final_distance_to_leader_m\": "
          << base::json_number(a.final_distance_to_leader_m);
    }
    out << "}" << (i + 1 < result.agents.size() ? "," : "") << "\n";
  }
  const pipeline::StageTimes& t = result.per_agent_step_ms;
  out << "  ],\n  \"collisions_total\": " << result.collisions.size()
      << ",\n  \"spinning_s_total\": " << base::json_number(summarize(result).spinning_s)
      << ",\n  \"per_agent_step_ms\": {\"render\": " << base::json_number(t.render)
      << ", \"flow\": " << base::json_number(t.flow)
      << ", \"segment\": " << base::json_number(t.segment)
      << ", \"features\": " << base::json_number(t.features)
      << ", \"control\": " << base::json_number(t.control)
      << ", \"total\": " << base::json_number(t.total) << "},\n  \"threads\": " << result.threads
      << ",\n  \"world_steps_per_s\": " << base::json_number(result.world_steps_per_s) << "\n}\n";
  base::write_text(path, out.str());
}

cv::Mat draw_overlay(const SimulatedAgent& agent) {
  const pipeline::Brain& brain = agent.brain();
  return pipeline::draw_overlay(agent.frame().image, brain.flow(), brain.objects(),
                                agent.intrinsics(), brain.goal_bearing_rad());
}

}  // namespace flowsteer::sim
