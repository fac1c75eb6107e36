#include "ground_motion_check.hpp"

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(FlatGround, WhereAGroundPointWasSeenBeforeMovingForwardIsItsDisplacementFlow) {
  const base::CameraMount mount{0.45, 8.0 * kDeg};
  const FlatGround ground(mount);
  const double interval_s = 0.2;
  const double speed_mps = 0.7;
  for (const double x : {-0.9, 0.0, 0.4}) {
    for (const double y : {0.05, 0.3, 0.7}) {
      const auto before = ground.seen_before_moving(x, y, {speed_mps * interval_s, 0.0});
      ASSERT_TRUE(before.has_value());
      const Eigen::Vector2d flow = (Eigen::Vector2d(x, y) - *before) / interval_s;
      const Eigen::Vector2d expected =
          ground.static_flow_at(x, y, *ground.depth_at(x, y), speed_mps, interval_s);
      EXPECT_NEAR((flow - expected).norm(), 0.0, 1e-9) << x << ", " << y;
    }
  }
  EXPECT_FALSE(ground.seen_before_moving(0.0, -0.2, {0.1, 0.0}).has_value());
}

TEST(FlatGround, WhereAGroundPointWasSeenBeforeMovingAsideIsWhereItLay) {
  const base::CameraMount mount{1.6, -3.0 * kDeg};
  const FlatGround ground(mount);
  const Eigen::Vector2d moved_m(0.3, -0.25);
  const auto point = ground.point_at(0.3, 0.5);
  ASSERT_TRUE(point.has_value());
  const auto expected = ground.image_of(*point + moved_m);
  const auto before = ground.seen_before_moving(0.3, 0.5, moved_m);
  ASSERT_TRUE(expected.has_value() && before.has_value());
  EXPECT_NEAR((*before - expected->head<2>()).norm(), 0.0, 1e-12);
}

TEST(GroundMotionCheck, AQuarterCircleLeftMovedTheBaseForwardAndRightOfWhereItLooksNow) {
  const double radius_m = 2.0;
  // Heading east from the origin round a centre 2 m north: it ends at (2, 2) heading north, so
  // its start lies 2 m behind and 2 m to its left.
  const Eigen::Vector2d moved =
      moved_since({0.5 * std::numbers::pi * radius_m, 0.5 * std::numbers::pi});
  EXPECT_NEAR(moved.x(), radius_m, 1e-12);
  EXPECT_NEAR(moved.y(), -radius_m, 1e-12);
  const Eigen::Vector2d straight = moved_since({0.3, 0.0});
  EXPECT_NEAR((straight - Eigen::Vector2d(0.3, 0.0)).norm(), 0.0, 1e-12);
}

// A camera over a textured floor, looking east, with optionally a textured wall across the way
// at x = wall_x_m: the image from the camera at (camera_x_m, 0).
class FloorScene {
 public:
  FloorScene(const base::CameraMount& mount, const base::CameraIntrinsics& intrinsics,
             std::optional<double> wall_x_m)
      : mount_(mount), intrinsics_(intrinsics), ground_(mount), wall_x_m_(wall_x_m) {
    cv::Mat noise(kTexturePx / 4, kTexturePx / 4, CV_8UC1);
    cv::RNG rng(11);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::resize(noise, texture_, cv::Size(kTexturePx, kTexturePx), 0, 0, cv::INTER_CUBIC);
  }

