#pragma once

#include <cstdint>
#include <limits>
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
  // How long the command is held: the time between frames. 0 when not known (the first frame).
  double period_s = 0.0;
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
// these follow from the feature's FeatureRate (dynamics.hpp). The curvatures are how fast those
// derivatives grow as a control is held: for L(s) with ṡ = ... + b u, L''(s) b² (Gauss–Newton,
// one control at a time), what GradientStep::implicit needs.
struct TermGradient {
  double cost = 0.0;
  double per_accel = 0.0;
  double per_turn = 0.0;
  double curvature_accel = 0.0;
  double curvature_turn = 0.0;
};

// One control function L_k of CGF §6 / MIG §3.3.
class CostTerm {
 public:
  virtual ~CostTerm() = default;
  virtual std::string_view name() const = 0;
  // Not const: a term may remember what it decided at the previous step (see commit_band).
  virtual TermGradient evaluate(const Percept& percept, const AgentState& agent) = 0;
  // The cost alone at a percept predicted for a candidate command (TurnCheck), after this step's
  // evaluate: it remembers nothing, so a term that remembers must override it.
  virtual double cost(const Percept& percept, const AgentState& agent) {
    return evaluate(percept, agent).cost;
  }
};

// Which way an agent turns to pass an object met head-on, when neither side is clearly shorter.
// People agree on one (keep right, in most countries), which breaks the symmetry of two agents
// meeting head-on that would otherwise mirror each other's moves.
enum class PassingSide { none, keep_right, keep_left };

// The width the flowsteer law's terms keep clear of an object: the agent's own (CGF §6.2's agent
// width) and personal space in proportion to the agent's speed, margin_m in full from
// margin_full_speed_mps on. A person keeps more room walking than stepping slowly up to a goal
// beside someone.
struct KeptWidth {
  double agent_width_m = 0.5;
  double margin_m = 0.0;
  double margin_full_speed_mps = 1.0;
  // Of margin_m, what is kept at any speed, even at rest: without it an agent stepping slowly
  // along a wall or up to a neighbour keeps exactly its own width and touches at the first error.
  double standing_margin_m = 0.1;
};

// I(τ) = max(0, slope·τ + intercept), how much an object τ away weighs (CGF Eq. 9: −2, 10; its
// horizon of 5 s is each term's horizon_s).
struct Importance {
  double slope = -2.0;
  double intercept = 10.0;
};

// How a term reads an object's depth. When use_depth is false, or when an object has no depth,
// τ v_c / Z is taken as depth_free_ratio (MIG 2019 §7.1: 1/2).
struct DepthGuess {
  bool use_depth = true;
  double depth_free_ratio = 0.5;
  // The depth-free guess Z = τ v_c / ratio needs a speed; below this one it uses this one. The
  // flowsteer law's terms take an agent slower than this as at rest.
  double min_speed_mps = 0.1;
};

// L_av's (avoidance_term).
struct AvoidanceTermOptions {
  double agent_width_m = 0.5;  // added to each object's image width (CGF §6.2)
  Importance importance;
  double horizon_s = 5.0;  // objects approaching later than this are left out (CGF Eq. 9)
  DepthGuess depth;
  // An object within this many σ of the cusp of its cost (|g − f| small) keeps the side the
  // agent chose to pass it on at the previous step, instead of flipping with the sign of g − f
  // (0 turns this off). Needs objects with a source id.
  double commit_band = 1.0;
};

// L_dark's (dark_term).
struct DarkOptions {
  double agent_width_m = 0.5;  // added to the image width of a dark region with a depth
  double commit_band = 1.0;    // as AvoidanceTermOptions::commit_band
};

// The papers' law's settings: each of its terms' options (goal_reaching, following).
struct PapersOptions {
  AvoidanceTermOptions avoidance;
  DarkOptions dark;
  DepthGuess align;
  DepthGuess leader_speed;
};

// L_v's of the flowsteer law (approach_speed_term).
struct ApproachSpeedOptions {
  KeptWidth kept_width;
  DepthGuess depth;
  // Objects approaching within this are the braking term's, not this one's.
  double horizon_s = 5.0;
  double stop_decel_mps2 = 0.5;  // a_b, the deceleration it plans to stop with
};

