#include "flowsteer/servo/make_room.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "contact_time.hpp"
#include "cost_term_helpers.hpp"

namespace flowsteer::servo {

namespace {

constexpr double kPi = std::numbers::pi;
// Stepping aside ends this near its point.
constexpr double kAsideReachedM = 0.3;
// Goals further round than this are out of any view it has: it cannot tell whether one is free.
constexpr double kGoalInViewRad = 1.4;
// How many comers it remembers; the oldest is forgotten first.
constexpr std::size_t kComers = 16;

// Bearing (positive right) and distance of `point` from a pose (x forward, y left, yaw
// counter-clockwise).
std::pair<double, double> bearing_and_distance(const Eigen::Vector2d& point,
                                               const Eigen::Vector2d& position, double yaw_rad) {
  const Eigen::Vector2d d = point - position;
  return {-std::remainder(std::atan2(d.y(), d.x()) - yaw_rad, 2.0 * kPi), d.norm()};
}

// The depth of an object's nearest point where it has one, else its mean depth.
std::optional<double> object_depth(const ObjectFeatures& object) {
  return object.nearest_depth_m ? object.nearest_depth_m : object.depth_m;
}

// The depth of an object at image column x within its extent, from its outline (its ends and its
// nearest point, on each piece of which, a plane, inverse depth is affine in x); its
// object_depth without depths at its ends. A wall seen aslant beside the line to the goal is
// near at the image's edge and far where the goal's column meets it.
std::optional<double> depth_at_column(const ObjectFeatures& object, double x) {
  if (!object.min_x_depth_m || !object.max_x_depth_m) {
    return object_depth(object);
  }
  if (object.nearest_depth_m && object.nearest_x > object.min_x &&
      object.nearest_x < object.max_x) {
    return x < object.nearest_x
               ? detail::plane_depth_at(x, object.min_x, *object.min_x_depth_m, object.nearest_x,
                                        *object.nearest_depth_m)
               : detail::plane_depth_at(x, object.nearest_x, *object.nearest_depth_m, object.max_x,
                                        *object.max_x_depth_m);
  }
  return detail::plane_depth_at(x, object.min_x, *object.min_x_depth_m, object.max_x,
                                *object.max_x_depth_m);
}

}  // namespace

MakeRoom::MakeRoom(const MakeRoomOptions& options) : options_(options) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) {
      throw std::invalid_argument("make room options: " + what);
    }
  };
  require(options.warn_s > 0.0, "warn_s must be positive");
  require(options.step_aside_m > kAsideReachedM, "step_aside_m must exceed 0.3 m");
  require(options.step_aside_max_s > 0.0, "step_aside_max_s must be positive");
  require(options.calm_s >= 0.0, "calm_s must not be negative");
  require(options.face_turn_rate > 0.0, "face_turn_rate must be positive");
  require(options.agent_width_m > 0.0, "agent_width_m must be positive");
  require(options.stop_decel_mps2 > 0.0, "stop_decel_mps2 must be positive");
  comers_.reserve(kComers);
}

std::optional<base::Command> MakeRoom::step(Percept& percept, const AgentState& agent,
                                            double turn_rate, double goal_radius_m) {
  move_odometry(agent, turn_rate);
  mode_s_ += agent.period_s;
  clock_s_ += agent.period_s;
  next_mode(percept, agent.period_s, goal_radius_m);
  switch (mode_) {
    case Mode::standing:
      return stop(agent, options_.look_turn_rate);
    case Mode::aside: {
      const double bearing = percept.goal_bearing_rad.value_or(0.0);
      return stop(agent,
                  std::clamp(2.0 * bearing, -options_.face_turn_rate, options_.face_turn_rate));
    }
    case Mode::giving_way: {
      const auto [bearing, distance] = bearing_and_distance(aside_m_, position_m_, yaw_rad_);
      percept.goal_bearing_rad = bearing;
      percept.goal_distance_m = distance;
      return std::nullopt;
    }
    case Mode::returning:
      return std::nullopt;
  }
  return std::nullopt;
}

