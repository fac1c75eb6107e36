#include "flowsteer/servo/motion_energy.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/analytic_scene.hpp"

namespace flowsteer::servo {
namespace {

constexpr int kSize = 64;
const base::CameraIntrinsics kCamera =
    base::CameraIntrinsics::from_horizontal_fov(kSize, kSize, 120.0 * std::acos(-1.0) / 180.0);
const base::CameraMount kMount{1.6, 0.0};
constexpr MotionEnergyLimits kLimits{1.0, 1.0, 1.5, 0.5};

// What a camera sees of an empty flat world: floor below the horizon, sky above.
struct Scene {
  std::vector<float> intensity = std::vector<float>(kSize * kSize, 0.5F);
  std::vector<PixelClass> classes = std::vector<PixelClass>(kSize * kSize);
  Scene() {
    for (int row = 0; row < kSize; ++row) {
      for (int col = 0; col < kSize; ++col) {
        at(col, row) = row > kCamera.cy_px ? PixelClass::floor : PixelClass::empty;
      }
    }
  }
  PixelClass& at(int col, int row) { return classes[static_cast<std::size_t>(row * kSize + col)]; }
  // Columns [c0, c1] and rows [r0, r1] have mass.
  void mass(int c0, int c1, int r0, int r1) {
    for (int row = r0; row <= r1; ++row) {
      for (int col = c0; col <= c1; ++col) {
        at(col, row) = PixelClass::mass;
      }
    }
  }
};

Percept goal_at(double bearing_rad, double distance_m) {
  Percept p;
  p.goal_bearing_rad = bearing_rad;
  p.goal_distance_m = distance_m;
  return p;
}

TEST(MotionEnergy, TurnsAwayFromTheHalfWithMoreEnergy) {
  Scene scene;
  scene.mass(0, 15, 10, 40);
  MotionEnergyController controller(kCamera, kMount, {}, kLimits);
  const base::Command c = controller.step(scene.intensity, scene.classes, {}, {1.0});
  EXPECT_GT(controller.state().energy_left, controller.state().energy_right);
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::energy);
  EXPECT_GT(c.turn_rate, 0.0);  // positive turns right, away from the mass on the left
}

TEST(MotionEnergy, FrameDifferenceIsTheMotionTerm) {
  Scene scene;
  scene.mass(40, 63, 10, 30);
  MotionEnergyOptions options;
  options.flow_weight = 1.0;  // no mass term: only what changed between frames
  MotionEnergyController controller(kCamera, kMount, options, kLimits);
  controller.step(scene.intensity, scene.classes, {}, {1.0});
  controller.step(scene.intensity, scene.classes, {}, {1.0});
  EXPECT_EQ(controller.state().energy_right, 0.0);
  std::fill(scene.intensity.begin(), scene.intensity.end(), 0.9F);
  const base::Command c = controller.step(scene.intensity, scene.classes, {}, {1.0});
  EXPECT_GT(controller.state().energy_right, 0.0);
  EXPECT_EQ(controller.state().energy_left, 0.0);
  EXPECT_LT(c.turn_rate, 0.0);
}

TEST(MotionEnergy, HeadOnPicksASideAndKeepsIt) {
  Scene scene;
  scene.mass(0, kSize - 1, 0, 45);  // a wall across the whole view, its foot not yet close
  MotionEnergyController controller(kCamera, kMount, {}, kLimits);
  base::Command c = controller.step(scene.intensity, scene.classes, goal_at(0.2, 8.0), {1.0});
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::head_on);
  EXPECT_DOUBLE_EQ(c.turn_rate, kLimits.max_turn_rate);  // to the goal's side
  // A little more energy on the right, still balanced, and the goal now on the other side: a
  // fresh choice would turn left, the side kept turns right.
  scene.mass(48, 63, 46, 47);
  c = controller.step(scene.intensity, scene.classes, goal_at(-0.2, 8.0), {1.0});
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::head_on);
  EXPECT_DOUBLE_EQ(c.turn_rate, kLimits.max_turn_rate);
}

