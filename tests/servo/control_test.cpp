#include "flowsteer/servo/control.hpp"

#include <cmath>
#include <memory>
#include <numbers>
#include <string_view>

#include <gtest/gtest.h>

#include "two_body.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kLn10 = 2.302585092994046;

ObjectFeatures object(double centre_x, double foe_x, double ttc_s, double depth_m,
                      double width = 0.1) {
  ObjectFeatures o;
  o.source_id = 1;
  o.pixel_count = 100;
  o.centre = {centre_x, 0.0};
  o.width = width;
  o.status = ttc_s > 0.0 ? MotionStatus::approaching : MotionStatus::receding;
  o.foe = {foe_x, 0.0};
  o.ttc_s = ttc_s;
  o.depth_m = depth_m;
  return o;
}

Controller goal_controller(double limit = 10.0) {
  return Controller(goal_reaching({}), 1.0, {limit, limit});
}

TEST(ControlSigns, GoalOnTheRightTurnsRight) {
  const Percept p{{}, 0.3, 10.0, {}};
  const ControlOutput out = goal_controller().step(p, {1.0});
  EXPECT_GT(out.command.turn_rate, 0.0);
  const double t = std::tan(0.3);
  EXPECT_NEAR(out.command.turn_rate, t * (1.0 + t * t), 1e-12);  // ω = λ α t (1 + t²)
  const ControlOutput left = goal_controller().step({{}, -0.3, 10.0, {}}, {1.0});
  EXPECT_LT(left.command.turn_rate, 0.0);
}

TEST(ControlSigns, StaticObstacleJustRightOfHeadingTurnsLeft) {
  // A static obstacle: FOE straight ahead, τ = Z / v_c.
  const std::vector<ObjectFeatures> objects = {object(0.1, 0.0, 2.0, 2.0)};
  const ControlOutput out = goal_controller().step({objects, 0.0, 10.0, {}}, {1.0});
  EXPECT_LT(out.command.turn_rate, 0.0);
  EXPECT_NEAR(out.command.accel_mps2, 0.0, 1e-12);  // f = 0: avoidance does not change speed
  const std::vector<ObjectFeatures> on_left = {object(-0.1, 0.0, 2.0, 2.0)};
  EXPECT_GT(goal_controller().step({on_left, 0.0, 10.0, {}}, {1.0}).command.turn_rate, 0.0);
}

TEST(ControlSigns, DarkRegionOnTheRightTurnsLeft) {
  ObjectFeatures dark = object(0.15, 0.0, 2.0, 3.0);
  dark.kind = RegionKind::dark;
  dark.status = MotionStatus::no_flow;
  const std::vector<ObjectFeatures> objects = {dark};
  GoalReachingWeights weights;
  weights.delta = 1.0;
  Controller controller(goal_reaching(weights), 1.0, {10.0, 10.0});
  const ControlOutput out = controller.step({objects, 0.0, 10.0, {}}, {1.0});
  EXPECT_LT(out.command.turn_rate, 0.0);
  // Without dark-region awareness the agent ignores it.
  EXPECT_EQ(goal_controller().step({objects, 0.0, 10.0, {}}, {1.0}).command.turn_rate, 0.0);
}

TEST(ControlSigns, SlowerLeaderAheadSlowsTheFollower) {
  // Leader 4 m ahead at 0.5 m/s, follower at 1 m/s: v_z = −0.5, τ = 8 s.
  ObjectFeatures leader = object(0.0, 0.0, 8.0, 4.0);
  leader.source_id = 42;
  const std::vector<ObjectFeatures> objects = {leader};
  Controller controller(following({}), 1.0, {10.0, 10.0});
  const ControlOutput out = controller.step({objects, {}, {}, 42}, {1.0});
  EXPECT_LT(out.command.accel_mps2, 0.0);
  EXPECT_NEAR(out.command.accel_mps2, -0.5, 1e-12);  // a_c = λ β v_z
  // A faster leader pulls away (τ < 0): speed up.
  leader.ttc_s = -8.0;
  leader.status = MotionStatus::receding;
  const std::vector<ObjectFeatures> faster = {leader};
  EXPECT_GT(controller.step({faster, {}, {}, 42}, {1.0}).command.accel_mps2, 0.0);
}

