// The flowsteer law's cost terms (control.hpp). Each keeps the papers' form, a cost over visual
// features whose gradient on (a_c, ω) comes from the features' rates (dynamics.hpp), and fixes a
// way the papers' law collides: see docs/NAVIGATION.md.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "contact_time.hpp"
#include "cost_term_helpers.hpp"
#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/dynamics.hpp"

namespace flowsteer::servo {

namespace {

using detail::accumulate;
using detail::half_square;

// φ(u) = exp(−u) for u ≥ 0 and its tangent 1 − u below: the cost keeps rising, but no faster than
// linearly, as the FOE goes deeper into an object's extent (a wall's extent is wide).
struct Falloff {
  double value;
  double slope;      // dφ/du
  double curvature;  // d²φ/du²
};
Falloff falloff(double u) {
  if (u >= 0.0) {
    const double e = std::exp(-u);
    return {e, -e, e};
  }
  return {1.0 - u, -1.0, 0.0};
}

// An approaching object's extent widened by half the kept width at each end, and the FOE's
// clearance from it on either side, in units of σ at that end (σ = the kept width there / ln 10,
// so the cost falls to a tenth one kept width clear of the widened edge).
struct Cone {
  double tau_over_depth = 0.0;
  double foe = 0.0;
  double end_x[2] = {0.0, 0.0};  // the object's ends, min_x and max_x
  double edge[2] = {0.0, 0.0};   // [0] left (min_x side), [1] right: the ends widened
  double depth[2] = {0.0, 0.0};  // of each end
  double sigma[2] = {0.0, 0.0};
  // clearance[0]: the FOE left of the left edge, the object passed on the agent's right;
  // clearance[1]: the FOE right of the right edge, the object passed on its left.
  double clearance[2] = {0.0, 0.0};

  bool cut = false;  // the image cuts the object at either end

  double best_clearance() const { return std::max(clearance[0], clearance[1]); }

  // The distance to the object's nearest point, the object taken as the plane through its ends
  // (on the ground, a segment). Where the image cuts it, its hidden part may be nearer than what
  // is seen, and the nearer end's depth is taken instead. Not the outline (contact_time.hpp): for
  // the goal's rule a person standing at the next goal, nearer by the front of their body, is
  // not in the way of the last step to the agent's own.
  double nearest_m() const {
    if (cut) {
      return std::min(depth[0], depth[1]);
    }
    return detail::distance_to_segment({end_x[0] * depth[0], depth[0]},
                                       {end_x[1] * depth[1], depth[1]});
  }

