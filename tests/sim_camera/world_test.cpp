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
