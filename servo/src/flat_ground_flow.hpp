#pragma once

// The flows a flat ground predicts at one pixel, as a field holds them (FlatGround::
// static_flow_at): instantaneous for interval_s 0, else the displacement over interval_s per
// second. The ground's own, and that of an upright surface standing a given distance ahead, which
// the ground test, the untextured fill and the obstacle memory tell apart.

#include <optional>

#include <Eigen/Core>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo::detail {

// The flow of the ground seen at (x, y); empty at or above the horizon.
inline std::optional<Eigen::Vector2d> floor_flow_at(const FlatGround& ground, double x, double y,
                                                    double speed_mps, double interval_s) {
  const auto depth_m = ground.depth_at(x, y);
  if (!depth_m) {
    return std::nullopt;
  }
  return ground.static_flow_at(x, y, *depth_m, speed_mps, interval_s);
}

// The flow at (x, y) of a static point distance_ahead_m ahead of the camera: an upright surface
// standing there. Empty where the ray through row y does not reach forward.
inline std::optional<Eigen::Vector2d> upright_flow_at(const FlatGround& ground, double x, double y,
                                                      double distance_ahead_m, double speed_mps,
                                                      double interval_s) {
  const auto depth_m = ground.depth_at_distance_ahead(y, distance_ahead_m);
  if (!depth_m) {
    return std::nullopt;
  }
  return ground.static_flow_at(x, y, *depth_m, speed_mps, interval_s);
}

}  // namespace flowsteer::servo::detail