  // The depth of the object along image column x, taken as a vertical plane through its two
  // ends: on a plane, inverse depth is affine in the image coordinate. For a person both ends
  // are at about one depth; for a wall met at a slant this is the depth where the FOE points,
  // which the mean depth of its pixels is not.
  double depth_at(double x) const {
    return detail::plane_depth_at(x, end_x[0], depth[0], end_x[1], depth[1]);
  }
};

// Whether the object's ends have depths (a simulator's): its outline and speed over the ground
// are then measured, not the depth-free guess from τ (MIG's τ v_c / Z).
bool ends_measured(const ObjectFeatures& object, const DepthGuess& depth) {
  return depth.use_depth && object.min_x_depth_m && object.max_x_depth_m;
}

Cone cone_of(const ObjectFeatures& object, const AgentState& agent, const DepthGuess& guess,
             double kept_width_m) {
  const auto [tau_over_depth, depth] = detail::depth_scale(object, agent, guess);
  Cone c;
  c.tau_over_depth = tau_over_depth;
  c.foe = object.foe.x();
  c.end_x[0] = object.min_x;
  c.end_x[1] = object.max_x;
  c.cut = object.cut_left || object.cut_right;
  const bool depths = ends_measured(object, guess);
  c.depth[0] = depths ? *object.min_x_depth_m : depth;
  c.depth[1] = depths ? *object.max_x_depth_m : depth;
  // Where the image cuts an end, the object may go on past it: an FOE beyond that end may lie on
  // its hidden part, so the end is taken at least as far out as the FOE (the papers' law takes
  // such an FOE as on the object too).
  const double left = object.cut_left ? std::min(object.min_x, c.foe) : object.min_x;
  const double right = object.cut_right ? std::max(object.max_x, c.foe) : object.max_x;
  for (int end = 0; end < 2; ++end) {
    const double width = kept_width_m / std::max(c.depth[end], 1e-3);
    c.sigma[end] = width / detail::kLn10;
    c.edge[end] = (end == 0 ? left - 0.5 * width : right + 0.5 * width);
  }
  c.clearance[0] = (c.edge[0] - c.foe) / c.sigma[0];
  c.clearance[1] = (c.foe - c.edge[1]) / c.sigma[1];
  return c;
}

// The time until an object comes within half the kept width, rather than CGF Eq. 9's τ, the time
// until it reaches the image plane: τ (1 − w / 2Z) at its nearer end's depth Z. A neighbour
// 0.6 m away closing in slowly from beside the agent, τ = 4.9 s, is 0.8 s from contact for a
// kept width of 1 m: CGF's I(τ) gives it 0.2, I(0.8 s) 8.4.
double time_to_contact(const ObjectFeatures& object, const Cone& cone, double kept_width_m) {
  const double nearest_m = std::min(cone.depth[0], cone.depth[1]);
  return object.ttc_s * std::max(0.0, 1.0 - 0.5 * kept_width_m / std::max(nearest_m, 1e-3));
}

// The approaching objects of a percept as cones, grouped where no path passes between them: two
// objects whose widened extents overlap, measured from each one's own FOE (where the agent's
// relative motion points), leave no gap for the FOE to go through. A corner of two walls, a door
// narrower than the agent or two people walking close side by side are each one obstacle, passed
// on the outside.
class ThreatCones {
 public:
  struct Entry {
    const ObjectFeatures* object;
    Cone cone;
    double contact_s;  // time_to_contact
    int group;
    bool passed_clear;  // no threat of its own; only shapes its group's ends (passed_clear)
  };
  struct Group {
    double clearance[2];  // of its outermost members, as Cone::clearance
    double sigma[2];      // σ of those ends
    double best_clearance() const { return std::max(clearance[0], clearance[1]); }
  };

  void build(const Percept& percept, const AgentState& agent, const ThreatOptions& options) {
    entries_.clear();
    groups_.clear();
    const double kept_width_m = detail::kept_width(agent, options.kept_width);
    still_.clear();
    still_.reserve(percept.objects.size());  // no reallocation: entries point into it
    for (const ObjectFeatures& seen : percept.objects) {
      const ObjectFeatures* threat = &seen;
      if (!detail::is_threat(seen, options.horizon_s)) {
        threat = as_walked_towards(seen, agent, options);
        if (threat == nullptr) {
          continue;
        }
      }
      const ObjectFeatures& object = *threat;
      const Cone cone = cone_of(object, agent, options.depth, kept_width_m);
      if (beyond_goal(cone, percept, kept_width_m)) {
        continue;
      }
      const bool clear = passed_clear(object, agent, percept, options, kept_width_m);
      if (!clear || ends_measured(object, options.depth)) {
        entries_.push_back({&object, cone, time_to_contact(object, cone, kept_width_m), -1, clear});
      }
    }
    order_.resize(entries_.size());
    for (std::size_t i = 0; i < order_.size(); ++i) {
      order_[i] = i;
    }
    std::sort(order_.begin(), order_.end(), [this](std::size_t a, std::size_t b) {
      return relative_edge(entries_[a], 0) < relative_edge(entries_[b], 0);
    });
    double reach = -std::numeric_limits<double>::infinity();
    for (const std::size_t i : order_) {
      Entry& e = entries_[i];
      if (groups_.empty() || relative_edge(e, 0) > reach) {
        groups_.push_back({{e.cone.clearance[0], 0.0}, {e.cone.sigma[0], 0.0}});
        reach = -std::numeric_limits<double>::infinity();
      }
      e.group = static_cast<int>(groups_.size()) - 1;
      if (relative_edge(e, 1) > reach) {
        reach = relative_edge(e, 1);
        Group& g = groups_.back();
        g.clearance[1] = e.cone.clearance[1];
        g.sigma[1] = e.cone.sigma[1];
      }
    }
  }