TEST(ControlSigns, LeaderDriftingRightIsFollowedToTheRight) {
  ObjectFeatures leader = object(0.05, 0.0, 20.0, 4.0);
  leader.source_id = 7;
  leader.moments.mean_u = 0.05;  // moving right in the image
  leader.moments.mean_inv_depth = 0.25;
  leader.moments.mean_x_inv_depth = 0.05 * 0.25;
  const std::vector<ObjectFeatures> objects = {leader};
  FollowingWeights w;
  w.beta = 0.0;
  w.gamma = 0.0;
  const ControlOutput out =
      Controller(following(w), 1.0, {10.0, 10.0}).step({objects, {}, {}, 7}, {1.0});
  EXPECT_GT(out.command.turn_rate, 0.0);
}

TEST(ControlSigns, SpeedTermPullsTowardsThePreferredSpeed) {
  GoalReachingWeights w;
  w.preferred_speed_mps = 1.0;
  Controller c(goal_reaching(w), 1.0, {10.0, 10.0});
  EXPECT_NEAR(c.step({}, {0.5}).command.accel_mps2, 0.1 * 0.5, 1e-12);
  EXPECT_NEAR(c.step({}, {1.5}).command.accel_mps2, -0.1 * 0.5, 1e-12);
}

// The avoidance gradient equals the finite difference of L_av along the two-body simulation:
// ∂L̇/∂ω = (dL/dt(a, ω) − dL/dt(a, 0)) / ω, with σ and I(τ) held constant as in CGF §6.2.
TEST(ControlGradient, AvoidanceGradientMatchesSimulation) {
  test::TwoBody s;
  s.point = {6.0, -0.4};
  s.point_velocity = {-0.3, 0.35};
  s.agent_speed = 1.2;
  const double width = 0.15;
  AvoidanceTermOptions options;
  options.agent_width_m = 0.0;
  const double sigma = width / kLn10;
  const double importance = -2.0 * s.ttc() + 10.0;
  auto cost = [&](const test::TwoBody& b) {
    return importance * std::exp(-std::abs(b.image_x() - b.foe_x()) / sigma);
  };
  ObjectFeatures o = object(s.image_x(), s.foe_x(), s.ttc(), s.depth(), width);
  const std::vector<ObjectFeatures> objects = {o};
  const TermGradient g = avoidance_term(options)->evaluate({objects, {}, {}, {}}, {s.agent_speed});
  EXPECT_NEAR(g.cost, cost(s), 1e-12);
  const double base = test::rate_of(s, 0.0, 0.0, cost);
  const double per_turn = (test::rate_of(s, 0.0, 0.5, cost) - base) / 0.5;
  const double per_accel = (test::rate_of(s, 0.8, 0.0, cost) - base) / 0.8;
  EXPECT_NEAR(g.per_turn, per_turn, 1e-4 * (1.0 + std::abs(per_turn)));
  EXPECT_NEAR(g.per_accel, per_accel, 1e-4 * (1.0 + std::abs(per_accel)));
  EXPECT_NE(g.per_accel, 0.0);
}

TEST(ControlGradient, LeaderSpeedGradientMatchesSimulation) {
  test::TwoBody s;
  s.point = {5.0, 0.7};
  s.point_velocity = {0.4, 0.3};
  s.agent_speed = 1.0;
  auto cost = [](const test::TwoBody& b) { return 0.5 * b.relative_vz() * b.relative_vz(); };
  ObjectFeatures leader = object(s.image_x(), s.foe_x(), s.ttc(), s.depth());
  const std::vector<ObjectFeatures> objects = {leader};
  const TermGradient g = leader_speed_term()->evaluate({objects, {}, {}, 1}, {s.agent_speed});
  const double base = test::rate_of(s, 0.0, 0.0, cost);
  EXPECT_NEAR(g.per_turn, (test::rate_of(s, 0.0, 0.5, cost) - base) / 0.5, 1e-4);
  EXPECT_NEAR(g.per_accel, (test::rate_of(s, 0.8, 0.0, cost) - base) / 0.8, 1e-4);
}