// What the clearance and braking terms take for an object in their way.
struct ThreatOptions {
  KeptWidth kept_width;
  DepthGuess depth;
  double horizon_s = 5.0;  // objects approaching later than this are left out
  // A static object the agent's straight course passes further than half its kept width plus
  // this from, within the horizon, is left out (infinity: none is).
  double static_clearance_m = 0.25;
  // An object whose FOE the fit could not tell from a static one's moves all the same when it
  // closes in faster than this many times the agent's own speed (Z / τ at its nearest point,
  // where the field has a depth per pixel): someone walking straight at the agent has the FOE of
  // a wall ahead, and half its τ (infinity: the fit's word is taken).
  double static_closing_ratio = 1.5;
};

// L_c's (clearance_term).
struct ClearanceOptions {
  ThreatOptions threats;
  Importance importance;
  double commit_band = 1.0;  // as AvoidanceTermOptions::commit_band
  // An agent at rest (below threats.depth.min_speed_mps) that changes the end it passes a group
  // of objects by keeps the new end this long, while a member it was taken for stays in view (0
  // turns this off). Turning in place takes objects in and out of view while nothing moves, and
  // a decision made with an object in view is not undone by turning away from it.
  double rest_commit_s = 1.0;
  // The passing convention, and how strongly it leans (in σ: an object whose two ways round
  // differ by less than this is passed on the convention's side).
  PassingSide passing_side = PassingSide::keep_right;
  double passing_band = 1.0;
  // An object crossing the agent's path (its velocity over the ground more across the agent's
  // course than along it) faster than this many times threats.kept_width.margin_full_speed_mps,
  // a car, is passed behind where the agent can still stop short of its path at stop_decel_mps2
  // (infinity: never).
  double yield_speed_ratio = 1.5;
  double stop_decel_mps2 = 0.5;  // the deceleration the agent plans to stop with
};

// L_b's (braking_term).
struct BrakingOptions {
  ThreatOptions threats;
  double stop_decel_mps2 = 0.5;  // a_b, the deceleration it plans to stop with
};

// L_a's (anticipation_term).
struct AnticipationOptions {
  KeptWidth kept_width;
  DepthGuess depth;
  double static_closing_ratio = 1.5;  // as ThreatOptions::static_closing_ratio
  double horizon_s = 5.0;             // contacts later than this are left out
  double tau0_s = 3.0;                // τ0 of its energy, how far ahead in time contacts matter
};

// The flowsteer law's settings: each of its terms' options (flowsteer_goal_reaching,
// flowsteer_following).
struct FlowsteerOptions {
  ApproachSpeedOptions approach_speed;
  ClearanceOptions clearance;
  BrakingOptions braking;
  AnticipationOptions anticipation;
  DarkOptions dark;
  DepthGuess align;
  DepthGuess leader_gap;
};

// The flowsteer law's settings for an agent that keeps kept_width clear and reads depth as
// `depth` in every term, each term's own options at their defaults. The dark term widens a dark
// region by kept_width.agent_width_m alone.
FlowsteerOptions flowsteer_options(const KeptWidth& kept_width, const DepthGuess& depth = {});

// L_t = ½ t_x² (CGF Eq. 7). Needs the goal's bearing; zero without one.
std::unique_ptr<CostTerm> goal_term();
// L_v = ½ (v_c − v*)² (CGF Eq. 12).
std::unique_ptr<CostTerm> speed_term(double preferred_speed_mps);
// L_av = Σ_i I(τ_i) exp(−|g_i − f_i| / σ_i) over approaching visible objects (CGF Eq. 9).
std::unique_ptr<CostTerm> avoidance_term(const AvoidanceTermOptions& options = {});
// L_dark = Σ_dark exp(−|g_i| / σ_i) (MIG 2019 Eq. 3).
std::unique_ptr<CostTerm> dark_term(const DarkOptions& options = {});
// L_min = (Σ_j u_j)² / N² over the leader (CGF Eq. 11).
std::unique_ptr<CostTerm> align_term(const DepthGuess& depth = {});
// L_τ = ½ v_z² of the leader (CGF Eq. 13).
std::unique_ptr<CostTerm> leader_speed_term(const DepthGuess& depth = {});

