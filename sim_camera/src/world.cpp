#include "flowsteer/sim_camera/world.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

namespace flowsteer::sim_camera {

namespace {

constexpr std::int32_t kObstacleIdBase = 10000;
constexpr std::int32_t kMovingIdBase = 20000;

std::uint64_t next_serial() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

std::string describe(const AgentSpec& a, std::size_t i) {
  return "agent " + std::to_string(i) + (a.name.empty() ? "" : " (" + a.name + ")");
}

}  // namespace

std::string_view to_string(Arrival arrival) {
  return arrival == Arrival::leave ? "leave" : "stay";
}

std::optional<Arrival> parse_arrival(std::string_view name) {
  if (name == "stay") {
    return Arrival::stay;
  }
  if (name == "leave") {
    return Arrival::leave;
  }
  return std::nullopt;
}

std::int32_t agent_render_id(std::size_t agent) {
  return static_cast<std::int32_t>(agent);
}
std::int32_t obstacle_render_id(std::size_t obstacle) {
  return kObstacleIdBase + static_cast<std::int32_t>(obstacle);
}
std::int32_t moving_render_id(std::size_t moving) {
  return kMovingIdBase + static_cast<std::int32_t>(moving);
}

Eigen::Vector2d AgentState::velocity_mps() const {
  return speed_mps * Eigen::Vector2d(std::cos(yaw_rad), std::sin(yaw_rad));
}

void AgentState::coast(double dt_s) {
  yaw_rad = std::remainder(yaw_rad - dt_s * turn_rate, 2.0 * 3.141592653589793);
  position_m += dt_s * velocity_mps();
}

double footprint_distance(const Solid& solid, const Eigen::Vector2d& point) {
  const Eigen::Vector2d d = point - solid.centre_m;
  if (solid.shape == Solid::Shape::cylinder) {
    return d.norm() - solid.radius_m;
  }
  // Into the box's own frame.
  const double c = std::cos(solid.yaw_rad);
  const double s = std::sin(solid.yaw_rad);
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  const Eigen::Vector2d q = local.cwiseAbs() - 0.5 * solid.size_m;
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(std::max(q.x(), q.y()), 0.0);
  return outside + inside;
}

World::World(WorldSpec spec) : spec_(std::move(spec)), serial_(next_serial()) {
  if (!(spec_.step_s > 0.0) || !(spec_.duration_s > 0.0)) {
    throw std::invalid_argument("world: step_s and duration_s must be positive");
  }
  if (spec_.agents.empty()) {
    throw std::invalid_argument("world '" + spec_.name + "' has no agent");
  }
  for (std::size_t i = 0; i < spec_.agents.size(); ++i) {
    const AgentSpec& a = spec_.agents[i];
    if (!(a.radius_m > 0.0) || !(a.height_m > 0.0)) {
      throw std::invalid_argument(describe(a, i) + ": radius_m and height_m must be positive");
    }
    if (a.leader && (*a.leader < 0 || static_cast<std::size_t>(*a.leader) >= spec_.agents.size() ||
                     static_cast<std::size_t>(*a.leader) == i)) {
      throw std::invalid_argument(describe(a, i) + ": leader " + std::to_string(*a.leader) +
                                  " is not another agent of the scenario");
    }
    if (!a.leader && a.goals.empty()) {
      throw std::invalid_argument(describe(a, i) + ": has neither a goal nor a leader");
    }
    for (std::size_t k = 0; k < spec_.obstacles.size(); ++k) {
      if (footprint_distance(spec_.obstacles[k], a.start_m) < a.radius_m) {
        throw std::invalid_argument(describe(a, i) + " starts inside obstacle " +
                                    std::to_string(k));
      }
    }
    for (std::size_t k = 0; k < spec_.moving.size(); ++k) {
      if (footprint_distance(spec_.moving[k].body, a.start_m) < a.radius_m) {
        throw std::invalid_argument(describe(a, i) + " starts inside moving obstacle " +
                                    std::to_string(k));
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      const AgentSpec& b = spec_.agents[j];
      if ((a.start_m - b.start_m).norm() < a.radius_m + b.radius_m) {
        throw std::invalid_argument(describe(a, i) + " starts overlapping " + describe(b, j));
      }
    }
    // A chain of leaders must end at an agent with goals, or nobody ever moves anywhere.
    std::size_t step_count = 0;
    for (std::optional<int> next = a.leader; next;
         next = spec_.agents[static_cast<std::size_t>(*next)].leader) {
      if (++step_count > spec_.agents.size()) {
        throw std::invalid_argument(describe(a, i) + ": its chain of leaders is a loop");
      }
      if (static_cast<std::size_t>(*next) >= spec_.agents.size()) {
        break;  // reported when that agent is checked
      }
    }
    AgentState state;
    state.position_m = a.start_m;
    state.yaw_rad = a.heading_rad;
    state.speed_mps = a.start_speed_mps;
    agents_.push_back(state);
  }
  for (std::size_t k = 0; k < spec_.moving.size(); ++k) {
    MovingObstacle& m = spec_.moving[k];
    if (m.waypoints.size() < 2 || !(m.speed_mps >= 0.0)) {
      throw std::invalid_argument("moving obstacle " + std::to_string(k) +
                                  ": needs two waypoints or more and a speed >= 0");
    }
    for (std::size_t w = 1; w < m.waypoints.size(); ++w) {
      if ((m.waypoints[w] - m.waypoints[w - 1]).norm() < 1e-6) {
        throw std::invalid_argument("moving obstacle " + std::to_string(k) + ": waypoints " +
                                    std::to_string(w - 1) + " and " + std::to_string(w) +
                                    " are the same point");
      }
    }
    m.body.centre_m = m.waypoints.front();
    MovingState state;
    state.position_m = m.waypoints.front();
    const Eigen::Vector2d heading = (m.waypoints[1] - m.waypoints[0]).normalized();
    state.velocity_mps = m.speed_mps * heading;
    state.yaw_rad = std::atan2(heading.y(), heading.x());
    moving_.push_back(state);
  }
  std::size_t lights = spec_.lighting.points.size();
  for (const AgentSpec& a : spec_.agents) {
    lights += a.carried_light ? 1 : 0;
  }
  if (lights > kMaxPointLights) {
    throw std::invalid_argument("lighting: " + std::to_string(lights) +
                                " point lights (carried ones included), at most " +
                                std::to_string(kMaxPointLights));
  }
  followed_.assign(agents_.size(), false);
  steers_after_arrival_.assign(agents_.size(), false);
  for (const AgentSpec& a : spec_.agents) {
    if (a.leader) {
      followed_[static_cast<std::size_t>(*a.leader)] = true;
    }
  }
  const std::size_t bodies = agents_.size() + spec_.obstacles.size() + spec_.moving.size();
  in_contact_.assign(agents_.size(), std::vector<bool>(bodies, false));
}

Solid World::moving_now(std::size_t moving) const {
  Solid body = spec_.moving[moving].body;
  body.centre_m = moving_[moving].position_m;
  body.yaw_rad = moving_[moving].yaw_rad;
  return body;
}

void World::step(const std::vector<base::Command>& commands) {
  if (commands.size() != agents_.size()) {
    throw std::invalid_argument("world step: " + std::to_string(commands.size()) +
                                " commands for " + std::to_string(agents_.size()) + " agents");
  }
  const double dt = spec_.step_s;
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    AgentState& s = agents_[i];
    const AgentSpec& a = spec_.agents[i];
    if (s.reached_goal && !a.leader && (!steers_after_arrival_[i] || !present(i))) {
      s.speed_mps = 0.0;
      s.turn_rate = 0.0;
      continue;
    }
    s.turn_rate = commands[i].turn_rate;
    s.speed_mps = std::clamp(s.speed_mps + dt * commands[i].accel_mps2, 0.0, a.max_speed_mps);
    s.coast(dt);
  }
  for (std::size_t k = 0; k < moving_.size(); ++k) {
    const MovingObstacle& m = spec_.moving[k];
    MovingState& s = moving_[k];
    double travel = m.speed_mps * dt;
    while (travel > 0.0 && s.next_waypoint < m.waypoints.size()) {
      const Eigen::Vector2d to_next = m.waypoints[s.next_waypoint] - s.position_m;
      const double distance = to_next.norm();
      if (distance > travel) {
        s.position_m += travel * to_next / distance;
        s.velocity_mps = m.speed_mps * to_next / distance;
        s.yaw_rad = std::atan2(to_next.y(), to_next.x());
        travel = 0.0;
      } else {
        s.position_m = m.waypoints[s.next_waypoint];
        travel -= distance;
        ++s.next_waypoint;
        if (s.next_waypoint == m.waypoints.size() && m.loop) {
          s.next_waypoint = 0;
        }
      }
    }
    if (s.next_waypoint >= m.waypoints.size()) {
      s.velocity_mps.setZero();
    }
  }
  time_s_ += dt;
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    advance_goals(i);
  }
  detect_collisions();
}

