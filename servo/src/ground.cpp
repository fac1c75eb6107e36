#include "flowsteer/servo/ground.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "flat_ground_flow.hpp"

namespace flowsteer::servo {

FlatGround::FlatGround(const base::CameraMount& mount)
    : mount_(mount),
      camera_to_body_(mount.camera_to_body()),
      cos_pitch_(std::cos(mount.pitch_rad)),
      sin_pitch_(std::sin(mount.pitch_rad)) {
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
  return detail::floor_flow_at(*this, x, y, speed_mps, 0.0);
}

Eigen::Vector2d FlatGround::static_flow_at(double x, double y, double depth_m, double speed_mps,
                                           double interval_s) const {
  // A static point moves relative to the camera at v = −v_c (0, −sin θ, cos θ); CGF Eq. 2.
  const double vy = speed_mps * sin_pitch_;
  const double vz = -speed_mps * cos_pitch_;
  Eigen::Vector2d flow((-x * vz) / depth_m, (vy - y * vz) / depth_m);
  if (interval_s > 0.0) {
    flow *= depth_m / (depth_m + speed_mps * cos_pitch_ * interval_s);
  }
  return flow;
}

double FlatGround::distance_ahead_m(double y, double depth_m) const {
  // The horizontal forward axis in the camera frame is (0, −sin θ, cos θ).
  return depth_m * (cos_pitch_ - y * sin_pitch_);
}

std::optional<double> FlatGround::depth_at_distance_ahead(double y, double distance_ahead_m) const {
  const double ahead = cos_pitch_ - y * sin_pitch_;
  if (ahead <= 1e-9) {
    return std::nullopt;
  }
  return distance_ahead_m / ahead;
}

std::optional<Eigen::Vector2d> FlatGround::point_at(double x, double y) const {
  const auto depth = depth_at(x, y);
  if (!depth) {
    return std::nullopt;
  }
  return (camera_to_body_ * (*depth * Eigen::Vector3d(x, y, 1.0))).head<2>().eval();
}

std::optional<Eigen::Vector2d> FlatGround::seen_before_moving(
    double x, double y, const Eigen::Vector2d& moved_m) const {
  const auto depth = depth_at(x, y);
  if (!depth) {
    return std::nullopt;
  }
  // Relative to where the camera was, the point lies moved_m further along the body's axes.
  const Eigen::Vector3d before =
      *depth * Eigen::Vector3d(x, y, 1.0) +
      camera_to_body_.transpose() * Eigen::Vector3d(moved_m.x(), moved_m.y(), 0.0);
  if (before.z() <= 1e-9) {
    return std::nullopt;
  }
  return Eigen::Vector2d(before.x() / before.z(), before.y() / before.z());
}

std::optional<Eigen::Vector3d> FlatGround::image_of(const Eigen::Vector2d& point_m,
                                                    double height_m) const {
  const Eigen::Vector3d camera =
      camera_to_body_.transpose() *
      Eigen::Vector3d(point_m.x(), point_m.y(), height_m - mount_.height_m);
  if (camera.z() <= 1e-9) {
    return std::nullopt;
  }
  return Eigen::Vector3d(camera.x() / camera.z(), camera.y() / camera.z(), camera.z());
}

namespace {

// The ground's flow (detail::floor_flow_at) along one image row, at_zero + x per_x: the ground's
// depth, and with it the flow's scale, depend on the row alone, so the pixel loops need no
// division.
struct GroundRowFlow {
  Eigen::Vector2d at_zero;
  Eigen::Vector2d per_x;
};

std::optional<GroundRowFlow> ground_row_flow(const FlatGround& ground, double y, double speed_mps,
                                             double interval_s) {
  const auto at_zero = detail::floor_flow_at(ground, 0.0, y, speed_mps, interval_s);
  if (!at_zero) {
    return std::nullopt;
  }
  const auto at_one = detail::floor_flow_at(ground, 1.0, y, speed_mps, interval_s);
  return GroundRowFlow{*at_zero, *at_one - *at_zero};
}

}  // namespace

GroundRemovalResult mark_ground(const FlowField& derotated, const base::CameraMount& mount,
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
  const auto mark = [&](std::size_t i, bool is_ground) {
    if (is_ground) {
      ground_mask[i] = 1;
      ++result.ground_pixels;
    }
  };
  for (int row = 0; row < derotated.height(); ++row) {
    const double y = derotated.y(row);
    const std::size_t first = derotated.index(0, row);
    if (use_depth) {
      // The ground's depth does not depend on x.
      const auto expected = ground.depth_at(0.0, y);
      if (!expected) {
        continue;
      }
      for (int col = 0; col < derotated.width(); ++col) {
        const std::size_t i = first + static_cast<std::size_t>(col);
        mark(i, std::isfinite(depth[i]) &&
                    std::abs(depth[i] - *expected) <= options.depth_tolerance * *expected);
      }
      continue;
    }
    const auto expected_row = ground_row_flow(ground, y, speed_mps, interval_s);
    if (!expected_row) {
      continue;
    }
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = first + static_cast<std::size_t>(col);
      const Eigen::Vector2d expected =
          expected_row->at_zero + derotated.x(col) * expected_row->per_x;
      const double error = (flow[i].cast<double>() - expected).norm();
      // NaN flow compares false: no flow, no ground.
      mark(i, error <= options.flow_tolerance * expected.norm() + options.flow_floor);
    }
  }
  return result;
}

