#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/control.hpp"

namespace flowsteer::launch {

// How the demo steers: which navigation function, its weights and the control law's settings.
struct ControllerSpec {
  enum class Kind { goal_reaching, following };
  Kind kind = Kind::goal_reaching;
  servo::GoalReachingWeights goal_weights;
  servo::FollowingWeights follow_weights;
  servo::AvoidanceOptions avoidance;
  double lambda = 1.0;
  servo::ControlLimits limits;
  std::optional<std::int32_t> leader_id;  // following only
};

// A scene for `flowsteer demo`: the analytic scene seen by the agent, the goal in the agent's
// body frame (x forward, y left, metres) and the controller.
struct DemoScene {
  servo::AnalyticScene scene;
  std::optional<Eigen::Vector2d> goal_m;
  ControllerSpec controller;
};

// A street: a post ahead right, a pedestrian coming the other way and a car crossing from the
// left, with the goal beyond them.
DemoScene default_demo_scene();

// Reads a demo scene from YAML (format: launch/scenes/demo_street.yaml). Throws base::ConfigError
// naming the file, line, column and field of the first problem.
DemoScene load_demo_scene(const std::filesystem::path& path);
DemoScene parse_demo_scene(const std::string& yaml_text, const std::string& source_name);

}  // namespace flowsteer::launch
