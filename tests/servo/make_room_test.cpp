#include "flowsteer/servo/make_room.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace flowsteer::servo {
namespace {

constexpr double kStep = 0.05;
constexpr double kGoalRadius = 0.5;

// A body `depth_m` ahead at image column x (normalised), 0.6 m wide; coming at the agent (its
// FOE on it) when ttc_s is finite, else standing still.
ObjectFeatures body(std::int32_t id, double x, double depth_m, double ttc_s) {
  ObjectFeatures o;
  o.source_id = id;
  o.centre = {x, 0.0};
  o.width = 0.6 / depth_m;
  o.min_x = x - 0.5 * o.width;
  o.max_x = x + 0.5 * o.width;
  o.depth_m = depth_m;
  o.nearest_depth_m = depth_m;
  if (std::isfinite(ttc_s)) {
    o.status = MotionStatus::approaching;
    o.ttc_s = ttc_s;
    o.foe = {x, 0.0};
  }
  return o;
}

// A percept views `objects`, which must outlive it: a temporary list is refused.
Percept percept_of(const std::vector<ObjectFeatures>& objects, double goal_bearing_rad,
                   double goal_distance_m) {
  return {objects, goal_bearing_rad, goal_distance_m, {}};
}
Percept percept_of(std::vector<ObjectFeatures>&& objects, double, double) = delete;
const std::vector<ObjectFeatures> kNothing;

TEST(MakeRoom, AtItsGoalItStandsLookingRound) {
  MakeRoom room;
  Percept seen = percept_of(kNothing, 0.0, 0.2);
  const auto command = room.step(seen, {0.3, kStep}, 0.0, kGoalRadius);
  ASSERT_TRUE(command);
  EXPECT_LT(command->accel_mps2, 0.0);  // it stops
  EXPECT_DOUBLE_EQ(command->turn_rate, MakeRoomOptions{}.look_turn_rate);
  EXPECT_EQ(room.mode(), MakeRoom::Mode::standing);
  // At rest it stays at rest: the base never backs up.
  EXPECT_DOUBLE_EQ(room.step(seen, {0.0, kStep}, 0.4, kGoalRadius)->accel_mps2, 0.0);
}

TEST(MakeRoom, OneComingAtItFromTheRightMakesItStepAsideToTheLeft) {
  MakeRoom room;
  const std::vector<ObjectFeatures> comer = {body(7, 0.3, 2.0, 1.5)};
  Percept seen = percept_of(comer, 0.0, 0.2);
  EXPECT_FALSE(room.step(seen, {0.0, kStep}, 0.0, kGoalRadius));  // the law steers
  EXPECT_EQ(room.mode(), MakeRoom::Mode::giving_way);
  // The point it steers for: 1.5 m away, 120° round from the comer's bearing, to the left.
  const double comer_bearing = std::atan(0.3);
  EXPECT_NEAR(*seen.goal_bearing_rad, comer_bearing - 2.0 * std::numbers::pi / 3.0, 1e-9);
  EXPECT_NEAR(*seen.goal_distance_m, MakeRoomOptions{}.step_aside_m, 1e-9);
}

TEST(MakeRoom, OnePassingByIsNoReasonToMove) {
  MakeRoom room;
  std::vector<ObjectFeatures> passer = {body(7, 0.3, 2.0, 1.5)};
  passer[0].foe = {1.5, 0.0};  // its course passes 2.4 m to the right
  Percept seen = percept_of(passer, 0.0, 0.2);
  EXPECT_TRUE(room.step(seen, {0.0, kStep}, 0.0, kGoalRadius));
  EXPECT_EQ(room.mode(), MakeRoom::Mode::standing);
}

TEST(MakeRoom, ItWalksAsideWaitsThenComesBackWhenItsGoalIsFree) {
  MakeRoom room;
  const std::vector<ObjectFeatures> comer = {body(7, 0.0, 2.0, 1.5)};
  Percept seen = percept_of(comer, 0.0, 0.2);
  room.step(seen, {0.0, kStep}, 0.0, kGoalRadius);
  ASSERT_EQ(room.mode(), MakeRoom::Mode::giving_way);
  // It turns to the point and walks there at 1 m/s (the odometry it keeps).
  const double turn = *seen.goal_bearing_rad / kStep;
  Percept walking = percept_of(kNothing, 0.0, 3.0);
  room.step(walking, {0.0, kStep}, turn, kGoalRadius);
  for (int k = 0; k < 40 && room.mode() == MakeRoom::Mode::giving_way; ++k) {
    walking = percept_of(kNothing, 0.0, 3.0);
    room.step(walking, {1.0, kStep}, 0.0, kGoalRadius);
  }
  ASSERT_EQ(room.mode(), MakeRoom::Mode::aside);
  // Aside, its goal free: after calm_s it walks back (the law steers for the goal).
  int steps = 0;
  for (; room.mode() == MakeRoom::Mode::aside && steps < 100; ++steps) {
    Percept free = percept_of(kNothing, 0.0, 1.5);
    room.step(free, {0.0, kStep}, 0.0, kGoalRadius);
  }
  EXPECT_EQ(room.mode(), MakeRoom::Mode::returning);
  EXPECT_NEAR(steps * kStep, MakeRoomOptions{}.calm_s, 2 * kStep);
  // Someone stands on its goal 1.5 m ahead: it waits, facing the goal.
  const std::vector<ObjectFeatures> on_goal = {body(9, 0.0, 1.2, INFINITY)};
  for (int k = 0; k < 20; ++k) {
    Percept taken = percept_of(on_goal, 0.2, 1.5);
    const auto command = room.step(taken, {0.0, kStep}, 0.0, kGoalRadius);
    ASSERT_TRUE(command);
    EXPECT_GT(command->turn_rate, 0.0);  // towards the goal, on the right
    EXPECT_EQ(room.mode(), MakeRoom::Mode::aside);
  }
  // Free again: back, and standing once there.
  Percept free = percept_of(kNothing, 0.0, 1.5);
  EXPECT_FALSE(room.step(free, {0.0, kStep}, 0.0, kGoalRadius));
  EXPECT_EQ(room.mode(), MakeRoom::Mode::returning);
  Percept home = percept_of(kNothing, 0.0, 0.4);
  EXPECT_TRUE(room.step(home, {0.5, kStep}, 0.0, kGoalRadius));
  EXPECT_EQ(room.mode(), MakeRoom::Mode::standing);
}

TEST(MakeRoom, OneSeenComingThatNowWaitsNearStillGetsThePlace) {
  MakeRoom room;
  // Seen coming from far (5 s away), then standing 1 m off, looked away from and back at.
  const std::vector<ObjectFeatures> coming = {body(7, 0.0, 4.0, 5.0)};
  Percept far = percept_of(coming, 0.0, 0.2);
  room.step(far, {0.0, kStep}, 0.0, kGoalRadius);
  EXPECT_EQ(room.mode(), MakeRoom::Mode::standing);
  Percept nothing = percept_of(kNothing, 0.0, 0.2);
  room.step(nothing, {0.0, kStep}, 0.0, kGoalRadius);
  const std::vector<ObjectFeatures> standing = {body(7, 0.0, 1.0, INFINITY)};
  Percept waiting = percept_of(standing, 0.0, 0.2);
  room.step(waiting, {0.0, kStep}, 0.0, kGoalRadius);
  EXPECT_EQ(room.mode(), MakeRoom::Mode::giving_way);
  // Something near it never saw come (a pillar) is no reason to move.
  MakeRoom other;
  const std::vector<ObjectFeatures> pillar = {body(8, 0.0, 1.0, INFINITY)};
  Percept beside_pillar = percept_of(pillar, 0.0, 0.2);
  other.step(beside_pillar, {0.0, kStep}, 0.0, kGoalRadius);
  EXPECT_EQ(other.mode(), MakeRoom::Mode::standing);
}

TEST(MakeRoom, OnItsWayItWaitsItsTurnAtATakenGoal) {
  const MakeRoom room;
  const base::Command law{0.8, -1.5};
  // Someone stands on the goal, 1.5 m ahead: it edges in, facing the goal.
  const std::vector<ObjectFeatures> on_goal = {body(7, 0.0, 1.1, INFINITY)};
  const base::Command waiting =
      room.approach(percept_of(on_goal, 0.1, 1.5), {0.5, kStep}, law, kGoalRadius);
  EXPECT_LT(waiting.accel_mps2, 0.0);  // down to wait_speed_mps
  EXPECT_GT(waiting.turn_rate, 0.0);   // to the goal, on the right
  EXPECT_GT(room.approach(percept_of(on_goal, 0.0, 1.5), {0.1, kStep}, law, kGoalRadius).accel_mps2,
            0.0);
  // A wall seen aslant beside the goal, 0.45 m deep at the image's left edge and 1.9 m where the
  // line to the goal (0.55 m) meets it.
  ObjectFeatures aslant = body(9, -1.7, 0.45, INFINITY);
  aslant.min_x = -3.7;
  aslant.max_x = 0.3;
  aslant.nearest_x = aslant.min_x;
  aslant.min_x_depth_m = 0.45;
  aslant.max_x_depth_m = 2.5;
  // A wall behind the goal, someone beside the way, a goal further than wait_range_m, the wall
  // aslant: the law's.
  for (const auto& [objects, distance_m] :
       {std::pair{std::vector<ObjectFeatures>{body(7, 0.0, 1.8, INFINITY)}, 1.5},
        {std::vector<ObjectFeatures>{body(7, 1.0, 1.1, INFINITY)}, 1.5},
        {on_goal, 2.5},
        {std::vector<ObjectFeatures>{aslant}, 0.55}}) {
    const base::Command command =
        room.approach(percept_of(objects, 0.0, distance_m), {0.5, kStep}, law, kGoalRadius);
    EXPECT_EQ(command.accel_mps2, law.accel_mps2);
    EXPECT_EQ(command.turn_rate, law.turn_rate);
  }
  // Crowded, with someone 0.4 m away beside it: it stops edging in.
  const std::vector<ObjectFeatures> crowded = {on_goal[0], body(8, -0.8, 0.4, INFINITY)};
  EXPECT_LT(room.approach(percept_of(crowded, 0.0, 1.5), {0.1, kStep}, law, kGoalRadius).accel_mps2,
            0.0);
}

// Someone walking at ground_mps (x right, z ahead), its near side 1 m ahead at image column 0.9.
ObjectFeatures walker(const Eigen::Vector2d& ground_mps, double agent_speed_mps) {
  ObjectFeatures o = body(7, 0.9, 1.0, INFINITY);
  const Eigen::Vector2d relative = ground_mps - Eigen::Vector2d(0.0, agent_speed_mps);
  o.status = relative.y() < 0.0 ? MotionStatus::approaching : MotionStatus::receding;
  o.ttc_s = -*o.depth_m / relative.y();
  o.foe = {relative.x() / relative.y(), 0.0};
  return o;
}

// Six walking to one point closed into a ring round it, each held by the two beside it, and none
// arrived (converge_six at 120² and 160²). One nearer the goal and walking to it gets there first:
// the agent waits its turn as at a taken goal.
TEST(MakeRoom, OnItsWayItLetsOneNearerItsGoalWalkingThereGoFirst) {
  const MakeRoom room;
  const base::Command law{0.8, -1.5};
  constexpr double kSpeed = 0.5;
  const double goal_bearing = 0.3;  // 1.8 m away: 0.8 m from the walker's centre, left of it
  const std::vector<ObjectFeatures> to_goal = {walker({-0.7, 0.7}, kSpeed)};
  const base::Command waiting =
      room.approach(percept_of(to_goal, goal_bearing, 1.8), {kSpeed, kStep}, law, kGoalRadius);
  EXPECT_LT(waiting.accel_mps2, 0.0);  // down to wait_speed_mps
  EXPECT_GT(waiting.turn_rate, 0.0);   // to the goal, on the right
  // Walking away from the goal, standing beside it, walking to it from further than the agent, or
  // the goal further than wait_range_m: the law's.
  const std::vector<ObjectFeatures> away = {walker({0.7, -0.7}, kSpeed)};
  const std::vector<ObjectFeatures> standing = {walker({0.0, 0.0}, kSpeed)};
  for (const auto& [objects, distance_m] :
       {std::pair{away, 1.8}, {standing, 1.8}, {to_goal, 0.6}, {to_goal, 2.5}}) {
    const base::Command command = room.approach(percept_of(objects, goal_bearing, distance_m),
                                                {kSpeed, kStep}, law, kGoalRadius);
    EXPECT_EQ(command.accel_mps2, law.accel_mps2) << distance_m;
    EXPECT_EQ(command.turn_rate, law.turn_rate) << distance_m;
  }
}

TEST(MakeRoom, OptionsOutOfRangeAreRefused) {
  EXPECT_THROW(MakeRoom({.warn_s = 0.0}), std::invalid_argument);
  EXPECT_THROW(MakeRoom({.step_aside_m = 0.2}), std::invalid_argument);
  EXPECT_THROW(MakeRoom({.agent_width_m = -1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::servo
