// Boots the CAN test VM (tests/vm/run_can_vm.sh), in which tests/vm/odrive_vm_probe drives a
// simulated ODrive pair on vcan0 while candump records the bus, and checks candump's record:
// the exact frames for activate and deactivate, that deactivate waits for both axes to report
// idle, the velocity stream, the watchdog's stop and the stops after an axis error and after a
// lost heartbeat.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "can_capture.hpp"
#include "vm_test_support.hpp"

namespace {

using flowsteer::vm_test::CanFrame;
using flowsteer::vm_test::drive_frames_between;
using flowsteer::vm_test::stamp;
using flowsteer::vm_test::times_driven;
using VmRun = flowsteer::vm_test::CanCaptureRun;

class OdriveVm : public flowsteer::vm_test::VmTest<VmRun, flowsteer::vm_test::parse_can_capture> {
 protected:
  void SetUp() override {
    VmTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) {
      return;
    }
    ASSERT_FALSE(run_.frames.empty()) << run_.console;
  }
};

constexpr double kTimeoutS = 0.3;  // the probe's watchdog timeout
constexpr double kPeriodS = 0.02;  // the probe's loop period
// candump stamps a frame when the kernel hands it over; the probe stamps just after the call.
constexpr double kStampSlackS = 0.005;

// When each update() of one of the probe's loops began (its line `key`-updates; in a loop driven
// into a fault the last is the update that failed).
std::vector<double> update_starts(const VmRun& run, const std::string& key) {
  std::vector<double> starts;
  std::istringstream in(run.probe.at(key + "-updates"));
  for (double start_s = 0.0; in >> start_s;) {
    starts.push_back(start_s);
  }
  return starts;
}

// How many of those began after from_s and before to_s (both clocks CLOCK_REALTIME; the slack
// covers the two stamps' distance from the events). A base that acts at the first update after
// from_s leaves at most one before it acted. A bound in time alone does not hold on a loaded
// host: the emulated machine may run an update late or stall inside one.
long updates_begun_after(const std::vector<double>& starts, double from_s, double to_s = INFINITY) {
  return std::count_if(starts.begin(), starts.end(), [&](double start_s) {
    return start_s > from_s + 2.0 * kStampSlackS && start_s < to_s;
  });
}

TEST_F(OdriveVm, MissingInterfaceIsAClearError) {
  EXPECT_NE(run_.probe["missing-interface"].find("CAN interface vcan7 not found: No such device"),
            std::string::npos)
      << run_.probe["missing-interface"];
}

TEST_F(OdriveVm, ActivateSendsVelocityModeZeroVelocityAndClosedLoop) {
  const std::vector<std::string> frames =
      drive_frames_between(run_, stamp(run_, "activate"), stamp(run_, "stream"));
  const std::vector<std::string> expected = {
      "06B#0200000001000000",  // node 3 Set_Controller_Modes: velocity control, passthrough
      "06D#0000000000000000",  // node 3 Set_Input_Vel 0
      "067#08000000",          // node 3 Set_Axis_Requested_State: closed-loop control
      "0AB#0200000001000000",  // node 5 likewise
      "0AD#0000000000000000", "0A7#08000000",
  };
  EXPECT_EQ(frames, expected);
}

TEST_F(OdriveVm, StreamsTheCommandedWheelSpeedsAtTheLoopRate) {
  const double from_s = stamp(run_, "stream");
  const double last_s = stamp(run_, "last-command");
  // At 0.5 m/s (the speed limit) and ω_cy = 0.6 rad/s (a right turn, ω_z = −0.6): left wheel
  // (0.5 + 0.6·0.2) / 0.05 rad/s forward; the right motor is mirrored (direction −1).
  const double left_turns = (0.5 + 0.6 * 0.2) / 0.05 / (2.0 * std::numbers::pi);
  const double right_turns = -(0.5 - 0.6 * 0.2) / 0.05 / (2.0 * std::numbers::pi);
  std::map<unsigned, std::vector<CanFrame>> vel;
  for (const CanFrame& f : run_.frames) {
    if (f.time_s > from_s && f.time_s <= last_s + kStampSlackS && f.cmd() == 0x0d && !f.rtr) {
      vel[f.node()].push_back(f);
    }
  }
  ASSERT_EQ(vel.size(), 2u);
  for (const auto& [node, frames] : vel) {
    SCOPED_TRACE("node " + std::to_string(node));
    // 1 s of commands at 50 Hz: allow for a slow emulated machine, not for a missing stream.
    EXPECT_GE(frames.size(), 35u);
    for (std::size_t i = 1; i < frames.size(); ++i) {
      EXPECT_LT(frames[i].time_s - frames[i - 1].time_s, 0.1) << "the stream paused";
    }
    EXPECT_NEAR(frames.back().f32(0), node == 3 ? left_turns : right_turns, 1e-5);
    EXPECT_EQ(frames.back().hex.substr(8), "00000000");  // no torque feed-forward
  }
}

