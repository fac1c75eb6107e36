// The flowsteer law's anticipation term (control.hpp): the time-to-collision energy of
// Karamouzas, Skinner and Guy, "Universal power law governing pedestrian interactions", Phys.
// Rev. Lett. 113, 238701 (2014), over the visual features of each object. See docs/NAVIGATION.md.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Core>

#include "cost_term_helpers.hpp"
#include "flowsteer/servo/control.hpp"

namespace flowsteer::servo {

namespace {

// Karamouzas et al.'s k: E(τ) = k e^(−τ/τ0) / τ² (their Eq. 1 with m = 2).
constexpr double kEnergyScale = 1.5;
// E grows as 1/τ² without bound; below this the energy and its slope are taken at it, and the
// controller's limits do the rest.
constexpr double kMinContactTime_s = 0.1;

// When an object moving at relative velocity V first comes within R of the agent (at the
// origin), and the unit normal n from the agent to where it touches.
struct Contact {
  double time_s = std::numeric_limits<double>::infinity();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
};

// A point p of the object: |p + V t| = R at the smaller root.
void point_contact(const Eigen::Vector2d& p, const Eigen::Vector2d& v, double radius,
                   Contact& first) {
  const double a = v.squaredNorm();
  const double b = p.dot(v);
  const double c = p.squaredNorm() - radius * radius;
  const double discriminant = b * b - a * c;
  if (b >= 0.0 || a <= 0.0 || discriminant < 0.0) {
    return;
  }
  const double t = std::max(0.0, c / (-b + std::sqrt(discriminant)));
  if (t < first.time_s) {
    first.time_s = t;
    first.normal = (p + v * t).normalized();
  }
}

// The segment [a, b]: its ends as points, and its inside, whose line comes within R when
// m·(a + V t) = R, m its unit normal towards the line, if the foot of the perpendicular from the
// agent then lies between the ends.
void segment_contact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& v,
                     double radius, Contact& first) {
  point_contact(a, v, radius, first);
  point_contact(b, v, radius, first);
  const double length = (b - a).norm();
  if (!(length > 0.0)) {
    return;
  }
  const Eigen::Vector2d along = (b - a) / length;
  Eigen::Vector2d m{-along.y(), along.x()};
  if (m.dot(a) < 0.0) {
    m = -m;
  }
  const double closing_mps = -m.dot(v);
  const double distance_m = m.dot(a);
  if (closing_mps <= 0.0 || distance_m < radius) {
    return;
  }
  const double t = (distance_m - radius) / closing_mps;
  const double foot = -along.dot(a + v * t);
  if (foot >= 0.0 && foot <= length && t < first.time_s) {
    first.time_s = t;
    first.normal = m;
  }
}

double distance_to_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp(-a.dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab).norm();
}

// The object's velocity relative to the agent (x right, z forward, m/s) from its flow: V_z =
// −Z/τ and V_x = f V_z at the depth the fit used (CGF Eq. 2–3); for lateral motion, the derotated
// flow u = V_x / Z gives V_x = mean(u) / mean(1/Z). Nothing for an object without a usable fit.
std::optional<Eigen::Vector2d> relative_velocity(const ObjectFeatures& object,
                                                 const AgentState& agent,
                                                 const AvoidanceOptions& options) {
  if (object.has_foe() && std::isfinite(object.ttc_s) && std::isfinite(object.foe.x())) {
    const double vz = -detail::depth_scale(object, agent, options).depth_m / object.ttc_s;
    return Eigen::Vector2d{object.foe.x() * vz, vz};
  }
  if (object.status == MotionStatus::lateral && object.moments.mean_inv_depth &&
      *object.moments.mean_inv_depth > 0.0) {
    return Eigen::Vector2d{object.moments.mean_u / *object.moments.mean_inv_depth, 0.0};
  }
  return std::nullopt;
}

// The object's two ends on the ground in the agent's frame, (x Z, Z) at each end's depth.
void ends_of(const ObjectFeatures& object, const AgentState& agent, const AvoidanceOptions& options,
             Eigen::Vector2d ends[2]) {
  const double depth = detail::depth_scale(object, agent, options).depth_m;
  const bool depths = options.use_depth && object.min_x_depth_m && object.max_x_depth_m;
  const double left_m = depths ? *object.min_x_depth_m : depth;
  const double right_m = depths ? *object.max_x_depth_m : depth;
  ends[0] = {object.min_x * left_m, left_m};
  ends[1] = {object.max_x * right_m, right_m};
}

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
  explicit AnticipationTerm(const AvoidanceOptions& options) : options_(options) {}
  std::string_view name() const override { return "anticipation"; }

  TermGradient evaluate(const Percept& percept, const AgentState& agent) override {
    const double radius_m = 0.5 * detail::kept_width(agent, options_);
    TermGradient sum;
    for (const ObjectFeatures& object : percept.objects) {
      if (object.kind != RegionKind::visible || !object.centre.allFinite()) {
        continue;
      }
      const std::optional<Eigen::Vector2d> velocity = relative_velocity(object, agent, options_);
      if (!velocity) {
        continue;
      }
      Eigen::Vector2d ends[2];
      ends_of(object, agent, options_, ends);
      const double now_m = distance_to_segment(ends[0], ends[1]);
      // Already nearer than R (which holds a margin): the contact is its coming nearer still.
      Contact contact;
      segment_contact(ends[0], ends[1], *velocity, std::min(radius_m, 0.99 * now_m), contact);
      if (contact.time_s <= options_.horizon_s && !beyond_goal(percept, agent, contact)) {
        detail::accumulate(sum, gradient(contact, *velocity, agent));
      }
    }
    return sum;
  }

 private:
  // A contact later than the agent takes to walk to its goal, where it stops: an agent stepping
  // up to a goal beside people already standing at theirs would otherwise be turned away from it
  // (in fan_in, the outer agents circled their goals and never reached them).
  static bool beyond_goal(const Percept& percept, const AgentState& agent, const Contact& contact) {
    return percept.goal_distance_m && contact.time_s * agent.speed_mps > *percept.goal_distance_m;
  }

  // L = E(τ_c), L̇ = E'(τ_c) τ̇_c. τ_c depends on the relative velocity V alone, which the frame's
  // turning does not change: ∂τ_c/∂V = −τ_c n / (n·V) (differentiating |contact| = R), and the
  // agent's own velocity turns at ω and grows at a_c, so V̇ = (−v_c ω, −a_c).
  TermGradient gradient(const Contact& contact, const Eigen::Vector2d& velocity,
                        const AgentState& agent) const {
    const double closing = contact.normal.dot(velocity);
    if (!(closing < 0.0)) {
      return {};
    }
    const double tau_s = std::max(contact.time_s, kMinContactTime_s);
    const Eigen::Vector2d per_velocity = -tau_s * contact.normal / closing;
    const FeatureRate contact_time_rate{0.0, -per_velocity.y(),
                                        -agent.speed_mps * per_velocity.x()};
    const Energy e = energy(tau_s, options_.anticipation_s);
    return detail::through_rate(e.value, e.slope, e.curvature, contact_time_rate);
  }

  AvoidanceOptions options_;
};

}  // namespace

std::unique_ptr<CostTerm> anticipation_term(const AvoidanceOptions& options) {
  detail::validate(options);
  return std::make_unique<AnticipationTerm>(options);
}

}  // namespace flowsteer::servo
