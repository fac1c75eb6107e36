#include "flowsteer/servo/control.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "contact_time.hpp"
#include "cost_term_helpers.hpp"
#include "flowsteer/servo/dynamics.hpp"
#include "turn_prediction.hpp"

namespace flowsteer::servo {

namespace {

using detail::accumulate;
using detail::exp_falloff;
using detail::find_leader;
using detail::floored_speed;
using detail::half_square;
using detail::kLn10;

// Goals further than this from the heading are treated as at this bearing; t_x = tan(bearing)
// has no meaning behind the camera.
constexpr double kMaxGoalBearing = 80.0 * std::numbers::pi / 180.0;

class GoalTerm final : public CostTerm {
 public:
  std::string_view name() const override { return "goal"; }
  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    if (!percept.goal_bearing_rad || !std::isfinite(*percept.goal_bearing_rad)) {
      return {};
    }
    const double goal_x =
        std::tan(std::clamp(*percept.goal_bearing_rad, -kMaxGoalBearing, kMaxGoalBearing));
    const double tau_goal = percept.goal_distance_m && agent.speed_mps > 0.0
                                ? *percept.goal_distance_m / agent.speed_mps
                                : std::numeric_limits<double>::infinity();
    return half_square(goal_x, goal_x_rate(goal_x, tau_goal));
  }
};

class SpeedTerm final : public CostTerm {
 public:
  explicit SpeedTerm(double preferred_speed_mps) : preferred_(preferred_speed_mps) {}
  std::string_view name() const override { return "speed"; }
  TermGradient evaluate(const Percept&, const AgentState& agent) override {
    // v̇_c = a_c.
    return half_square(agent.speed_mps - preferred_, FeatureRate{0.0, 1.0, 0.0});
  }

 private:
  double preferred_;
};

class AvoidanceTerm final : public detail::SideRememberingTerm {
 public:
  explicit AvoidanceTerm(const AvoidanceTermOptions& options) : options_(options) {}
  std::string_view name() const override { return "avoidance"; }

 private:
  // CGF Eq. 9 and 10; the gradient sign follows docs/CONVENTIONS.md ("Signs"), not the printed
  // Eq. 17.
  TermGradient assess(const Percept& percept, const AgentState& agent) override {
    TermGradient sum;
    for (const ObjectFeatures& object : percept.objects) {
      if (!detail::is_threat(object, options_.horizon_s)) {
        continue;
      }
      const double tau = object.ttc_s;
      const double importance = detail::importance(tau, options_.importance);
      const auto [tau_over_depth, depth] = detail::depth_scale(object, agent, options_.depth);
      const double sigma = (object.width + options_.agent_width_m / depth) / kLn10;
      const double foe = object.foe.x();
      double centre = object.centre.x();
      double separation = centre - foe;
      const double side = sides_.side(object.source_id, separation, sigma, options_.commit_band);
      // An object cut by the image edge may go on past it, and an FOE beyond the cut side may
      // then lie on its hidden part: a car crossing close in front fills the image while the
      // FOE of a slow agent runs far out (f = v_x / v_z). Its visible centroid is then no
      // measure of how far the FOE is from the object. The worst case that the image allows
      // is taken: the term is that of the object's point at the FOE, |g − f| = 0, whose
      // separation from the FOE changes by Eq. 10 with g = f. Its gradient brakes (f a_c
      // term), which moves the FOE further out, until the object's end comes into view. The
      // side stays that of the visible part, the side the FOE is being moved away from.
      if ((object.cut_left && foe < object.min_x) || (object.cut_right && foe > object.max_x)) {
        centre = foe;
        separation = 0.0;
      }
      accumulate(sum,
                 exp_falloff(importance, separation, side, sigma,
                             separation_rate(centre, foe, tau, tau_over_depth, agent.speed_mps)));
    }
    return sum;
  }

  AvoidanceTermOptions options_;
};

class DarkTerm final : public detail::SideRememberingTerm {
 public:
  explicit DarkTerm(const DarkOptions& options) : options_(options) {}
  std::string_view name() const override { return "dark"; }