void World::advance_goals(std::size_t i) {
  AgentState& s = agents_[i];
  const AgentSpec& a = spec_.agents[i];
  while (s.next_goal < a.goals.size() &&
         (a.goals[s.next_goal] - s.position_m).norm() <= a.goal_radius_m) {
    ++s.next_goal;
  }
  if (!a.goals.empty() && s.next_goal == a.goals.size() && !s.reached_goal) {
    s.reached_goal = true;
    s.time_to_goal_s = time_s_;
    if (steers_after_arrival_[i]) {
      s.speed_mps = 0.0;
      s.turn_rate = 0.0;
    }
  }
  s.left_world = s.left_world || (s.reached_goal && spec_.arrival == Arrival::leave &&
                                  !followed_[i] && time_s_ >= s.time_to_goal_s + a.idle_s - 1e-9);
}

double World::clearance(std::size_t i) const {
  const AgentState& s = agents_[i];
  const double r = spec_.agents[i].radius_m;
  double best = std::numeric_limits<double>::infinity();
  if (!present(i)) {
    return best;
  }
  for (std::size_t j = 0; j < agents_.size(); ++j) {
    if (j != i && present(j)) {
      best = std::min(best,
                      (agents_[j].position_m - s.position_m).norm() - r - spec_.agents[j].radius_m);
    }
  }
  for (const Solid& o : spec_.obstacles) {
    best = std::min(best, footprint_distance(o, s.position_m) - r);
  }
  for (std::size_t k = 0; k < moving_.size(); ++k) {
    best = std::min(best, footprint_distance(moving_now(k), s.position_m) - r);
  }
  return best;
}

