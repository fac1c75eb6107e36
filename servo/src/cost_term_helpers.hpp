#pragma once

// What the cost terms of control.cpp (the papers' law) and clearance_terms.cpp (the flowsteer law)
// share: the falloff of a cost with a feature, the side memory and the sums.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/dynamics.hpp"

namespace flowsteer::servo::detail {

// ln 10: σ = w / ln 10 makes exp(−|Δx|/σ) fall to 1/10 at |Δx| = w (CGF §6.2).
constexpr double kLn10 = 2.302585092994046;

// A term L(s) over a feature s whose rate is `rate`, from L, L'(s) and L''(s): L̇ = L'(s) ṡ, so
// ∂L̇/∂u = L'(s) ∂ṡ/∂u, and the curvature along u is L''(s) (∂ṡ/∂u)².
inline TermGradient through_rate(double cost, double slope, double curvature,
                                 const FeatureRate& rate) {
  return {cost, slope * rate.per_accel, slope * rate.per_turn,
          curvature * rate.per_accel * rate.per_accel, curvature * rate.per_turn * rate.per_turn};
}

// The gradient of L = w·exp(−|s|/σ) (w constant) through the rate of s: L̇ = −L sign(s)/σ · ṡ.
// `side` is the sign of s that the gradient takes (see SideMemory).
inline TermGradient exp_falloff(double weight, double s, double side, double sigma,
                                const FeatureRate& rate) {
  const double value = weight * std::exp(-std::abs(s) / sigma);
  return through_rate(value, -value * side / sigma, value / (sigma * sigma), rate);
}

// The gradient of L = ½ s² through the rate of s: L̇ = s ṡ.
inline TermGradient half_square(double s, const FeatureRate& rate) {
  return through_rate(0.5 * s * s, s, 1.0, rate);
}

inline void accumulate(TermGradient& sum, const TermGradient& g, double weight = 1.0) {
  sum.cost += weight * g.cost;
  sum.per_accel += weight * g.per_accel;
  sum.per_turn += weight * g.per_turn;
  sum.curvature_accel += weight * g.curvature_accel;
  sum.curvature_turn += weight * g.curvature_turn;
}

inline double floored_speed(const AgentState& agent, const DepthGuess& depth) {
  return std::max(std::abs(agent.speed_mps), depth.min_speed_mps);
}

// The depth along image column x of a vertical plane seen at columns x0 and x1 with depths
// depth0_m and depth1_m: on a plane, inverse depth is affine in the image coordinate. Taken at the
// nearer end beyond them; the nearer depth where the two columns coincide.
inline double plane_depth_at(double x, double x0, double depth0_m, double x1, double depth1_m) {
  const double span = x1 - x0;
  if (!(span > 0.0)) {
    return std::min(depth0_m, depth1_m);
  }
  const double t = std::clamp((x - x0) / span, 0.0, 1.0);
  return 1.0 / ((1.0 - t) / depth0_m + t / depth1_m);
}

// The width the flowsteer law's terms keep clear: the agent's own and its speed's share of the
// margin, at least its standing part.
inline double kept_width(const AgentState& agent, const KeptWidth& options) {
  const double share = std::min(1.0, std::abs(agent.speed_mps) / options.margin_full_speed_mps);
  return options.agent_width_m +
         std::max(std::min(options.standing_margin_m, options.margin_m), options.margin_m * share);
}

// τ/Z of an approaching object and its depth: from the object's depth where the term uses it
// and it has one, else from the depth-free guess τ v_c / Z = depth_free_ratio (MIG §7.1).
struct DepthScale {
  double tau_over_depth;
  double depth_m;
};
inline DepthScale depth_scale(const ObjectFeatures& object, const AgentState& agent,
                              const DepthGuess& depth) {
  if (depth.use_depth && object.depth_m && *object.depth_m > 0.0) {
    return {object.ttc_s / *object.depth_m, *object.depth_m};
  }
  const double tau_over_depth = depth.depth_free_ratio / floored_speed(agent, depth);
  return {tau_over_depth, object.ttc_s / tau_over_depth};
}

// Whether the object stands still: its fit found the static FOE and, where the field has a depth
// per pixel (a simulator's), it does not close in faster than static_closing_ratio times the
// agent's speed at its nearest point's depth. Not the mean depth: the fit of a wall along the
// path leans on its near pixels, and its τ is a third of the mean depth over the agent's speed.
// Not with a camera's depth from the ground: numerical flow's τ errs by more than the ratio
// allows, walls came out moving, and DIS flow lost.
inline bool stands_still(const ObjectFeatures& object, const AgentState& agent,
                         const DepthGuess& depth, double static_closing_ratio) {
  if (!object.fit.static_foe) {
    return false;
  }
  const std::optional<double>& nearest_m = object.nearest_depth_m;
  // An agent at rest or nearly sees no expansion from what stands still to measure this by.
  if (!depth.use_depth || !object.depth_m || !nearest_m || !std::isfinite(object.ttc_s) ||
      std::abs(agent.speed_mps) < depth.min_speed_mps) {
    return true;
  }
  // Infinity times a τ of 0 is NaN: still standing.
  return !(static_closing_ratio * std::abs(agent.speed_mps) * object.ttc_s < *nearest_m);
}

// An object the avoidance terms weigh: visible, approaching within the horizon, fitted.
inline bool is_threat(const ObjectFeatures& object, double horizon_s) {
  return object.kind == RegionKind::visible && object.status == MotionStatus::approaching &&
         object.ttc_s <= horizon_s && object.foe.allFinite() && object.centre.allFinite();
}

// I(τ) of CGF Eq. 9.
inline double importance(double ttc_s, const Importance& importance) {
  return std::max(0.0, importance.slope * ttc_s + importance.intercept);
}

// The leader's features: the visible object of percept.leader_id with valid flow, if seen.
const ObjectFeatures* find_leader(const Percept& percept);
// Each throws std::invalid_argument "<term> options: ..." naming the option that is out of range.
void require_option(bool ok, std::string_view term, const std::string& what);
void validate_agent_width(double agent_width_m, std::string_view term);
void validate(const KeptWidth& options, std::string_view term);
void validate(const Importance& options, std::string_view term);
void validate(const DepthGuess& options, std::string_view term);
void validate(const ThreatOptions& options, std::string_view term);
void validate_horizon(double horizon_s, std::string_view term);
void validate_commit_band(double commit_band, std::string_view term);
void validate_stop_decel(double stop_decel_mps2, std::string_view term);
void validate_static_closing(double static_closing_ratio, std::string_view term);
// Throws std::invalid_argument for a negative or non-finite weight.
void require_weight(double value, const char* name);

// Which side of the cusp of exp(−|s|/σ) an object is on: sign(s), except that an object whose
// s is within band·σ of the cusp keeps the side it had at the previous step. At the cusp the
// gradient flips with the sign of s, and a saturated command that carries s across it in one
// control period flips back at the next: the agent chatters between both sides and goes
// straight on. Keeping the side taken commits the agent to passing on one side, as a person
// does. Objects are recognised by source id; those without one (-1) get no memory.
class SideMemory {
 public:
  // What is remembered of an object: the side taken (+1 or −1) and how much longer it is held
  // whatever the object's features say (0: not held; ClearanceTerm's rest_commit_s).
  struct Taken {
    std::int32_t id;
    double side;
    double held_s;
  };