 private:
  // MIG Eq. 3. A dark region has no flow to fit; it is taken as static, so its FOE is straight
  // ahead and its centre moves as ġ = g/τ − (1 + g²) ω whatever its depth. MIG Eq. 7 prints
  // (1 − g²) for that factor; the sign of the g² term does not survive the derivation.
  TermGradient assess(const Percept& percept, const AgentState&) override {
    TermGradient sum;
    for (const ObjectFeatures& object : percept.objects) {
      if (object.kind != RegionKind::dark || object.pixel_count == 0 ||
          !object.centre.allFinite()) {
        continue;
      }
      double width = object.width;
      if (object.depth_m && *object.depth_m > 0.0) {
        width += options_.agent_width_m / *object.depth_m;
      }
      const double g = object.centre.x();
      // The drift does not enter the gradient; an infinite τ leaves it out.
      const FeatureRate rate = centre_x_rate(g, 0.0, std::numeric_limits<double>::infinity());
      const double sigma = width / kLn10;
      const double side = sides_.side(object.source_id, g, sigma, options_.commit_band);
      accumulate(sum, exp_falloff(1.0, g, side, sigma, rate));
    }
    return sum;
  }

  DarkOptions options_;
};

class AlignTerm final : public CostTerm {
 public:
  explicit AlignTerm(const DepthGuess& depth) : depth_(depth) {}
  std::string_view name() const override { return "align"; }

  // CGF Eq. 11 with Eq. 6 averaged over the leader's pixels: L = U², U = (Σ u_j)/N.
  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    const ObjectFeatures* leader = find_leader(percept);
    if (leader == nullptr) {
      return {};
    }
    const FlowMoments& m = leader->moments;
    double mean_inv_depth = 0.0;
    double mean_x_inv_depth = 0.0;
    if (depth_.use_depth && m.mean_inv_depth && m.mean_x_inv_depth) {
      mean_inv_depth = *m.mean_inv_depth;
      mean_x_inv_depth = *m.mean_x_inv_depth;
    } else if (leader->has_foe() && std::isfinite(leader->ttc_s)) {
      // τ v_c / Z = ratio, as for avoidance.
      mean_inv_depth =
          depth_.depth_free_ratio / (std::abs(leader->ttc_s) * floored_speed(agent, depth_));
      mean_x_inv_depth = leader->centre.x() * mean_inv_depth;
    }
    const double u = m.mean_u;
    const FeatureRate rate{0.0, mean_x_inv_depth,
                           -(agent.speed_mps * mean_inv_depth + 2.0 * m.mean_xu)};
    return detail::through_rate(u * u, 2.0 * u, 2.0, rate);
  }

 private:
  DepthGuess depth_;
};

class LeaderSpeedTerm final : public CostTerm {
 public:
  explicit LeaderSpeedTerm(const DepthGuess& depth) : depth_(depth) {}
  std::string_view name() const override { return "leader_speed"; }

  // CGF Eq. 13 with v_z = −Z/τ. The printed Eq. 19 takes v_z = +Z/τ, which would speed the
  // agent up behind a slower leader. Needs the leader's depth: without it the relative speed
  // is not observable from flow alone and the term is zero.
  TermGradient evaluate(const Percept& percept, const AgentState&) override {
    const ObjectFeatures* leader = find_leader(percept);
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
    return half_square(vz, relative_vz_rate(vx));
  }

 private:
  DepthGuess depth_;
};

}  // namespace

