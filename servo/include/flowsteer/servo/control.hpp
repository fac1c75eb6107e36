#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "flowsteer/base/command.hpp"
#include "flowsteer/servo/features.hpp"

namespace flowsteer::servo {

// What the agent knows about itself.
struct AgentState {
  double speed_mps = 0.0;  // v_c, forward, along the optical axis
};

// What the agent perceives in one control step.
struct Percept {
  std::span<const ObjectFeatures> objects;
  // Bearing of the goal from the direction of motion, positive to the right.
  std::optional<double> goal_bearing_rad;
  // Distance to the goal, for the goal's time to reach (optional: L_t's gradient needs none).
  std::optional<double> goal_distance_m;
  // Object id of the leader to follow (matched against ObjectFeatures::source_id).
  std::optional<std::int32_t> leader_id;
};

// A control term's value L and the partial derivatives of its time derivative L̇ with respect
// to the controls: ∂L̇/∂a_c and ∂L̇/∂ω. Since every feature rate is affine in the controls,
// these follow from the feature's FeatureRate (dynamics.hpp).
struct TermGradient {
  double cost = 0.0;
  double per_accel = 0.0;
  double per_turn = 0.0;
};

// One control function L_k of CGF §6 / MIG §3.3.
class CostTerm {
 public:
  virtual ~CostTerm() = default;
  virtual std::string_view name() const = 0;
  // Not const: a term may remember what it decided at the previous step (see commit_band).
  virtual TermGradient evaluate(const Percept& percept, const AgentState& agent) = 0;
};

// How the avoidance terms size objects and guess what depth does not tell them.
struct AvoidanceOptions {
  double agent_width_m = 0.5;  // added to each object's image width (CGF §6.2)
  // I(τ) = slope·τ + intercept for 0 ≤ τ ≤ horizon, zero outside (CGF Eq. 9: −2, 10, 5 s).
  double importance_slope = -2.0;
  double importance_intercept = 10.0;
  double horizon_s = 5.0;
  // When false, or when an object has no depth, τ v_c / Z is taken as depth_free_ratio
  // (MIG 2019 §7.1: 1/2).
  bool use_depth = true;
  double depth_free_ratio = 0.5;
  // The depth-free guess Z = τ v_c / ratio needs a speed; below this one it uses this one.
  double min_speed_mps = 0.1;
  // An object within this many σ of the cusp of its cost (|g − f| small) keeps the side the
  // agent chose to pass it on at the previous step, instead of flipping with the sign of g − f
  // (0 turns this off). Needs objects with a source id.
  double commit_band = 1.0;
};

// L_t = ½ t_x² (CGF Eq. 7). Needs the goal's bearing; zero without one.
std::unique_ptr<CostTerm> goal_term();
// L_v = ½ (v_c − v*)² (CGF Eq. 12).
std::unique_ptr<CostTerm> speed_term(double preferred_speed_mps);
// L_av = Σ_i I(τ_i) exp(−|g_i − f_i| / σ_i) over approaching visible objects (CGF Eq. 9).
std::unique_ptr<CostTerm> avoidance_term(const AvoidanceOptions& options = {});
// L_dark = Σ_dark exp(−|g_i| / σ_i) (MIG 2019 Eq. 3).
std::unique_ptr<CostTerm> dark_term(const AvoidanceOptions& options = {});
// L_min = (Σ_j u_j)² / N² over the leader (CGF Eq. 11).
std::unique_ptr<CostTerm> align_term(const AvoidanceOptions& options = {});
// L_τ = ½ v_z² of the leader (CGF Eq. 13).
std::unique_ptr<CostTerm> leader_speed_term(const AvoidanceOptions& options = {});

struct TermEvaluation {
  std::string name;
  double weight = 0.0;
  TermGradient gradient;  // unweighted
};

// L = Σ_k α_k L_k (CGF Eq. 14).
class NavigationFunction {
 public:
  NavigationFunction& add(double weight, std::unique_ptr<CostTerm> term);
  // Fills `out` with one entry per term (reusing its storage) and returns the weighted sum.
  TermGradient evaluate(const Percept& percept, const AgentState& agent,
                        std::vector<TermEvaluation>& out);

 private:
  struct Weighted {
    double weight;
    std::unique_ptr<CostTerm> term;
  };
  std::vector<Weighted> terms_;
};

struct GoalReachingWeights {  // CGF Eq. 16, MIG Eq. 4
  double alpha = 1.0;         // goal
  double beta = 0.1;          // speed
  double gamma = 1.0;         // avoidance
  double delta = 0.0;         // dark regions; MIG uses 1 and asks for γ ≥ δ
  double preferred_speed_mps = 1.0;
};
struct FollowingWeights {  // CGF Eq. 18
  double alpha = 1.0;      // alignment
  double beta = 1.0;       // leader speed
  double gamma = 1.0;      // avoidance
};

// Throws std::invalid_argument when a weight is negative or δ > γ.
NavigationFunction goal_reaching(const GoalReachingWeights& weights,
                                 const AvoidanceOptions& avoidance = {});
NavigationFunction following(const FollowingWeights& weights,
                             const AvoidanceOptions& avoidance = {});

struct ControlLimits {
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;  // rad/s
};

struct ControlOutput {
  base::Command command;
  base::Command unclamped;
  double cost = 0.0;
  std::vector<TermEvaluation> terms;
};

// The gradient update of CGF Eq. 15, a_c = −λ ∂L̇/∂a_c and ω = −λ ∂L̇/∂ω, clamped to the limits.
class Controller {
 public:
  Controller(NavigationFunction navigation, double lambda, const ControlLimits& limits);

  // Reuses `out.terms`' storage.
  void step(const Percept& percept, const AgentState& agent, ControlOutput& out);
  ControlOutput step(const Percept& percept, const AgentState& agent);

 private:
  NavigationFunction navigation_;
  double lambda_;
  ControlLimits limits_;
};

}  // namespace flowsteer::servo
