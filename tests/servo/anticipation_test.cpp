// The flowsteer law's anticipation term (anticipation_term.cpp): its gradient against finite
// differences of the time-to-collision energy along the two-body simulation, and what the term is
// there for.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/control.hpp"
#include "two_body.hpp"

namespace flowsteer::servo {
namespace {

// Karamouzas et al.'s energy with the term's k and the default τ0.
double energy(double tau_s) {
  return 1.5 * std::exp(-tau_s / 3.0) / (tau_s * tau_s);
}

// The features of the object of the two-body simulation: a point, or the segment from the
// point to `other_end`, a point of the same object.
ObjectFeatures features(const test::TwoBody& s, const Eigen::Vector2d& other_end) {
  test::TwoBody end = s;
  end.point = other_end;
  const bool ordered = s.image_x() <= end.image_x();
  const test::TwoBody& left = ordered ? s : end;
  const test::TwoBody& right = ordered ? end : s;
  ObjectFeatures o;
  o.source_id = 1;
  o.pixel_count = 100;
  o.min_x = left.image_x();
  o.max_x = right.image_x();
  o.centre = {0.5 * (o.min_x + o.max_x), 0.0};
  o.min_x_depth_m = left.depth();
  o.max_x_depth_m = right.depth();
  o.depth_m = s.depth();
  o.status = MotionStatus::approaching;
  o.foe = {s.foe_x(), 0.0};
  o.ttc_s = s.ttc();
  return o;
}
ObjectFeatures features(const test::TwoBody& s) {
  return features(s, s.point);
}

TermGradient evaluate(const ObjectFeatures& object, const test::TwoBody& s,
                      std::optional<double> goal_distance_m = std::nullopt) {
  AnticipationOptions options;
  options.kept_width.agent_width_m = 0.8;
  const std::vector<ObjectFeatures> objects = {object};
  return anticipation_term(options)->evaluate({objects, {}, goal_distance_m, {}}, {s.agent_speed});
}

// When the agent, a disc of radius 0.4 m going straight on, first touches the segment [a, b]
// moving with the object: by bisection on the distance, independent of the term's algebra.
double contact_time(const test::TwoBody& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  auto distance = [&](double t) {
    const Eigen::Vector2d agent = s.agent_position + t * s.agent_speed * s.forward();
    const Eigen::Vector2d shift = t * s.point_velocity;
    const Eigen::Vector2d ab = b - a;
    const double u =
        std::clamp((agent - a - shift).dot(ab) / std::max(ab.squaredNorm(), 1e-30), 0.0, 1.0);
    return (a + shift + u * ab - agent).norm();
  };
  double touching = 0.0;
  while (distance(touching) > 0.4) {
    touching += 0.01;
  }
  double apart = touching - 0.01;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (apart + touching);
    (distance(mid) > 0.4 ? apart : touching) = mid;
  }
  return touching;
}

// ∂L̇/∂a_c and ∂L̇/∂ω of E(τ_c) along the simulation, by finite differences, against the term.
void expect_matches_simulation(const test::TwoBody& s, const Eigen::Vector2d& other_end) {
  const Eigen::Vector2d offset = other_end - s.point;  // the segment moves with the point
  auto cost = [&](const test::TwoBody& b) {
    return energy(contact_time(b, b.point, b.point + offset));
  };
  const double base = test::rate_of(s, 0.0, 0.0, cost);
  const double per_accel = (test::rate_of(s, 0.8, 0.0, cost) - base) / 0.8;
  const double per_turn = (test::rate_of(s, 0.0, 0.5, cost) - base) / 0.5;
  const TermGradient g = evaluate(features(s, other_end), s);
  EXPECT_NEAR(g.cost, cost(s), 1e-9 * cost(s));
  EXPECT_NEAR(g.per_accel, per_accel, 1e-3 * (1.0 + std::abs(per_accel)));
  EXPECT_NEAR(g.per_turn, per_turn, 1e-3 * (1.0 + std::abs(per_turn)));
  EXPECT_NE(g.per_turn, 0.0);
}

TEST(AnticipationGradient, AStaticPointAheadMatchesSimulation) {
  test::TwoBody s;
  s.point = {4.0, -0.3};
  expect_matches_simulation(s, s.point);
}

TEST(AnticipationGradient, ACrossingPointMatchesSimulation) {
  test::TwoBody s;
  s.agent_speed = 1.2;
  s.point = {3.0, -2.5};
  s.point_velocity = {0.1, 0.9};
  expect_matches_simulation(s, s.point);
}

TEST(AnticipationGradient, AWallMetAtASlantMatchesSimulation) {
  test::TwoBody s;
  s.point = {3.0, 2.0};  // the wall runs from 2 m left to 1 m right, 3 to 5 m ahead
  expect_matches_simulation(s, {5.0, -1.0});
}

TEST(AnticipationBehaviour, AWallAlongThePathCostsNothing) {
  test::TwoBody s;
  s.point = {0.5, -1.0};  // 1 m to the right, from 0.5 m to 12 m ahead
  const TermGradient g = evaluate(features(s, {12.0, -1.0}), s);
  EXPECT_EQ(g.cost, 0.0);
  EXPECT_EQ(g.per_turn, 0.0);
}

// A neighbour walking beside the agent at its speed and drifting into its path shows no
// expansion: the fit calls it lateral, and the FOE-based clearance term sees no threat in it.
TEST(AnticipationBehaviour, ANeighbourDriftingIntoThePathMakesTheAgentGiveWay) {
  test::TwoBody s;
  s.point = {0.3, -0.9};          // 0.9 m to the right, a step ahead
  s.point_velocity = {1.0, 0.3};  // as fast forward as the agent, 0.3 m/s to its left
  ObjectFeatures neighbour = features(s);
  neighbour.status = MotionStatus::lateral;
  neighbour.foe = {NAN, NAN};
  neighbour.ttc_s = INFINITY;
  neighbour.moments.mean_u = s.flow_x();
  neighbour.moments.mean_inv_depth = 1.0 / s.depth();
  const std::vector<ObjectFeatures> objects = {neighbour};
  EXPECT_EQ(clearance_term()->evaluate({objects, {}, {}, {}}, {s.agent_speed}).cost, 0.0);

  const TermGradient g = evaluate(neighbour, s);
  EXPECT_GT(g.cost, 0.0);
  EXPECT_GT(g.per_accel, 0.0);  // a_c = −λ ∂L̇/∂a_c: slows down, and lets it pass in front
  EXPECT_GT(g.per_turn, 0.0);   // ω < 0: turns left, away from it
}

TEST(AnticipationBehaviour, AContactAfterTheGoalIsLeftOut) {
  test::TwoBody s;
  s.point = {4.0, 0.0};  // a person standing 4 m ahead: contact in 3.6 s at 1 m/s
  EXPECT_EQ(evaluate(features(s), s, 3.0).cost, 0.0);
  EXPECT_GT(evaluate(features(s), s, 3.8).cost, 0.0);
}

TEST(AnticipationBehaviour, AnObjectMovingAwayCostsNothing) {
  test::TwoBody s;
  s.point = {2.0, 0.0};
  s.point_velocity = {1.5, 0.0};
  ObjectFeatures ahead = features(s);
  ahead.status = MotionStatus::receding;
  EXPECT_EQ(evaluate(ahead, s).cost, 0.0);
}

}  // namespace
}  // namespace flowsteer::servo