namespace detail {

const ObjectFeatures* find_leader(const Percept& percept) {
  if (!percept.leader_id) {
    return nullptr;
  }
  for (const ObjectFeatures& object : percept.objects) {
    if (object.source_id == *percept.leader_id && object.kind == RegionKind::visible &&
        object.pixel_count > object.invalid_flow_count) {
      return &object;
    }
  }
  return nullptr;
}

void require_option(bool ok, std::string_view term, const std::string& what) {
  if (!ok) {
    throw std::invalid_argument(std::string(term) + " options: " + what);
  }
}

void validate_agent_width(double agent_width_m, std::string_view term) {
  require_option(std::isfinite(agent_width_m) && agent_width_m >= 0.0, term,
                 "agent_width_m must be >= 0, got " + std::to_string(agent_width_m));
}

void validate(const KeptWidth& o, std::string_view term) {
  validate_agent_width(o.agent_width_m, term);
  require_option(std::isfinite(o.margin_m) && o.margin_m >= 0.0, term,
                 "margin_m must be >= 0, got " + std::to_string(o.margin_m));
  require_option(std::isfinite(o.standing_margin_m) && o.standing_margin_m >= 0.0, term,
                 "standing_margin_m must be >= 0, got " + std::to_string(o.standing_margin_m));
  require_option(
      std::isfinite(o.margin_full_speed_mps) && o.margin_full_speed_mps > 0.0, term,
      "margin_full_speed_mps must be positive, got " + std::to_string(o.margin_full_speed_mps));
}

void validate(const Importance& o, std::string_view term) {
  require_option(std::isfinite(o.slope) && std::isfinite(o.intercept), term,
                 "importance slope and intercept must be finite");
}

void validate(const DepthGuess& o, std::string_view term) {
  require_option(std::isfinite(o.depth_free_ratio) && o.depth_free_ratio > 0.0, term,
                 "depth_free_ratio must be positive, got " + std::to_string(o.depth_free_ratio));
  require_option(std::isfinite(o.min_speed_mps) && o.min_speed_mps > 0.0, term,
                 "min_speed_mps must be positive, got " + std::to_string(o.min_speed_mps));
}

void validate(const ThreatOptions& o, std::string_view term) {
  validate(o.kept_width, term);
  validate(o.depth, term);
  validate_horizon(o.horizon_s, term);
  require_option(o.static_clearance_m >= 0.0, term,
                 "static_clearance_m must be >= 0, got " + std::to_string(o.static_clearance_m));
  validate_static_closing(o.static_closing_ratio, term);
}

void validate_horizon(double horizon_s, std::string_view term) {
  require_option(std::isfinite(horizon_s) && horizon_s > 0.0, term,
                 "horizon_s must be positive, got " + std::to_string(horizon_s));
}

void validate_commit_band(double commit_band, std::string_view term) {
  require_option(std::isfinite(commit_band) && commit_band >= 0.0, term,
                 "commit_band must be >= 0, got " + std::to_string(commit_band));
}

void validate_stop_decel(double stop_decel_mps2, std::string_view term) {
  require_option(std::isfinite(stop_decel_mps2) && stop_decel_mps2 > 0.0, term,
                 "stop_decel_mps2 must be positive, got " + std::to_string(stop_decel_mps2));
}

void validate_static_closing(double static_closing_ratio, std::string_view term) {
  require_option(static_closing_ratio > 0.0, term,
                 "static_closing_ratio must be > 0, got " + std::to_string(static_closing_ratio));
}

void require_weight(double value, const char* name) {
  if (!std::isfinite(value) || value < 0.0) {
    throw std::invalid_argument(std::string("navigation weight ") + name + " must be >= 0, got " +
                                std::to_string(value));
  }
}

}  // namespace detail

using detail::require_weight;
using detail::validate;
using detail::validate_agent_width;
using detail::validate_commit_band;
using detail::validate_horizon;

std::unique_ptr<CostTerm> goal_term() {
  return std::make_unique<GoalTerm>();
}

std::unique_ptr<CostTerm> speed_term(double preferred_speed_mps) {
  if (!std::isfinite(preferred_speed_mps)) {
    throw std::invalid_argument("preferred speed must be finite");
  }
  return std::make_unique<SpeedTerm>(preferred_speed_mps);
}

std::unique_ptr<CostTerm> avoidance_term(const AvoidanceTermOptions& options) {
  validate_agent_width(options.agent_width_m, "avoidance");
  validate(options.importance, "avoidance");
  validate_horizon(options.horizon_s, "avoidance");
  validate(options.depth, "avoidance");
  validate_commit_band(options.commit_band, "avoidance");
  return std::make_unique<AvoidanceTerm>(options);
}

std::unique_ptr<CostTerm> dark_term(const DarkOptions& options) {
  validate_agent_width(options.agent_width_m, "dark");
  validate_commit_band(options.commit_band, "dark");
  return std::make_unique<DarkTerm>(options);
}

std::unique_ptr<CostTerm> align_term(const DepthGuess& depth) {
  validate(depth, "align");
  return std::make_unique<AlignTerm>(depth);
}

std::unique_ptr<CostTerm> leader_speed_term(const DepthGuess& depth) {
  validate(depth, "leader_speed");
  return std::make_unique<LeaderSpeedTerm>(depth);
}

NavigationFunction& NavigationFunction::add(double weight, std::unique_ptr<CostTerm> term) {
  if (!term) {
    throw std::invalid_argument("NavigationFunction::add: null term");
  }
  require_weight(weight, std::string(term->name()).c_str());
  terms_.push_back({weight, std::move(term)});
  return *this;
}

TermGradient NavigationFunction::evaluate(const Percept& percept, const AgentState& agent,
                                          std::vector<TermEvaluation>& out) {
  out.resize(terms_.size());
  TermGradient total;
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    auto& [weight, term] = terms_[k];
    out[k].name = term->name();
    out[k].weight = weight;
    out[k].gradient = term->evaluate(percept, agent);
    accumulate(total, out[k].gradient, weight);
  }
  return total;
}

