#include "flowsteer/servo/ground.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace flowsteer::servo {

FlatGround::FlatGround(const CameraMount& mount)
    : mount_(mount), cos_pitch_(std::cos(mount.pitch_rad)), sin_pitch_(std::sin(mount.pitch_rad)) {
  mount_.validate();
}

std::optional<double> FlatGround::depth_at([[maybe_unused]] double x, double y) const {
  // The ground is the plane n·P = h with n = (0, cos θ, sin θ) the downward vertical in the
  // camera frame; along the ray P = Z (x, y, 1) that gives Z = h / (y cos θ + sin θ).
  const double down = y * cos_pitch_ + sin_pitch_;
  if (down <= 1e-9) {
    return std::nullopt;
  }
  return mount_.height_m / down;
}

std::optional<Eigen::Vector2d> FlatGround::flow_at(double x, double y, double speed_mps) const {
  const auto depth = depth_at(x, y);
  if (!depth) {
    return std::nullopt;
  }
  // A static point moves relative to the camera at v = −v_c (0, −sin θ, cos θ); CGF Eq. 2.
  const double vy = speed_mps * sin_pitch_;
  const double vz = -speed_mps * cos_pitch_;
  return Eigen::Vector2d((-x * vz) / *depth, (vy - y * vz) / *depth);
}

namespace {

// The ground's flow at (x, y) as the field holds it: instantaneous, or the displacement over
// the field's interval, which is the instantaneous flow scaled by τ / (τ + Δ), τ = Z / v_z
// (flow_field.hpp): on near ground, far below the instantaneous flow.
std::optional<Eigen::Vector2d> expected_ground_flow(const FlatGround& ground, double x, double y,
                                                    double speed_mps, double approach_mps,
                                                    double interval_s) {
  auto expected = ground.flow_at(x, y, speed_mps);
  if (expected && interval_s > 0.0) {
    const double depth_m = *ground.depth_at(x, y);
    *expected *= depth_m / (depth_m + approach_mps * interval_s);
  }
  return expected;
}

}  // namespace

GroundRemovalResult mark_ground(const FlowField& derotated, const CameraMount& mount,
                                double speed_mps, const GroundRemovalOptions& options,
                                std::span<std::uint8_t> ground_mask) {
  if (ground_mask.size() != derotated.size()) {
    throw std::invalid_argument("mark_ground: mask has " + std::to_string(ground_mask.size()) +
                                " entries for a field of " + std::to_string(derotated.size()) +
                                " pixels");
  }
  const FlatGround ground(mount);
  GroundRemovalResult result;
  const bool use_depth = derotated.has_depth();
  if (!use_depth && !(std::abs(speed_mps) >= options.min_speed_mps)) {
    return result;
  }
  result.test = use_depth ? GroundTest::depth : GroundTest::flow;
  const auto flow = derotated.flow();
  const auto depth = derotated.depth();
  const double interval_s = derotated.interval_s();
  const double approach_mps = speed_mps * std::cos(mount.pitch_rad);
  for (int row = 0; row < derotated.height(); ++row) {
    const double y = derotated.y(row);
    for (int col = 0; col < derotated.width(); ++col) {
      const double x = derotated.x(col);
      const std::size_t i = derotated.index(col, row);
      bool is_ground = false;
      if (use_depth) {
        const auto expected = ground.depth_at(x, y);
        is_ground = expected && std::isfinite(depth[i]) &&
                    std::abs(depth[i] - *expected) <= options.depth_tolerance * *expected;
      } else {
        const auto expected =
            expected_ground_flow(ground, x, y, speed_mps, approach_mps, interval_s);
        if (expected && flow[i].allFinite()) {
          const double error = (flow[i].cast<double>() - *expected).norm();
          is_ground = error <= options.flow_tolerance * expected->norm() + options.flow_floor;
        }
      }
      if (is_ground) {
        ground_mask[i] = 1;
        ++result.ground_pixels;
      }
    }
  }
  return result;
}

int mark_ground_regions(const FlowField& derotated, const CameraMount& mount, double speed_mps,
                        const GroundRemovalOptions& options, Segmentation& segmentation) {
  if (segmentation.labels.size() != derotated.size()) {
    throw std::invalid_argument("mark_ground_regions: segmentation has " +
                                std::to_string(segmentation.labels.size()) +
                                " pixels for a field of " + std::to_string(derotated.size()));
  }
  if (!(std::abs(speed_mps) >= options.min_speed_mps)) {
    return 0;
  }
  const FlatGround ground(mount);
  const auto regions = static_cast<std::size_t>(segmentation.region_count());
  std::vector<std::vector<double>> errors(regions);
  std::vector<bool> above_horizon(regions, false);
  const auto flow = derotated.flow();
  const double interval_s = derotated.interval_s();
  const double approach_mps = speed_mps * std::cos(mount.pitch_rad);
  for (int row = 0; row < derotated.height(); ++row) {
    const double y = derotated.y(row);
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = derotated.index(col, row);
      const std::int32_t label = segmentation.labels[i];
      if (label == Segmentation::kNoRegion) {
        continue;
      }
      const auto r = static_cast<std::size_t>(label);
      const auto expected =
          expected_ground_flow(ground, derotated.x(col), y, speed_mps, approach_mps, interval_s);
      if (!expected) {
        above_horizon[r] = true;
      } else if (flow[i].allFinite()) {
        errors[r].push_back((flow[i].cast<double>() - *expected).norm() /
                            (expected->norm() + options.flow_floor));
      }
    }
  }
  int marked = 0;
  for (std::size_t r = 0; r < regions; ++r) {
    auto& e = errors[r];
    if (segmentation.kinds[r] != RegionKind::visible || above_horizon[r] || e.empty()) {
      continue;
    }
    const auto middle = e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2);
    std::nth_element(e.begin(), middle, e.end());
    if (*middle <= options.region_tolerance) {
      segmentation.kinds[r] = RegionKind::ground;
      ++marked;
    }
  }
  return marked;
}

}  // namespace flowsteer::servo
