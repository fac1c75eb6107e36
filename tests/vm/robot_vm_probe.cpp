// Runs inside the robot test VM (tests/vm/robot_init.sh): `flowsteer run` as a user runs it,
// with vivid's capture node as the camera and two simulated ODrive axes on vcan0 as the drive,
// ended four ways while it drives: SIGINT, SIGTERM, the camera unplugged (vivid's "Disconnect")
// and the CAN interface taken down. For each it prints, as "PROBE key value" lines, the
// CLOCK_REALTIME of the fault (candump's clock), how and when flowsteer exited and what it said,
// and for the CAN interface when flowsteer reported the dead bus; tests/robot/robot_vm_test.cpp
// checks those against candump's record of the bus. Two runs record themselves (--mcap): the
// probe prints what their /cmd_vel holds, for the test to compare with the bus.

#include <net/if.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/drivers/simulated_odrive.hpp"
#include "flowsteer/recording/mcap_reader.hpp"
#include "flowsteer/recording/ros2_messages.hpp"
#include "probe_support.hpp"
#include "vivid_control.hpp"

namespace {

using flowsteer::base::monotonic_now_s;
using flowsteer::vm_test::realtime_s;

constexpr char kLaunchPath[] = "/tmp/robot.yaml";
constexpr char kCamera[] = "/dev/video0";
constexpr char kCanInterface[] = "vcan0";

// vivid's webcam input at its smallest size, so the emulated CPU keeps up; the goal far away,
// so the robot is still driving when the fault comes.
constexpr char kLaunch[] = R"(camera:
  type: v4l2
  timeout_s: 1.0
  horizontal_fov_rad: 1.047
  v4l2: {device: /dev/video0, width_px: 320, height_px: 180, frame_rate_hz: 15,
         pixel_format: YUYV}
drive:
  type: odrive_can
  loop_rate_hz: 50
  geometry: {wheel_separation_m: 0.40, wheel_radius_m: 0.05}
  limits: {max_speed_mps: 0.5, max_accel_mps2: 0.5, max_turn_rate: 1.0}
  watchdog: {timeout_s: 0.5, ramp_s: 0.1}
  odrive:
    can_interface: vcan0
    left: {node_id: 3, direction: 1}
    right: {node_id: 5, direction: -1}
    timeout_s: 0.5
perception:
  flow: dis_ultrafast
  segmentation: flow_graph_fast
  height_m: 0.35
  pitch_deg: 5.0
controller:
  preferred_speed_mps: 0.3
  robot_width_m: 0.45
  max_accel_mps2: 0.5
  max_turn_rate: 1.0
goal:
  bearing_rad: 0.0
  distance_m: 50.0
)";

// Takes the interface down with one ioctl, as a cable pulled out or a bus-off would, at the
// moment it is called: `ip link set ... down` would first fork and exec two programs, which on
// the emulated CPU takes some 50 ms of the time measured. An empty string when done, else why not.
std::string take_link_down(const char* interface) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) {
    return std::string("socket: ") + std::strerror(errno);
  }
  ifreq request{};
  std::strncpy(request.ifr_name, interface, IFNAMSIZ - 1);
  std::string error;
  if (::ioctl(fd, SIOCGIFFLAGS, &request) != 0) {
    error = std::string("SIOCGIFFLAGS: ") + std::strerror(errno);
  } else {
    request.ifr_flags = static_cast<short>(request.ifr_flags & ~IFF_UP);
    if (::ioctl(fd, SIOCSIFFLAGS, &request) != 0) {
      error = std::string("SIOCSIFFLAGS: ") + std::strerror(errno);
    }
  }
  ::close(fd);
  return error;
}