double NavigationFunction::cost(const Percept& percept, const AgentState& agent) {
  double total = 0.0;
  for (auto& [weight, term] : terms_) {
    total += weight * term->cost(percept, agent);
  }
  return total;
}

NavigationFunction goal_reaching(const GoalReachingWeights& w, const PapersOptions& options) {
  require_weight(w.alpha, "alpha");
  require_weight(w.beta, "beta");
  require_weight(w.gamma, "gamma");
  require_weight(w.delta, "delta");
  if (w.delta > w.gamma) {
    throw std::invalid_argument("navigation weights: delta (" + std::to_string(w.delta) +
                                ") must not exceed gamma (" + std::to_string(w.gamma) +
                                "): visible obstacles weigh at least as much as dark ones");
  }
  NavigationFunction f;
  f.add(w.alpha, goal_term())
      .add(w.beta, speed_term(w.preferred_speed_mps))
      .add(w.gamma, avoidance_term(options.avoidance));
  if (w.delta > 0.0) {
    f.add(w.delta, dark_term(options.dark));
  }
  return f;
}

NavigationFunction following(const FollowingWeights& w, const PapersOptions& options) {
  NavigationFunction f;
  f.add(w.alpha, align_term(options.align))
      .add(w.beta, leader_speed_term(options.leader_speed))
      .add(w.gamma, avoidance_term(options.avoidance));
  return f;
}

Controller::Controller(NavigationFunction navigation, double lambda, const ControlLimits& limits,
                       GradientStep gradient_step, const TurnCheck& turn_check,
                       const StopCheck& stop_check)
    : navigation_(std::move(navigation)),
      lambda_(lambda),
      limits_(limits),
      gradient_step_(gradient_step),
      turn_check_(turn_check),
      stop_check_(stop_check) {
  if (!std::isfinite(lambda) || lambda <= 0.0) {
    throw std::invalid_argument("controller: lambda must be positive, got " +
                                std::to_string(lambda));
  }
  if (!std::isfinite(limits.max_accel_mps2) || limits.max_accel_mps2 <= 0.0) {
    throw std::invalid_argument("controller: max_accel_mps2 must be positive, got " +
                                std::to_string(limits.max_accel_mps2));
  }
  if (!std::isfinite(limits.max_turn_rate) || limits.max_turn_rate <= 0.0) {
    throw std::invalid_argument("controller: max_turn_rate must be positive, got " +
                                std::to_string(limits.max_turn_rate));
  }
  if (std::isnan(limits.max_speed_mps) || limits.max_speed_mps <= 0.0) {
    throw std::invalid_argument("controller: max_speed_mps must be positive, got " +
                                std::to_string(limits.max_speed_mps));
  }
}

void Controller::step(const Percept& percept, const AgentState& agent, ControlOutput& out) {
  if (!std::isfinite(agent.speed_mps)) {
    throw std::invalid_argument("controller: agent speed is not finite");
  }
  if (!std::isfinite(agent.period_s) || agent.period_s < 0.0) {
    throw std::invalid_argument("controller: the control period must be >= 0, got " +
                                std::to_string(agent.period_s));
  }
  const TermGradient total = navigation_.evaluate(percept, agent, out.terms);
  out.cost = total.cost;
  // u = −λ g / (1 + λ T c): minimises g u T + ½ c (u T)² + T u² / (2λ), the cost's change over
  // the period to second order plus the papers' gain as a penalty on the command.
  const double period_s = gradient_step_ == GradientStep::implicit_euler ? agent.period_s : 0.0;
  const double accel_damping = 1.0 + lambda_ * period_s * std::max(0.0, total.curvature_accel);
  const double turn_damping = 1.0 + lambda_ * period_s * std::max(0.0, total.curvature_turn);
  out.unclamped = {-lambda_ * total.per_accel / accel_damping,
                   -lambda_ * total.per_turn / turn_damping};
  if (!std::isfinite(out.unclamped.accel_mps2) || !std::isfinite(out.unclamped.turn_rate)) {
    for (const TermEvaluation& t : out.terms) {
      if (!std::isfinite(t.gradient.per_accel) || !std::isfinite(t.gradient.per_turn)) {
        throw std::domain_error("controller: term '" + t.name + "' gave a non-finite gradient");
      }
    }
    throw std::domain_error("controller: the command is not finite");
  }
  double accel_mps2 = out.unclamped.accel_mps2;
  TurnRound round;
  if (agent.period_s > 0.0) {
    round = turn_round(percept, agent);
    const double max_speed_mps = std::min(limits_.max_speed_mps, round.max_speed_mps);
    accel_mps2 = std::min(accel_mps2, (max_speed_mps - agent.speed_mps) / agent.period_s);
  }
  out.command = {
      std::clamp(accel_mps2, -limits_.max_accel_mps2, limits_.max_accel_mps2),
      std::clamp(out.unclamped.turn_rate, -limits_.max_turn_rate, limits_.max_turn_rate)};
  if (turn_check_.enabled && agent.period_s > 0.0 && out.command.turn_rate != 0.0) {
    out.command.turn_rate =
        round.at_limit ? (*percept.goal_bearing_rad > 0.0 ? 1.0 : -1.0) * limits_.max_turn_rate
                       : checked_turn_rate(percept, agent, out.command.turn_rate);
  }
  if (stop_check_.enabled && agent.period_s > 0.0) {
    check_stop(percept, agent, out.command);
  }
}