void MakeRoom::next_mode(const Percept& percept, double period_s, double goal_radius_m) {
  const bool watching = mode_ == Mode::standing || mode_ == Mode::aside;
  const ObjectFeatures* comer = watching ? coming_at(percept) : nullptr;
  calm_s_ = comer != nullptr ? 0.0 : calm_s_ + period_s;
  if (comer != nullptr) {
    start_giving_way(*comer);
  }
  if (mode_ == Mode::giving_way &&
      ((aside_m_ - position_m_).norm() < kAsideReachedM || mode_s_ > options_.step_aside_max_s)) {
    set_mode(Mode::aside);
    calm_s_ = 0.0;  // calm is what it sees once stopped, watching
  }
  if (mode_ == Mode::aside && calm_s_ >= options_.calm_s && !goal_taken(percept, goal_radius_m)) {
    set_mode(Mode::returning);
  }
  if (mode_ == Mode::returning) {
    if (percept.goal_distance_m && *percept.goal_distance_m <= goal_radius_m) {
      set_mode(Mode::standing);
    } else if (goal_taken(percept, goal_radius_m)) {
      set_mode(Mode::aside);
    }
  }
}

void MakeRoom::set_mode(Mode mode) {
  mode_ = mode;
  mode_s_ = 0.0;
}

base::Command MakeRoom::approach(const Percept& percept, const AgentState& agent,
                                 const base::Command& command, double goal_radius_m) const {
  if (!percept.goal_distance_m || !percept.goal_bearing_rad ||
      *percept.goal_distance_m > options_.wait_range_m ||
      !(goal_taken(percept, goal_radius_m) || goal_contested(percept, agent))) {
    return command;
  }
  const bool crowded =
      std::any_of(percept.objects.begin(), percept.objects.end(), [this](const ObjectFeatures& o) {
        const std::optional<double> depth_m = object_depth(o);
        return o.kind == RegionKind::visible && depth_m &&
               *depth_m < 0.5 * options_.agent_width_m + options_.wait_gap_m;
      });
  const double speed_mps = crowded ? 0.0 : options_.wait_speed_mps;
  const double to_wait_speed = agent.period_s > 0.0 ? (speed_mps - agent.speed_mps) / agent.period_s
                                                    : -options_.stop_decel_mps2;
  const double bearing = *percept.goal_bearing_rad;
  return {std::min(command.accel_mps2, std::max(-options_.stop_decel_mps2, to_wait_speed)),
          std::clamp(2.0 * bearing, -options_.face_turn_rate, options_.face_turn_rate)};
}

const ObjectFeatures* MakeRoom::coming_at(const Percept& percept) {
  std::erase_if(comers_,
                [this](const Comer& c) { return clock_s_ - c.seen_s > options_.remember_s; });
  const ObjectFeatures* soonest = nullptr;
  double soonest_s = std::numeric_limits<double>::infinity();
  for (const ObjectFeatures& o : percept.objects) {
    if (o.kind != RegionKind::visible) {
      continue;
    }
    const std::optional<double> depth_m = object_depth(o);
    const bool near = depth_m && *depth_m < options_.warn_depth_m;
    // Its FOE on it, widened by half the agent's width: its course meets the agent.
    const double margin =
        depth_m && *depth_m > 0.0 ? 0.5 * options_.agent_width_m / *depth_m : 0.5 * o.width;
    const bool coming = detail::is_threat(o, std::numeric_limits<double>::infinity()) &&
                        o.foe.x() >= o.min_x - margin && o.foe.x() <= o.max_x + margin;
    const auto known = std::find_if(comers_.begin(), comers_.end(),
                                    [&o](const Comer& c) { return c.id == o.source_id; });
    const bool seen_coming = known != comers_.end();
    if (coming && o.source_id >= 0) {
      remember(o.source_id, known);
    }
    // What comes soon comes first; one waiting near, as if it came now.
    const double when_s = coming && (o.ttc_s < options_.warn_s || near) ? o.ttc_s
                          : near && seen_coming                         ? 0.0
                                                                        : soonest_s;
    if (when_s < soonest_s) {
      soonest = &o;
      soonest_s = when_s;
    }
  }
  return soonest;
}

