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

constexpr unsigned kNodes[] = {3, 5};
constexpr unsigned kSetAxisRequestedState = 0x07;
constexpr char kIdleRequest[] = "01000000";
// The VM emulates its CPU: flowsteer's loop, a frame's perception included, takes a few times
// what it takes on the machine itself. A stop must still come within this.
constexpr double kStopWithinS = 0.5;

// One run of flowsteer as the probe ended it.
struct EndedRun {
  double fault_s = NAN;  // CLOCK_REALTIME, as candump's stamps
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
    run.fault_s = stamp(run_, name + "-fault");
    EXPECT_TRUE(std::isfinite(run.fault_s)) << name << "-fault " << run_.probe[name + "-fault"];
    std::istringstream(run_.probe[name + "-exit"]) >> run.status >> run.exited_s;
    run.log = log_of(name);
    expect_driving_before(name, run.fault_s);
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

  // Both axes: a zero velocity within kStopWithinS of the fault, no other velocity after it
  // until the run ended, then an idle request. Returns the later of the two zero commands'
  // delays.
  double expect_wheels_stopped(double fault_s, double exit_s) {
    double slowest_s = 0.0;
    for (const unsigned node : kNodes) {
      SCOPED_TRACE("node " + std::to_string(node));
      const std::optional<double> zero_s = first_zero_velocity(run_, node, fault_s);
      if (!zero_s) {
        ADD_FAILURE() << "no zero velocity on the bus after the fault";
        continue;
      }
      slowest_s = std::max(slowest_s, *zero_s - fault_s);
      EXPECT_LT(*zero_s - fault_s, kStopWithinS);
      EXPECT_FALSE(driven(run_, node, *zero_s, exit_s))
          << "a wheel was driven again after the stop";
      bool idle_requested = false;
      for (const CanFrame& f : run_.frames) {
        idle_requested |= f.time_s > *zero_s && f.time_s <= exit_s && f.node() == node &&
                          f.cmd() == kSetAxisRequestedState && f.hex == kIdleRequest;
      }
      EXPECT_TRUE(idle_requested) << "the axis was not set idle before flowsteer exited";
    }
    return slowest_s;
  }

  // The run had been driving: the controller sent non-zero wheel speeds before the fault.
  void expect_driving_before(const std::string& name, double fault_s) {
    const double start_s = stamp(run_, name + "-start");
    for (const unsigned node : kNodes) {
      EXPECT_TRUE(driven(run_, node, start_s, fault_s))
          << "node " << node << " never driven before the fault\n"
          << log_of(name);
    }
  }

  void check_signal_stop(const std::string& name) {
    const EndedRun run = ended(name, 0);
    EXPECT_NE(run.log.find("flowsteer run: stop requested: base odrive vcan0 stopped"),
              std::string::npos)
        << run.log;
    const double stop_s = expect_wheels_stopped(run.fault_s, run.exited_s);
    std::printf("%s: first zero command on the bus %.1f ms after the signal, exit after %.1f ms\n",
                name.c_str(), 1e3 * stop_s, 1e3 * (run.exited_s - run.fault_s));
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
  const double stop_s = expect_wheels_stopped(run.fault_s, run.exited_s);
  std::printf("camera unplugged: first zero command on the bus %.1f ms after the fault\n",
              1e3 * stop_s);
}

TEST_F(RobotVm, CanInterfaceDownEndsTheRunAtOnceNamingTheInterface) {
  const EndedRun run = ended("can-down", 1);
  // Nothing can reach the axes any more; the run says so instead of claiming a stop.
  EXPECT_NE(run.log.find("the stop could not be sent either"), std::string::npos) << run.log;
  EXPECT_NE(run.log.find("vcan0"), std::string::npos) << run.log;
  EXPECT_NE(run.log.find("Network is down"), std::string::npos) << run.log;
  // No retrying on a dead bus: the run gives up at the first update after the fault, a frame's
  // perception and a loop period at most. The exit that follows (closing the camera, unloading
  // the libraries) takes the emulated CPU another 100-300 ms and is not what is timed here.
  const double reported_s = stamp(run_, "can-down-reported");
  ASSERT_TRUE(std::isfinite(reported_s)) << "the dead bus was never reported\n" << run.log;
  EXPECT_LT(reported_s - run.fault_s, kStopWithinS) << run.log;
  std::printf("CAN interface down: reported %.1f ms after the fault, exit after %.1f ms\n",
              1e3 * (reported_s - run.fault_s), 1e3 * (run.exited_s - run.fault_s));
}

}  // namespace
