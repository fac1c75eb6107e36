#include "flowsteer/launch/agent_pipeline.hpp"

#include <chrono>
#include <string>

namespace flowsteer::launch {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

servo::Controller make_controller(const sim_camera::ControllerSpec& c, double agent_width_m,
                                  double preferred_speed_mps) {
  servo::AvoidanceOptions avoidance;
  avoidance.agent_width_m = agent_width_m + c.clearance_margin_m;
  avoidance.use_depth = c.use_depth;
  const servo::ControlLimits limits{c.max_accel_mps2, c.max_turn_rate};
  if (c.kind == "following") {
    return servo::Controller(servo::following({c.alpha, c.beta, c.gamma}, avoidance), c.lambda,
                             limits);
  }
  servo::GoalReachingWeights weights;
  weights.alpha = c.alpha;
  weights.beta = c.beta;
  weights.gamma = c.gamma;
  weights.delta = c.delta;
  weights.preferred_speed_mps = preferred_speed_mps;
  return servo::Controller(servo::goal_reaching(weights, avoidance), c.lambda, limits);
}

servo::Controller make_controller(const sim_camera::AgentSpec& agent) {
  return make_controller(agent.controller, 2.0 * agent.radius_m, agent.preferred_speed_mps);
}

PerceptionOptions perception_options(const sim_camera::AgentSpec& agent) {
  PerceptionOptions options;
  options.flow = agent.perception.flow;
  options.segmentation = agent.perception.segmentation;
  options.dark_regions = agent.controller.delta > 0.0;
  options.use_depth = agent.controller.use_depth;
  options.mount = {agent.camera.height_m, agent.camera.pitch_rad};
  return options;
}

AgentPipeline::AgentPipeline(const sim_camera::World& world, sim_camera::Renderer& renderer,
                             std::size_t agent)
    : world_(world),
      agent_(agent),
      camera_(world, renderer, agent),
      controller_(make_controller(world.spec().agents.at(agent))),
      perception_(camera_.intrinsics(), perception_options(world.spec().agents.at(agent))) {
  const std::string& type = world.spec().agents.at(agent).controller.type;
  if (type == "geometric") {
    geometric_.emplace(world, agent, camera_.intrinsics(), perception_.options().mount);
  } else if (type == "motion_energy") {
    motion_energy_.emplace(world.spec().agents.at(agent), camera_.intrinsics(),
                           perception_.options().mount);
  }
}

const servo::ControlOutput& AgentPipeline::step(StageTimes& times) {
  const sim_camera::AgentSpec& agent = world_.spec().agents[agent_];
  const sim_camera::AgentState& state = world_.agents()[agent_];
  const auto start = Clock::now();
  camera_.read(frame_, 0.0);
  times.render = ms_since(start);

  // The geometric reference perceives by exact geometry: flow would only cost it time.
  if (!geometric_) {
    perception_.process(frame_, state.speed_mps, state.turn_rate, times);
  }

  auto stage = Clock::now();
  objects_ = geometric_ ? geometric_->perceive() : perception_.objects();
  percept_ = servo::Percept{objects_, {}, {}, {}};
  if (agent.leader) {
    percept_.leader_id = sim_camera::agent_render_id(static_cast<std::size_t>(*agent.leader));
  } else if (state.next_goal < agent.goals.size()) {
    // The goal is a known point (CGF §6.1): its bearing, positive to the right.
    const Eigen::Vector2d to_goal = agent.goals[state.next_goal] - state.position_m;
    percept_.goal_bearing_rad = goal_bearing_rad(to_goal.x(), to_goal.y(), state.yaw_rad);
    percept_.goal_distance_m = to_goal.norm();
  }
  if (motion_energy_) {
    motion_energy_->step(frame_, perception_.flow(), percept_, {state.speed_mps}, output_);
  } else {
    controller_.step(percept_, {state.speed_mps}, output_);
  }
  times.control = ms_since(stage);
  times.total = ms_since(start);
  return output_;
}

}  // namespace flowsteer::launch
