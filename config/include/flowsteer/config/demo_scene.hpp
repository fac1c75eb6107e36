#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::config {

// A scene for `flowsteer demo`: the analytic scene seen by the agent, the goal in the agent's
// body frame (x forward, y left, metres) and the controller.
struct DemoScene {
  servo::AnalyticScene scene;
  std::optional<Eigen::Vector2d> goal_m;
  // The demo's agent width is the whole width its avoidance keeps clear: no clearance margin.
  servo::ControllerConfig controller = [] {
    servo::ControllerConfig c;
    c.clearance_margin_m = 0.0;
    return c;
  }();
  double agent_width_m = 0.5;
  double preferred_speed_mps = 1.0;
  std::optional<std::int32_t> leader_id;  // following only
};

// A street: a post ahead right, a pedestrian coming the other way and a car crossing from the
// left, with the goal beyond them.
DemoScene default_demo_scene();

// Reads a demo scene from YAML (format: launch/scenes/demo_street.yaml). Throws base::ConfigError
// naming the file, line, column and field of the first problem.
DemoScene load_demo_scene(const std::filesystem::path& path);
DemoScene parse_demo_scene(const std::string& yaml_text, const std::string& source_name);

}  // namespace flowsteer::config