  std::span<Entry> entries() { return entries_; }
  std::span<const Entry> entries() const { return entries_; }
  std::span<const Group> groups() const { return groups_; }

 private:
  static double relative_edge(const Entry& e, int end) { return e.cone.edge[end] - e.cone.foe; }

  // An object further than the goal by half the kept width does not stand in the way: the
  // agent stops at the goal short of it (a wall behind the goal, people waiting past it). Every
  // point of the straight path to a goal d away is within d of the agent, so an object further
  // than d + w/2 is at least w/2 from all of it: distances, not depths, which are shorter for an
  // object seen at an angle (a person standing beside a goal the agent is turning towards).
  static bool beyond_goal(const Cone& cone, const Percept& percept, double kept_width_m) {
    return percept.goal_distance_m &&
           cone.nearest_m() > *percept.goal_distance_m + 0.5 * kept_width_m;
  }

  // An agent at rest, or almost, sees no flow from what stands still around it: no expansion, no
  // τ, nothing to avoid, and it set off into the wall or the neighbour it stood against, or
  // stood facing someone who stood facing it, each waiting for the other. An object that shows
  // no motion of its own, with depth, is then taken as the agent will see it once it walks at
  // its preferred speed (KeptWidth::margin_full_speed_mps): static, its FOE where the agent heads,
  // τ its nearer end's depth over that speed. Null where the object is not such.
  const ObjectFeatures* as_walked_towards(const ObjectFeatures& seen, const AgentState& agent,
                                          const ThreatOptions& options) {
    const double rest_mps = options.depth.min_speed_mps;
    if (!(std::abs(agent.speed_mps) < rest_mps) || seen.kind != RegionKind::visible ||
        !ends_measured(seen, options.depth)) {
      return nullptr;
    }
    const std::optional<Eigen::Vector2d> motion =
        detail::relative_velocity(seen, agent, options.depth, options.static_closing_ratio);
    if (motion && motion->norm() > rest_mps) {
      return nullptr;
    }
    const double ttc_s = std::min(*seen.min_x_depth_m, *seen.max_x_depth_m) /
                         options.kept_width.margin_full_speed_mps;
    if (!(ttc_s <= options.horizon_s)) {
      return nullptr;
    }
    ObjectFeatures& still = still_.emplace_back(seen);
    still.status = MotionStatus::approaching;
    still.foe = {0.0, std::isfinite(seen.foe.y()) ? seen.foe.y() : 0.0};
    still.ttc_s = ttc_s;
    still.fit.static_foe = true;
    return &still;
  }

