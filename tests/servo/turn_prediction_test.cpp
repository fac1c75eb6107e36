// The percept after a turn in place (servo/src/turn_prediction.hpp) against the two-body
// simulation's features of the same point seen from the turned agent.
#include "turn_prediction.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "two_body.hpp"

namespace flowsteer::servo {
namespace {

ObjectFeatures features_of(const test::TwoBody& s, bool static_foe) {
  ObjectFeatures o;
  o.source_id = 3;
  o.pixel_count = 100;
  o.centre = {s.image_x(), 0.0};
  o.min_x = o.max_x = o.nearest_x = s.image_x();
  o.depth_m = o.min_x_depth_m = o.max_x_depth_m = o.nearest_depth_m = s.depth();
  o.status = MotionStatus::approaching;
  o.foe = {s.foe_x(), 0.0};
  o.ttc_s = s.ttc();
  o.fit.static_foe = static_foe;
  return o;
}

test::TwoBody turned_in_place(test::TwoBody s, double turn_rad) {
  s.agent_yaw -= turn_rad;  // a right turn lowers the yaw
  return s;
}

void expect_turned(const test::TwoBody& before, bool static_foe, double turn_rad) {
  const std::vector<ObjectFeatures> objects = {features_of(before, static_foe)};
  const Percept now{objects, 0.3, 8.0, {}};
  std::vector<ObjectFeatures> storage;
  Percept after;
  detail::percept_after_turn(now, {before.agent_speed, 0.05}, turn_rad, DepthGuess{}, 1.5, storage,
                             after);
  const test::TwoBody truth = turned_in_place(before, turn_rad);
  ASSERT_EQ(after.objects.size(), 1u);
  const ObjectFeatures& o = after.objects[0];
  EXPECT_NEAR(o.min_x, truth.image_x(), 1e-9);
  EXPECT_NEAR(o.centre.x(), truth.image_x(), 1e-9);
  EXPECT_NEAR(*o.min_x_depth_m, truth.depth(), 1e-9);
  EXPECT_NEAR(*o.depth_m, truth.depth(), 1e-9);
  EXPECT_NEAR(o.foe.x(), truth.foe_x(), 1e-9);
  EXPECT_NEAR(o.ttc_s, truth.ttc(), 1e-9);
  EXPECT_NEAR(*after.goal_bearing_rad, 0.3 - turn_rad, 1e-12);
  EXPECT_EQ(*after.goal_distance_m, 8.0);
}

TEST(PerceptAfterTurn, AStandingPointKeepsItsPlaceInTheWorld) {
  test::TwoBody s;
  s.point = {4.0, 1.2};
  for (const double turn_rad : {0.075, -0.075, 0.3}) {
    expect_turned(s, true, turn_rad);
  }
}

TEST(PerceptAfterTurn, AMovingPointKeepsItsVelocityOverTheGround) {
  test::TwoBody s;
  s.agent_speed = 1.3;
  s.point = {6.0, 2.0};
  s.point_velocity = {-1.1, -0.4};  // walking towards the agent from ahead on its left
  for (const double turn_rad : {0.075, -0.075, 0.3}) {
    expect_turned(s, false, turn_rad);
  }
}

// A small turn moves the FOE as its rate says, ḟ = −ω (1 + f² + v_c / v_z) (dynamics.hpp).
TEST(PerceptAfterTurn, AgreesWithTheFoeRateForASmallTurn) {
  test::TwoBody s;
  s.point = {5.0, -1.0};
  s.point_velocity = {-1.0, 0.3};
  const std::vector<ObjectFeatures> objects = {features_of(s, false)};
  std::vector<ObjectFeatures> storage;
  Percept after;
  constexpr double kTurnRad = 1e-6;
  detail::percept_after_turn({objects, {}, {}, {}}, {s.agent_speed, 0.05}, kTurnRad, DepthGuess{},
                             1.5, storage, after);
  const double f = s.foe_x();
  const double expected = -(1.0 + f * f + s.agent_speed / s.relative_vz());
  EXPECT_NEAR((after.objects[0].foe.x() - f) / kTurnRad, expected, 1e-5);
}

TEST(PerceptAfterTurn, AnObjectTurnedAwayFromRecedesAndIsNoThreat) {
  test::TwoBody s;
  s.agent_speed = 0.5;
  s.point = {3.0, 0.0};
  s.point_velocity = {0.3, 0.9};  // ahead, walking off to the left
  const std::vector<ObjectFeatures> objects = {features_of(s, false)};
  ASSERT_LT(s.relative_vz(), 0.0);
  std::vector<ObjectFeatures> storage;
  Percept after;
  // Turned 60° left, the agent faces the way the point walks, faster than the agent.
  detail::percept_after_turn({objects, {}, {}, {}}, {s.agent_speed, 0.05}, -1.05, DepthGuess{}, 1.5,
                             storage, after);
  EXPECT_GT(turned_in_place(s, -1.05).relative_vz(), 0.0);
  EXPECT_EQ(after.objects[0].status, MotionStatus::receding);
  EXPECT_TRUE(std::isinf(after.objects[0].ttc_s));
}

}  // namespace
}  // namespace flowsteer::servo