TEST_F(OdriveVm, MeasuresSpeedTurnRateAndOdometryFromTheAxesEstimates) {
  double speed_mps = 0, turn_rate = 0, left_rad = 0, right_rad = 0;
  std::size_t faults = 99;
  ASSERT_EQ(std::sscanf(run_.probe["measured"].c_str(), "%lf %lf %lf %lf %zu", &speed_mps,
                        &turn_rate, &left_rad, &right_rad, &faults),
            5)
      << run_.probe["measured"];
  // The axes echo the commanded velocity; estimates lag by at most a loop period.
  EXPECT_NEAR(speed_mps, 0.5, 1e-4);
  EXPECT_NEAR(turn_rate, 0.6, 1e-4);  // back in the controller's sign: turning right
  EXPECT_GT(left_rad, right_rad);     // both forward (the mirrored axis turned back)
  EXPECT_GT(right_rad, 0.0);
  EXPECT_EQ(faults, 0u);
}

TEST_F(OdriveVm, WatchdogStopsTheWheelsAtTheFirstUpdateAfterTheTimeout) {
  const double last_s = stamp(run_, "last-command");
  const double deactivate_s = stamp(run_, "deactivate");
  for (const unsigned node : {3u, 5u}) {
    SCOPED_TRACE("node " + std::to_string(node));
    std::optional<double> first_zero_s;
    double previous = INFINITY;
    for (const CanFrame& f : run_.frames) {
      if (f.time_s <= last_s || f.time_s >= deactivate_s || f.node() != node || f.cmd() != 0x0d ||
          f.rtr) {
        continue;
      }
      const double magnitude = std::abs(f.f32(0));
      if (first_zero_s) {
        EXPECT_EQ(f.hex, "0000000000000000") << "moving again after the watchdog's stop";
      } else {
        EXPECT_LE(magnitude, previous + 1e-6) << "the ramp to zero went up";
        previous = magnitude;
        if (f.hex == "0000000000000000") {
          first_zero_s = f.time_s;
        }
      }
    }
    ASSERT_TRUE(first_zero_s) << "no zero velocity after the last command";
    EXPECT_LE(updates_begun_after(update_starts(run_, "stream"), last_s + kTimeoutS, *first_zero_s),
              1)
        << "the base was updated after the watchdog's timeout and not stopped";
    EXPECT_GT(*first_zero_s - last_s, kTimeoutS - kPeriodS);  // a ramp, not an instant stop
  }
}

TEST_F(OdriveVm, DeactivateSendsZeroVelocityThenIdle) {
  const std::vector<std::string> frames =
      drive_frames_between(run_, stamp(run_, "deactivate"), stamp(run_, "deactivated"));
  const std::vector<std::string> expected = {
      "06D#0000000000000000", "067#01000000",  // node 3: zero, then idle
      "0AD#0000000000000000", "0A7#01000000",  // node 5
  };
  ASSERT_GE(frames.size(), 4u);
  // An update() just before may have streamed one more zero; the last four are deactivate's.
  EXPECT_EQ(std::vector<std::string>(frames.end() - 4, frames.end()), expected);
}

// deactivate() returns only once each axis has sent a heartbeat saying idle after its idle
// request: a base reported deactivated has its motors disarmed, not just asked to disarm.
TEST_F(OdriveVm, DeactivateReturnsOnlyAfterBothAxesReportIdle) {
  const double deactivated_s = stamp(run_, "deactivated");
  for (const unsigned node : {3u, 5u}) {
    SCOPED_TRACE("node " + std::to_string(node));
    double requested_s = NAN;  // the last idle request
    double confirmed_s = NAN;  // the first idle heartbeat after it
    for (const CanFrame& f : run_.frames) {
      if (f.node() != node || f.time_s > deactivated_s + kStampSlackS) {
        continue;
      }
      if (f.cmd() == 0x07 && f.hex == "01000000") {
        requested_s = f.time_s;
        confirmed_s = NAN;
      } else if (!std::isnan(requested_s) && std::isnan(confirmed_s) && f.cmd() == 0x01 &&
                 f.hex.size() >= 10 && f.hex.substr(8, 2) == "01") {
        confirmed_s = f.time_s;
      }
    }
    ASSERT_FALSE(std::isnan(requested_s)) << "no idle request";
    ASSERT_FALSE(std::isnan(confirmed_s)) << "deactivate returned before an idle heartbeat";
    std::printf("node %u: idle confirmed %.1f ms after the request\n", node,
                1e3 * (confirmed_s - requested_s));
  }
}