  // A static object (stands_still) whose ends, taken as a segment on the ground, stay further than
  // half the kept width plus static_clearance_m from the agent for the whole horizon if it goes
  // straight on, or until it reaches its goal, where it stops or turns to the next: a wall along
  // the path, people standing beside the course, a wall the course meets past the goal. Their
  // clearance cost would still pull: its importance is that of their nearer end, small in time for
  // anything beside the agent, so a corridor's walls pulled agents to its middle and people
  // standing at their goals made an agent circle its own goal among them. Moving objects keep it,
  // as they may turn into the path: circles and crossings need the early avoidance of the cost's
  // tail. Such an object with measured ends stays in the groups, costing nothing: left out of them
  // too, it no longer closed the gap between itself and a neighbour, and `bottleneck`,
  // `doorway_two_way`, `corridor_pillar` and `hallway_two_way` were clean on 20 of their 40 suite
  // runs against 38. Without depths its outline is a guess from τ, and numerical flow's static
  // regions kept in the groups took DIS flow at 128² from 15 to 11 clean cases: it is left out.
  static bool passed_clear(const ObjectFeatures& object, const AgentState& agent,
                           const Percept& percept, const ThreatOptions& options,
                           double kept_width_m) {
    const std::optional<Eigen::Vector2d> velocity =
        detail::relative_velocity(object, agent, options.depth, options.static_closing_ratio);
    if (!detail::stands_still(object, agent, options.depth, options.static_closing_ratio) ||
        !velocity) {
      return false;
    }
    detail::Outline outline;
    detail::outline_of(object, agent, options.depth, outline);
    const double radius_m = 0.5 * kept_width_m + options.static_clearance_m;
    detail::Contact contact;
    detail::outline_contact(outline, *velocity, radius_m, contact);
    const bool beyond_goal =
        percept.goal_distance_m && contact.time_s * velocity->norm() > *percept.goal_distance_m;
    return !(contact.time_s <= options.horizon_s && !beyond_goal) &&
           detail::distance_to_outline(outline) > radius_m;
  }

  std::vector<ObjectFeatures> still_;  // as_walked_towards's objects of this step
  std::vector<Entry> entries_;
  std::vector<Group> groups_;
  std::vector<std::size_t> order_;
};

class ClearanceTerm final : public detail::SideRememberingTerm {
 public:
  explicit ClearanceTerm(const ClearanceOptions& options) : options_(options) {}
  std::string_view name() const override { return "clearance"; }

 private:
  TermGradient assess(const Percept& percept, const AgentState& agent) override {
    cones_.build(percept, agent, options_.threats);
    group_ends_.clear();
    for (std::size_t g = 0; g < cones_.groups().size(); ++g) {
      const int yielding = yield_end(static_cast<int>(g), agent);
      group_ends_.push_back(yielding >= 0 ? yielding : passing_end(static_cast<int>(g)));
    }
    TermGradient sum;
    for (const ThreatCones::Entry& entry : cones_.entries()) {
      if (entry.passed_clear) {
        continue;
      }
      const Cone& cone = entry.cone;
      const int end = group_ends_[static_cast<std::size_t>(entry.group)];
      const double side = end == 0 ? 1.0 : -1.0;
      sides_.remember(entry.object->source_id, side,
                      held_for(entry.object->source_id, side, agent));
      // The widened end is a point of the object (same τ/Z, its own depth): its separation from
      // the FOE moves by CGF Eq. 10. The clearance is that separation, signed to be positive
      // outside, over σ.
      const double tau_end = cone.depth[end] * cone.tau_over_depth;
      const FeatureRate separation =
          separation_rate(cone.edge[end], cone.foe, tau_end, cone.tau_over_depth, agent.speed_mps);
      const double sign = (end == 0 ? 1.0 : -1.0) / cone.sigma[end];
      const Falloff phi = falloff(cone.clearance[end]);
      const double importance = detail::importance(entry.contact_s, options_.importance);
      accumulate(sum, detail::through_rate(importance * phi.value, importance * phi.slope * sign,
                                           importance * phi.curvature * sign * sign, separation));
    }
    return sum;
  }