TEST(ControlBorder, FoeBeyondTheCutSideOfAnObjectCountsAsOnIt) {
  // A car crossing close in front of a slow agent overflows the image on the left; the FOE is
  // far out on that side (f = v_x / v_z with a small v_z), past the visible part.
  ObjectFeatures car = object(-1.5, -12.0, 3.0, 0.8, 2.0);
  car.min_x = -3.7;
  car.max_x = 0.7;
  const std::vector<ObjectFeatures> uncut = {car};
  const ControlOutput seen_whole = goal_controller().step({uncut, 0.0, 10.0, {}}, {0.3});
  EXPECT_LT(seen_whole.terms[2].gradient.cost, 1e-3);  // |g − f| ≫ w: almost no cost

  car.cut_left = true;
  const std::vector<ObjectFeatures> cut = {car};
  const ControlOutput out = goal_controller().step({cut, 0.0, 10.0, {}}, {0.3});
  const double importance = -2.0 * 3.0 + 10.0;
  EXPECT_NEAR(out.terms[2].gradient.cost, importance, 1e-12);  // the FOE may be on the car
  // The object's point at the FOE (g = f in Eq. 10): a_c = −λ γ ∂L̇/∂a_c with
  // ∂L̇/∂a_c = −I sign(g − f)/σ · (τ/Z) f; the visible part is right of the FOE.
  // The speed term adds β (v* − v_c).
  const double sigma = (2.0 + AvoidanceTermOptions{}.agent_width_m / 0.8) / kLn10;
  const double tau_over_depth = 3.0 / 0.8;
  const double speed_term = 0.1 * (1.0 - 0.3);
  EXPECT_NEAR(out.unclamped.accel_mps2, speed_term + importance / sigma * tau_over_depth * -12.0,
              1e-9);
  EXPECT_LT(out.command.accel_mps2, 0.0);  // brakes: lets the car pass
  // With g = f only −τ v_c / Z is left of the ω factor; the goal is straight ahead.
  EXPECT_NEAR(out.unclamped.turn_rate, -importance / sigma * tau_over_depth * 0.3, 1e-9);

  // Mirrored: cut on the right with the FOE beyond it also brakes.
  ObjectFeatures mirrored = object(1.5, 12.0, 3.0, 0.8, 2.0);
  mirrored.min_x = -0.7;
  mirrored.max_x = 3.7;
  mirrored.cut_right = true;
  const std::vector<ObjectFeatures> right = {mirrored};
  const ControlOutput out_right = goal_controller().step({right, 0.0, 10.0, {}}, {0.3});
  EXPECT_NEAR(out_right.terms[2].gradient.cost, importance, 1e-12);
  EXPECT_NEAR(out_right.unclamped.accel_mps2, out.unclamped.accel_mps2, 1e-9);
  EXPECT_NEAR(out_right.unclamped.turn_rate, -out.unclamped.turn_rate, 1e-9);

  // The FOE on the uncut side, or within the visible part, is measured as before.
  car.foe = {4.0, 0.0};
  const std::vector<ObjectFeatures> other_side = {car};
  EXPECT_LT(goal_controller().step({other_side, 0.0, 10.0, {}}, {0.3}).terms[2].gradient.cost,
            0.1 * importance);
}

TEST(ControlInput, ObjectsThatCannotCollideAreIgnored) {
  std::vector<ObjectFeatures> objects = {object(0.1, 0.0, 6.0, 6.0),    // beyond the 5 s horizon
                                         object(0.1, 0.0, -2.0, 2.0)};  // receding
  ObjectFeatures lateral = object(0.1, 0.0, 2.0, 2.0);
  lateral.status = MotionStatus::lateral;
  lateral.ttc_s = std::numeric_limits<double>::infinity();
  objects.push_back(lateral);
  ObjectFeatures unfitted = object(0.1, 0.0, 2.0, 2.0);
  unfitted.status = MotionStatus::no_flow;
  unfitted.foe.setConstant(std::numeric_limits<double>::quiet_NaN());
  objects.push_back(unfitted);
  const ControlOutput out = goal_controller().step({objects, 0.0, 10.0, {}}, {1.0});
  EXPECT_EQ(out.command.turn_rate, 0.0);
  EXPECT_EQ(out.terms.size(), 3U);
  EXPECT_EQ(out.terms[2].name, "avoidance");
  EXPECT_EQ(out.terms[2].gradient.cost, 0.0);
}

TEST(ControlInput, ZeroSpeedWithoutDepthStaysFinite) {
  ObjectFeatures o = object(0.05, 0.02, 1.5, 0.0);
  o.depth_m.reset();
  const std::vector<ObjectFeatures> objects = {o};
  const ControlOutput out = goal_controller().step({objects, 0.2, {}, {}}, {0.0});
  EXPECT_TRUE(std::isfinite(out.command.accel_mps2));
  EXPECT_TRUE(std::isfinite(out.command.turn_rate));
  EXPECT_NE(out.command.turn_rate, 0.0);
}

TEST(ControlInput, LimitsClampAndTheUnclampedCommandIsKept) {
  Controller c(goal_reaching({}), 1.0, {0.5, 0.2});
  const ControlOutput out = c.step({{}, 1.2, 5.0, {}}, {1.0});
  EXPECT_EQ(out.command.turn_rate, 0.2);
  EXPECT_GT(out.unclamped.turn_rate, 0.2);
}

