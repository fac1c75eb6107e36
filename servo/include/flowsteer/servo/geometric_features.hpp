#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/features.hpp"

namespace flowsteer::servo {

// A body the agent would see, described by exact geometry instead of by its flow: an upright
// prism standing on the ground, in the agent's body frame (x forward, y left, z up; the origin
// under the camera).
struct GeometricBody {
  std::int32_t id = -1;  // becomes ObjectFeatures::source_id
  // Convex footprint, vertices in order (either winding).
  std::span<const Eigen::Vector2d> footprint_m;
  double height_m = 1.0;
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();  // over the ground, body axes
};

// The features each body would produce if perception were perfect (CGF §5 evaluated on
// geometry): a reference that separates the error perception adds from the behaviour of the
// control law. Bodies are seen through the camera's horizontal field of view but through each
// other (no occlusion) and at any size (no pixel threshold). Per body, from its footprint cut
// to the part in front of the camera and inside the field of view, at the camera's height:
//   min_x, max_x  the extent of that part in normalised image coordinates, width = max − min,
//                 centre g at the middle of the extent, cut_left/right where the view cuts it;
//   depth Z       the smallest depth of that part (where the agent would touch it first), and
//                 the depths of the corners at min_x and max_x;
//   v             relative velocity (body − agent) in the camera frame, FOE f = (v_x, v_y)/v_z
//                 (CGF Eq. 3), τ = −Z/v_z, status from the sign of τ like the flow fit's;
//   fit.static_foe whether the body stands still, which the flow fit tells from its flow;
//   moments       those of the flow u = (v_x − x v_z)/Z (CGF Eq. 2) at the centre, standing for
//                 every pixel of the body (enough for the leader's alignment term).
// Keeps its output storage between calls; one instance per thread.
class GeometricFeatures {
 public:
  // Features of the bodies seen by a camera at `mount` on an agent moving forward at
  // agent_speed_mps, in the order of `bodies`, leaving out those entirely out of view.
  std::span<const ObjectFeatures> compute(std::span<const GeometricBody> bodies,
                                          const base::CameraIntrinsics& intrinsics,
                                          const base::CameraMount& mount, double agent_speed_mps);

 private:
  std::vector<ObjectFeatures> features_;
  std::vector<Eigen::Vector2d> clip_in_;
  std::vector<Eigen::Vector2d> clip_out_;
};

}  // namespace flowsteer::servo