// The flowsteer law's terms (clearance_terms.cpp): the papers' structure, with what their law
// collides in replaced.
//
// L_θ = ½ θ², θ = atan t_x the goal's bearing: ω = λ α θ stays bounded for a goal beside or behind
// the agent, where L_t's t_x (1 + t_x²) grows without bound and outweighs any avoidance.
std::unique_ptr<CostTerm> heading_term();
// L_v = ½ (v_c − v_t)² with v_t = min(v*, ω_t d / (2 sin|θ|), √(2 a_g d), √(2 a_b s)): no faster
// than lets the agent turn onto a goal d away at bearing θ at turn rate ω_t (half the controller's
// limit), so that it does not circle a goal inside its turning circle (sin|θ| taken as 1 beyond
// 90°), no faster than it stops from at the goal at a_g (arrival_decel_mps2), as a walker slows to
// step up to a goal beside others, and no faster than it stops from at a_b (stop_decel_mps2)
// within s, how far it walks straight on before it comes within half its kept width of a visible
// object that is not approaching, taken as standing (objects with depth only).
std::unique_ptr<CostTerm> approach_speed_term(double preferred_speed_mps, double max_turn_rate,
                                              double arrival_decel_mps2 = 0.5,
                                              const ApproachSpeedOptions& options = {});
// L_c = Σ_i I(τ_i) φ(c_i / σ_i) over approaching visible objects: c_i is the FOE's clearance from
// the object's extent [min_x, max_x] widened at each end by half the kept width (agent_width_m and
// the speed's share of margin_m) at that end's depth, on the side the agent passes it on; φ(u) =
// exp(−u) outside (u ≥ 0), 1 − u inside. Its extent, unlike CGF Eq. 9's centre, makes a wall along
// the path cost nothing and one across it cost everything. An object further than the goal by half
// the kept width is left out: the agent stops at the goal short of it. So is a static object that
// the agent's straight course passes by more than half the kept width and static_clearance_m.
// See clearance_terms.cpp.
std::unique_ptr<CostTerm> clearance_term(const ClearanceOptions& options = {});
// L_b = Σ_i ψ_i ½ max(0, v_c − v_i)², v_i = √(2 a_b (Z_i − w/2)) the speed from which the agent
// stops at a_b (stop_decel_mps2) half its width w short of object i, Z_i the object's depth where
// the FOE points (a vertical plane through its ends), ψ_i = min(1, φ(c_i/σ_i)) on
// the better side: brakes for an object whose widened extent holds the FOE, which no turning
// term does for a static obstacle met head-on (its FOE is straight ahead, f = 0, and CGF Eq. 10's
// f a_c term vanishes).
std::unique_ptr<CostTerm> braking_term(const BrakingOptions& options = {});
// L_a = Σ_i E(τ_i), E(τ) = k e^(−τ/τ0) / τ² (k = 1.5, τ0 = tau0_s): Karamouzas et al.'s
// time-to-collision energy (PRL 2014), τ_i the time until object i, moving at the velocity its
// flow shows (V_z = −Z/τ, V_x = f V_z), first comes within half the kept width of the agent, the
// object taken as the segment between its ends on the ground. Its gradient turns or slows the
// agent for what will touch it, whatever its FOE says (a neighbour closing in sideways has no
// expansion, its FOE at infinity), and costs nothing for what will not (a wall along the path).
// Contacts later than the agent takes to reach its goal are left out. See anticipation_term.cpp.
std::unique_ptr<CostTerm> anticipation_term(const AnticipationOptions& options = {});
// L_g = ½ (v_z + (Z − G)/T)² of the leader: close the gap to G metres with time constant T,
// then match its speed (CGF Eq. 13's L_τ is the case G = 0, T → ∞). Needs the leader's depth.
std::unique_ptr<CostTerm> leader_gap_term(double gap_m, double gap_time_s,
                                          const DepthGuess& depth = {});

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
  // The weighted sum of the terms' CostTerm::cost.
  double cost(const Percept& percept, const AgentState& agent);

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
// The flowsteer law's weights; the papers' α..δ keep their roles.
struct FlowsteerWeights {
  double alpha = 1.0;         // heading
  double beta = 1.0;          // approach speed (a walker reaches its speed in about a second)
  double gamma = 1.0;         // clearance
  double delta = 0.0;         // dark regions (MIG Eq. 3), at most gamma
  double braking = 2.0;       // braking
  double anticipation = 1.0;  // anticipation (time-to-collision energy)
  double preferred_speed_mps = 1.0;
  double max_turn_rate = 1.0;       // the controller's limit, for the approach speed
  double arrival_decel_mps2 = 0.5;  // the approach speed's braking to stop at the goal
  double follow_gap_m = 2.0;        // following: the gap kept behind the leader
  double gap_time_s = 1.0;
};

