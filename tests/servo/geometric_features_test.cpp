#include "flowsteer/servo/geometric_features.hpp"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "flowsteer/servo/analytic_scene.hpp"

namespace flowsteer::servo {
namespace {

const base::CameraIntrinsics kCamera =
    base::CameraIntrinsics::from_horizontal_fov(64, 64, 2.0 * std::atan(1.0));
const base::CameraMount kMount{1.6, 0.0};

// A box footprint centred at (x, y), body frame.
std::array<Eigen::Vector2d, 4> square(double x, double y, double half) {
  return {Eigen::Vector2d(x - half, y - half), Eigen::Vector2d(x + half, y - half),
          Eigen::Vector2d(x + half, y + half), Eigen::Vector2d(x - half, y + half)};
}

TEST(GeometricFeatures, StaticBoxAheadGivesItsExtentDepthAndTtc) {
  const auto box = square(5.0, 0.0, 0.5);
  const GeometricBody body{7, box, 1.8, {0.0, 0.0}};
  GeometricFeatures features;
  const auto out = features.compute({&body, 1}, kCamera, kMount, 1.0);
  ASSERT_EQ(out.size(), 1U);
  const ObjectFeatures& f = out[0];
  EXPECT_EQ(f.source_id, 7);
  EXPECT_EQ(f.status, MotionStatus::approaching);
  EXPECT_NEAR(f.min_x, -0.5 / 4.5, 1e-12);
  EXPECT_NEAR(f.max_x, 0.5 / 4.5, 1e-12);
  EXPECT_NEAR(f.width, 1.0 / 4.5, 1e-12);
  EXPECT_NEAR(f.centre.x(), 0.0, 1e-12);
  EXPECT_NEAR(*f.depth_m, 4.5, 1e-12);
  EXPECT_NEAR(f.ttc_s, 4.5, 1e-12);  // τ = −Z / v_z with v_z = −1 m/s
  EXPECT_NEAR(f.foe.x(), 0.0, 1e-12);
  EXPECT_FALSE(f.cut_left || f.cut_right);
}

TEST(GeometricFeatures, SidesBehindAndEdgesOfTheView) {
  const auto left = square(5.0, 2.0, 0.5);
  const auto behind = square(-5.0, 0.0, 0.5);
  // A wall along the right side, from behind the camera to far ahead.
  const std::array<Eigen::Vector2d, 4> wall = {
      Eigen::Vector2d(-10.0, -2.1), Eigen::Vector2d(10.0, -2.1), Eigen::Vector2d(10.0, -1.9),
      Eigen::Vector2d(-10.0, -1.9)};
  const std::array<GeometricBody, 3> bodies = {GeometricBody{1, left, 1.0, {0.0, 0.0}},
                                               GeometricBody{2, behind, 1.0, {0.0, 0.0}},
                                               GeometricBody{3, wall, 2.5, {0.0, 0.0}}};
  GeometricFeatures features;
  const auto out = features.compute(bodies, kCamera, kMount, 1.0);
  ASSERT_EQ(out.size(), 2U);  // the box behind is not seen
  EXPECT_EQ(out[0].source_id, 1);
  EXPECT_LT(out[0].centre.x(), 0.0);  // y to the left is x < 0 in the image
  EXPECT_EQ(out[1].source_id, 3);
  EXPECT_TRUE(out[1].cut_right);
  EXPECT_FALSE(out[1].cut_left);
  const double right_edge = (kCamera.width_px - 0.5 - kCamera.cx_px) / kCamera.fx_px;
  EXPECT_NEAR(out[1].max_x, right_edge, 1e-9);
  EXPECT_GT(out[1].min_x, 0.0);
  // The wall's nearest visible point is where the edge of the view meets it.
  EXPECT_NEAR(*out[1].depth_m, 1.9 / right_edge, 1e-9);
}

// A box ahead and to the right, seen at its corner: its nearest point is the corner, not an end.
TEST(GeometricFeatures, ABoxSeenAtItsCornerIsNearestThere) {
  const auto box = square(5.0, -2.0, 1.0);  // corners at x 4..6, y -3..-1
  const GeometricBody body{7, box, 1.8, {0.0, 0.0}};
  GeometricFeatures features;
  const auto out = features.compute({&body, 1}, kCamera, kMount, 1.0);
  ASSERT_EQ(out.size(), 1U);
  const ObjectFeatures& f = out[0];
  EXPECT_NEAR(f.min_x, 1.0 / 6.0, 1e-12);  // the far corner of the face along the course
  EXPECT_NEAR(f.max_x, 3.0 / 4.0, 1e-12);  // the far corner of the face towards the agent
  ASSERT_TRUE(f.nearest_depth_m.has_value());
  EXPECT_NEAR(f.nearest_x, 1.0 / 4.0, 1e-12);
  EXPECT_NEAR(*f.nearest_depth_m, 4.0, 1e-12);
}

TEST(GeometricFeatures, MovingBodyHasTheAnalyticFoe) {
  AnalyticScene scene;
  scene.intrinsics = kCamera;
  scene.mount = kMount;
  scene.agent_speed_mps = 1.2;
  SceneObject car;
  car.position_m = {6.0, 1.5};
  car.length_m = car.width_m = 1.0;
  car.velocity_mps = {0.3, -0.8};
  const ObjectTruth truth = object_truth(scene, car);
  const auto box = square(6.0, 1.5, 0.5);
  const GeometricBody body{1, box, 1.8, car.velocity_mps};
  GeometricFeatures features;
  const auto out = features.compute({&body, 1}, kCamera, kMount, scene.agent_speed_mps);
  ASSERT_EQ(out.size(), 1U);
  EXPECT_NEAR(out[0].foe.x(), truth.foe.x(), 1e-12);
  // Same relative velocity, nearest face 0.5 m closer than the centre.
  EXPECT_NEAR(out[0].ttc_s * -truth.relative_velocity_mps.z(), 5.5, 1e-9);
}

TEST(GeometricFeatures, BodyMovingAlongWithTheAgentIsLateral) {
  const auto box = square(4.0, 0.0, 0.3);
  const GeometricBody body{1, box, 1.8, {1.0, 0.0}};
  GeometricFeatures features;
  const auto out = features.compute({&body, 1}, kCamera, kMount, 1.0);
  ASSERT_EQ(out.size(), 1U);
  EXPECT_EQ(out[0].status, MotionStatus::lateral);
  EXPECT_FALSE(out[0].has_foe());
}

}  // namespace
}  // namespace flowsteer::servo