  // The end a group is passed by: the one with more clearance, except that the end its members
  // were passed by at the previous step keeps commit_band σ of advantage (no chatter between
  // both ways round) and the passing convention's end passing_band σ (two agents meeting
  // head-on pass each other on the same side instead of mirroring each other), and that a
  // member's held end (held_for) is kept outright. The ends are compared by their image gaps
  // over the smaller σ, the far end's: over the near end's σ, which grows without bound as the
  // agent closes in, the bands would outweigh any difference between the ways round, and an
  // agent at a wall's near corner would be sent along the wall.
  int passing_end(int group) {
    const ThreatCones::Group& g = cones_.groups()[static_cast<std::size_t>(group)];
    const double sigma = std::min(g.sigma[0], g.sigma[1]);
    double score[2] = {g.clearance[0] * g.sigma[0] / sigma, g.clearance[1] * g.sigma[1] / sigma};
    if (options_.passing_side != PassingSide::none) {
      // Keeping right passes an object on its left: the FOE goes right of it, out by end 1.
      score[options_.passing_side == PassingSide::keep_right ? 1 : 0] += options_.passing_band;
    }
    double previous = 0.0;  // the members' votes: +1 passed by end 0, -1 by end 1
    for (const ThreatCones::Entry& entry : cones_.entries()) {
      const detail::SideMemory::Taken* taken =
          entry.group == group ? sides_.previous(entry.object->source_id) : nullptr;
      if (taken != nullptr && taken->held_s > 0.0) {
        return taken->side > 0.0 ? 0 : 1;
      }
      previous += taken != nullptr ? taken->side : 0.0;
    }
    if (previous != 0.0) {
      score[previous > 0.0 ? 0 : 1] += options_.commit_band;
    }
    return score[0] >= score[1] ? 0 : 1;
  }

  // How much longer the side taken for `id` is held: rest_commit_s from a change of side made at
  // rest, less the time since. An agent at rest turns in place, and what it turns to or from
  // enters or leaves its view while nothing moves: in hallway_two_way a wall coming into view
  // joined the agent ahead into one group, passed by its other end; turning back took the wall
  // out of view and the end back, and the agent turned at ±max_turn_rate every other step, face
  // to face with the other one, until the run ended.
  double held_for(std::int32_t id, double side, const AgentState& agent) const {
    const detail::SideMemory::Taken* taken = sides_.previous(id);
    if (taken == nullptr) {
      return 0.0;
    }
    if (taken->side != side) {
      return std::abs(agent.speed_mps) < options_.threats.depth.min_speed_mps
                 ? options_.rest_commit_s
                 : 0.0;
    }
    return std::max(0.0, taken->held_s - agent.period_s);
  }

  // The end a group is passed by to give way to a member crossing the agent's path faster than
  // the agent walks (a car): the end the object leaves behind, −1 where the group has no such
  // member or the agent can no longer stop short of the band the member sweeps (it is on that
  // band or nearly; then it passes as it would anything else). The ends' image gaps say nothing
  // of which way is safe here: stopping always lets a crossing object pass (the FOE goes out by
  // its rear end as v_c falls), passing in front means outrunning it, and the gradient's way to
  // pass in front of a car coming from the left (speed up, turn right) turned the car out of a
  // 150° view, after which the agent walked into its side (`street`). Objects with depth only:
  // without it the speed over the ground is the depth-free guess's (MIG's τ v_c / Z), not a
  // measurement.
  int yield_end(int group, const AgentState& agent) const {
    const ThreatOptions& threats = options_.threats;
    const double fast_mps = options_.yield_speed_ratio * threats.kept_width.margin_full_speed_mps;
    const double stop_m = agent.speed_mps * agent.speed_mps / (2.0 * options_.stop_decel_mps2);
    const double half_width_m = 0.5 * detail::kept_width(agent, threats.kept_width);
    double across = 0.0;  // the yielded-to members' velocities across the course
    for (const ThreatCones::Entry& entry : cones_.entries()) {
      const ObjectFeatures& object = *entry.object;
      const bool measured = ends_measured(object, threats.depth);
      const std::optional<Eigen::Vector2d> relative =
          entry.group == group && measured &&
                  !detail::stands_still(object, agent, threats.depth, threats.static_closing_ratio)
              ? detail::relative_velocity(object, agent, threats.depth,
                                          threats.static_closing_ratio)
              : std::nullopt;
      if (!relative) {
        continue;
      }
      const Eigen::Vector2d ground = *relative + Eigen::Vector2d{0.0, agent.speed_mps};
      if (!(ground.norm() > fast_mps && std::abs(ground.x()) > std::abs(ground.y()))) {
        continue;
      }
      detail::Outline outline;
      detail::outline_of(object, agent, threats.depth, outline);
      if (detail::distance_to_path_m(outline, ground, half_width_m) > stop_m) {
        across += ground.x();
      }
    }
    // Moving right, an object's rear is its left end: passed by end 0.
    return across > 0.0 ? 0 : across < 0.0 ? 1 : -1;
  }

