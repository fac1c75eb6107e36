#pragma once

#include <cstdint>
#include <vector>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/servo/servo.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::pipeline {

// Blumberg's controller (model motion_energy), fed with the frame's image and the pixel classes:
// from the renderer's ids, or with mass_from ground from the flat-ground test on the flow.
class MotionEnergySteering {
 public:
  // body_radius_m: the agent's half width with half its clearance margin, which the danger zone
  // keeps clear.
  MotionEnergySteering(const servo::ControllerConfig& config,
                       const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount,
                       double preferred_speed_mps, double body_radius_m);

  // `derotated` is used with mass_from ground only. Fills out.command (and out.unclamped);
  // the navigation function's cost and terms stay empty.
  void step(const camera_io::Frame& frame, const servo::FlowField& derotated,
            const servo::Percept& percept, const servo::AgentState& agent,
            servo::ControlOutput& out);

 private:
  bool mass_from_ground_;
  base::CameraMount mount_;
  servo::MotionEnergyController controller_;
  std::vector<float> intensity_;
  std::vector<servo::PixelClass> classes_;
  std::vector<std::uint8_t> ground_mask_;
};

}  // namespace flowsteer::pipeline
