#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::sim {

// One simulated agent: its head camera renders the world, and the Brain a robot would run turns
// the frame, the agent's measured speed and turn rate and its goal into a command. The agent's
// controller model picks the brain's last stages; the geometric model gets its features from
// the world's exact geometry.
class SimulatedAgent {
 public:
  // The world must outlive the agent. The camera draws the lit image only where the brain reads
  // it or `caller_reads` asks for it (a video of the agent's view). Throws std::invalid_argument
  // naming the agent when its controller cannot run (motion energy following a leader).
  SimulatedAgent(const sim_camera::World& world, std::size_t agent,
                 sim_camera::RenderChannels caller_reads = sim_camera::RenderChannels::geometry);

  // Renders the agent's view at the world's current state with `renderer` (the calling thread's:
  // an OpenGL context is current on one thread) and runs the brain on it; `times` receives what
  // each stage took, the rendering included.
  const servo::ControlOutput& step(sim_camera::Renderer& renderer, pipeline::StageTimes& times);

  // Whether the camera draws the geometry channels alone: then the agent's view may be rendered
  // with other agents' in one submission (Renderer::render_geometry of view() into
  // rendered_view()), and think() run on it in place of step().
  bool renders_geometry_only() const { return channels_ == sim_camera::RenderChannels::geometry; }
  sim_camera::View view() const { return sim_camera::View::of_agent(world_, agent_); }
  sim_camera::RenderedView& rendered_view() { return view_; }
  // Runs the brain on rendered_view(), rendered at the world's current state in `render_ms`.
  const servo::ControlOutput& think(double render_ms, pipeline::StageTimes& times);

  const camera_io::Frame& frame() const { return frame_; }
  const pipeline::Brain& brain() const { return brain_; }
  const base::CameraIntrinsics& intrinsics() const { return intrinsics_; }

 private:
  const sim_camera::World& world_;
  std::size_t agent_;
  base::CameraIntrinsics intrinsics_;
  pipeline::Brain brain_;
  sim_camera::RenderChannels channels_;
  sim_camera::RenderedView view_;
  camera_io::Frame frame_;
  std::uint64_t sequence_ = 0;
};

// The brain a scenario's agent asks for, with its camera's intrinsics.
pipeline::BrainConfig brain_config(const sim_camera::AgentSpec& agent);

}  // namespace flowsteer::sim
