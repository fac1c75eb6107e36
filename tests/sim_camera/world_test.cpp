#include "flowsteer/sim_camera/world.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace flowsteer::sim_camera {
namespace {

AgentSpec walker(Eigen::Vector2d start, double heading_rad, Eigen::Vector2d goal) {
  AgentSpec a;
  a.start_m = start;
  a.heading_rad = heading_rad;
  a.start_speed_mps = 1.0;
  a.goals = {goal};
  return a;
}

TEST(World, UnicycleTurnsRightForPositiveTurnRate) {
  WorldSpec spec;
  spec.agents = {walker({0, 0}, 0.0, {10, 0})};
  World world(spec);
  for (int k = 0; k < 10; ++k) {
    world.step({{0.0, 0.5}});
  }
  EXPECT_LT(world.agents()[0].yaw_rad, 0.0);  // clockwise: to the right of +x
  EXPECT_LT(world.agents()[0].position_m.y(), 0.0);
  EXPECT_NEAR(world.time_s(), 0.5, 1e-12);
}

TEST(World, HeadOnAgentsCollideOnceAndBothCount) {
  WorldSpec spec;
  spec.agents = {walker({0, 0}, 0.0, {10, 0}), walker({3, 0}, M_PI, {-10, 0})};
  World world(spec);
  std::vector<Collision> all;
  for (int k = 0; k < 60; ++k) {
    world.step({{0.0, 0.0}, {0.0, 0.0}});
    all.insert(all.end(), world.new_collisions().begin(), world.new_collisions().end());
  }
  ASSERT_EQ(all.size(), 1U);  // one contact, however long it lasts
  EXPECT_EQ(all[0].agent, 0U);
  EXPECT_EQ(all[0].with, "agent 1");
  EXPECT_EQ(all[0].body, Body::agent);
  ASSERT_TRUE(all[0].other_agent.has_value());
  EXPECT_EQ(*all[0].other_agent, 1U);
  EXPECT_NEAR(all[0].time_s, 1.25, 0.051);  // 3 m apart, closing at 2 m/s, radii 0.25 each
}

TEST(World, AContactSaysWhatKindOfBodyWasTouched) {
  WorldSpec spec;
  spec.agents = {walker({0, 0}, 0.0, {10, 0}), walker({0, 5}, 0.0, {10, 5})};
  Solid wall;  // across the first agent's way, 2 m ahead
  wall.centre_m = {2.5, 0.0};
  wall.size_m = {0.2, 2.0};
  spec.obstacles = {wall};
  MovingObstacle car;  // a 1 m box parked across the second agent's way, touched later
  car.body.centre_m = {4.0, 5.0};
  car.waypoints = {{4.0, 5.0}, {4.0, 5.1}};
  spec.moving = {car};
  World world(spec);
  std::vector<Collision> all;
  for (int k = 0; k < 80; ++k) {
    world.step({{0.0, 0.0}, {0.0, 0.0}});
    all.insert(all.end(), world.new_collisions().begin(), world.new_collisions().end());
  }
  ASSERT_EQ(all.size(), 2U);
  EXPECT_EQ(all[0].body, Body::obstacle);
  EXPECT_EQ(all[0].with, "obstacle 0");
  EXPECT_FALSE(all[0].other_agent.has_value());
  EXPECT_EQ(all[1].body, Body::moving);
  EXPECT_EQ(all[1].with, "moving 0");
}

// Agent 1 stands at its goal; agent 0 walks through where it stands.
WorldSpec walk_through_standing(Arrival arrival) {
  WorldSpec spec;
  spec.arrival = arrival;
  spec.agents = {walker({0, 0}, 0.0, {10, 0}), walker({3, 0}, 0.0, {3, 0})};
  spec.agents[1].start_speed_mps = 0.0;
  return spec;
}

TEST(World, UnderLeaveAnArrivedAgentIsTouchedByNoOne) {
  for (const Arrival arrival : {Arrival::stay, Arrival::leave}) {
    SCOPED_TRACE(std::string(to_string(arrival)));
    World world(walk_through_standing(arrival));
    int contacts = 0;
    for (int k = 0; k < 60; ++k) {
      world.step({{0.0, 0.0}, {0.0, 0.0}});
      contacts += static_cast<int>(world.new_collisions().size());
    }
    EXPECT_TRUE(world.agents()[1].reached_goal);
    EXPECT_NEAR(world.agents()[1].time_to_goal_s, 0.05, 1e-12);  // at the first step
    EXPECT_EQ(world.present(1), arrival == Arrival::stay);
    EXPECT_EQ(contacts, arrival == Arrival::stay ? 1 : 0);
    // Agent 0 is 3 m past the standing one's place: under leave only the world is near it.
    EXPECT_EQ(std::isinf(world.clearance(0)), arrival == Arrival::leave);
    EXPECT_EQ(std::isinf(world.clearance(1)), arrival == Arrival::leave);
  }
}

TEST(World, UnderLeaveAnIdlingAgentLeavesAfterItsIdleTime) {
  WorldSpec spec = walk_through_standing(Arrival::leave);
  spec.agents[1].idle_s = 1.0;
  World world(spec);
  for (int k = 0; k < 40 && world.present(1); ++k) {
    world.step({{0.0, 0.0}, {0.0, 0.0}});
  }
  EXPECT_FALSE(world.present(1));
  EXPECT_NEAR(world.time_s(), 0.05 + 1.0, 1e-9);  // arrived at the first step, idled 1 s
}

TEST(World, AnAgentOthersFollowStaysUnderLeave) {
  WorldSpec spec = walk_through_standing(Arrival::leave);
  spec.agents[0].goals.clear();
  spec.agents[0].leader = 1;
  World world(spec);
  world.step({{0.0, 0.0}, {0.0, 0.0}});
  EXPECT_TRUE(world.agents()[1].reached_goal);
  EXPECT_TRUE(world.present(1));
}

TEST(World, ArrivalRulesHaveNames) {
  for (const Arrival arrival : {Arrival::stay, Arrival::leave}) {
    EXPECT_EQ(parse_arrival(to_string(arrival)), arrival);
  }
  EXPECT_FALSE(parse_arrival("go"));
}

TEST(World, CarsFollowTheirWaypoints) {
  WorldSpec spec;
  spec.agents = {walker({0, -5}, 0.0, {10, -5})};
  MovingObstacle car;
  car.waypoints = {{0, 0}, {4, 0}, {4, 4}};
  car.speed_mps = 2.0;
  spec.moving = {car};
  World world(spec);
  for (int k = 0; k < 60; ++k) {  // 3 s: 4 m along x, then 2 m along y
    world.step({{0.0, 0.0}});
  }
  EXPECT_NEAR(world.moving()[0].position_m.x(), 4.0, 1e-9);
  EXPECT_NEAR(world.moving()[0].position_m.y(), 2.0, 1e-9);
  EXPECT_NEAR(world.moving()[0].velocity_mps.y(), 2.0, 1e-9);
  for (int k = 0; k < 40; ++k) {
    world.step({{0.0, 0.0}});
  }
  EXPECT_EQ(world.moving()[0].velocity_mps, Eigen::Vector2d::Zero());  // stopped at the end
}

TEST(World, BadWorldsAreRejectedWithTheirReason) {
  WorldSpec spec;
  spec.agents = {walker({0, 0}, 0.0, {5, 0})};
  Solid box;
  box.centre_m = {0.2, 0.0};
  spec.obstacles = {box};
  EXPECT_THROW(World{spec}, std::invalid_argument);
  spec.obstacles.clear();
  spec.agents[0].leader = 3;
  spec.agents[0].goals.clear();
  try {
    World world(spec);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("leader 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(World{WorldSpec{}}, std::invalid_argument);  // no agent
}

TEST(Footprint, DistanceToARotatedBox) {
  Solid box;
  box.size_m = {2.0, 1.0};
  box.yaw_rad = M_PI / 2;  // long side along y
  EXPECT_NEAR(footprint_distance(box, {0.0, 2.0}), 1.0, 1e-12);
  EXPECT_NEAR(footprint_distance(box, {1.0, 0.0}), 0.5, 1e-12);
  EXPECT_NEAR(footprint_distance(box, {0.0, 0.0}), -0.5, 1e-12);
}

}  // namespace
}  // namespace flowsteer::sim_camera
