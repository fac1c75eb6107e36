#include "flowsteer/servo/steering.hpp"

#include <array>
#include <utility>

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
std::optional<SteeringModel> parse_steering_model(std::string_view name) {
  return value_of(kModels, name);
}
std::optional<NavigationKind> parse_navigation_kind(std::string_view name) {
  return value_of(kKinds, name);
}
std::optional<MassSource> parse_mass_source(std::string_view name) {
  return value_of(kMassSources, name);
}

std::string steering_model_names() {
  std::string names;
  for (const auto& [model, name] : kModels) {
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  return names;
}

Controller make_controller(const ControllerConfig& c, double agent_width_m,
                           double preferred_speed_mps) {
  AvoidanceOptions avoidance;
  avoidance.agent_width_m = agent_width_m + c.clearance_margin_m;
  avoidance.use_depth = c.use_depth;
  const ControlLimits limits{c.max_accel_mps2, c.max_turn_rate};
  if (c.kind == NavigationKind::following) {
    return Controller(following({c.alpha, c.beta, c.gamma}, avoidance), c.lambda, limits);
  }
  GoalReachingWeights weights;
  weights.alpha = c.alpha;
  weights.beta = c.beta;
  weights.gamma = c.gamma;
  weights.delta = c.delta;
  weights.preferred_speed_mps = preferred_speed_mps;
  return Controller(goal_reaching(weights, avoidance), c.lambda, limits);
}

}  // namespace flowsteer::servo
