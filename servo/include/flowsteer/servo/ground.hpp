#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include <Eigen/Core>

#include "flowsteer/servo/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::servo {

// A flat ground seen from a camera at a known height and pitch (CGF §5: Z = h / y and
// flow (x y, y²) v_c / h for zero pitch; generalised here to a pitched camera).
class FlatGround {
 public:
  explicit FlatGround(const CameraMount& mount);

  // Depth of the ground along the ray through (x, y); empty at or above the horizon.
  std::optional<double> depth_at(double x, double y) const;
  // Derotated flow of the ground at (x, y) for an agent moving forward at speed_mps;
  // empty at or above the horizon.
  std::optional<Eigen::Vector2d> flow_at(double x, double y, double speed_mps) const;

 private:
  CameraMount mount_;
  double cos_pitch_;
  double sin_pitch_;
};

struct GroundRemovalOptions {
  // A pixel is ground when its depth is within this fraction of the ground's depth...
  double depth_tolerance = 0.03;
  // ...or, without depth, when its flow differs from the ground's by less than this fraction
  // of the ground flow's magnitude plus flow_floor (normalised units per second).
  double flow_tolerance = 0.1;
  double flow_floor = 1e-3;
  // Below this speed the ground has no flow to tell it by: the flow test marks nothing.
  double min_speed_mps = 0.05;
};

enum class GroundTest { depth, flow, skipped_no_motion };

struct GroundRemovalResult {
  GroundTest test = GroundTest::skipped_no_motion;
  int ground_pixels = 0;
};

// Sets ground_mask[i] = 1 for every pixel that matches the flat ground and leaves the others
// untouched. Uses the depth test when the field has depth, the flow test otherwise; the flow
// must already be derotated. ground_mask must have one entry per pixel.
GroundRemovalResult mark_ground(const FlowField& derotated, const CameraMount& mount,
                                double speed_mps, const GroundRemovalOptions& options,
                                std::span<std::uint8_t> ground_mask);

}  // namespace flowsteer::servo
