#pragma once

#include <cstddef>
#include <span>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::eval {

// One simulated agent: its head camera renders the world, and the Brain a robot would run turns
// the frame, the agent's measured speed and turn rate and its goal into a command. The agent's
// controller model picks the brain's last stages; the geometric model gets its features from
// the world's exact geometry.
class SimulatedAgent {
 public:
  // The world and the renderer must outlive the agent. Throws std::invalid_argument naming the
  // agent when its controller cannot run (motion energy following a leader).
  SimulatedAgent(const sim_camera::World& world, sim_camera::Renderer& renderer, std::size_t agent);

  // Renders the agent's view at the world's current state and runs the brain on it; `times`
  // receives what each stage took, the rendering included.
  const servo::ControlOutput& step(pipeline::StageTimes& times);

  const camera_io::Frame& frame() const { return frame_; }
  const pipeline::Brain& brain() const { return brain_; }
  const base::CameraIntrinsics& intrinsics() const { return camera_.intrinsics(); }

 private:
  const sim_camera::World& world_;
  std::size_t agent_;
  sim_camera::SimCamera camera_;
  pipeline::Brain brain_;
  camera_io::Frame frame_;
};

// The brain a scenario's agent asks for, with its camera's intrinsics.
pipeline::BrainConfig brain_config(const sim_camera::AgentSpec& agent);

}  // namespace flowsteer::eval
