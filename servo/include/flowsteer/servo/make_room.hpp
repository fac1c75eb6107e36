#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/servo/control.hpp"

namespace flowsteer::servo {

// What an agent does once it has arrived at its last goal and stays there (the world's
// Arrival::stay), as a person at a meeting point does: it stands in its goal's circle looking
// round; when it sees someone come at it, it steps aside, out of the way; once nobody has come
// at it for a while and its goal is free, it walks back; while someone stands on its goal, it
// waits where it is. Walking aside and back is the law's, steered for a point of this class's
// choosing; standing and waiting are a stop. What it sees is the percept, so it makes room only
// for what is in view, which is why it looks round while it stands.
struct MakeRoomOptions {
  // An object that comes at the agent (its FOE on it, widened by half the agent's width) with a
  // time to contact below warn_s, or slowly from nearer than warn_depth_m (one waiting its turn
  // at the agent's goal, edging in), makes it step aside.
  double warn_s = 3.0;
  double warn_depth_m = 1.5;
  // One seen coming at it within this long, and nearer than warn_depth_m now, makes it step
  // aside too, though it stands still: it waits for the agent's place (objects told apart by
  // their source ids).
  double remember_s = 10.0;
  double step_aside_m = 1.5;  // how far it steps aside
  // Stepping aside ends at its point, or after this long (something was in the way).
  double step_aside_max_s = 4.0;
  double calm_s = 1.5;           // nobody coming at it for this long, aside: it walks back
  double look_turn_rate = 0.75;  // rad/s while it stands at its goal, positive right
  double face_turn_rate = 0.6;   // rad/s, at most, while it waits aside facing its goal
  double agent_width_m = 0.5;    // its own width
  double stop_decel_mps2 = 1.0;  // how it stops
  // On its way: within this of its goal and with the goal taken, or someone nearer it walking
  // there faster than wait_speed_mps, it waits its turn, facing the goal and edging in no faster
  // than wait_speed_mps while nothing in view is nearer than wait_gap_m, instead of going round
  // and round it, or closing with the others into a ring round it that none can leave.
  double wait_range_m = 2.0;
  double wait_speed_mps = 0.2;
  double wait_gap_m = 0.25;  // it edges in only while everything in view is further than this
  // Whether someone walks to its goal is judged as the law's terms judge motion: depths guessed
  // and what stands still told apart as their ThreatOptions say (make_room_options).
  DepthGuess depth = {};
  double static_closing_ratio = ThreatOptions{}.static_closing_ratio;
};

class MakeRoom {
 public:
  enum class Mode {
    standing,    // at its goal, looking round
    giving_way,  // walking to a point aside
    aside,       // stopped aside (or short of its occupied goal), facing its goal
    returning,   // walking back to its goal
  };

  // Throws std::invalid_argument naming an option out of range.
  explicit MakeRoom(const MakeRoomOptions& options = {});

  // One control step of an agent that has arrived: `percept` holds what it sees and the bearing
  // and distance of the goal it arrived at, goal_radius_m how near that goal counts as at it.
  // Walking modes put the point to steer for into `percept` (as its goal) and return nothing:
  // the law then steers; standing modes return the command.
  std::optional<base::Command> step(Percept& percept, const AgentState& agent, double turn_rate,
                                    double goal_radius_m);
  // One control step of an agent on its way to its last goal, after the law gave `command`:
  // where that goal is near and taken, the command of one that waits its turn.
  base::Command approach(const Percept& percept, const AgentState& agent,
                         const base::Command& command, double goal_radius_m) const;
  Mode mode() const { return mode_; }

 private:
  // An object seen coming at the agent, by its source id, and when it last was.
  struct Comer {
    std::int32_t id;
    double seen_s;
  };

  // The mode for this step, from what it sees and where it is.
  void next_mode(const Percept& percept, double period_s, double goal_radius_m);
  void set_mode(Mode mode);
  // The object in view coming at the agent soonest, or near and seen coming at it before, if
  // any; remembers what it sees coming.
  const ObjectFeatures* coming_at(const Percept& percept);
  // Whether something stands on the goal's circle, on the near side of its centre, in view.
  bool goal_taken(const Percept& percept, double goal_radius_m) const;
  // Whether someone in view, nearer the goal than the agent, walks towards it faster than
  // wait_speed_mps: it gets there first.
  bool goal_contested(const Percept& percept, const AgentState& agent) const;
  void start_giving_way(const ObjectFeatures& comer);
  // Notes that `id` comes at it now; `known`: its entry, or end() for a new one.
  void remember(std::int32_t id, std::vector<Comer>::iterator known);
  void move_odometry(const AgentState& agent, double turn_rate);
  base::Command stop(const AgentState& agent, double turn_rate) const;

  MakeRoomOptions options_;
  std::vector<Comer> comers_;  // reserved: a step does not allocate
  double clock_s_ = 0.0;       // since it arrived
  Mode mode_ = Mode::standing;
  double mode_s_ = 0.0;  // time in this mode
  double calm_s_ = 0.0;  // time since something last came at it
  // The agent's pose by odometry since it arrived (x forward, y left at arrival), and the point
  // it steps aside to, in that frame.
  Eigen::Vector2d position_m_ = Eigen::Vector2d::Zero();
  double yaw_rad_ = 0.0;
  Eigen::Vector2d aside_m_ = Eigen::Vector2d::Zero();
};

}  // namespace flowsteer::servo
