#include "flowsteer/drivers/command_stage.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace flowsteer::drivers {
namespace {

CommandStageConfig config() {
  CommandStageConfig c;
  c.geometry = {0.4, 0.05};
  c.limits.max_speed_mps = 1.0;
  c.limits.max_reverse_speed_mps = 0.0;
  c.limits.max_accel_mps2 = 1.0;
  c.limits.max_turn_rate = 1.0;
  c.limits.max_wheel_speed_radps = 100.0;
  c.watchdog = {0.5, 0.2};
  return c;
}

TEST(WheelMapping, PositiveTurnRateTurnsRightSoTheLeftWheelIsFaster) {
  const WheelSpeeds w = to_wheels({1.0, 0.5}, {0.4, 0.05});
  // ω_z = −0.5 rad/s: left rolls (1 + 0.5·0.2) / 0.05, right (1 − 0.5·0.2) / 0.05.
  EXPECT_DOUBLE_EQ(w.left_radps, 22.0);
  EXPECT_DOUBLE_EQ(w.right_radps, 18.0);
  const WheelSpeeds left_turn = to_wheels({1.0, -0.5}, {0.4, 0.05});
  EXPECT_LT(left_turn.left_radps, left_turn.right_radps);
}

TEST(WheelMapping, TurnOnTheSpotAndRoundTrip) {
  const WheelSpeeds spin = to_wheels({0.0, 1.0}, {0.5, 0.1});
  EXPECT_DOUBLE_EQ(spin.left_radps, 2.5);
  EXPECT_DOUBLE_EQ(spin.right_radps, -2.5);
  const BodyVelocity back = from_wheels({22.0, 18.0}, {0.4, 0.05});
  EXPECT_DOUBLE_EQ(back.speed_mps, 1.0);
  EXPECT_NEAR(back.turn_rate, 0.5, 1e-12);
}

TEST(CommandStage, IntegratesAccelerationWithinTheLimits) {
  CommandStage stage(config());
  stage.update(0.0);
  ASSERT_FALSE(stage.command({5.0, 3.0}, 0.0));  // both beyond their limits
  StageOutput out = stage.update(0.25);
  EXPECT_NEAR(out.body.speed_mps, 0.25, 1e-12);  // a_c clamped to 1 m/s²
  EXPECT_NEAR(out.body.turn_rate, 1.0, 1e-12);   // ω clamped to 1 rad/s
  EXPECT_GT(out.wheels.left_radps, out.wheels.right_radps);
  for (int i = 1; i <= 8; ++i) {
    stage.command({5.0, 0.0}, 0.25 * i);
    out = stage.update(0.25 * (i + 1));
  }
  EXPECT_DOUBLE_EQ(out.body.speed_mps, 1.0);  // max_speed_mps
  EXPECT_FALSE(out.watchdog_tripped);
  stage.command({-5.0, 0.0}, 2.25);
  EXPECT_NEAR(stage.update(2.5).body.speed_mps, 0.75, 1e-12);
  for (int i = 0; i < 8; ++i) {
    stage.command({-5.0, 0.0}, 2.5 + 0.25 * i);
    out = stage.update(2.75 + 0.25 * i);
  }
  EXPECT_DOUBLE_EQ(out.body.speed_mps, 0.0);  // no reversing by default
}

TEST(CommandStage, ScalesBothWheelsToTheWheelSpeedLimitKeepingCurvature) {
  CommandStageConfig c = config();
  c.limits.max_wheel_speed_radps = 11.0;
  c.limits.max_accel_mps2 = 100.0;  // reach max_speed_mps in one step
  CommandStage stage(c);
  stage.update(0.0);
  stage.command({100.0, 0.5}, 0.0);
  const StageOutput out = stage.update(0.1);
  EXPECT_DOUBLE_EQ(out.wheels.left_radps, 11.0);
  // Unscaled at 1 m/s this would be 22 and 18: the ratio (the curvature) is kept.
  EXPECT_NEAR(out.wheels.right_radps, 9.0, 1e-9);
  EXPECT_NEAR(out.body.speed_mps / out.body.turn_rate, 1.0 / 0.5, 1e-9);
}

TEST(CommandStage, RejectsNaNAndInfAndTheyDoNotFeedTheWatchdog) {
  CommandStage stage(config());
  stage.update(0.0);
  ASSERT_FALSE(stage.command({1.0, 0.0}, 0.0));
  const auto nan = std::numeric_limits<double>::quiet_NaN();
  const auto inf = std::numeric_limits<double>::infinity();
  const auto rejected = stage.command({nan, 0.0}, 0.1);
  ASSERT_TRUE(rejected);
  EXPECT_NE(rejected->find("not finite"), std::string::npos) << *rejected;
  EXPECT_TRUE(stage.command({0.0, inf}, 0.2));
  EXPECT_TRUE(stage.command({-inf, 0.0}, 0.3));
  EXPECT_TRUE(stage.last_rejection());
  // Only the command at t = 0 counts: stopped at 0.5 s.
  EXPECT_TRUE(stage.update(0.5).watchdog_tripped);
  EXPECT_EQ(stage.update(0.5).wheels.left_radps, 0.0);
}

TEST(CommandStage, WatchdogRampsToZeroByTheTimeoutAndReportsIt) {
  CommandStageConfig c = config();
  c.watchdog = {0.5, 0.25};  // times in binary fractions keep the comparisons exact
  CommandStage stage(c);
  stage.update(0.0);
  for (int i = 0; i < 8; ++i) {
    stage.command({1.0, 0.4}, 0.125 * i);
    stage.update(0.125 * (i + 1));
  }
  // The last command was at 0.875 s; speed 1.0 m/s, turn rate 0.4 rad/s.
  StageOutput out = stage.update(1.125);  // 0.25 s old: the ramp starts
  EXPECT_TRUE(out.watchdog_ramping);
  EXPECT_FALSE(out.watchdog_tripped);
  EXPECT_NEAR(out.body.speed_mps, 1.0, 1e-12);
  out = stage.update(1.25);  // halfway down the ramp
  EXPECT_NEAR(out.body.speed_mps, 0.5, 1e-12);
  EXPECT_NEAR(out.body.turn_rate, 0.2, 1e-12);
  out = stage.update(1.375);  // the command is timeout_s old
  EXPECT_TRUE(out.watchdog_tripped);
  EXPECT_EQ(out.wheels.left_radps, 0.0);
  EXPECT_EQ(out.wheels.right_radps, 0.0);
  // A fresh command resumes from rest.
  ASSERT_FALSE(stage.command({1.0, 0.0}, 1.5));
  out = stage.update(1.625);
  EXPECT_FALSE(out.watchdog_tripped);
  EXPECT_NEAR(out.body.speed_mps, 0.25, 1e-12);  // integrated since the last update
}

TEST(CommandStage, NoCommandYetMeansStopped) {
  CommandStage stage(config());
  const StageOutput out = stage.update(3.0);
  EXPECT_TRUE(out.watchdog_tripped);
  EXPECT_EQ(out.wheels.left_radps, 0.0);
}

TEST(CommandStage, EmergencyStopHoldsUntilClearedThenWaitsForAFreshCommand) {
  CommandStage stage(config());
  stage.update(0.0);
  stage.command({1.0, 0.0}, 0.0);
  EXPECT_GT(stage.update(0.2).body.speed_mps, 0.0);
  stage.emergency_stop();
  StageOutput out = stage.update(0.21);
  EXPECT_TRUE(out.emergency_stopped);
  EXPECT_EQ(out.body.speed_mps, 0.0);
  const auto rejected = stage.command({1.0, 0.0}, 0.3);
  ASSERT_TRUE(rejected);
  EXPECT_NE(rejected->find("emergency stop"), std::string::npos);
  EXPECT_EQ(stage.update(0.4).body.speed_mps, 0.0);
  stage.clear_emergency_stop();
  out = stage.update(0.5);
  EXPECT_FALSE(out.emergency_stopped);
  EXPECT_EQ(out.body.speed_mps, 0.0);  // the command from before the stop does not come back
  stage.command({1.0, 0.0}, 0.5);
  EXPECT_NEAR(stage.update(0.6).body.speed_mps, 0.1, 1e-9);
}

TEST(CommandStage, RejectsBadConfiguration) {
  CommandStageConfig c = config();
  c.geometry.wheel_radius_m = 0.0;
  EXPECT_THROW(CommandStage{c}, std::invalid_argument);
  c = config();
  c.watchdog.ramp_s = 1.0;  // longer than the timeout
  EXPECT_THROW(CommandStage{c}, std::invalid_argument);
  c = config();
  c.limits.max_turn_rate = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(CommandStage{c}, std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::drivers
