#include "flowsteer/drivers/mobile_base.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/drivers/sim_base.hpp"

namespace flowsteer::drivers {
namespace {

CommandStageConfig stage_config() {
  CommandStageConfig c;
  c.geometry = {0.4, 0.05};
  c.limits.max_speed_mps = 1.0;
  c.limits.max_accel_mps2 = 2.0;
  c.limits.max_turn_rate = 1.0;
  c.watchdog = {0.5, 0.25};
  return c;
}

struct SimClock {
  double now_s = 0.0;
};

std::unique_ptr<SimBase> sim_base(SimClock& clock) {
  SimBaseConfig c;
  c.geometry = {0.4, 0.05};
  c.clock = [&clock] { return clock.now_s; };
  return std::make_unique<SimBase>(c);
}

TEST(SimBase, PositiveTurnRateTurnsTheBaseRightClockwise) {
  SimClock clock;
  auto owned = sim_base(clock);
  SimBase* sim = owned.get();
  MobileBase base(std::move(owned), stage_config());
  base.configure();
  base.activate(clock.now_s);
  BaseState state;
  for (int i = 0; i < 100; ++i) {
    base.command({2.0, 0.5}, clock.now_s);
    state = base.update(clock.now_s);
    clock.now_s += 0.01;
  }
  state = base.update(clock.now_s);
  EXPECT_GT(sim->pose().x_m, 0.3);
  EXPECT_LT(sim->pose().y_m, 0.0);                   // drifted to the right (REP-103 y is left)
  EXPECT_LT(sim->pose().yaw_rad, 0.0);               // clockwise seen from above
  EXPECT_NEAR(state.measured.turn_rate, 0.5, 1e-9);  // measured back in the controller's sign
  EXPECT_NEAR(state.measured.speed_mps, 1.0, 1e-9);
  EXPECT_GT(state.drive.odometry.left_rad, state.drive.odometry.right_rad);
  // Odometry agrees with the distance travelled: mean wheel angle × radius.
  const double mean_rad = 0.5 * (state.drive.odometry.left_rad + state.drive.odometry.right_rad);
  EXPECT_NEAR(mean_rad * 0.05, 0.75, 0.02);  // 0.5 s at 2 m/s² to 1 m/s, then 0.5 s at 1 m/s
  base.deactivate();
  EXPECT_EQ(base.lifecycle(), Lifecycle::inactive);
}

TEST(SimBase, WheelLagAndStopWhenCommandsCease) {
  SimClock clock;
  SimBaseConfig c;
  c.geometry = {0.4, 0.05};
  c.wheel_time_constant_s = 0.1;
  c.clock = [&clock] { return clock.now_s; };
  SimBase sim(c);
  sim.configure();
  sim.activate();
  sim.write({10.0, 10.0});
  clock.now_s = 0.1;
  EXPECT_NEAR(sim.read().measured.left_radps, 10.0 * (1.0 - std::exp(-1.0)), 1e-9);

  SimClock clock2;
  MobileBase base(sim_base(clock2), stage_config());
  base.configure();
  base.activate(0.0);
  base.command({2.0, 0.0}, 0.0);
  for (int i = 0; i < 100; ++i) {
    clock2.now_s = 0.01 * (i + 1);
    const BaseState state = base.update(clock2.now_s);
    if (clock2.now_s >= 0.5) {
      EXPECT_TRUE(state.sent.watchdog_tripped);
      EXPECT_EQ(state.sent.wheels.left_radps, 0.0);
    }
    if (clock2.now_s >= 0.52) {  // the sim measures what it was sent over the last step
      EXPECT_EQ(state.measured.speed_mps, 0.0);
    }
  }
}

TEST(SimBase, AStopIsTakenInAnyPhaseOnceConfigured) {
  SimClock clock;
  const std::unique_ptr<SimBase> sim = sim_base(clock);
  EXPECT_THROW(sim->write({}), DriveError);  // not configured: no device to stop
  sim->configure();
  EXPECT_NO_THROW(sim->write({}));
  EXPECT_THROW(sim->write({1.0, 1.0}), DriveError);
  sim->activate();
  sim->write({1.0, 1.0});
  sim->deactivate();
  EXPECT_NO_THROW(sim->write({}));
}

// A drive whose write fails on demand, recording what the base did about it.
class FlakyDrive final : public Drive {
 public:
  std::string_view name() const override { return "flaky"; }
  void configure() override { calls.push_back("configure"); }
  void activate() override { calls.push_back("activate"); }
  void deactivate() override { calls.push_back("deactivate"); }
  DriveState read() override { return {}; }
  void write(const WheelSpeeds& wheels) override {
    calls.push_back(wheels.left_radps == 0.0 && wheels.right_radps == 0.0 ? "write zero" : "write");
    if (fail_next) {
      fail_next = false;
      throw DriveError("link garbled");
    }
  }
  bool fail_next = false;
  std::vector<std::string> calls;
};

TEST(MobileBase, AFailingDriveIsStoppedAndTheErrorNamesIt) {
  auto owned = std::make_unique<FlakyDrive>();
  FlakyDrive* drive = owned.get();
  MobileBase base(std::move(owned), stage_config());
  base.configure();
  base.activate(0.0);
  base.command({1.0, 0.0}, 0.0);
  base.update(0.1);
  drive->fail_next = true;
  try {
    base.update(0.2);
    FAIL() << "update did not throw";
  } catch (const DriveError& e) {
    EXPECT_NE(std::string(e.what()).find("flaky: update failed, base stopped: link garbled"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(base.lifecycle(), Lifecycle::failed);
  const std::vector<std::string> tail(drive->calls.end() - 3, drive->calls.end());
  EXPECT_EQ(tail, (std::vector<std::string>{"write", "write zero", "deactivate"}));
  EXPECT_THROW(base.update(0.3), DriveError);  // failed: no more commands reach the drive
}

TEST(MobileBase, EmergencyStopWritesZeroAtOnce) {
  auto owned = std::make_unique<FlakyDrive>();
  FlakyDrive* drive = owned.get();
  MobileBase base(std::move(owned), stage_config());
  base.configure();
  base.activate(0.0);
  base.command({1.0, 0.0}, 0.0);
  base.update(0.1);
  base.emergency_stop();
  EXPECT_EQ(drive->calls.back(), "write zero");
  EXPECT_TRUE(base.command({1.0, 0.0}, 0.15));
  EXPECT_TRUE(base.update(0.2).sent.emergency_stopped);
  EXPECT_EQ(drive->calls.back(), "write zero");
  base.clear_emergency_stop();
  EXPECT_FALSE(base.command({1.0, 0.0}, 0.25));
  EXPECT_GT(base.update(0.3).sent.body.speed_mps, 0.0);
}

TEST(MobileBase, LifecycleOrderIsEnforced) {
  MobileBase base(std::make_unique<FlakyDrive>(), stage_config());
  EXPECT_THROW(base.activate(0.0), DriveError);
  EXPECT_THROW(base.update(0.0), DriveError);
  base.configure();
  EXPECT_THROW(base.update(0.0), DriveError);
  EXPECT_THROW(MobileBase(nullptr, stage_config()), std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::drivers