namespace {

// The contact's time once the agent has turned by angle_rad (positive: right) from going straight
// on towards `s`: the outline and the object's velocity over the ground turn the other way in the
// agent's frame.
double contact_after_turn_s(const detail::StraightOn& s, double speed_mps, double angle_rad) {
  detail::Outline outline = s.outline;
  for (int i = 0; i < outline.count; ++i) {
    outline.points[i] = detail::seen_after_turn(s.outline.points[i], angle_rad);
  }
  const Eigen::Vector2d own{0.0, speed_mps};
  detail::Contact contact;
  detail::outline_contact(outline, detail::seen_after_turn(s.velocity + own, angle_rad) - own,
                          s.radius_m, contact);
  return contact.time_s;
}

}  // namespace

void Controller::check_stop(const Percept& percept, const AgentState& agent,
                            base::Command& command) const {
  const double decel_mps2 = limits_.max_accel_mps2;
  const double stop_s = std::abs(agent.speed_mps) / decel_mps2 + agent.period_s;
  const double radius_m = 0.5 * detail::kept_width(agent, stop_check_.kept_width);
  // The command's turn, none and the opposite turn, and the earliest contact after each.
  const std::array<double, 3> turn_rates{command.turn_rate, 0.0, -command.turn_rate};
  std::array<double, 3> earliest_s;
  earliest_s.fill(std::numeric_limits<double>::infinity());
  bool brake = false;
  for (const ObjectFeatures& object : percept.objects) {
    if (detail::stands_still(object, agent, stop_check_.depth, stop_check_.static_closing_ratio)) {
      continue;
    }
    const std::optional<detail::StraightOn> s = detail::straight_on(
        object, agent, stop_check_.depth, stop_check_.static_closing_ratio, radius_m);
    if (!s || !(s->contact.time_s < stop_s)) {
      continue;
    }
    const double braking_s = detail::contact_while_braking_s(
        s->outline, s->velocity + Eigen::Vector2d{0.0, agent.speed_mps},
        std::max(0.0, agent.speed_mps), decel_mps2, s->radius_m, agent.period_s,
        s->contact.time_s + stop_s);
    brake = brake || braking_s > s->contact.time_s + agent.period_s;
    for (std::size_t k = 0; k < turn_rates.size(); ++k) {
      earliest_s[k] = std::min(
          earliest_s[k], contact_after_turn_s(*s, agent.speed_mps, turn_rates[k] * agent.period_s));
    }
  }
  if (brake) {
    command.accel_mps2 = -decel_mps2;
  }
  // The command's turn where none is later, or no such contact comes after it.
  if (command.turn_rate == 0.0 || !std::isfinite(earliest_s[0])) {
    return;
  }
  std::size_t best = 0;
  for (std::size_t k = 1; k < turn_rates.size(); ++k) {
    if (earliest_s[k] > earliest_s[best]) {
      best = k;
    }
  }
  command.turn_rate = turn_rates[best];
}