  ClearanceOptions options_;
  ThreatCones cones_;
  std::vector<int> group_ends_;
};

class BrakingTerm final : public CostTerm {
 public:
  explicit BrakingTerm(const BrakingOptions& options) : options_(options) {}
  std::string_view name() const override { return "braking"; }

  // ψ and the stopping speed are held constant in the gradient, as CGF §6.2 holds σ and I(τ):
  // v̇_c = a_c is all that moves. ψ is the object's group's: the FOE between two objects too
  // close to pass between is on course.
  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    cones_.build(percept, agent, options_.threats);
    TermGradient sum;
    for (const ThreatCones::Entry& entry : cones_.entries()) {
      if (entry.passed_clear) {
        continue;
      }
      const ThreatCones::Group& group = cones_.groups()[static_cast<std::size_t>(entry.group)];
      const double on_course = std::min(1.0, falloff(group.best_clearance()).value);
      const double ahead_m = entry.cone.depth_at(entry.cone.foe);
      const double room =
          std::max(0.0, ahead_m - 0.5 * detail::kept_width(agent, options_.threats.kept_width));
      const double stopping_speed = std::sqrt(2.0 * options_.stop_decel_mps2 * room);
      const double excess = agent.speed_mps - stopping_speed;
      if (excess > 0.0) {
        accumulate(sum, half_square(excess, FeatureRate{0.0, 1.0, 0.0}), on_course);
      }
    }
    return sum;
  }

 private:
  BrakingOptions options_;
  ThreatCones cones_;
};

class HeadingTerm final : public CostTerm {
 public:
  std::string_view name() const override { return "heading"; }
  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    if (!percept.goal_bearing_rad || !std::isfinite(*percept.goal_bearing_rad)) {
      return {};
    }
    const double bearing = std::remainder(*percept.goal_bearing_rad, 2.0 * std::numbers::pi);
    const double distance =
        percept.goal_distance_m.value_or(std::numeric_limits<double>::infinity());
    return half_square(bearing, goal_bearing_rate(bearing, distance, agent.speed_mps));
  }
};

