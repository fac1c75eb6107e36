#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/command.hpp"
#include "flowsteer/sim_camera/world_spec.hpp"

namespace flowsteer::sim_camera {

struct AgentState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  double speed_mps = 0.0;
  double turn_rate = 0.0;  // ω about the camera's y axis: positive turns right (yaw rate −ω)
  std::size_t next_goal = 0;
  bool reached_goal = false;
  double time_to_goal_s = -1.0;
  // Under Arrival::leave, once it has reached its last goal: no longer drawn, touched or moved.
  bool left_world = false;

  Eigen::Vector2d velocity_mps() const;
  // Moves on for dt_s at this speed and turn rate, as the world's step integrates them.
  void coast(double dt_s);
};

struct MovingState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();
  std::size_t next_waypoint = 1;
  double yaw_rad = 0.0;
};

// What an agent touched: another agent, a static obstacle or a moving object (a car).
enum class Body { agent, obstacle, moving };

struct Collision {
  double time_s;
  std::size_t agent;
  std::string with;  // "agent N", "obstacle N", "moving N"
  Eigen::Vector2d position_m;
  std::optional<std::size_t> other_agent;  // when two agents collide: the other one
  Body body = Body::agent;
};

// The simulated world: agents move as unicycles driven by (a_c, ω), cars along waypoints.
class World {
 public:
  // Throws std::invalid_argument naming the agent or obstacle that is wrong (an agent that
  // starts inside an obstacle or another agent, a leader that does not exist...).
  explicit World(WorldSpec spec);

  const WorldSpec& spec() const { return spec_; }
  // Unique among the worlds of this process, so that caches keyed on it never mix two worlds.
  std::uint64_t serial() const { return serial_; }
  double time_s() const { return time_s_; }
  const std::vector<AgentState>& agents() const { return agents_; }
  // Whether agent i is still in the world (see Arrival): what views, distances and contacts
  // take in.
  bool present(std::size_t agent) const { return !agents_[agent].left_world; }
  const std::vector<MovingState>& moving() const { return moving_; }

  // Advances by one step with one command per agent; agents that reached their last goal stop,
  // except those that keep steering there.
  void step(const std::vector<base::Command>& commands);
  // Agent i keeps steering at its goal once it has arrived and stays (Arrival::stay): it stops
  // at once on arrival, as the others do, and then moves by its commands.
  void keep_steering_after_arrival(std::size_t agent) { steers_after_arrival_.at(agent) = true; }
  bool steers_after_arrival(std::size_t agent) const { return steers_after_arrival_[agent]; }

  // Collisions that started during the last step (a contact counts once until it ends).
  const std::vector<Collision>& new_collisions() const { return new_collisions_; }
  // Signed distance from agent i's disc to the nearest other body (negative: overlap).
  double clearance(std::size_t agent) const;
  bool finished() const;

  // A moving obstacle's solid at its current pose, for rendering, distances and top views.
  Solid moving_now(std::size_t moving) const;

 private:
  void detect_collisions();
  void advance_goals(std::size_t agent);

  WorldSpec spec_;
  std::uint64_t serial_;
  double time_s_ = 0.0;
  std::vector<AgentState> agents_;
  std::vector<MovingState> moving_;
  std::vector<bool> followed_;                 // per agent: some agent's leader
  std::vector<bool> steers_after_arrival_;     // per agent
  std::vector<std::vector<bool>> in_contact_;  // per agent, per body
  std::vector<Collision> new_collisions_;
};

// Distance from a point to a solid's footprint (negative inside).
double footprint_distance(const Solid& solid, const Eigen::Vector2d& point);

// The corners of a box's footprint (size_m turned by yaw_rad about centre_m), counter-clockwise
// from the front left.
std::array<Eigen::Vector2d, 4> box_corners(const Solid& box);

}  // namespace flowsteer::sim_camera