void MakeRoom::remember(std::int32_t id, std::vector<Comer>::iterator known) {
  if (known == comers_.end() && comers_.size() == kComers) {
    known = std::min_element(comers_.begin(), comers_.end(),
                             [](const Comer& a, const Comer& b) { return a.seen_s < b.seen_s; });
  }
  if (known == comers_.end()) {
    comers_.push_back({id, clock_s_});
  } else {
    *known = {id, clock_s_};
  }
}

bool MakeRoom::goal_taken(const Percept& percept, double goal_radius_m) const {
  if (!percept.goal_bearing_rad || !percept.goal_distance_m ||
      std::abs(*percept.goal_bearing_rad) > kGoalInViewRad) {
    return false;
  }
  const double goal_x = std::tan(*percept.goal_bearing_rad);
  // A body on the goal's circle, across the line to the goal, has its near side short of the
  // goal by at most the circle's radius and one body where the line meets it; one nearer stands
  // in the way, one further (a wall) behind the goal.
  const double goal_m = *percept.goal_distance_m;
  for (const ObjectFeatures& o : percept.objects) {
    if (o.kind != RegionKind::visible || goal_x < o.min_x || goal_x > o.max_x) {
      continue;
    }
    const std::optional<double> depth_m = depth_at_column(o, goal_x);
    if (depth_m && *depth_m < goal_m &&
        *depth_m >= goal_m - goal_radius_m - options_.agent_width_m) {
      return true;
    }
  }
  return false;
}

bool MakeRoom::goal_contested(const Percept& percept, const AgentState& agent) const {
  const double goal_m = *percept.goal_distance_m;
  const Eigen::Vector2d goal = goal_m * Eigen::Vector2d(std::sin(*percept.goal_bearing_rad),
                                                        std::cos(*percept.goal_bearing_rad));
  for (const ObjectFeatures& o : percept.objects) {
    const std::optional<double> depth_m = object_depth(o);
    if (o.kind != RegionKind::visible || !depth_m || !o.centre.allFinite()) {
      continue;
    }
    // Its near side where the image shows it; its centre half a body further on.
    const Eigen::Vector2d near = *depth_m * Eigen::Vector2d(o.centre.x(), 1.0);
    const Eigen::Vector2d centre = near + 0.5 * options_.agent_width_m * near.normalized();
    const Eigen::Vector2d to_goal = goal - centre;
    if (!(to_goal.norm() < goal_m)) {
      continue;
    }
    const std::optional<Eigen::Vector2d> relative =
        detail::relative_velocity(o, agent, options_.depth, options_.static_closing_ratio);
    if (relative && (*relative + Eigen::Vector2d(0.0, agent.speed_mps)).dot(to_goal.normalized()) >
                        options_.wait_speed_mps) {
      return true;
    }
  }
  return false;
}

// Away from the comer and to the side nearer the agent's heading: 120° round from the comer's
// bearing, which clears the comer's way whether it walks to the agent's place or past it.
void MakeRoom::start_giving_way(const ObjectFeatures& comer) {
  // It has been given its way: waiting near later is no reason to step aside again.
  std::erase_if(comers_, [&comer](const Comer& c) { return c.id == comer.source_id; });
  const double comer_bearing = std::atan(comer.centre.x());
  const double away =
      comer_bearing >= 0.0 ? comer_bearing - 2.0 * kPi / 3.0 : comer_bearing + 2.0 * kPi / 3.0;
  const double heading = yaw_rad_ - away;  // bearings are positive right, yaw counter-clockwise
  aside_m_ =
      position_m_ + options_.step_aside_m * Eigen::Vector2d(std::cos(heading), std::sin(heading));
  set_mode(Mode::giving_way);
}

void MakeRoom::move_odometry(const AgentState& agent, double turn_rate) {
  yaw_rad_ -= agent.period_s * turn_rate;
  position_m_ +=
      agent.period_s * agent.speed_mps * Eigen::Vector2d(std::cos(yaw_rad_), std::sin(yaw_rad_));
}

base::Command MakeRoom::stop(const AgentState& agent, double turn_rate) const {
  const double decel = agent.period_s > 0.0
                           ? std::min(options_.stop_decel_mps2, agent.speed_mps / agent.period_s)
                           : options_.stop_decel_mps2;
  return {agent.speed_mps > 0.0 ? -decel : 0.0, turn_rate};
}

}  // namespace flowsteer::servo
