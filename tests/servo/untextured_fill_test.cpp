#include "flowsteer/servo/untextured_fill.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kSpeedMps = 0.7;
constexpr double kIntervalS = 0.2;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A robot's camera: 0.45 m up, pitched 8° down, 90° across 96×72.
struct View {
  base::CameraMount mount{0.45, 8.0 * std::numbers::pi / 180.0};
  FlowField field{base::CameraIntrinsics::from_horizontal_fov(96, 72, std::numbers::pi / 2)};
  cv::Mat grey{72, 96, CV_8UC1, cv::Scalar(0)};
  std::vector<std::uint8_t> ground_mask = std::vector<std::uint8_t>(96 * 72, 0);
  std::vector<double> truth_distance_m = std::vector<double>(96 * 72, 0.0);  // 0: not the wall
};

// A plain wall 2 m tall standing on a textured floor, `ahead_m(x)` metres ahead in column x
// (normalised); the floor has exact flow, the wall and the sky none, as a camera's texture test
// leaves them. Grey: floor 90, wall 170, sky 230.
template <typename AheadOf>
View wall_view(AheadOf ahead_m) {
  View v;
  const FlatGround ground(v.mount);
  const double cos_pitch = std::cos(v.mount.pitch_rad);
  const double sin_pitch = std::sin(v.mount.pitch_rad);
  v.field.set_interval_s(kIntervalS);
  for (int row = 0; row < v.field.height(); ++row) {
    const double y = v.field.y(row);
    for (int col = 0; col < v.field.width(); ++col) {
      const double x = v.field.x(col);
      const std::size_t i = v.field.index(col, row);
      const double wall_ahead_m = ahead_m(x);
      const auto floor_depth = ground.depth_at(x, y);
      if (floor_depth && ground.distance_ahead_m(y, *floor_depth) < wall_ahead_m) {
        v.field.flow()[i] =
            ground.static_flow_at(x, y, *floor_depth, kSpeedMps, kIntervalS).cast<float>();
        v.grey.at<std::uint8_t>(row, col) = 90;
        continue;
      }
      v.field.flow()[i] = Eigen::Vector2f(kNaN, kNaN);
      // The ray's height above the floor where it reaches the wall.
      const double depth_m = wall_ahead_m / (cos_pitch - y * sin_pitch);
      const double height_m = v.mount.height_m - depth_m * (y * cos_pitch + sin_pitch);
      if (height_m < 2.0) {
        v.grey.at<std::uint8_t>(row, col) = 170;
        v.truth_distance_m[i] = wall_ahead_m;
      } else {
        v.grey.at<std::uint8_t>(row, col) = 230;
      }
    }
  }
  mark_ground(v.field, v.mount, kSpeedMps, {}, v.ground_mask);
  return v;
}

// The share of the wall's pixels whose filled flow is within 0.5 px + 20% of a static point's
// flow there; no pixel but the wall's is filled.
double share_filled_right(View& v) {
  UntexturedFill fill;
  fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask);
  const FlatGround ground(v.mount);
  const double to_px = v.field.intrinsics().fx_px * kIntervalS;
  int wall = 0;
  int right = 0;
  for (int row = 0; row < v.field.height(); ++row) {
    for (int col = 0; col < v.field.width(); ++col) {
      const std::size_t i = v.field.index(col, row);
      if (v.truth_distance_m[i] == 0.0) {
        EXPECT_EQ(fill.filled()[i], 0) << "col " << col << " row " << row;
        continue;
      }
      ++wall;
      if (fill.filled()[i] == 0) {
        continue;
      }
      const double y = v.field.y(row);
      const double depth_m = *ground.depth_at_distance_ahead(y, v.truth_distance_m[i]);
      const Eigen::Vector2d exact =
          ground.static_flow_at(v.field.x(col), y, depth_m, kSpeedMps, kIntervalS);
      const double error_px = (v.field.flow()[i].cast<double>() - exact).norm() * to_px;
      right += error_px <= 0.5 + 0.2 * exact.norm() * to_px ? 1 : 0;
    }
  }
  return static_cast<double>(right) / wall;
}

TEST(UntexturedFill, APlainWallHeadOnGetsItsFootsFlow) {
  View v = wall_view([](double) { return 1.2; });
  EXPECT_GT(share_filled_right(v), 0.95);
}

TEST(UntexturedFill, AnObliqueWallGetsEachColumnsFoot) {
  // From 0.8 m ahead at the left edge to 3 m at the right.
  View v = wall_view([](double x) { return 1.9 + 1.1 * x; });
  EXPECT_GT(share_filled_right(v), 0.9);
}

TEST(UntexturedFill, ACorridorsWallsEachGetTheirFoot) {
  // Two walls 0.8 m either side, seen receding: each column's foot is as far ahead as the ray
  // meets its wall.
  View v = wall_view([](double x) { return 0.8 / std::max(std::abs(x), 0.05); });
  EXPECT_GT(share_filled_right(v), 0.8);
}

TEST(UntexturedFill, TheFloorAndTheSkyAloneGetNothing) {
  View v = wall_view([](double) { return 1e6; });
  UntexturedFill fill;
  EXPECT_EQ(fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask), 0);
}

TEST(UntexturedFill, NoiseRaisesTheEdgeThreshold) {
  // A wall whose foot steps by 80 grey levels is not found when the image's noise is such that
  // a step of that size is within what noise makes.
  View v = wall_view([](double) { return 1.2; });
  UntexturedFill fill;
  EXPECT_GT(fill.fill(v.field, v.grey, 1.0, v.mount, kSpeedMps, v.ground_mask), 0);
  View noisy = wall_view([](double) { return 1.2; });
  EXPECT_EQ(fill.fill(noisy.field, noisy.grey, 25.0, noisy.mount, kSpeedMps, noisy.ground_mask), 0);
}

}  // namespace
}  // namespace flowsteer::servo
