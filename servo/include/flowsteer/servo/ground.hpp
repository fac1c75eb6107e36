#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

// A flat ground seen from a camera at a known height and pitch (CGF §5: Z = h / y and
// flow (x y, y²) v_c / h for zero pitch; generalised here to a pitched camera).
class FlatGround {
 public:
  explicit FlatGround(const base::CameraMount& mount);

  // Depth of the ground along the ray through (x, y); empty at or above the horizon.
  std::optional<double> depth_at(double x, double y) const;
  // Derotated flow of the ground at (x, y) for an agent moving forward at speed_mps;
  // empty at or above the horizon.
  std::optional<Eigen::Vector2d> flow_at(double x, double y, double speed_mps) const;
  // Derotated flow of a static point at depth_m along the ray through (x, y), for an agent moving
  // forward at speed_mps: instantaneous for interval_s 0, else its displacement over interval_s
  // per second, which is the instantaneous flow scaled by Z / (Z + v_z Δ) (flow_field.hpp).
  Eigen::Vector2d static_flow_at(double x, double y, double depth_m, double speed_mps,
                                 double interval_s) const;
  // Horizontal distance ahead of the camera of the point at depth_m on the ray through row y, and
  // back: a vertical surface keeps it from its foot to its top.
  double distance_ahead_m(double y, double depth_m) const;
  // Empty where the ray through row y does not reach forward (pointing straight up or back).
  std::optional<double> depth_at_distance_ahead(double y, double distance_ahead_m) const;
  // Where the ground's point seen at (x, y) was seen before the camera moved by moved_m (metres,
  // in the body frame of now: x forward, y left) without turning: normalised (x, y); empty at or
  // above the horizon, or where the point was not in front of the camera.
  std::optional<Eigen::Vector2d> seen_before_moving(double x, double y,
                                                    const Eigen::Vector2d& moved_m) const;
  // The ground's point seen at (x, y), in the body frame below the camera (x forward, y left,
  // metres); empty at or above the horizon.
  std::optional<Eigen::Vector2d> point_at(double x, double y) const;
  // Where the point height_m above the ground's point (body frame, as point_at's) is seen:
  // (x, y) normalised and its depth Z; empty where it is not in front of the camera.
  std::optional<Eigen::Vector3d> image_of(const Eigen::Vector2d& point_m,
                                          double height_m = 0.0) const;

 private:
  base::CameraMount mount_;
  Eigen::Matrix3d camera_to_body_;
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
  // A region of numerical flow is ground when the median over its pixels of |u − u_ground| /
  // (|u_ground| + flow_floor) is below this. Per pixel, numerical flow on weakly textured ground
  // errs by more than flow_tolerance often enough to leave patches that the segmentation joins
  // into wide regions at a TTC of 1–3 s (the ground's own τ = h / (y v)); their median is far
  // tighter. An upright obstacle differs by h / (h − η) at height η, so its median pixel (half
  // its height) stays above this for any obstacle over 2 h t / (1 + t), 0.64 m at h = 1.6 m.
  double region_tolerance = 0.25;
};

enum class GroundTest { depth, flow, skipped_no_motion };

struct GroundRemovalResult {
  GroundTest test = GroundTest::skipped_no_motion;
  int ground_pixels = 0;
};

// Sets ground_mask[i] = 1 for every pixel that matches the flat ground and leaves the others
// untouched. Uses the depth test when the field has depth, the flow test otherwise; the flow
// must already be derotated. ground_mask must have one entry per pixel.
GroundRemovalResult mark_ground(const FlowField& derotated, const base::CameraMount& mount,
                                double speed_mps, const GroundRemovalOptions& options,
                                std::span<std::uint8_t> ground_mask);

// The region-level ground test, for flow segmentation of numerical flow. Keeps its per-region
// counts from call to call, so that a stream of frames does not allocate; one per thread.
class GroundRegionMarker {
 public:
  // Marks as RegionKind::ground every visible region of `segmentation` whose flow as a whole
  // matches the flat ground (region_tolerance above). A region with any pixel at or above the
  // horizon is never ground. Returns how many it marked.
  int mark(const FlowField& derotated, const base::CameraMount& mount, double speed_mps,
           const GroundRemovalOptions& options, Segmentation& segmentation);

 private:
  struct Tally {
    int errors = 0;
    int within = 0;
    bool above_horizon = false;
  };
  std::vector<Tally> tallies_;
};

}  // namespace flowsteer::servo