struct FollowingWeights {  // CGF Eq. 18
  double alpha = 1.0;      // alignment
  double beta = 1.0;       // leader speed
  double gamma = 1.0;      // avoidance
};

// Throws std::invalid_argument when a weight is negative or δ > γ.
NavigationFunction goal_reaching(const GoalReachingWeights& weights,
                                 const PapersOptions& options = {});
NavigationFunction following(const FollowingWeights& weights, const PapersOptions& options = {});

// The flowsteer law: L = α L_θ + β L_v + γ L_c + ε L_b + ζ L_a (+ δ L_dark), ζ the anticipation
// weight, and for following L = α L_min + β L_g + γ L_c + ε L_b. Throws std::invalid_argument like
// goal_reaching.
NavigationFunction flowsteer_goal_reaching(const FlowsteerWeights& weights,
                                           const FlowsteerOptions& options = {});
NavigationFunction flowsteer_following(const FlowsteerWeights& weights,
                                       const FlowsteerOptions& options = {});

struct ControlLimits {
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;  // rad/s
  // The acceleration is held so that the speed does not pass this within the control period
  // (and brings it back down where it has). Unlimited by default: the papers' laws have none.
  double max_speed_mps = std::numeric_limits<double>::infinity();
};

struct ControlOutput {
  base::Command command;
  base::Command unclamped;
  double cost = 0.0;
  std::vector<TermEvaluation> terms;
};

// How the controller turns the gradient into a command.
enum class GradientStep {
  // CGF Eq. 15 as printed: u = −λ ∂L̇/∂u, the papers' continuous-time law.
  explicit_euler,
  // The same descent taken over the period the command is held (AgentState::period_s), with the
  // gradient at the period's end: u = −λ ∂L̇/∂u / (1 + λ T c), c the term's curvature. Where the
  // cost is stiff (the far ends of a corridor's walls, seen a few σ from the FOE) the explicit
  // step turns the FOE past the minimum by many σ in one period and the command flips between
  // its limits from frame to frame; the implicit one moves it at most about σ per period and
  // equals the explicit one where λ T c ≪ 1.
  implicit_euler,
};

// Whether the turn the gradient asks for is checked against the cost it leads to. The gradient
// sees a term's cost change only through its features' rates, not where an object's importance
// or its being passed clear changes with the course: a wall beside the agent costs nothing while
// the course runs along it and its full importance once the course turns a few hundredths of a
// radian towards it, less than one period's turn at the limit. The command then flips between
// the limits at every step, each turn undoing the last. Checked, the turn rate is the
// gradient's, or its half, quarter or eighth, whichever leads to the predicted percept
// (turn_prediction.hpp: the view turned, the translation left out) that costs least.
// A goal beyond an object's end (a corridor's mouth, a building's corner) lies past courses that
// cross that end: each fraction's course costs more than the last, the check keeps the smallest,
// and the agent walks along the object past its goal. So where the check holds the turn towards
// the goal back, or the gradient turns away from it, and the way onto the goal (the turn onto its
// bearing at the turn limit and the present speed, then straight on to it) passes every object in
// view clear, the objects that stand still are left out of the check (the way passes them clear,
// though the course now crosses them), and turns towards the goal, at the limit or its half,
// quarter or eighth, compete with the checked one.
// A goal behind the agent (beyond a quarter turn) only falls further behind as the agent walks on,
// and in a corridor every turn onto it at walking pace crosses a wall: the check weighed each turn
// against that wall's cost, kept an eighth of it, and the agent walked away from its goal for good.
// So where the way onto a goal behind keeps half the kept width from every object (contact, not
// the clearance cost's reach: the terms do not steer this turn), the agent turns onto it at the
// limit; where it does not, but would at the present speed's half, quarter, eighth or at rest, the
// agent slows to the fastest such speed and turns round within the corridor. Where no speed makes
// the way clear (a wall between the agent and its goal) the terms steer, as before, until the goal
// is no longer behind.
struct TurnCheck {
  bool enabled = false;
  // What the terms take objects' depths and motion from (ThreatOptions), for the prediction.
  DepthGuess depth;
  double static_closing_ratio = 1.5;
  // Whether the way onto the goal is judged at all: only where the percept holds what stands
  // beside the agent, steadily (StaticPercept, steering.hpp).
  bool way_onto_goal = false;
  // The way onto the goal is clear where it keeps half the kept width and static_clearance_m
  // from every object: where a static object's clearance cost ends (ThreatOptions), so that once
  // on it the terms agree.
  KeptWidth kept_width;
  double static_clearance_m = 0.25;
};

