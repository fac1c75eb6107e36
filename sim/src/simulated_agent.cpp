#include "flowsteer/sim/simulated_agent.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/servo/geometric_features.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"
#include "flowsteer/sim_camera/world_geometry.hpp"

namespace flowsteer::sim {

namespace {

// The geometric model's features: what the agent would perceive if perception were perfect,
// from the world's exact geometry.
class GeometricOracle final : public pipeline::FeatureOracle {
 public:
  GeometricOracle(const sim_camera::World& world, std::size_t agent,
                  const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount)
      : world_(world), agent_(agent), intrinsics_(intrinsics), mount_(mount) {}

  std::span<const servo::ObjectFeatures> perceive(double speed_mps) override {
    return features_.compute(geometry_.bodies_seen_by(world_, agent_), intrinsics_, mount_,
                             speed_mps);
  }

 private:
  const sim_camera::World& world_;
  std::size_t agent_;
  base::CameraIntrinsics intrinsics_;
  base::CameraMount mount_;
  sim_camera::WorldGeometry geometry_;
  servo::GeometricFeatures features_;
};

pipeline::Brain make_brain(const sim_camera::World& world, std::size_t agent,
                           const base::CameraIntrinsics& intrinsics) {
  const sim_camera::AgentSpec& spec = world.spec().agents.at(agent);
  const pipeline::BrainConfig config = brain_config(spec);
  std::unique_ptr<pipeline::FeatureOracle> oracle;
  if (spec.controller.model == servo::SteeringModel::geometric) {
    oracle = std::make_unique<GeometricOracle>(world, agent, intrinsics, config.perception.mount);
  }
  try {
    return pipeline::Brain(intrinsics, config, std::move(oracle));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("agent '" + spec.name + "': " + e.what());
  }
}

}  // namespace

pipeline::BrainConfig brain_config(const sim_camera::AgentSpec& agent) {
  pipeline::BrainConfig config;
  config.controller = agent.controller;
  config.perception = pipeline::perception_options(agent.perception, agent.controller,
                                                   {agent.camera.height_m, agent.camera.pitch_rad});
  config.agent_width_m = 2.0 * agent.radius_m;
  config.preferred_speed_mps = agent.preferred_speed_mps;
  return config;
}

SimulatedAgent::SimulatedAgent(const sim_camera::World& world, std::size_t agent,
                               sim_camera::RenderChannels caller_reads)
    : world_(world),
      agent_(agent),
      intrinsics_(sim_camera::View::of_agent(world, agent).intrinsics()),
      brain_(make_brain(world, agent, intrinsics_)),
      channels_(caller_reads == sim_camera::RenderChannels::all || brain_.reads_image()
                    ? sim_camera::RenderChannels::all
                    : sim_camera::RenderChannels::geometry) {}

const servo::ControlOutput& SimulatedAgent::step(sim_camera::Renderer& renderer,
                                                 pipeline::StageTimes& times) {
  const base::Stopwatch render;
  renderer.render(world_, view(), view_, channels_);
  return think(render.elapsed_ms(), times);
}

const servo::ControlOutput& SimulatedAgent::think(double render_ms, pipeline::StageTimes& times) {
  const sim_camera::AgentSpec& agent = world_.spec().agents[agent_];
  const sim_camera::AgentState& state = world_.agents()[agent_];
  sim_camera::point_frame_at(view_, world_, frame_);
  frame_.sequence = sequence_++;
  pipeline::BrainInput input{frame_, state.speed_mps, state.turn_rate, {}, {}, {}, {}, false};
  if (agent.leader) {
    input.leader_id = sim_camera::agent_render_id(static_cast<std::size_t>(*agent.leader));
  } else if (state.next_goal < agent.goals.size() || world_.steers_after_arrival(agent_)) {
    // The goal is a known point (CGF §6.1): its bearing, positive to the right. Once arrived,
    // the last one, where it stays.
    const std::size_t goal = std::min(state.next_goal, agent.goals.size() - 1);
    const Eigen::Vector2d to_goal = agent.goals[goal] - state.position_m;
    input.goal_bearing_rad = pipeline::goal_bearing_rad(to_goal.x(), to_goal.y(), state.yaw_rad);
    input.goal_distance_m = to_goal.norm();
    if (goal + 1 == agent.goals.size()) {
      input.last_goal_radius_m = agent.goal_radius_m;
      input.arrived = state.reached_goal;
    }
  }
  const servo::ControlOutput& output = brain_.step(input);
  times = brain_.times();
  times.render = render_ms;
  times.total += render_ms;
  return output;
}

}  // namespace flowsteer::sim