TEST(MotionEnergy, DangerZoneBrakesAndTurns) {
  Scene scene;
  scene.mass(26, 37, 20, kSize - 1);  // something standing right in front, down to the bottom
  MotionEnergyController controller(kCamera, kMount, {}, kLimits);
  const base::Command c = controller.step(scene.intensity, scene.classes, goal_at(0.0, 8.0), {1.0});
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::danger);
  EXPECT_DOUBLE_EQ(c.accel_mps2, -kLimits.max_accel_mps2);
  EXPECT_DOUBLE_EQ(std::abs(c.turn_rate), kLimits.max_turn_rate);
}

TEST(MotionEnergy, RidgeGivesFreePathAndOpenings) {
  Scene scene;
  MotionEnergyController controller(kCamera, kMount, {}, kLimits);
  base::Command c = controller.step(scene.intensity, scene.classes, goal_at(0.3, 5.0), {1.0});
  EXPECT_TRUE(controller.state().free_path);
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::goal);
  EXPECT_NEAR(c.turn_rate, MotionEnergyOptions{}.goal_gain * 0.3, 1e-12);
  ASSERT_EQ(controller.openings().size(), 1U);  // the whole view

  // An obstacle straight ahead, its foot 3 m away: row cy + fy h / 3.
  const int foot = static_cast<int>(std::lround(kCamera.cy_px + kCamera.fy_px * 1.6 / 3.0));
  scene.mass(26, 37, 10, foot);
  c = controller.step(scene.intensity, scene.classes, goal_at(0.0, 5.0), {1.0});
  EXPECT_FALSE(controller.state().free_path);
  EXPECT_EQ(controller.ridge()[30], foot);
  EXPECT_EQ(controller.ridge()[10], static_cast<int>(std::floor(kCamera.cy_px)));
  ASSERT_EQ(controller.openings().size(), 2U);  // either side of it
  EXPECT_LT(controller.openings()[0].bearing_rad, 0.0);
  EXPECT_GT(controller.openings()[1].bearing_rad, 0.0);
  EXPECT_EQ(controller.state().mode, MotionEnergyMode::opening);
  EXPECT_NE(c.turn_rate, 0.0);
}

TEST(MotionEnergy, ClassesFromIdsAndSizeChecks) {
  const std::vector<std::int32_t> ids = {3, kGroundId, kSkyId, 0};
  std::vector<PixelClass> classes(ids.size());
  classify_by_ids(ids, classes);
  EXPECT_EQ(classes[0], PixelClass::mass);
  EXPECT_EQ(classes[1], PixelClass::floor);
  EXPECT_EQ(classes[2], PixelClass::empty);
  EXPECT_EQ(classes[3], PixelClass::mass);
  MotionEnergyController controller(kCamera, kMount, {}, kLimits);
  const std::vector<float> small(10, 0.0F);
  EXPECT_THROW(controller.step(small, classes, {}, {1.0}), std::invalid_argument);
  MotionEnergyOptions bad;
  bad.flow_weight = 1.5;
  EXPECT_THROW(MotionEnergyController(kCamera, kMount, bad, kLimits), std::invalid_argument);
}

TEST(MotionEnergy, GroundTestStandsInForIds) {
  // A flow field with depth: the ground at its depth, a wall 4 m ahead on the left half, sky.
  FlowField field(kCamera, true);
  const FlatGround plane(kMount);
  auto depth = field.depth();
  auto flow = field.flow();
  for (int row = 0; row < kSize; ++row) {
    for (int col = 0; col < kSize; ++col) {
      const std::size_t i = field.index(col, row);
      const auto ground = plane.depth_at(field.x(col), field.y(row));
      const bool wall = col < kSize / 2 && (!ground || *ground > 4.0);
      depth[i] = wall ? 4.0F : ground ? static_cast<float>(*ground) : INFINITY;
      flow[i] = wall ? Eigen::Vector2f(static_cast<float>(field.x(col) / 4.0), 0.0F)
                     : Eigen::Vector2f::Zero();
    }
  }
  std::vector<std::uint8_t> mask(field.size());
  std::vector<PixelClass> classes(field.size());
  classify_by_ground(field, kMount, 1.0, {}, 0.01, mask, classes);
  EXPECT_EQ(classes[field.index(10, 10)], PixelClass::mass);   // the wall, above the horizon
  EXPECT_EQ(classes[field.index(50, 10)], PixelClass::empty);  // sky
  EXPECT_EQ(classes[field.index(50, 60)], PixelClass::floor);
}

}  // namespace
}  // namespace flowsteer::servo