// Whether the command is checked against the contacts it leads to. The gradient weighs a
// crosser's cost against every other term's: the clearance term's gradient in a_c ("speed up to
// pass in front") took agents into a crossroads at the speed limit, where they met crossers they
// could no longer stop for, and the terms turned a walker into the neighbour beside it, out of
// view until it came within reach (four_way_intersection). Checked (where the percept's depths
// are exact, StaticPercept in steering.hpp), a moving object (not standing still, stands_still)
// that would come within half the kept width of the agent, both going straight on
// (contact_time.hpp), sooner than the agent stops at max_accel_mps2 (one period included):
// - makes it brake at the limit, where braking puts that contact off;
// - has the turn checked: of the command's turn, none and the opposite turn, the one after which
//   the earliest such contact comes latest (the view turned by one period's turn, the objects'
//   velocities over the ground kept), the command's where none is later.
struct StopCheck {
  bool enabled = false;
  // What the terms take objects' depths and motion from (ThreatOptions).
  DepthGuess depth;
  double static_closing_ratio = 1.5;
  KeptWidth kept_width;
};

// The gradient update of CGF Eq. 15, a_c = −λ ∂L̇/∂a_c and ω = −λ ∂L̇/∂ω, clamped to the limits.
class Controller {
 public:
  Controller(NavigationFunction navigation, double lambda, const ControlLimits& limits,
             GradientStep gradient_step = GradientStep::explicit_euler,
             const TurnCheck& turn_check = {}, const StopCheck& stop_check = {});

  // Reuses `out.terms`' storage.
  void step(const Percept& percept, const AgentState& agent, ControlOutput& out);
  ControlOutput step(const Percept& percept, const AgentState& agent);

 private:
  double checked_turn_rate(const Percept& percept, const AgentState& agent, double turn_rate);
  // The command checked against the contacts it leads to (StopCheck).
  void check_stop(const Percept& percept, const AgentState& agent, base::Command& command) const;
  // Whether the goal lies beyond one period's turn and the way onto it (TurnCheck) is clear of
  // every object in view, and some of them stand still; fills open_objects_ with the others.
  bool leaves_static_objects_out(const Percept& percept, const AgentState& agent);
  // Whether the way onto the goal is judged and the goal lies beyond a quarter turn.
  bool goal_is_behind(const Percept& percept) const;
  // Whether the way onto a goal behind, at speed_mps, keeps half the kept width from every object.
  bool way_onto_goal_behind_is_clear(const Percept& percept, const AgentState& agent,
                                     double speed_mps) const;
  // What turning round for a goal behind asks of this step (TurnCheck).
  struct TurnRound {
    // The fastest speed at which the way onto the goal is clear, where the present speed and one
    // period's acceleration past it are not; infinity where no speed is limited so.
    double max_speed_mps = std::numeric_limits<double>::infinity();
    bool at_limit = false;  // the way is clear at the present speed: turn onto it at the limit
  };
  // Where no speed makes the way clear, sets way_round_blocked_; clears it once the goal is not
  // behind.
  TurnRound turn_round(const Percept& percept, const AgentState& agent);

  NavigationFunction navigation_;
  double lambda_;
  ControlLimits limits_;
  GradientStep gradient_step_;
  TurnCheck turn_check_;
  StopCheck stop_check_;
  std::vector<ObjectFeatures> turned_objects_;  // reused by each check
  std::vector<ObjectFeatures> open_objects_;    // the objects that do not stand still
  // The way onto the goal behind was seen blocked at every speed: the terms steer until the goal
  // is no longer behind. Turning onto it had brought the wall between into view, turning away took
  // it out again, and the agent turned to and fro at rest in a dead end (u_dead_end_inside).
  bool way_round_blocked_ = false;
};

}  // namespace flowsteer::servo
