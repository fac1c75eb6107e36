#include "flowsteer/servo/steering.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace flowsteer::servo {
namespace {

ControllerConfig flowsteer_without(LawMechanism mechanism) {
  ControllerConfig config;
  config.without = mechanism;
  return config;
}

// An object 3 m ahead between `left_m` and `right_m` of the course (positive: right), facing the
// agent, whose FOE the fit finds where a standing object's lies, straight ahead.
ObjectFeatures object_3m_ahead(double left_m, double right_m, double ttc_s) {
  ObjectFeatures object;
  object.source_id = 7;
  object.pixel_count = 200;
  object.min_x = left_m / 3.0;
  object.max_x = right_m / 3.0;
  object.width = object.max_x - object.min_x;
  object.min_x_depth_m = 3.0;
  object.max_x_depth_m = 3.0;
  object.depth_m = 3.0;
  object.nearest_x = 0.5 * (object.min_x + object.max_x);
  object.nearest_depth_m = 3.0;
  object.status = MotionStatus::approaching;
  object.foe = {0.0, 0.0};
  object.ttc_s = ttc_s;
  object.fit.static_foe = true;
  return object;
}

// A standing object 3 m dead ahead, 0.4 m wide, seen by an agent walking at 1.3 m/s towards a goal
// straight on: both ways round are the same but for the passing convention.
ControlOutput step_towards_object_ahead(const ControllerConfig& config) {
  const std::vector<ObjectFeatures> objects = {object_3m_ahead(-0.2, 0.2, 3.0 / 1.3)};
  Controller controller = make_controller(config, 0.6, 1.3);
  return controller.step({objects, 0.0, 20.0, {}}, {1.3, 0.05});
}

TEST(LawMechanism, EveryNameReadsBack) {
  std::istringstream names(law_mechanism_names());
  std::string name;
  int count = 0;
  while (std::getline(names >> std::ws, name, ',')) {
    const std::optional<LawMechanism> mechanism = parse_law_mechanism(name);
    ASSERT_TRUE(mechanism) << name;
    EXPECT_EQ(to_string(*mechanism), name);
    ++count;
  }
  EXPECT_EQ(count, 11);
  EXPECT_FALSE(parse_law_mechanism("brake"));
}

TEST(LawMechanism, ATermSwitchedOffWeighsNothingWhateverItsWeight) {
  ControllerConfig config = flowsteer_without(LawMechanism::braking);
  config.braking = 3.0;
  EXPECT_EQ(navigation_weights(config).braking, 0.0);
  EXPECT_EQ(navigation_weights(config).anticipation, 1.0);
  config = flowsteer_without(LawMechanism::anticipation);
  EXPECT_EQ(navigation_weights(config).anticipation, 0.0);
  EXPECT_EQ(navigation_weights(config).braking, 2.0);
}

// Keep right passes the object on its left: the agent turns right (ω > 0). Without the
// convention nothing prefers that side.
TEST(LawMechanism, WithoutThePassingConventionNothingTurnsTheAgentRight) {
  EXPECT_GT(step_towards_object_ahead({}).command.turn_rate, 0.0);
  EXPECT_LE(step_towards_object_ahead(flowsteer_without(LawMechanism::passing_convention))
                .command.turn_rate,
            0.0);
}

// The same percept under the explicit step turns harder: the implicit one damps the stiff cost.
TEST(LawMechanism, WithoutTheImplicitStepTheTurnIsTheExplicitOne) {
  const double implicit = step_towards_object_ahead({}).unclamped.turn_rate;
  const ControlOutput explicit_step =
      step_towards_object_ahead(flowsteer_without(LawMechanism::implicit_step));
  EXPECT_GT(std::abs(explicit_step.unclamped.turn_rate), std::abs(implicit));
}

// An agent at 2 m/s for a preferred 1.3 m/s: the limit (1.1 × 1.3) brakes it at the most the
// controller may; without it, the approach speed term alone slows it, more gently.
TEST(LawMechanism, WithoutTheSpeedLimitOnlyTheApproachTermSlowsAFastAgent) {
  const auto accel = [](LawMechanism mechanism) {
    Controller controller = make_controller(flowsteer_without(mechanism), 0.6, 1.3);
    return controller.step({{}, 0.0, 20.0, {}}, {2.0, 0.05}).command.accel_mps2;
  };
  EXPECT_DOUBLE_EQ(accel(LawMechanism::none), -1.0);
  EXPECT_GT(accel(LawMechanism::speed_limit), -1.0);
  EXPECT_LT(accel(LawMechanism::speed_limit), 0.0);
}

// Someone 3 m ahead, 1 to 1.4 m right of the course, walking straight at the agent (1.3 m/s each:
// τ = 3 / 2.6 s) with the FOE a standing object would have. Taken as standing, the course passes
// it clear and the agent walks on as if it were not there.
TEST(LawMechanism, WithoutTheClosingCheckAnObjectWalkingStraightAtTheAgentIsTakenAsStanding) {
  const ObjectFeatures person = object_3m_ahead(1.0, 1.4, 3.0 / 2.6);
  const auto step = [](const ControllerConfig& config, const std::vector<ObjectFeatures>& objects) {
    Controller controller = make_controller(config, 0.6, 1.3);
    return controller.step({objects, 0.0, 20.0, {}}, {1.3, 0.05}).unclamped;
  };
  const ControllerConfig without = flowsteer_without(LawMechanism::static_closing);
  EXPECT_EQ(step(without, {person}).turn_rate, step(without, {}).turn_rate);
  EXPECT_EQ(step(without, {person}).accel_mps2, step(without, {}).accel_mps2);
  EXPECT_NE(step({}, {person}).turn_rate, step({}, {}).turn_rate);
}

}  // namespace
}  // namespace flowsteer::servo