  cv::Mat image(double camera_x_m) const {
    cv::Mat map_x(intrinsics_.height_px, intrinsics_.width_px, CV_32FC1, cv::Scalar(-1));
    cv::Mat map_y(intrinsics_.height_px, intrinsics_.width_px, CV_32FC1, cv::Scalar(-1));
    for (int row = 0; row < intrinsics_.height_px; ++row) {
      for (int col = 0; col < intrinsics_.width_px; ++col) {
        const auto at = texture_at(x(col), y(row), camera_x_m);
        if (at) {
          map_x.at<float>(row, col) = static_cast<float>(at->x());
          map_y.at<float>(row, col) = static_cast<float>(at->y());
        }
      }
    }
    cv::Mat out;
    cv::remap(texture_, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
    return out;
  }

  // Seen from the camera at x = 0, where the wall is nearer than the floor along the ray through
  // (x, y): its depth.
  std::optional<double> wall_depth(double x, double y) const {
    if (!wall_x_m_)
      return std::nullopt;
    const auto wall = ground_.depth_at_distance_ahead(y, *wall_x_m_);
    const auto floor = ground_.depth_at(x, y);
    if (wall && (!floor || *wall < *floor))
      return wall;
    return std::nullopt;
  }

  double x(int col) const { return (col - intrinsics_.cx_px) / intrinsics_.fx_px; }
  double y(int row) const { return (row - intrinsics_.cy_px) / intrinsics_.fy_px; }

 private:
  static constexpr int kTexturePx = 2048;
  static constexpr double kTexelM = 0.01;

  // The texel seen through (x, y) from the camera at (camera_x_m, 0).
  std::optional<Eigen::Vector2d> texture_at(double x, double y, double camera_x_m) const {
    const Eigen::Vector3d ray = mount_.camera_to_body() * Eigen::Vector3d(x, y, 1.0);
    if (wall_x_m_ && ray.x() > 1e-9) {
      const double depth = (*wall_x_m_ - camera_x_m) / ray.x();
      const Eigen::Vector3d hit = depth * ray;
      if (hit.z() > -mount_.height_m) {
        return Eigen::Vector2d(hit.y() / kTexelM + kTexturePx / 2.0,
                               (mount_.height_m + hit.z()) / kTexelM + 10.0);
      }
    }
    const auto point = ground_.point_at(x, y);
    if (!point)
      return std::nullopt;
    return Eigen::Vector2d((camera_x_m + point->x()) / kTexelM + 10.0,
                           point->y() / kTexelM + kTexturePx / 2.0);
  }

  base::CameraMount mount_;
  base::CameraIntrinsics intrinsics_;
  FlatGround ground_;
  std::optional<double> wall_x_m_;
  cv::Mat texture_;
};

// DIS over the pair of images from 0.2 s apart, the camera having driven `driven_m` forward
// between them; the ground is tested only when `tell_motion`.
FlowField floor_flow(const FloorScene& scene, const base::CameraMount& mount,
                     const base::CameraIntrinsics& intrinsics, double driven_m, bool tell_motion) {
  const std::unique_ptr<FlowSource> flow = make_flow_source(FlowMethod::dis_medium);
  CameraMotion motion;
  if (tell_motion) {
    motion.travelled = [&](double from_s, double to_s) {
      return BaseTravel{driven_m * (to_s - from_s) / 0.2, 0.0};
    };
    motion.ground_mount = mount;
  }
  FlowField field(intrinsics);
  EXPECT_EQ(flow->update({scene.image(-driven_m), 0.0}, motion, field),
            FlowStatus::no_previous_frame);
  EXPECT_EQ(flow->update({scene.image(0.0), 0.2}, motion, field), FlowStatus::ok);
  return field;
}

// The share of the measured pixels among `pixels` within 20 % of `expected`'s flow.
template <typename Pixels, typename Expected>
double share_within(const FlowField& field, Pixels pixels, Expected expected) {
  int measured = 0;
  int within = 0;
  pixels([&](int col, int row) {
    const Eigen::Vector2f& u = field.at(col, row);
    if (!u.allFinite())
      return;
    ++measured;
    const Eigen::Vector2d e = expected(col, row);
    within += (u.cast<double>() - e).norm() <= 0.2 * e.norm();
  });
  EXPECT_GT(measured, 100);
  return measured > 0 ? static_cast<double>(within) / measured : 0.0;
}

const base::CameraMount kRobotMount{0.45, 8.0 * kDeg};
const auto kRobotCamera = base::CameraIntrinsics::from_horizontal_fov(160, 120, 90.0 * kDeg);

// Over 0.2 s at 1 m/s the floor in the lowest quarter of a robot's view moves 20–60 px, more than
// DIS follows; the ground's own motion matches it there.
TEST(GroundMotionCheck, TheNearFloorGetsItsMotionWhereTheEstimatorFallsShort) {
  const FloorScene scene(kRobotMount, kRobotCamera, std::nullopt);
  const FlatGround ground(kRobotMount);
  const double driven_m = 0.2;
  const auto lowest_quarter = [&](auto&& visit) {
    for (int row = kRobotCamera.height_px * 3 / 4; row < kRobotCamera.height_px - 2; ++row)
      for (int col = 2; col < kRobotCamera.width_px - 2; ++col)
        visit(col, row);
  };
  const auto floor_motion = [&](int col, int row) {
    const double x = scene.x(col);
    const double y = scene.y(row);
    return ground.static_flow_at(x, y, *ground.depth_at(x, y), driven_m / 0.2, 0.2);
  };
  const double without = share_within(floor_flow(scene, kRobotMount, kRobotCamera, driven_m, false),
                                      lowest_quarter, floor_motion);
  const double with = share_within(floor_flow(scene, kRobotMount, kRobotCamera, driven_m, true),
                                   lowest_quarter, floor_motion);
  EXPECT_GT(with, 0.9);
  EXPECT_GT(with, without + 0.1);
}

// A wall 1.5 m ahead moves as itself, not as the floor behind it would, but at its foot: it keeps
// the estimator's flow.
TEST(GroundMotionCheck, AWallAcrossTheWayKeepsItsOwnMotion) {
  const double wall_x_m = 1.5;
  const FloorScene scene(kRobotMount, kRobotCamera, wall_x_m);
  const FlatGround ground(kRobotMount);
  const double driven_m = 0.2;
  const auto foot_y = *ground.image_of({wall_x_m, 0.0}, 0.0);
  const int foot_row = static_cast<int>(foot_y.y() * kRobotCamera.fy_px + kRobotCamera.cy_px);
  // The wall from 6 rows above its foot up to the view's top.
  const auto wall = [&](auto&& visit) {
    for (int row = 2; row < foot_row - 6; ++row)
      for (int col = 2; col < kRobotCamera.width_px - 2; ++col)
        visit(col, row);
  };
  const auto wall_motion = [&](int col, int row) {
    const double x = scene.x(col);
    const double y = scene.y(row);
    return ground.static_flow_at(x, y, *scene.wall_depth(x, y), driven_m / 0.2, 0.2);
  };
  const FlowField without = floor_flow(scene, kRobotMount, kRobotCamera, driven_m, false);
  const FlowField with = floor_flow(scene, kRobotMount, kRobotCamera, driven_m, true);
  EXPECT_GT(share_within(with, wall, wall_motion), 0.8);
  EXPECT_NEAR(share_within(with, wall, wall_motion), share_within(without, wall, wall_motion),
              0.02);
}

TEST(GroundMotionCheck, NegativeOptionsAreRefused) {
  for (const auto set : {+[](OpticalFlowOptions& o) { o.ground_match_ratio = -0.1; },
                         +[](OpticalFlowOptions& o) { o.ground_match_px = -1.0; },
                         +[](OpticalFlowOptions& o) { o.ground_match_noise_margin = -2.0; }}) {
    OpticalFlowOptions options;
    set(options);
    EXPECT_THROW(make_flow_source(FlowMethod::dis_medium, options), std::invalid_argument);
  }
}

}  // namespace
}  // namespace flowsteer::servo