double Controller::checked_turn_rate(const Percept& percept, const AgentState& agent,
                                     double turn_rate) {
  constexpr std::array kFractions{1.0, 0.5, 0.25, 0.125};
  double best_rate = turn_rate;
  double best_cost = std::numeric_limits<double>::infinity();
  const auto weigh = [&](const Percept& seen, double rate) {
    Percept turned;
    detail::percept_after_turn(seen, agent, rate * agent.period_s, turn_check_.depth,
                               turn_check_.static_closing_ratio, turned_objects_, turned);
    const double cost = navigation_.cost(turned, agent);
    if (cost < best_cost) {
      best_cost = cost;
      best_rate = rate;
    }
  };
  for (const double fraction : kFractions) {
    weigh(percept, fraction * turn_rate);
  }
  // Only where the check holds the turn towards the goal back, or the gradient turns away from it,
  // and the way onto the goal is clear: then the static objects, which that way passes clear, are
  // left out, and turns towards the goal compete with the checked one.
  const double goal_side = percept.goal_bearing_rad && *percept.goal_bearing_rad > 0.0 ? 1.0 : -1.0;
  if (!(goal_side * best_rate < goal_side * turn_rate || goal_side * turn_rate <= 0.0) ||
      !leaves_static_objects_out(percept, agent)) {
    return best_rate;
  }
  Percept open = percept;
  open.objects = open_objects_;
  const double law_rate = best_rate;
  best_cost = std::numeric_limits<double>::infinity();
  weigh(open, law_rate);
  for (const double fraction : kFractions) {
    weigh(open, fraction * goal_side * limits_.max_turn_rate);
  }
  return best_rate;
}

bool Controller::goal_is_behind(const Percept& percept) const {
  return turn_check_.enabled && turn_check_.way_onto_goal && percept.goal_bearing_rad &&
         percept.goal_distance_m && std::abs(*percept.goal_bearing_rad) > 0.5 * std::numbers::pi;
}

bool Controller::way_onto_goal_behind_is_clear(const Percept& percept, const AgentState& agent,
                                               double speed_mps) const {
  AgentState at = agent;
  at.speed_mps = speed_mps;
  const double goal_side = *percept.goal_bearing_rad > 0.0 ? 1.0 : -1.0;
  return detail::way_onto_goal_is_clear(percept, at, goal_side * limits_.max_turn_rate,
                                        turn_check_.depth, turn_check_.static_closing_ratio,
                                        0.5 * detail::kept_width(agent, turn_check_.kept_width));
}

Controller::TurnRound Controller::turn_round(const Percept& percept, const AgentState& agent) {
  if (!goal_is_behind(percept)) {
    way_round_blocked_ = false;
    return {};
  }
  if (way_round_blocked_) {
    return {};
  }
  const double speed_mps = std::max(0.0, agent.speed_mps);
  const bool clear_now = way_onto_goal_behind_is_clear(percept, agent, speed_mps);
  if (way_onto_goal_behind_is_clear(percept, agent,
                                    speed_mps + limits_.max_accel_mps2 * agent.period_s)) {
    return {.at_limit = clear_now};
  }
  if (clear_now) {
    return {.max_speed_mps = speed_mps, .at_limit = true};
  }
  for (const double fraction : {0.5, 0.25, 0.125, 0.0}) {
    if (way_onto_goal_behind_is_clear(percept, agent, fraction * speed_mps)) {
      return {.max_speed_mps = fraction * speed_mps};
    }
  }
  way_round_blocked_ = true;
  return {};
}

bool Controller::leaves_static_objects_out(const Percept& percept, const AgentState& agent) {
  if (!turn_check_.way_onto_goal || !percept.goal_bearing_rad || !percept.goal_distance_m ||
      std::abs(*percept.goal_bearing_rad) <= limits_.max_turn_rate * agent.period_s) {
    return false;
  }
  open_objects_.clear();
  for (const ObjectFeatures& object : percept.objects) {
    if (!detail::stands_still(object, agent, turn_check_.depth, turn_check_.static_closing_ratio)) {
      open_objects_.push_back(object);
    }
  }
  if (open_objects_.size() == percept.objects.size()) {
    return false;
  }
  const double goal_side = *percept.goal_bearing_rad > 0.0 ? 1.0 : -1.0;
  const double clearance_m =
      0.5 * detail::kept_width(agent, turn_check_.kept_width) + turn_check_.static_clearance_m;
  return detail::way_onto_goal_is_clear(percept, agent, goal_side * limits_.max_turn_rate,
                                        turn_check_.depth, turn_check_.static_closing_ratio,
                                        clearance_m);
}

ControlOutput Controller::step(const Percept& percept, const AgentState& agent) {
  ControlOutput out;
  step(percept, agent, out);
  return out;
}

}  // namespace flowsteer::servo
