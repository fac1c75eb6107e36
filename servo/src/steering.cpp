#include "flowsteer/servo/steering.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "cost_term_helpers.hpp"

namespace flowsteer::servo {

namespace {

constexpr std::array<std::pair<SteeringModel, std::string_view>, 3> kModels{{
    {SteeringModel::vision, "vision"},
    {SteeringModel::geometric, "geometric"},
    {SteeringModel::motion_energy, "motion_energy"},
}};
constexpr std::array<std::pair<NavigationKind, std::string_view>, 2> kKinds{{
    {NavigationKind::goal_reaching, "goal_reaching"},
    {NavigationKind::following, "following"},
}};
constexpr std::array<std::pair<MassSource, std::string_view>, 2> kMassSources{{
    {MassSource::ids, "ids"},
    {MassSource::ground, "ground"},
}};
constexpr std::array<std::pair<DepthSource, std::string_view>, 2> kDepthSources{{
    {DepthSource::renderer, "renderer"},
    {DepthSource::ground, "ground"},
}};

constexpr std::array<std::pair<NavigationLaw, std::string_view>, 3> kLaws{{
    {NavigationLaw::flowsteer, "flowsteer"},
    {NavigationLaw::cgf2019, "cgf2019"},
    {NavigationLaw::mig2019, "mig2019"},
}};

constexpr std::array<std::pair<LawMechanism, std::string_view>, 13> kMechanisms{{
    {LawMechanism::none, "none"},
    {LawMechanism::braking, "braking"},
    {LawMechanism::anticipation, "anticipation"},
    {LawMechanism::passing_convention, "passing_convention"},
    {LawMechanism::commitment, "commitment"},
    {LawMechanism::passed_clear, "passed_clear"},
    {LawMechanism::giving_way, "giving_way"},
    {LawMechanism::speed_limit, "speed_limit"},
    {LawMechanism::implicit_step, "implicit_step"},
    {LawMechanism::proportional_margin, "proportional_margin"},
    {LawMechanism::static_closing, "static_closing"},
    {LawMechanism::turn_check, "turn_check"},
    {LawMechanism::stop_check, "stop_check"},
}};

template <typename Enum, std::size_t N>
std::string names_of(const std::array<std::pair<Enum, std::string_view>, N>& table) {
  std::string names;
  for (const auto& [value, name] : table) {
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  return names;
}

template <typename Enum, std::size_t N>
std::string_view name_of(const std::array<std::pair<Enum, std::string_view>, N>& table, Enum e) {
  for (const auto& [value, name] : table) {
    if (value == e)
      return name;
  }
  return "?";
}

template <typename Enum, std::size_t N>
std::optional<Enum> value_of(const std::array<std::pair<Enum, std::string_view>, N>& table,
                             std::string_view name) {
  for (const auto& [value, n] : table) {
    if (n == name)
      return value;
  }
  return std::nullopt;
}

// The terms' part of LawMechanism; the weights, the speed limit and the step are
// make_controller's.
void disable(LawMechanism mechanism, FlowsteerOptions& o) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  switch (mechanism) {
    case LawMechanism::passing_convention:
      o.clearance.passing_side = PassingSide::none;
      break;
    case LawMechanism::commitment:
      o.clearance.commit_band = 0.0;
      o.clearance.rest_commit_s = 0.0;
      o.dark.commit_band = 0.0;
      break;
    case LawMechanism::passed_clear:
      o.clearance.threats.static_clearance_m = kNever;
      o.braking.threats.static_clearance_m = kNever;
      break;
    case LawMechanism::giving_way:
      o.clearance.yield_speed_ratio = kNever;
      break;
    case LawMechanism::proportional_margin:
      for (KeptWidth* kept : {&o.approach_speed.kept_width, &o.clearance.threats.kept_width,
                              &o.braking.threats.kept_width, &o.anticipation.kept_width}) {
        kept->standing_margin_m = kept->margin_m;
      }
      break;
    case LawMechanism::static_closing:
      o.clearance.threats.static_closing_ratio = kNever;
      o.braking.threats.static_closing_ratio = kNever;
      o.anticipation.static_closing_ratio = kNever;
      break;
    case LawMechanism::none:
    case LawMechanism::braking:
    case LawMechanism::anticipation:
    case LawMechanism::speed_limit:
    case LawMechanism::implicit_step:
    case LawMechanism::turn_check:
    case LawMechanism::stop_check:
      break;
  }
}

// The flowsteer law's terms for a config: they keep the agent's width and the margin in
// proportion to its speed, in full from full_speed_mps on; the mechanism switched off is off.
FlowsteerOptions flowsteer_terms(const ControllerConfig& c, double agent_width_m,
                                 double full_speed_mps) {
  KeptWidth kept;
  kept.agent_width_m = agent_width_m;
  kept.margin_m = c.clearance_margin_m;
  kept.margin_full_speed_mps = full_speed_mps;
  DepthGuess depth;
  depth.use_depth = c.use_depth;
  FlowsteerOptions options = flowsteer_options(kept, depth);
  disable(c.without, options);
  return options;
}

// The papers' law's terms for a config: the margin is part of the agent's width (CGF §6.2).
PapersOptions papers_terms(const ControllerConfig& c, double agent_width_m) {
  PapersOptions o;
  o.avoidance.agent_width_m = agent_width_m + c.clearance_margin_m;
  o.avoidance.depth.use_depth = c.use_depth;
  o.dark.agent_width_m = o.avoidance.agent_width_m;
  o.align.use_depth = c.use_depth;
  o.leader_speed.use_depth = c.use_depth;
  return o;
}

}  // namespace

std::string_view to_string(SteeringModel model) {
  return name_of(kModels, model);
}
std::string_view to_string(NavigationKind kind) {
  return name_of(kKinds, kind);
}
std::string_view to_string(MassSource source) {
  return name_of(kMassSources, source);
}
std::string_view to_string(DepthSource source) {
  return name_of(kDepthSources, source);
}
std::optional<SteeringModel> parse_steering_model(std::string_view name) {
  return value_of(kModels, name);
}
std::optional<NavigationKind> parse_navigation_kind(std::string_view name) {
  return value_of(kKinds, name);
}
std::optional<MassSource> parse_mass_source(std::string_view name) {
  return value_of(kMassSources, name);
}
std::optional<DepthSource> parse_depth_source(std::string_view name) {
  return value_of(kDepthSources, name);
}
std::string depth_source_names() {
  return names_of(kDepthSources);
}

std::string_view to_string(NavigationLaw law) {
  return name_of(kLaws, law);
}
std::optional<NavigationLaw> parse_navigation_law(std::string_view name) {
  return value_of(kLaws, name);
}

std::string_view to_string(LawMechanism mechanism) {
  return name_of(kMechanisms, mechanism);
}
std::optional<LawMechanism> parse_law_mechanism(std::string_view name) {
  return value_of(kMechanisms, name);
}
std::string law_mechanism_names() {
  return names_of(kMechanisms);
}

std::string steering_model_names() {
  return names_of(kModels);
}
std::string navigation_law_names() {
  return names_of(kLaws);
}

NavigationWeights navigation_weights(const ControllerConfig& c) {
  NavigationWeights w;  // flowsteer's
  if (c.law == NavigationLaw::flowsteer) {
    w.braking = 2.0;
    w.anticipation = 1.0;
  } else if (c.law == NavigationLaw::mig2019) {
    w.delta = 1.0;
  } else if (c.kind == NavigationKind::goal_reaching) {
    w.beta = 0.1;
  }
  w.alpha = c.alpha.value_or(w.alpha);
  w.beta = c.beta.value_or(w.beta);
  w.gamma = c.gamma.value_or(w.gamma);
  w.delta = c.delta.value_or(w.delta);
  w.braking = c.braking.value_or(w.braking);
  w.anticipation = c.anticipation.value_or(w.anticipation);
  if (c.without == LawMechanism::braking) {
    w.braking = 0.0;
  } else if (c.without == LawMechanism::anticipation) {
    w.anticipation = 0.0;
  }
  return w;
}

MakeRoomOptions make_room_options(const ControllerConfig& c, double agent_width_m) {
  // The terms' depth guess and still-standing test do not depend on the speed their margin
  // grows to.
  const ThreatOptions threats =
      flowsteer_terms(c, agent_width_m, DepthGuess{}.min_speed_mps).clearance.threats;
  MakeRoomOptions options;
  options.agent_width_m = agent_width_m;
  options.depth = threats.depth;
  options.static_closing_ratio = threats.static_closing_ratio;
  return options;
}

Controller make_controller(const ControllerConfig& c, double agent_width_m,
                           double preferred_speed_mps, const StaticPercept& statics) {
  ControlLimits limits{c.max_accel_mps2, c.max_turn_rate};
  const NavigationWeights w = navigation_weights(c);
  if (c.law == NavigationLaw::flowsteer) {
    // The margin is in full from the preferred speed on, or from the speed below which the terms
    // take the agent as at rest.
    const double full_speed_mps = std::max(preferred_speed_mps, DepthGuess{}.min_speed_mps);
    // A follower keeps its leader's pace.
    if (c.kind == NavigationKind::goal_reaching && c.without != LawMechanism::speed_limit) {
      limits.max_speed_mps = c.max_speed_ratio * full_speed_mps;
    }
    const FlowsteerOptions options = flowsteer_terms(c, agent_width_m, full_speed_mps);
    FlowsteerWeights weights;
    weights.alpha = w.alpha;
    weights.beta = w.beta;
    weights.gamma = w.gamma;
    weights.delta = w.delta;
    weights.braking = w.braking;
    weights.anticipation = w.anticipation;
    weights.preferred_speed_mps = preferred_speed_mps;
    weights.max_turn_rate = c.max_turn_rate;
    weights.follow_gap_m = c.follow_gap_m;
    const ThreatOptions& threats = options.clearance.threats;
    // Anything within the way's clearance beside the agent must have been in view until the
    // agent's front came level with it; with a narrower view (a robot's 90° camera) a pillar just
    // passed is out of it.
    const double clearance_m = 0.5 * detail::kept_width({full_speed_mps, 0.0}, threats.kept_width) +
                               threats.static_clearance_m;
    const bool wide_view =
        std::tan(std::min(statics.view_half_angle_rad, 0.49 * std::numbers::pi)) * 0.5 *
            agent_width_m >=
        clearance_m;
    // Goal reaching only: a follower turning to keep its leader fell behind it with the check.
    const TurnCheck turn_check{
        c.kind == NavigationKind::goal_reaching && c.without != LawMechanism::turn_check,
        threats.depth,
        threats.static_closing_ratio,
        statics.exact_depth && wide_view,
        threats.kept_width,
        threats.static_clearance_m};
    // Goal reaching only, as the speed limit: a follower keeps its leader's pace.
    StopCheck stop_check;
    stop_check.enabled = c.kind == NavigationKind::goal_reaching &&
                         c.without != LawMechanism::stop_check && statics.exact_depth;
    stop_check.depth = threats.depth;
    stop_check.static_closing_ratio = threats.static_closing_ratio;
    stop_check.kept_width = threats.kept_width;
    return Controller(c.kind == NavigationKind::following
                          ? flowsteer_following(weights, options)
                          : flowsteer_goal_reaching(weights, options),
                      c.lambda, limits,
                      c.without == LawMechanism::implicit_step ? GradientStep::explicit_euler
                                                               : GradientStep::implicit_euler,
                      turn_check, stop_check);
  }
  const PapersOptions options = papers_terms(c, agent_width_m);
  if (c.kind == NavigationKind::following) {
    return Controller(following({w.alpha, w.beta, w.gamma}, options), c.lambda, limits);
  }
  const GoalReachingWeights weights{w.alpha, w.beta, w.gamma, w.delta, preferred_speed_mps};
  return Controller(goal_reaching(weights, options), c.lambda, limits);
}

}  // namespace flowsteer::servo
