#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/launch/perception.hpp"
#include "flowsteer/launch/steering_models.hpp"
#include "flowsteer/servo/servo.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::launch {

// One simulated agent's perception-action loop: its head camera renders the world, Perception
// turns the frame into features the way the agent's PerceptionSpec asks (synthetic or numerical
// flow derotated with the agent's turn rate, segmented by object id or by flow, dark regions
// when its controller weighs them), and its controller turns them into a command. The agent's
// controller type swaps the last stages: geometric takes the features from exact geometry (and
// computes no flow), motion_energy steers by Blumberg's motion energy instead of by the
// navigation function.
class AgentPipeline {
 public:
  // The world and the renderer must outlive the pipeline.
  AgentPipeline(const sim_camera::World& world, sim_camera::Renderer& renderer, std::size_t agent);

  // Runs one step at the world's current state; `times` receives what each stage took.
  const servo::ControlOutput& step(StageTimes& times);

  const camera_io::Frame& frame() const { return frame_; }
  const Perception& perception() const { return perception_; }
  const servo::FlowField& flow() const { return perception_.flow(); }  // zero for geometric
  // The features the controller saw: from the flow, or from exact geometry (type geometric).
  std::span<const servo::ObjectFeatures> objects() const { return objects_; }
  const servo::Percept& percept() const { return percept_; }
  const base::CameraIntrinsics& intrinsics() const { return camera_.intrinsics(); }

 private:
  const sim_camera::World& world_;
  std::size_t agent_;
  sim_camera::SimCamera camera_;
  servo::Controller controller_;
  Perception perception_;
  camera_io::Frame frame_;
  std::span<const servo::ObjectFeatures> objects_;
  servo::Percept percept_;
  servo::ControlOutput output_;
  std::optional<GeometricPerception> geometric_;       // type geometric
  std::optional<MotionEnergySteering> motion_energy_;  // type motion_energy
};

// The servo controller a scenario's agent asks for.
servo::Controller make_controller(const sim_camera::AgentSpec& agent);
// The same from the controller settings, the agent's (or robot's) own width and its preferred
// speed v*.
servo::Controller make_controller(const sim_camera::ControllerSpec& controller,
                                  double agent_width_m, double preferred_speed_mps);

// The perception a scenario's agent asks for.
PerceptionOptions perception_options(const sim_camera::AgentSpec& agent);

}  // namespace flowsteer::launch