int GroundRegionMarker::mark(const FlowField& derotated, const base::CameraMount& mount,
                             double speed_mps, const GroundRemovalOptions& options,
                             Segmentation& segmentation) {
  if (segmentation.labels.size() != derotated.size()) {
    throw std::invalid_argument("GroundRegionMarker::mark: segmentation has " +
                                std::to_string(segmentation.labels.size()) +
                                " pixels for a field of " + std::to_string(derotated.size()));
  }
  if (!(std::abs(speed_mps) >= options.min_speed_mps)) {
    return 0;
  }
  const FlatGround ground(mount);
  // The median of a region's errors is within region_tolerance exactly when more than half of
  // them (the middle one among them) are: counts serve, no error needs keeping. Counted by runs
  // of one label, which neighbouring pixels mostly share.
  tallies_.assign(static_cast<std::size_t>(segmentation.region_count()), Tally{});
  const auto flow = derotated.flow();
  const double interval_s = derotated.interval_s();
  for (int row = 0; row < derotated.height(); ++row) {
    const auto expected_row = ground_row_flow(ground, derotated.y(row), speed_mps, interval_s);
    std::int32_t label = Segmentation::kNoRegion;
    Tally run;
    const auto flush = [&] {
      if (label != Segmentation::kNoRegion) {
        Tally& tally = tallies_[static_cast<std::size_t>(label)];
        tally.errors += run.errors;
        tally.within += run.within;
        tally.above_horizon = tally.above_horizon || run.above_horizon;
      }
      run = {};
    };
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = derotated.index(col, row);
      if (segmentation.labels[i] != label) {
        flush();
        label = segmentation.labels[i];
      }
      if (label == Segmentation::kNoRegion) {
        continue;
      }
      if (!expected_row) {
        run.above_horizon = true;
      } else if (flow[i].allFinite()) {
        const Eigen::Vector2d expected =
            expected_row->at_zero + derotated.x(col) * expected_row->per_x;
        const double error =
            (flow[i].cast<double>() - expected).norm() / (expected.norm() + options.flow_floor);
        ++run.errors;
        run.within += error <= options.region_tolerance ? 1 : 0;
      }
    }
    flush();
  }
  int marked = 0;
  for (std::size_t r = 0; r < tallies_.size(); ++r) {
    const Tally& tally = tallies_[r];
    if (segmentation.kinds[r] != RegionKind::visible || tally.above_horizon || tally.errors == 0) {
      continue;
    }
    if (tally.within > tally.errors / 2) {
      segmentation.kinds[r] = RegionKind::ground;
      ++marked;
    }
  }
  return marked;
}

}  // namespace flowsteer::servo