class ApproachSpeedTerm final : public CostTerm {
 public:
  ApproachSpeedTerm(double preferred_speed_mps, double max_turn_rate, double arrival_decel_mps2,
                    const ApproachSpeedOptions& options)
      : preferred_(preferred_speed_mps),
        turn_rate_(0.5 * max_turn_rate),
        arrival_decel_(arrival_decel_mps2),
        options_(options) {}
  std::string_view name() const override { return "approach_speed"; }
  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    double target = preferred_;
    if (percept.goal_bearing_rad && percept.goal_distance_m &&
        std::isfinite(*percept.goal_bearing_rad)) {
      const double bearing =
          std::abs(std::remainder(*percept.goal_bearing_rad, 2.0 * std::numbers::pi));
      const double sine = bearing >= 0.5 * std::numbers::pi ? 1.0 : std::sin(bearing);
      if (sine > 0.0) {
        target = std::min(target, turn_rate_ * *percept.goal_distance_m / (2.0 * sine));
      }
      target = std::min(target, std::sqrt(2.0 * arrival_decel_ * *percept.goal_distance_m));
    }
    target =
        std::min(target, std::sqrt(2.0 * options_.stop_decel_mps2 * course_room_m(percept, agent)));
    // v̇_c = a_c.
    return half_square(agent.speed_mps - target, FeatureRate{0.0, 1.0, 0.0});
  }

 private:
  // How far the agent walks straight on before it comes within half its kept width of an object
  // that is not approaching, taken as standing (with depth only). The braking term weighs what
  // approaches against the speed to walk at, a cost beside this one's; for what stands, a target
  // of zero is what keeps an agent that has stopped against a wall from setting off into it
  // again, a step at a time.
  double course_room_m(const Percept& percept, const AgentState& agent) const {
    double room_m = std::numeric_limits<double>::infinity();
    if (!options_.depth.use_depth) {
      return room_m;
    }
    const double radius_m = 0.5 * detail::kept_width(agent, options_.kept_width);
    for (const ObjectFeatures& object : percept.objects) {
      if (object.kind == RegionKind::visible && object.min_x_depth_m && object.max_x_depth_m &&
          !detail::is_threat(object, options_.horizon_s)) {
        room_m = std::min(room_m, detail::course_room_m(object, agent, options_.depth, radius_m));
      }
    }
    return room_m;
  }

  double preferred_;
  double turn_rate_;
  double arrival_decel_;
  ApproachSpeedOptions options_;
};

class LeaderGapTerm final : public CostTerm {
 public:
  LeaderGapTerm(double gap_m, double gap_time_s, const DepthGuess& depth)
      : gap_m_(gap_m), gap_time_s_(gap_time_s), depth_(depth) {}
  std::string_view name() const override { return "leader_gap"; }

  // v_z = −Z/τ and v_x = f v_z from the leader's fit; a leader moving only sideways has v_z = 0.
  TermGradient evaluate(const Percept& percept, const AgentState&) override {
    const ObjectFeatures* leader = detail::find_leader(percept);
    if (leader == nullptr || !depth_.use_depth || !leader->depth_m) {
      return {};
    }
    double vz = 0.0;
    double vx = 0.0;
    if (leader->has_foe() && std::isfinite(leader->ttc_s)) {
      vz = -*leader->depth_m / leader->ttc_s;
      vx = leader->foe.x() * vz;
    } else if (leader->status != MotionStatus::lateral) {
      return {};
    }
    const double depth = *leader->depth_m;
    const double error = vz + (depth - gap_m_) / gap_time_s_;
    return half_square(error, gap_error_rate(vx, vz, leader->centre.x(), depth, gap_time_s_));
  }

 private:
  double gap_m_;
  double gap_time_s_;
  DepthGuess depth_;
};

void require_positive(double value, const char* what) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(std::string(what) + " must be positive, got " +
                                std::to_string(value));
  }
}

}  // namespace

std::unique_ptr<CostTerm> heading_term() {
  return std::make_unique<HeadingTerm>();
}

std::unique_ptr<CostTerm> approach_speed_term(double preferred_speed_mps, double max_turn_rate,
                                              double arrival_decel_mps2,
                                              const ApproachSpeedOptions& options) {
  if (!std::isfinite(preferred_speed_mps)) {
    throw std::invalid_argument("preferred speed must be finite");
  }
  require_positive(max_turn_rate, "approach speed: max_turn_rate");
  require_positive(arrival_decel_mps2, "approach speed: arrival_decel_mps2");
  detail::validate(options.kept_width, "approach_speed");
  detail::validate(options.depth, "approach_speed");
  detail::validate_horizon(options.horizon_s, "approach_speed");
  detail::validate_stop_decel(options.stop_decel_mps2, "approach_speed");
  return std::make_unique<ApproachSpeedTerm>(preferred_speed_mps, max_turn_rate, arrival_decel_mps2,
                                             options);
}

