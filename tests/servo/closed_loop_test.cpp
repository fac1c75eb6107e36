// The servo core in a closed loop: an agent renders the analytic scene from its own pose,
// extracts features, steers by the goal-reaching navigation function and moves as a unicycle.
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "flowsteer/servo/servo.hpp"

namespace flowsteer::servo {
namespace {

struct WorldObstacle {
  SceneObject shape;  // position and velocity in the world frame
};

struct RunResult {
  bool reached_goal = false;
  double min_clearance_m = std::numeric_limits<double>::infinity();
  double time_s = 0.0;
  int turn_flips = 0;  // steps whose turn rate changed sign by 1 rad/s or more
};

double clearance(const SceneObject& o, const Eigen::Vector2d& p, double agent_radius) {
  const Eigen::Vector2d d = p - o.position_m;
  if (o.shape == SceneObject::Shape::cylinder) {
    return d.norm() - o.radius_m - agent_radius;
  }
  const Eigen::Vector2d outside(std::max(std::abs(d.x()) - 0.5 * o.length_m, 0.0),
                                std::max(std::abs(d.y()) - 0.5 * o.width_m, 0.0));
  return outside.norm() - agent_radius;
}

constexpr double kAgentRadius = 0.25;

Controller papers_controller() {
  PapersOptions options;
  options.avoidance.agent_width_m = 2.0 * kAgentRadius;
  return Controller(goal_reaching({}, options), 1.0, {1.0, 1.5});
}

RunResult run(std::vector<SceneObject> world, const Eigen::Vector2d& goal,
              Controller controller = papers_controller()) {
  constexpr double kDt = 0.1;
  FeatureExtractor extractor;
  Segmentation segmentation;
  ControlOutput out;

  Eigen::Vector2d position(0.0, 0.0);
  double yaw = 0.0;
  double speed = 1.0;
  double turn_rate = 0.0;
  RunResult result;
  for (int step = 0; step < 400; ++step) {
    const Eigen::Rotation2Dd to_body(-yaw);
    AnalyticScene scene;
    scene.intrinsics =
        base::CameraIntrinsics::from_horizontal_fov(96, 72, 100.0 * std::numbers::pi / 180);
    scene.mount = {1.0, 0.0};
    scene.agent_speed_mps = speed;
    scene.agent_turn_rate = turn_rate;
    for (SceneObject o : world) {
      result.min_clearance_m =
          std::min(result.min_clearance_m, clearance(o, position, kAgentRadius));
      o.position_m = to_body * (o.position_m - position);
      o.velocity_mps = to_body * o.velocity_mps;
      scene.objects.push_back(o);
    }
    SceneRender render = render_scene(scene);
    derotate(render.flow, camera_angular_velocity(turn_rate, scene.mount.pitch_rad));
    std::vector<std::uint8_t> ground(render.flow.size(), 0);
    mark_ground(render.flow, scene.mount, speed, {}, ground);
    segment_by_ids(render.ids, render.flow.width(), render.flow.height(), ground, segmentation);
    const auto objects = extractor.extract(render.flow, segmentation);

    const Eigen::Vector2d to_goal = to_body * (goal - position);
    if (to_goal.norm() < 0.5) {
      result.reached_goal = true;
      break;
    }
    // Bearing positive to the right; body y points left.
    const Percept percept{objects, -std::atan2(to_goal.y(), to_goal.x()), to_goal.norm(), {}};
    controller.step(percept, {speed, kDt}, out);

    if (turn_rate * out.command.turn_rate < 0.0 &&
        std::abs(turn_rate - out.command.turn_rate) >= 1.0) {
      ++result.turn_flips;
    }
    turn_rate = out.command.turn_rate;
    speed = std::max(0.0, speed + kDt * out.command.accel_mps2);
    yaw -= kDt * turn_rate;  // ω about the camera's y axis (down): yaw rate −ω
    position += kDt * speed * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
    for (SceneObject& o : world) {
      o.position_m += kDt * o.velocity_mps;
    }
    result.time_s += kDt;
  }
  return result;
}

TEST(ClosedLoop, GoesAroundAStaticPostToTheGoal) {
  SceneObject post;
  post.id = 1;
  post.shape = SceneObject::Shape::cylinder;
  post.radius_m = 0.4;
  post.position_m = {6.0, -0.1};
  const RunResult r = run({post}, {12.0, 0.0});
  EXPECT_TRUE(r.reached_goal);
  EXPECT_GT(r.min_clearance_m, 0.0);
  EXPECT_LT(r.time_s, 20.0);
}

TEST(ClosedLoop, LetsACrossingObstacleBy) {
  SceneObject crossing;
  crossing.id = 2;
  crossing.length_m = 0.8;
  crossing.width_m = 0.8;
  crossing.position_m = {6.0, 6.0};
  crossing.velocity_mps = {0.0, -1.0};  // on a collision course at t ≈ 6 s
  const RunResult r = run({crossing}, {12.0, 0.0});
  EXPECT_TRUE(r.reached_goal);
  EXPECT_GT(r.min_clearance_m, 0.0);
}

TEST(ClosedLoop, ThreadsBetweenTwoPosts) {
  SceneObject left;
  left.id = 1;
  left.shape = SceneObject::Shape::cylinder;
  left.radius_m = 0.3;
  left.position_m = {5.0, 1.2};
  SceneObject right = left;
  right.id = 2;
  right.position_m = {7.0, -0.6};
  const RunResult r = run({left, right}, {12.0, 0.0});
  EXPECT_TRUE(r.reached_goal);
  EXPECT_GT(r.min_clearance_m, 0.0);
}

// A corridor 3 m wide, the agent walking along it 0.6 m left of its middle. The walls' far ends
// make the flowsteer law's clearance stiff: held for a step, the explicit command (CGF Eq. 15)
// turns the FOE past the balance and the next one turns it back, at the limits; the implicit
// step walks the corridor without that chatter.
Controller flowsteer_controller(GradientStep step) {
  const FlowsteerOptions options =
      flowsteer_options({.agent_width_m = 2.0 * kAgentRadius, .margin_m = 0.5});
  return Controller(flowsteer_goal_reaching({}, options), 1.0, {1.0, 1.5}, step);
}

// Each wall a row of short blocks: the analytic scene's boxes keep their sides along the agent's
// axes as it turns, which a short block does not notice and a 15 m wall would.
std::vector<SceneObject> corridor() {
  std::vector<SceneObject> walls;
  for (int k = 0; k < 30; ++k) {
    SceneObject block;
    block.length_m = 0.5;
    block.width_m = 0.2;
    for (const double y : {0.9 + 0.1, -2.1 - 0.1}) {
      block.id = static_cast<std::int32_t>(walls.size()) + 1;
      block.position_m = {0.25 + 0.5 * k, y};
      walls.push_back(block);
    }
  }
  return walls;
}

TEST(ClosedLoop, TheImplicitStepWalksACorridorWithoutChatter) {
  const RunResult implicit_step =
      run(corridor(), {16.0, 0.0}, flowsteer_controller(GradientStep::implicit_euler));
  EXPECT_TRUE(implicit_step.reached_goal);
  EXPECT_GT(implicit_step.min_clearance_m, 0.0);
  const RunResult explicit_step =
      run(corridor(), {16.0, 0.0}, flowsteer_controller(GradientStep::explicit_euler));
  EXPECT_GT(explicit_step.turn_flips, 10);
  EXPECT_LE(implicit_step.turn_flips, explicit_step.turn_flips / 10);
}

}  // namespace
}  // namespace flowsteer::servo
