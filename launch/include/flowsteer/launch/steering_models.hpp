#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/servo/servo.hpp"
#include "flowsteer/sim_camera/world.hpp"
#include "flowsteer/sim_camera/world_geometry.hpp"

namespace flowsteer::launch {

// The steering models an agent's ControllerSpec::type selects, besides the vision one.

// type geometric: the features an agent would perceive if perception were perfect, from the
// world's exact geometry, for the same navigation function as the vision controller.
class GeometricPerception {
 public:
  // The world must outlive this. `intrinsics` and `mount` are the agent's camera's.
  GeometricPerception(const sim_camera::World& world, std::size_t agent,
                      const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount);
  std::span<const servo::ObjectFeatures> perceive();

 private:
  const sim_camera::World& world_;
  std::size_t agent_;
  base::CameraIntrinsics intrinsics_;
  base::CameraMount mount_;
  sim_camera::WorldGeometry geometry_;
  servo::GeometricFeatures features_;
};

// type motion_energy: Blumberg's controller, fed with the frame's image and the pixel classes
// (from the renderer's ids, or with mass_from: ground from the flat-ground test on the flow).
class MotionEnergySteering {
 public:
  // `intrinsics` and `mount` are the agent's camera's.
  MotionEnergySteering(const sim_camera::AgentSpec& agent,
                       const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount);

  // `derotated` is used with mass_from: ground only. Fills out.command (and out.unclamped);
  // the navigation function's cost and terms stay empty.
  void step(const camera_io::Frame& frame, const servo::FlowField& derotated,
            const servo::Percept& percept, const servo::AgentState& agent,
            servo::ControlOutput& out);

  const servo::MotionEnergyController& controller() const { return controller_; }

 private:
  bool mass_from_ground_;
  base::CameraMount mount_;
  servo::MotionEnergyController controller_;
  std::vector<float> intensity_;
  std::vector<servo::PixelClass> classes_;
  std::vector<std::uint8_t> ground_mask_;
};

}  // namespace flowsteer::launch