std::unique_ptr<CostTerm> clearance_term(const ClearanceOptions& options) {
  constexpr std::string_view kTerm = "clearance";
  detail::validate(options.threats, kTerm);
  detail::validate(options.importance, kTerm);
  detail::validate_commit_band(options.commit_band, kTerm);
  detail::require_option(
      std::isfinite(options.rest_commit_s) && options.rest_commit_s >= 0.0, kTerm,
      "rest_commit_s must be >= 0, got " + std::to_string(options.rest_commit_s));
  detail::require_option(std::isfinite(options.passing_band) && options.passing_band >= 0.0, kTerm,
                         "passing_band must be >= 0, got " + std::to_string(options.passing_band));
  detail::require_option(
      options.yield_speed_ratio > 0.0, kTerm,
      "yield_speed_ratio must be positive, got " + std::to_string(options.yield_speed_ratio));
  detail::validate_stop_decel(options.stop_decel_mps2, kTerm);
  return std::make_unique<ClearanceTerm>(options);
}

std::unique_ptr<CostTerm> braking_term(const BrakingOptions& options) {
  detail::validate(options.threats, "braking");
  detail::validate_stop_decel(options.stop_decel_mps2, "braking");
  return std::make_unique<BrakingTerm>(options);
}

std::unique_ptr<CostTerm> leader_gap_term(double gap_m, double gap_time_s,
                                          const DepthGuess& depth) {
  detail::validate(depth, "leader_gap");
  if (!std::isfinite(gap_m) || gap_m < 0.0) {
    throw std::invalid_argument("leader gap must be >= 0, got " + std::to_string(gap_m));
  }
  require_positive(gap_time_s, "leader gap time");
  return std::make_unique<LeaderGapTerm>(gap_m, gap_time_s, depth);
}

FlowsteerOptions flowsteer_options(const KeptWidth& kept_width, const DepthGuess& depth) {
  FlowsteerOptions o;
  o.approach_speed.kept_width = kept_width;
  o.approach_speed.depth = depth;
  o.clearance.threats.kept_width = kept_width;
  o.clearance.threats.depth = depth;
  o.braking.threats = o.clearance.threats;
  o.anticipation.kept_width = kept_width;
  o.anticipation.depth = depth;
  o.dark.agent_width_m = kept_width.agent_width_m;
  o.align = depth;
  o.leader_gap = depth;
  return o;
}

NavigationFunction flowsteer_goal_reaching(const FlowsteerWeights& w,
                                           const FlowsteerOptions& options) {
  detail::require_weight(w.alpha, "alpha");
  detail::require_weight(w.beta, "beta");
  detail::require_weight(w.gamma, "gamma");
  detail::require_weight(w.delta, "delta");
  detail::require_weight(w.braking, "braking");
  detail::require_weight(w.anticipation, "anticipation");
  if (w.delta > w.gamma) {
    throw std::invalid_argument("navigation weights: delta (" + std::to_string(w.delta) +
                                ") must not exceed gamma (" + std::to_string(w.gamma) + ")");
  }
  NavigationFunction f;
  f.add(w.alpha, heading_term())
      .add(w.beta, approach_speed_term(w.preferred_speed_mps, w.max_turn_rate, w.arrival_decel_mps2,
                                       options.approach_speed))
      .add(w.gamma, clearance_term(options.clearance))
      .add(w.braking, braking_term(options.braking))
      .add(w.anticipation, anticipation_term(options.anticipation));
  if (w.delta > 0.0) {
    f.add(w.delta, dark_term(options.dark));
  }
  return f;
}

NavigationFunction flowsteer_following(const FlowsteerWeights& w, const FlowsteerOptions& options) {
  detail::require_weight(w.braking, "braking");
  NavigationFunction f;
  f.add(w.alpha, align_term(options.align))
      .add(w.beta, leader_gap_term(w.follow_gap_m, w.gap_time_s, options.leader_gap))
      .add(w.gamma, clearance_term(options.clearance))
      .add(w.braking, braking_term(options.braking));
  return f;
}

}  // namespace flowsteer::servo