// CLOCK_REALTIME when a line of the log first holds `text`, looked for every 5 ms (as
// wait_for_exit looks for the exit); NaN when it has not within `limit_s`.
double when_logged(const std::string& log_path, const std::string& text, double limit_s) {
  const double start_s = monotonic_now_s();
  while (!flowsteer::vm_test::log_has(log_path, text)) {
    if (monotonic_now_s() - start_s > limit_s) {
      return NAN;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return realtime_s();
}

// The fault comes once the run has driven: each axis has taken kMovingSetpoints non-zero
// velocities and at least `drive_s` has passed since the loop started (its first line names the
// drive). Updates, not time alone: on a loaded host the emulated CPU can spend seconds on the
// first pictures' perception, and a recorded run must hold commands that moved the base (a
// wheel's velocity is not zero on a turn in place either: eight leaves room for those beside the
// test's three). False when it did not start, or not drive, within the limits.
constexpr std::uint64_t kMovingSetpoints = 8;
constexpr double kStartLimitS = 20.0;
constexpr double kDriveLimitS = 20.0;  // four cases at 20 + 20 + 10 s stay within the VM's 240 s

bool wait_until_driving(const std::string& log_path,
                        const flowsteer::drivers::SimulatedOdrive& axes, double drive_s) {
  const auto before = axes.axes();  // the axes serve every case of the probe
  if (std::isnan(when_logged(log_path, "drive odrive", kStartLimitS))) {
    return false;
  }
  const auto has_driven = [&] {
    const auto now = axes.axes();
    return std::equal(now.begin(), now.end(), before.begin(),
                      [](const auto& axis, const auto& was) {
                        return axis.moving_setpoints - was.moving_setpoints >= kMovingSetpoints;
                      });
  };
  const double driving_s = monotonic_now_s();
  while (monotonic_now_s() - driving_s < drive_s || !has_driven()) {
    if (monotonic_now_s() - driving_s > kDriveLimitS) {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

struct Exit {
  int status = -1;        // exit status; 128 + signal when killed
  double exited_s = 0.0;  // CLOCK_REALTIME
};

// Waits up to `limit_s` for the process to end; kills it (status 128 + 9) when it does not.
Exit wait_for_exit(pid_t pid, double limit_s) {
  const double start_s = monotonic_now_s();
  Exit result;
  int raw = 0;
  while (::waitpid(pid, &raw, WNOHANG) == 0) {
    if (monotonic_now_s() - start_s > limit_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &raw, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  result.exited_s = realtime_s();
  result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  return result;
}

// A run's recording as the probe reads it: "PROBE <name>-cmd_vel-<k> SPEED YAW_RATE" for each
// /cmd_vel message, its count, and how the metadata says the run ended; or why it cannot be read.
void print_recording(const std::string& name, const std::string& path) {
  namespace ros2 = flowsteer::recording::ros2;
  try {
    flowsteer::recording::McapReader reader(path);
    int count = 0;
    while (const auto m = reader.next()) {
      if (m->channel->topic == "/cmd_vel") {
        const ros2::Twist t = ros2::MessageType<ros2::Twist>::decode(m->data);
        std::printf("PROBE %s-cmd_vel-%d %.17g %.17g\n", name.c_str(), count++, t.linear.x,
                    t.angular.z);
      }
    }
    std::printf("PROBE %s-cmd_vel-count %d\n", name.c_str(), count);
    std::printf("PROBE %s-recording-ended %s\n", name.c_str(),
                reader.metadata().at("flowsteer").at("ended").c_str());
  } catch (const std::exception& e) {
    std::printf("PROBE %s-recording-error %s\n", name.c_str(), e.what());
  }
}

// One run ended by `fault`, called with flowsteer's pid and log: prints "PROBE <name>-start T",
// "PROBE <name>-fault T", "PROBE <name>-exit STATUS T" and each line flowsteer wrote as "PROBE
// <name>-log-<k> LINE"; with `recorded`, the run records itself and print_recording follows.
void run_case(const std::string& name, const flowsteer::drivers::SimulatedOdrive& axes,
              const std::function<void(pid_t, const std::string&)>& fault, bool recorded = false) {
  const std::string log_path = "/tmp/" + name + ".log";
  const std::string recording = "/tmp/" + name + ".mcap";
  std::printf("PROBE %s-start %.6f\n", name.c_str(), realtime_s());
  std::vector<const char*> argv = {"/bin/flowsteer", "run", kLaunchPath};
  if (recorded) {
    argv.insert(argv.end(), {"--mcap", recording.c_str(), "--mcap-images", "0"});
  }
  const pid_t pid = flowsteer::vm_test::start_logged(log_path, argv);
  if (!wait_until_driving(log_path, axes, 2.0)) {
    std::printf("PROBE %s-fault never: flowsteer did not start driving\n", name.c_str());
  } else {
    std::printf("PROBE %s-fault %.6f\n", name.c_str(), realtime_s());
    fault(pid, log_path);
  }
  const Exit exit = wait_for_exit(pid, 10.0);
  std::printf("PROBE %s-exit %d %.6f\n", name.c_str(), exit.status, exit.exited_s);
  std::ifstream in(log_path);
  std::string line;
  for (int k = 0; std::getline(in, line); ++k) {
    std::printf("PROBE %s-log-%d %s\n", name.c_str(), k, line.c_str());
  }
  if (recorded) {
    print_recording(name, recording);
  }
}

int run() {
  std::ofstream(kLaunchPath) << kLaunch;
  flowsteer::drivers::SimulatedOdrive axes(kCanInterface, 3, 5);
  run_case(
      "sigint", axes, [](pid_t pid, const std::string&) { ::kill(pid, SIGINT); }, true);
  run_case("sigterm", axes, [](pid_t pid, const std::string&) { ::kill(pid, SIGTERM); });
  // A button: any value presses it. vivid answers every call on the node with ENODEV until
  // its last file handle is closed, as a USB camera pulled out does.
  run_case(
      "camera-gone", axes,
      [](pid_t, const std::string&) {
        flowsteer::vm_test::set_vivid_control(kCamera, "Disconnect", 1);
      },
      true);
  run_case("can-down", axes, [](pid_t, const std::string& log_path) {
    const std::string error = take_link_down(kCanInterface);
    if (!error.empty()) {
      std::printf("PROBE can-down-failed %s %s\n", kCanInterface, error.c_str());
      return;
    }
    std::printf("PROBE can-down-reported %.6f\n",
                when_logged(log_path, "the stop could not be sent either", 10.0));
  });
  std::printf("PROBE done\n");
  return 0;
}

}  // namespace

int main() {
  return flowsteer::vm_test::probe_main(run);
}