TEST_F(OdriveVm, AxisErrorIsReportedAndBothAxesAreStoppedAtTheNextPass) {
  const std::string& message = run_.probe["axis-error"];
  EXPECT_NE(message.find("ODrive node 5 (right) on vcan0 reports axis error 0x00000200 "
                         "(CONTROLLER_FAILED)"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("base stopped"), std::string::npos) << message;
  // The first heartbeat with the error, then the stops for both axes, and no motion after.
  const auto error_hb = std::find_if(run_.frames.begin(), run_.frames.end(), [](const CanFrame& f) {
    return f.id == 0x0a1 && f.hex.starts_with("00020000");
  });
  ASSERT_NE(error_hb, run_.frames.end());
  const double next_case_s = stamp(run_, "heartbeat-lost-start");  // the base is reactivated
  std::vector<std::string> after;
  for (auto it = error_hb; it != run_.frames.end() && it->time_s < next_case_s; ++it) {
    if (from_drive(*it)) {
      after.push_back(it->text());
    }
  }
  for (const char* stop :
       {"06D#0000000000000000", "067#01000000", "0AD#0000000000000000", "0A7#01000000"}) {
    EXPECT_NE(std::find(after.begin(), after.end(), stop), after.end()) << stop;
  }
  // At the loop's next pass: the next read() finds the heartbeat. The pass that had read before
  // it came may still send its velocities; no later one does.
  const std::vector<double> updates = update_starts(run_, "axis-error");
  ASSERT_FALSE(updates.empty());
  EXPECT_LE(updates_begun_after(updates, error_hb->time_s), 1)
      << "the base was updated after the axis error's heartbeat and not stopped";
  struct AxisStop {
    unsigned node;
    std::string frame;
  };
  for (const AxisStop& axis :
       {AxisStop{3, "06D#0000000000000000"}, AxisStop{5, "0AD#0000000000000000"}}) {
    const unsigned node = axis.node;
    const std::string& stop = axis.frame;
    const auto first_stop = std::find_if(error_hb, run_.frames.end(),
                                         [&](const CanFrame& f) { return f.text() == stop; });
    ASSERT_NE(first_stop, run_.frames.end()) << stop;
    EXPECT_LE(times_driven(run_, node, error_hb->time_s, first_stop->time_s), 1)
        << stop << ": the base drove on after the heartbeat that reported the error";
    std::printf("%s %.1f ms after the axis error's heartbeat, %.1f ms after its update began\n",
                stop.c_str(), 1e3 * (first_stop->time_s - error_hb->time_s),
                1e3 * (first_stop->time_s - updates.back()));
    EXPECT_GT(first_stop->time_s, updates.back() - kStampSlackS);  // sent by the failed update
  }
  const auto first_idle = std::find(after.begin(), after.end(), "067#01000000");
  for (auto it = first_idle; it != after.end(); ++it) {
    EXPECT_TRUE(it->starts_with("06D#00000000") || it->starts_with("0AD#00000000") ||
                it->ends_with("#01000000"))
        << "motion after the stop: " << *it;
  }
}

// The left axis stops sending heartbeats while the base drives: the first update() that begins
// once the drive's timeout has passed since the last heartbeat commands both axes to zero and
// idle, and the error names the silent axis. The drive dates each heartbeat by the kernel's
// receive stamp and checks it at each read(), so an update() that began a little earlier may
// already stop; none after the first late one may still drive.
TEST_F(OdriveVm, LostHeartbeatStopsBothAxesAtTheFirstUpdateAfterTheTimeout) {
  const std::string& message = run_.probe["heartbeat-lost"];
  EXPECT_NE(message.find("no heartbeat from ODrive node 3 (left) on vcan0 for 0.3"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("base stopped"), std::string::npos) << message;
  const auto last_heartbeat = std::find_if(run_.frames.rbegin(), run_.frames.rend(),
                                           [](const CanFrame& f) { return f.id == 0x061; });
  ASSERT_NE(last_heartbeat, run_.frames.rend());
  const double lost_s = last_heartbeat->time_s;
  const std::vector<double> updates = update_starts(run_, "heartbeat-lost");
  ASSERT_FALSE(updates.empty());
  EXPECT_LE(updates_begun_after(updates, lost_s + kTimeoutS), 1)
      << "the base was updated after the heartbeat was late and not stopped";
  const double failed_update_s = updates.back();
  for (const char* stop : {"06D#0000000000000000", "0AD#0000000000000000"}) {
    SCOPED_TRACE(stop);
    const auto first_stop =
        std::find_if(run_.frames.begin(), run_.frames.end(),
                     [&](const CanFrame& f) { return f.time_s > lost_s && f.text() == stop; });
    ASSERT_NE(first_stop, run_.frames.end()) << "no stop after the last heartbeat";
    const double delay_s = first_stop->time_s - lost_s;
    std::printf("%s %.1f ms after the last heartbeat, %.1f ms after its update began\n", stop,
                1e3 * delay_s, 1e3 * (first_stop->time_s - failed_update_s));
    EXPECT_GT(delay_s, kTimeoutS - kStampSlackS);  // not before the heartbeat was late
    EXPECT_GT(first_stop->time_s, failed_update_s - kStampSlackS);  // sent by the failed update
  }
  std::vector<std::string> after;
  for (const CanFrame& f : run_.frames) {
    if (f.time_s > lost_s && from_drive(f)) {
      after.push_back(f.text());
    }
  }
  const auto first_zero = std::find(after.begin(), after.end(), "06D#0000000000000000");
  const auto first_zero_right = std::find(after.begin(), after.end(), "0AD#0000000000000000");
  for (auto it = std::max(first_zero, first_zero_right); it != after.end(); ++it) {
    EXPECT_TRUE(it->ends_with("#0000000000000000") || it->ends_with("#01000000"))
        << "motion after the stop: " << *it;
  }
}

}  // namespace