void World::detect_collisions() {
  new_collisions_.clear();
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    const Eigen::Vector2d p = agents_[i].position_m;
    const double r = spec_.agents[i].radius_m;
    // An agent that has left touches nothing; its contacts end.
    const bool here = present(i);
    std::size_t body = 0;
    // The name of what was hit is built only when a contact starts.
    auto check = [&](bool touching, Body kind, std::size_t index) {
      const bool was = in_contact_[i][body];
      in_contact_[i][body] = touching;
      if (touching && !was) {
        const char* name = kind == Body::agent      ? "agent"
                           : kind == Body::obstacle ? "obstacle"
                                                    : "moving";
        new_collisions_.push_back(
            {.time_s = time_s_,
             .agent = i,
             .with = std::string(name) + " " + std::to_string(index),
             .position_m = p,
             .other_agent = kind == Body::agent ? std::optional(index) : std::nullopt,
             .body = kind});
      }
      ++body;
    };
    for (std::size_t j = 0; j < agents_.size(); ++j) {
      // Each pair once, on the lower index; the higher one's slot stays unused.
      const bool touching = here && j > i && present(j) &&
                            (agents_[j].position_m - p).norm() < r + spec_.agents[j].radius_m;
      check(touching, Body::agent, j);
    }
    for (std::size_t k = 0; k < spec_.obstacles.size(); ++k) {
      check(here && footprint_distance(spec_.obstacles[k], p) < r, Body::obstacle, k);
    }
    for (std::size_t k = 0; k < moving_.size(); ++k) {
      check(here && footprint_distance(moving_now(k), p) < r, Body::moving, k);
    }
  }
}

bool World::finished() const {
  if (time_s_ >= spec_.duration_s - 1e-9) {
    return true;
  }
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    if (!spec_.agents[i].leader && !agents_[i].reached_goal) {
      return false;
    }
  }
  return true;
}

}  // namespace flowsteer::sim_camera