  double side(std::int32_t id, double s, double sigma, double band) {
    double side = s >= 0.0 ? 1.0 : -1.0;
    if (const Taken* taken = previous(id); taken && std::abs(s) < band * sigma) {
      side = taken->side;
    }
    remember(id, side);
    return side;
  }
  // What `id` had at the previous step, if it was seen then.
  const Taken* previous(std::int32_t id) const {
    for (const Taken& taken : previous_) {
      if (taken.id == id && id >= 0) {
        return &taken;
      }
    }
    return nullptr;
  }
  void remember(std::int32_t id, double side, double held_s = 0.0) {
    if (id >= 0) {
      current_.push_back({id, side, held_s});
    }
  }
  // Call once per step, after every object: forgets the objects no longer seen.
  void next_step() {
    previous_.swap(current_);
    current_.clear();
  }
  // Forgets what was remembered since next_step: a probe of a predicted percept (CostTerm::cost).
  void discard_step() { current_.clear(); }

 private:
  std::vector<Taken> previous_;
  std::vector<Taken> current_;
};

// A term that remembers the side each object was passed by (SideMemory): evaluate keeps what
// this step decided, cost (a probe of a predicted percept) forgets it.
class SideRememberingTerm : public CostTerm {
 public:
  TermGradient evaluate(const Percept& percept, const AgentState& agent) final {
    const TermGradient sum = assess(percept, agent);
    sides_.next_step();
    return sum;
  }
  double cost(const Percept& percept, const AgentState& agent) final {
    const double cost = assess(percept, agent).cost;
    sides_.discard_step();
    return cost;
  }

 protected:
  // The term's value and gradient, remembering the sides taken in sides_.
  virtual TermGradient assess(const Percept& percept, const AgentState& agent) = 0;
  SideMemory sides_;
};

}  // namespace flowsteer::servo::detail
