// The flowsteer law's anticipation term (control.hpp): the time-to-collision energy of
// Karamouzas, Skinner and Guy, "Universal power law governing pedestrian interactions", Phys.
// Rev. Lett. 113, 238701 (2014), over the visual features of each object. See docs/NAVIGATION.md.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "contact_time.hpp"
#include "cost_term_helpers.hpp"
#include "flowsteer/servo/control.hpp"

namespace flowsteer::servo {

namespace {

// Karamouzas et al.'s k: E(τ) = k e^(−τ/τ0) / τ² (their Eq. 1 with m = 2).
constexpr double kEnergyScale = 1.5;
// E grows as 1/τ² without bound; below this the energy and its slope are taken at it, and the
// controller's limits do the rest.
constexpr double kMinContactTime_s = 0.1;

// E(τ) = k e^(−τ/τ0) / τ², its slope and its curvature.
struct Energy {
  double value;
  double slope;
  double curvature;
};
Energy energy(double tau_s, double tau0_s) {
  const double e = kEnergyScale * std::exp(-tau_s / tau0_s);
  const double t2 = tau_s * tau_s;
  return {e / t2, -e * (2.0 / (t2 * tau_s) + 1.0 / (t2 * tau0_s)),
          e * (6.0 / (t2 * t2) + 4.0 / (t2 * tau_s * tau0_s) + 1.0 / (t2 * tau0_s * tau0_s))};
}

class AnticipationTerm final : public CostTerm {
 public:
  explicit AnticipationTerm(const AnticipationOptions& options) : options_(options) {}
  std::string_view name() const override { return "anticipation"; }

  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    const double radius_m = 0.5 * detail::kept_width(agent, options_.kept_width);
    TermGradient sum;
    for (const ObjectFeatures& object : percept.objects) {
      const std::optional<detail::StraightOn> s = detail::straight_on(
          object, agent, options_.depth, options_.static_closing_ratio, radius_m);
      if (s && s->contact.time_s <= options_.horizon_s &&
          !beyond_goal(percept, agent, s->contact)) {
        detail::accumulate(sum, gradient(s->contact, s->velocity, agent));
      }
    }
    return sum;
  }

 private:
  // A contact later than the agent takes to walk to its goal, where it stops: an agent stepping
  // up to a goal beside people already standing at theirs would otherwise be turned away from it
  // (in fan_in, the outer agents circled their goals and never reached them).
  static bool beyond_goal(const Percept& percept, const AgentState& agent,
                          const detail::Contact& contact) {
    return percept.goal_distance_m && contact.time_s * agent.speed_mps > *percept.goal_distance_m;
  }

  // L = E(τ_c), L̇ = E'(τ_c) τ̇_c. τ_c depends on the relative velocity V alone, which the frame's
  // turning does not change: ∂τ_c/∂V = −τ_c n / (n·V) (differentiating |contact| = R), and the
  // agent's own velocity turns at ω and grows at a_c, so V̇ = (−v_c ω, −a_c).
  TermGradient gradient(const detail::Contact& contact, const Eigen::Vector2d& velocity,
                        const AgentState& agent) const {
    const double closing = contact.normal.dot(velocity);
    if (!(closing < 0.0)) {
      return {};
    }
    const double tau_s = std::max(contact.time_s, kMinContactTime_s);
    const Eigen::Vector2d per_velocity = -tau_s * contact.normal / closing;
    const FeatureRate contact_time_rate{0.0, -per_velocity.y(),
                                        -agent.speed_mps * per_velocity.x()};
    const Energy e = energy(tau_s, options_.tau0_s);
    return detail::through_rate(e.value, e.slope, e.curvature, contact_time_rate);
  }

  AnticipationOptions options_;
};

}  // namespace

std::unique_ptr<CostTerm> anticipation_term(const AnticipationOptions& options) {
  constexpr std::string_view kTerm = "anticipation";
  detail::validate(options.kept_width, kTerm);
  detail::validate(options.depth, kTerm);
  detail::validate_static_closing(options.static_closing_ratio, kTerm);
  detail::validate_horizon(options.horizon_s, kTerm);
  detail::require_option(std::isfinite(options.tau0_s) && options.tau0_s > 0.0, kTerm,
                         "tau0_s must be positive, got " + std::to_string(options.tau0_s));
  return std::make_unique<AnticipationTerm>(options);
}

}  // namespace flowsteer::servo
