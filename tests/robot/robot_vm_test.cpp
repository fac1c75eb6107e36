// Boots the robot test VM (tests/vm/run_robot_vm.sh), in which tests/vm/robot_vm_probe runs
// `flowsteer run` on vivid's camera and a simulated ODrive pair on vcan0 and ends it four
// ways, and checks each end against candump's record of the bus: SIGINT and SIGTERM stop the
// wheels and exit 0; the camera unplugged stops the wheels and exits 1 naming the camera; the
// CAN interface taken down ends the run at once with status 1 naming the interface. Each test
// prints the time from the fault to the first zero command on the bus (or to the report). The
// SIGINT and camera runs record themselves (--mcap): their /cmd_vel must be what the bus carried.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

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

// The launch file's wheels (robot_vm_probe.cpp): left node 3 forward, right node 5 mirrored.
constexpr double kWheelRadiusM = 0.05;
constexpr double kWheelSeparationM = 0.40;

// What ODrive's Set_Input_Vel frames carried, in turns/s, for one update: left and right axis.
struct AxisVelocities {
  float left;
  float right;
};

// The k-th Set_Input_Vel to each node between the times, paired: the drive writes both axes at
// each update.
std::vector<AxisVelocities> bus_velocities(const CanCaptureRun& run, double from_s, double to_s) {
  std::vector<float> left;
  std::vector<float> right;
  for (const CanFrame& f : run.frames) {
    if (f.time_s >= from_s && f.time_s <= to_s) {
      if (flowsteer::vm_test::is_set_input_vel(f, kNodes[0]))
        left.push_back(f.f32(0));
      if (flowsteer::vm_test::is_set_input_vel(f, kNodes[1]))
        right.push_back(f.f32(0));
    }
  }
  std::vector<AxisVelocities> out;
  for (std::size_t k = 0; k < std::min(left.size(), right.size()); ++k) {
    out.push_back({left[k], right[k]});
  }
  return out;
}

// A recorded cmd_vel (speed, ROS yaw rate) as the axes' turns/s, rounded to the float the CAN
// frame holds.
AxisVelocities axis_velocities(double speed_mps, double yaw_rate) {
  const double left_radps = (speed_mps - 0.5 * kWheelSeparationM * yaw_rate) / kWheelRadiusM;
  const double right_radps = (speed_mps + 0.5 * kWheelSeparationM * yaw_rate) / kWheelRadiusM;
  return {static_cast<float>(left_radps / (2.0 * M_PI)),
          static_cast<float>(-right_radps / (2.0 * M_PI))};
}

// The run's recorded /cmd_vel is a stretch of the bus's velocity frames, update for update, and
// ends in the stop's zero.
void expect_recording_is_the_bus(const CanCaptureRun& run, const std::string& name,
                                 const EndedRun& ended) {
  ASSERT_EQ(run.probe.count(name + "-recording-error"), 0u)
      << run.probe.at(name + "-recording-error");
  const int count = std::atoi(run.probe.at(name + "-cmd_vel-count").c_str());
  std::vector<AxisVelocities> recorded;
  int moving = 0;
  for (int k = 0; k < count; ++k) {
    double speed = NAN;
    double yaw_rate = NAN;
    std::istringstream(run.probe.at(name + "-cmd_vel-" + std::to_string(k))) >> speed >> yaw_rate;
    recorded.push_back(axis_velocities(speed, yaw_rate));
    moving += speed != 0.0 ? 1 : 0;
  }
  // The probe faults a run once each axis has taken 8 moving velocities, 2 s at the least.
  ASSERT_GE(moving, 3) << "the recording holds too few commands that moved the base";
  EXPECT_EQ(recorded.back().left, 0.0f) << "the recording does not end with the stop";
  const std::vector<AxisVelocities> bus = bus_velocities(run, ended.start_s, ended.exited_s);
  // 1e-6 relative: the float the frame holds, from the same double the recording holds.
  const auto same = [](const AxisVelocities& a, const AxisVelocities& b) {
    return std::abs(a.left - b.left) <= 1e-6f * std::max(1.0f, std::abs(b.left)) &&
           std::abs(a.right - b.right) <= 1e-6f * std::max(1.0f, std::abs(b.right));
  };
  bool found = false;
  for (std::size_t offset = 0; !found && offset + recorded.size() <= bus.size(); ++offset) {
    found = std::equal(recorded.begin(), recorded.end(), bus.begin() + offset, same);
  }
  EXPECT_TRUE(found) << name << ": the " << recorded.size()
                     << " recorded /cmd_vel are not a stretch of the " << bus.size()
                     << " velocity updates on the bus";
  std::printf("%s: %zu recorded /cmd_vel (%d moving) found on the bus, %zu updates there\n",
              name.c_str(), recorded.size(), moving, bus.size());
}

TEST_F(RobotVm, SigintStopsTheWheelsAndExitsZero) {
  check_signal_stop("sigint");
}

TEST_F(RobotVm, ARecordedRunsCmdVelIsWhatTheBusCarried) {
  expect_recording_is_the_bus(run_, "sigint", ended("sigint", 0));
  // A run that ended by an error finishes its recording too, and says how it ended.
  const EndedRun gone = ended("camera-gone", 1);
  EXPECT_NE(run_.probe["camera-gone-recording-ended"].find("error: "), std::string::npos)
      << run_.probe["camera-gone-recording-ended"];
  expect_recording_is_the_bus(run_, "camera-gone", gone);
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
