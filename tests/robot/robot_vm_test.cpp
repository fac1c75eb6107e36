// Boots the robot test VM (tests/vm/run_robot_vm.sh), in which tests/vm/robot_vm_probe runs
// `flowsteer run` on vivid's camera and a simulated ODrive pair on vcan0 and ends it four
// ways, and checks each end against candump's record of the bus: SIGINT and SIGTERM stop the
// wheels and exit 0; the camera unplugged stops the wheels and exits 1 naming the camera; the
// CAN interface taken down ends the run at once with status 1 naming the interface. Each test
// prints the time from the fault to the first zero command on the bus (or to the report).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "can_capture.hpp"
#include "vm_test_support.hpp"

namespace {

using flowsteer::vm_test::CanCaptureRun;
using flowsteer::vm_test::CanFrame;
using flowsteer::vm_test::driven;
using flowsteer::vm_test::first_zero_velocity;
using flowsteer::vm_test::stamp;
using flowsteer::vm_test::stop_bound_s;

constexpr unsigned kNodes[] = {3, 5};
constexpr unsigned kSetAxisRequestedState = 0x07;
constexpr char kIdleRequest[] = "01000000";
// A stop within this of a fault, or within the loop's pass the fault came in where the VM's
// emulated CPU makes a pass longer (stop_bound_s).
constexpr double kStopWithinS = 0.5;

// One run of flowsteer as the probe ended it.
struct EndedRun {
  double start_s = NAN;  // CLOCK_REALTIME, as candump's stamps
  double fault_s = NAN;
  double stop_within_s = NAN;  // what the stop may take: stop_bound_s
  int status = -1;
  double exited_s = NAN;
  std::string log;  // what flowsteer printed
};

class RobotVm
    : public flowsteer::vm_test::VmTest<CanCaptureRun, flowsteer::vm_test::parse_can_capture> {
 protected:
  // The case's fault, exit and output, after checking that it was driving when the fault came
  // and exited with `status`.
  EndedRun ended(const std::string& name, int status) {
    EndedRun run;
    run.start_s = stamp(run_, name + "-start");
    run.fault_s = stamp(run_, name + "-fault");
    run.stop_within_s = stop_bound_s(run_, kNodes, run.start_s, run.fault_s, kStopWithinS);
    EXPECT_TRUE(std::isfinite(run.fault_s)) << name << "-fault " << run_.probe[name + "-fault"];
    std::istringstream(run_.probe[name + "-exit"]) >> run.status >> run.exited_s;
    run.log = log_of(name);
    expect_driving_before(run);
    EXPECT_EQ(run.status, status) << run.log;
    return run;
  }

  // flowsteer's output for the case, one line per line.
  std::string log_of(const std::string& name) {
    std::string log;
    for (int k = 0; run_.probe.count(name + "-log-" + std::to_string(k)); ++k) {
      log += run_.probe[name + "-log-" + std::to_string(k)] + "\n";
    }
    return log;
  }

  // Both axes: a zero velocity in time (EndedRun::stop_within_s), no other velocity after it
  // until the run ended, then an idle request. Returns the later of the two zero commands'
  // delays.
  double expect_wheels_stopped(const EndedRun& run) {
    double slowest_s = 0.0;
    for (const unsigned node : kNodes) {
      SCOPED_TRACE("node " + std::to_string(node));
      const std::optional<double> zero_s = first_zero_velocity(run_, node, run.fault_s);
      if (!zero_s) {
        ADD_FAILURE() << "no zero velocity on the bus after the fault";
        continue;
      }
      slowest_s = std::max(slowest_s, *zero_s - run.fault_s);
      EXPECT_LT(*zero_s - run.fault_s, run.stop_within_s);
      EXPECT_FALSE(driven(run_, node, *zero_s, run.exited_s))
          << "a wheel was driven again after the stop";
      bool idle_requested = false;
      for (const CanFrame& f : run_.frames) {
        idle_requested |= f.time_s > *zero_s && f.time_s <= run.exited_s && f.node() == node &&
                          f.cmd() == kSetAxisRequestedState && f.hex == kIdleRequest;
      }
      EXPECT_TRUE(idle_requested) << "the axis was not set idle before flowsteer exited";
    }
    return slowest_s;
  }

  // The run had been driving: the controller sent non-zero wheel speeds before the fault.
  void expect_driving_before(const EndedRun& run) {
    for (const unsigned node : kNodes) {
      EXPECT_TRUE(driven(run_, node, run.start_s, run.fault_s))
          << "node " << node << " never driven before the fault\n"
          << run.log;
    }
  }

  void check_signal_stop(const std::string& name) {
    const EndedRun run = ended(name, 0);
    EXPECT_NE(run.log.find("flowsteer run: stop requested: base odrive vcan0 stopped"),
              std::string::npos)
        << run.log;
    const double stop_s = expect_wheels_stopped(run);
    std::printf(
        "%s: first zero command on the bus %.1f ms after the signal (bound %.1f ms), exit after "
        "%.1f ms\n",
        name.c_str(), 1e3 * stop_s, 1e3 * run.stop_within_s, 1e3 * (run.exited_s - run.fault_s));
  }
};

TEST_F(RobotVm, SigintStopsTheWheelsAndExitsZero) {
  check_signal_stop("sigint");
}

TEST_F(RobotVm, SigtermStopsTheWheelsAndExitsZero) {
  check_signal_stop("sigterm");
}

TEST_F(RobotVm, CameraUnpluggedStopsTheWheelsAndExitsOneNamingTheCamera) {
  const EndedRun run = ended("camera-gone", 1);
  EXPECT_NE(run.log.find("flowsteer run: the run failed: base odrive vcan0 stopped\n"
                         "flowsteer: error: "),
            std::string::npos)
      << run.log;
  EXPECT_TRUE(flowsteer::vm_test::says_camera_gone(run.log, "/dev/video0")) << run.log;
  const double stop_s = expect_wheels_stopped(run);
  std::printf(
      "camera unplugged: first zero command on the bus %.1f ms after the fault (bound %.1f ms)\n",
      1e3 * stop_s, 1e3 * run.stop_within_s);
}

TEST_F(RobotVm, CanInterfaceDownEndsTheRunAtOnceNamingTheInterface) {
  const EndedRun run = ended("can-down", 1);
  // Nothing can reach the axes any more; the run says so instead of claiming a stop.
  EXPECT_NE(run.log.find("the stop could not be sent either"), std::string::npos) << run.log;
  EXPECT_NE(run.log.find("vcan0"), std::string::npos) << run.log;
  EXPECT_NE(run.log.find("Network is down"), std::string::npos) << run.log;
  // No retrying on a dead bus: the run gives up at the first update after the fault, at the end
  // of the pass the fault came in. The exit that follows (closing the camera, unloading the
  // libraries) takes the emulated CPU another 100-300 ms and is not what is timed here.
  const double reported_s = stamp(run_, "can-down-reported");
  ASSERT_TRUE(std::isfinite(reported_s)) << "the dead bus was never reported\n" << run.log;
  EXPECT_LT(reported_s - run.fault_s, run.stop_within_s) << run.log;
  std::printf(
      "CAN interface down: reported %.1f ms after the fault (bound %.1f ms), exit after "
      "%.1f ms\n",
      1e3 * (reported_s - run.fault_s), 1e3 * run.stop_within_s,
      1e3 * (run.exited_s - run.fault_s));
}

}  // namespace