// A term that always asks for more speed, as the clearance term does to widen a gap in front.
class SpeedUpTerm final : public CostTerm {
 public:
  std::string_view name() const override { return "speed up"; }
  TermGradient evaluate(const Percept&, const AgentState&) override { return {0.0, -5.0, 0.0}; }
};

// The speed limit holds the acceleration so that the period ends at the limit, and brings a
// speed above it back down (within max_accel_mps2); without a period it does nothing.
TEST(ControlInput, TheSpeedLimitHoldsTheAcceleration) {
  NavigationFunction f;
  f.add(1.0, std::make_unique<SpeedUpTerm>());
  ControlLimits limits{1.0, 1.0};
  limits.max_speed_mps = 1.43;
  Controller c(std::move(f), 1.0, limits);
  const Percept nothing{{}, {}, {}, {}};
  EXPECT_DOUBLE_EQ(c.step(nothing, {1.0, 0.05}).command.accel_mps2, 1.0);
  EXPECT_NEAR(c.step(nothing, {1.4, 0.05}).command.accel_mps2, 0.03 / 0.05, 1e-12);
  EXPECT_NEAR(c.step(nothing, {1.43, 0.05}).command.accel_mps2, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(c.step(nothing, {2.0, 0.05}).command.accel_mps2, -1.0);
  EXPECT_DOUBLE_EQ(c.step(nothing, {2.0, 0.0}).command.accel_mps2, 1.0);
  EXPECT_EQ(c.step(nothing, {1.43, 0.05}).unclamped.accel_mps2, 5.0);
}

// A term whose cost is stiff along ω: the explicit step (CGF Eq. 15) turns by −λ g however long
// the command is held; the implicit one by −λ g / (1 + λ T c), and by −λ g when T is not known.
class StiffTerm final : public CostTerm {
 public:
  std::string_view name() const override { return "stiff"; }
  TermGradient evaluate(const Percept&, const AgentState&) override {
    return {1.0, 0.5, 4.0, 2.0, 300.0};
  }
};

TEST(ControlStep, TheImplicitStepDampsAStiffCostByItsCurvatureOverThePeriod) {
  auto controller = [](GradientStep step) {
    NavigationFunction f;
    f.add(1.0, std::make_unique<StiffTerm>());
    return Controller(std::move(f), 2.0, {100.0, 100.0}, step);
  };
  Controller explicit_step = controller(GradientStep::explicit_euler);
  Controller implicit_step = controller(GradientStep::implicit_euler);
  const Percept nothing{{}, {}, {}, {}};
  const ControlOutput e = explicit_step.step(nothing, {1.0, 0.05});
  EXPECT_DOUBLE_EQ(e.command.turn_rate, -8.0);
  EXPECT_DOUBLE_EQ(e.command.accel_mps2, -1.0);
  const ControlOutput i = implicit_step.step(nothing, {1.0, 0.05});
  EXPECT_DOUBLE_EQ(i.command.turn_rate, -8.0 / (1.0 + 2.0 * 0.05 * 300.0));
  EXPECT_DOUBLE_EQ(i.command.accel_mps2, -1.0 / (1.0 + 2.0 * 0.05 * 2.0));
  EXPECT_DOUBLE_EQ(implicit_step.step(nothing, {1.0, 0.0}).command.turn_rate, -8.0);
  EXPECT_THROW(implicit_step.step(nothing, {1.0, -0.05}), std::invalid_argument);
}

TEST(ControlInput, BadSettingsAreRejected) {
  EXPECT_THROW(Controller(goal_reaching({}), 0.0, {}), std::invalid_argument);
  EXPECT_THROW(Controller(goal_reaching({}), 1.0, {-1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(Controller(goal_reaching({}), 1.0, {1.0, 1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(Controller(goal_reaching({}), 1.0, {1.0, 1.0, std::nan("")}), std::invalid_argument);
  GoalReachingWeights w;
  w.delta = 2.0;  // more than γ
  EXPECT_THROW(goal_reaching(w), std::invalid_argument);
  w.delta = 0.0;
  w.alpha = -1.0;
  EXPECT_THROW(goal_reaching(w), std::invalid_argument);
  AvoidanceTermOptions bad;
  bad.horizon_s = 0.0;
  EXPECT_THROW(avoidance_term(bad), std::invalid_argument);
  EXPECT_THROW(goal_controller().step({}, {std::nan("")}), std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::servo
