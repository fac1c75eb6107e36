// `flowsteer run` on a ROS 2 robot: a ros2 camera and a ros2 drive against a peer (peer/) that
// plays the robot's camera driver and diff_drive_controller with its own types, on Cyclone DDS
// (flowsteer_ros2_robot_peer) and on Fast DDS, ROS 2's default middleware
// (flowsteer_ros2_robot_peer_fastdds). The peer records every command it takes; each case checks,
// as the robot VM test does on the CAN bus, that the base was driven, that a zero command came
// within the bound after the fault, that nothing moved it afterwards, and the exit status and
// message.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../vm/probe_support.hpp"
#include "loopback_dds.hpp"

namespace {

namespace fs = std::filesystem;
using flowsteer::vm_test::realtime_s;
using flowsteer::vm_test::start_logged;

// A stop may take the loop's pass in which the fault is seen (perception at 160x120 takes
// milliseconds) plus DDS delivery on loopback; 0.5 s as the VM test allows.
constexpr double kStopWithin_s = 0.5;
constexpr double kCameraTimeout_s = 0.5;
constexpr double kOdomTimeout_s = 0.4;
// The peers' lens without their CameraInfo: 160 px wide at a focal length of 100 px.
const std::string kPeerLens = "  horizontal_fov_rad: 1.349482\n";

struct Command {
  double t_s;
  double linear;
  double angular;
  bool moves() const { return linear != 0.0 || angular != 0.0; }
};

struct PeerRecord {
  std::vector<Command> commands;
  std::map<std::string, double> events;
};

PeerRecord read_record(const std::string& path) {
  PeerRecord record;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string kind, time, rest;
    std::getline(fields, kind, ',');
    std::getline(fields, time, ',');
    std::getline(fields, rest);
    if (kind == "cmd") {
      const auto comma = rest.find(',');
      record.commands.push_back(
          {std::stod(time), std::stod(rest.substr(0, comma)), std::stod(rest.substr(comma + 1))});
    } else if (kind == "event") {
      record.events[rest] = std::stod(time);
    }
  }
  return record;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Waits for the process to exit, up to timeout_s; its exit status, or -1 (then killed).
int wait_exit(pid_t pid, double timeout_s, double* exited_s = nullptr) {
  const double deadline_s = realtime_s() + timeout_s;
  for (;;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      if (exited_s != nullptr) {
        *exited_s = realtime_s();
      }
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    if (realtime_s() > deadline_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

struct Peer {
  const char* name;
  const char* program;
};

class Ros2Robot : public ::testing::TestWithParam<Peer> {
 protected:
  void SetUp() override {
    flowsteer::ros2_dds_test::use_loopback_dds();
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::path(FLOWSTEER_TEST_OUT) / GetParam().name / name.substr(0, name.find('/'));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A domain of its own for each case and peer: cases that run at once (ctest -j, each case a
    // process) or one after the other never hear each other.
    const std::string cases[] = {"SigintStopsTheBaseWithTwistStampedAndCameraInfo",
                                 "SigtermStopsTheBaseWithTwist", "ACameraGoneSilentStopsTheBase",
                                 "OdometryGoneSilentStopsTheBaseAndFailsTheRun",
                                 "AnUnreadableEncodingEndsTheRunBeforeAnyCommand"};
    const auto found =
        std::find(std::begin(cases), std::end(cases), name.substr(0, name.find('/')));
    ASSERT_NE(found, std::end(cases)) << "give " << name << " a domain";
    domain_ = 150 + static_cast<int>(found - std::begin(cases)) +
              (std::string(GetParam().name) == "fastdds" ? 10 : 0);
  }

  std::string path(const std::string& file) const { return (dir_ / file).string(); }

  // camera_ros2: more of camera.ros2; lens: more of camera.
  std::string write_launch(const std::string& camera_ros2, const std::string& lens,
                           const std::string& cmd_vel) const {
    const std::string d = std::to_string(domain_);
    std::ofstream(path("robot.yaml"))
        << "camera:\n"
           "  type: ros2\n"
           "  timeout_s: "
        << kCameraTimeout_s
        << "\n"
           "  ros2:\n"
           "    domain_id: "
        << d
        << "\n"
           "    image: {topic: /camera/image_raw, type: sensor_msgs/msg/Image}\n"
        << camera_ros2 << lens
        << "drive:\n"
           "  type: ros2\n"
           "  loop_rate_hz: 50\n"
           "  geometry: {wheel_separation_m: 0.3, wheel_radius_m: 0.05}\n"
           "  limits: {max_speed_mps: 0.4, max_accel_mps2: 0.5, max_turn_rate: 1.0}\n"
           "  watchdog: {timeout_s: 0.25, ramp_s: 0.1}\n"
           "  ros2:\n"
           "    domain_id: "
        << d
        << "\n"
           "    cmd_vel: "
        << cmd_vel
        << "\n"
           "    odom: {topic: /odom, type: nav_msgs/msg/Odometry}\n"
           "    timeout_s: "
        << kOdomTimeout_s
        << "\n"
           "perception: {flow: dis_fast, segmentation: flow_graph_fast, height_m: 0.3, pitch_deg: "
           "0}\n"
           "controller: {preferred_speed_mps: 0.3, robot_width_m: 0.3, max_accel_mps2: 0.5, "
           "max_turn_rate: 1.0}\n"
           "goal: {bearing_rad: 0.0, distance_m: 5.0}\n";
    return path("robot.yaml");
  }

  pid_t start_peer(std::vector<std::string> extra) const {
    std::vector<std::string> args = {
        GetParam().program, "--domain", std::to_string(domain_), "--record", path("peer.csv"),
        "--duration",       "40"};
    args.insert(args.end(), extra.begin(), extra.end());
    return start(path("peer.log"), args);
  }

  pid_t start_flowsteer(const std::string& launch) const {
    return start(path("flowsteer.log"), {FLOWSTEER_BIN, "run", launch});
  }

  static pid_t start(const std::string& log, const std::vector<std::string>& args) {
    std::vector<const char*> argv;
    for (const std::string& a : args) {
      argv.push_back(a.c_str());
    }
    return start_logged(log, argv);
  }

  // Waits until the peer has taken a command that moves the base; its time, or NaN.
  double wait_until_moving(double timeout_s) const {
    const double deadline_s = realtime_s() + timeout_s;
    while (realtime_s() < deadline_s) {
      const PeerRecord record = read_record(path("peer.csv"));
      if (record.events.count("moving") != 0) {
        return record.events.at("moving");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return NAN;
  }

  // The checks of every stop: driven before the fault, a zero within `bound_s` of it, nothing
  // that moves the base after that zero, the last command a zero.
  void expect_stopped(const PeerRecord& record, double fault_s, double bound_s) const {
    int driven = 0;
    const Command* first_zero = nullptr;
    for (const Command& c : record.commands) {
      driven += c.t_s < fault_s && c.moves() ? 1 : 0;
      if (first_zero == nullptr && c.t_s >= fault_s && !c.moves()) {
        first_zero = &c;
      }
    }
    EXPECT_GE(driven, 10) << "the base was hardly driven before the fault";
    ASSERT_NE(first_zero, nullptr) << "no zero command after the fault";
    EXPECT_LT(first_zero->t_s - fault_s, bound_s);
    for (const Command& c : record.commands) {
      EXPECT_FALSE(c.t_s > first_zero->t_s && c.moves())
          << "moved at " << c.t_s - fault_s << " s after the fault, after the stop";
    }
    EXPECT_FALSE(record.commands.back().moves());
    std::printf("first zero command %.1f ms after the fault (bound %.1f ms)\n",
                1e3 * (first_zero->t_s - fault_s), 1e3 * bound_s);
  }

  // Runs until the base moves, sends `signal` 1.5 s later, and checks the stop: exit 0.
  void expect_signal_stops(int signal, const std::string& launch,
                           const std::vector<std::string>& peer_options) {
    const pid_t peer = start_peer(peer_options);
    const pid_t run = start_flowsteer(launch);
    ASSERT_TRUE(std::isfinite(wait_until_moving(30.0))) << read_file(path("flowsteer.log"));
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    const double fault_s = realtime_s();
    ::kill(run, signal);
    const int status = wait_exit(run, 10.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ::kill(peer, SIGTERM);
    EXPECT_EQ(wait_exit(peer, 10.0), 0) << read_file(path("peer.log"));
    const std::string log = read_file(path("flowsteer.log"));
    EXPECT_EQ(status, 0) << log;
    EXPECT_NE(log.find("stop requested: base ros2 /cmd_vel (domain " + std::to_string(domain_) +
                       ") stopped"),
              std::string::npos)
        << log;
    expect_stopped(read_record(path("peer.csv")), fault_s, kStopWithin_s);
  }

  fs::path dir_;
  int domain_ = 0;
};

TEST_P(Ros2Robot, SigintStopsTheBaseWithTwistStampedAndCameraInfo) {
  expect_signal_stops(SIGINT,
                      write_launch("    camera_info: {topic: /camera/camera_info}\n", "",
                                   "{topic: /cmd_vel, type: geometry_msgs/msg/TwistStamped, "
                                   "frame_id: base_link}"),
                      {"--stamped", "--camera-info"});
  const std::string log = read_file(path("flowsteer.log"));
  EXPECT_NE(log.find("(160x120, fx 100 px)"), std::string::npos) << "CameraInfo's lens\n" << log;
}

TEST_P(Ros2Robot, SigtermStopsTheBaseWithTwist) {
  expect_signal_stops(SIGTERM, write_launch("", kPeerLens, "{topic: /cmd_vel}"), {});
}

TEST_P(Ros2Robot, ACameraGoneSilentStopsTheBase) {
  const std::string launch = write_launch("", kPeerLens, "{topic: /cmd_vel}");
  const pid_t peer = start_peer({"--silence", "camera", "--silence-after", "2"});
  const pid_t run = start_flowsteer(launch);
  const int status = wait_exit(run, 40.0);
  ::kill(peer, SIGTERM);
  EXPECT_EQ(wait_exit(peer, 10.0), 0) << read_file(path("peer.log"));
  const std::string log = read_file(path("flowsteer.log"));
  EXPECT_EQ(status, 3) << log;  // the camera's timeout, as for V4L2
  EXPECT_NE(log.find("camera timeout"), std::string::npos) << log;
  const PeerRecord record = read_record(path("peer.csv"));
  ASSERT_EQ(record.events.count("silent camera"), 1u) << log;
  expect_stopped(record, record.events.at("silent camera"), kCameraTimeout_s + kStopWithin_s);
}

TEST_P(Ros2Robot, OdometryGoneSilentStopsTheBaseAndFailsTheRun) {
  const std::string launch = write_launch("", kPeerLens, "{topic: /cmd_vel}");
  const pid_t peer = start_peer({"--silence", "odom", "--silence-after", "2"});
  const pid_t run = start_flowsteer(launch);
  const int status = wait_exit(run, 40.0);
  ::kill(peer, SIGTERM);
  EXPECT_EQ(wait_exit(peer, 10.0), 0) << read_file(path("peer.log"));
  const std::string log = read_file(path("flowsteer.log"));
  EXPECT_EQ(status, 1) << log;
  EXPECT_NE(log.find("ros2 /cmd_vel (domain " + std::to_string(domain_) +
                     "): update failed, base stopped: no odometry on /odom for 0.4"),
            std::string::npos)
      << log;
  const PeerRecord record = read_record(path("peer.csv"));
  ASSERT_EQ(record.events.count("silent odom"), 1u) << log;
  expect_stopped(record, record.events.at("silent odom"), kOdomTimeout_s + kStopWithin_s);
}

// A camera driver publishing Bayer images: the run ends before the base was ever commanded.
TEST_P(Ros2Robot, AnUnreadableEncodingEndsTheRunBeforeAnyCommand) {
  const std::string launch = write_launch("", kPeerLens, "{topic: /cmd_vel}");
  const pid_t peer = start_peer({"--encoding", "bayer_rggb8"});
  const pid_t run = start_flowsteer(launch);
  const int status = wait_exit(run, 30.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(peer, SIGTERM);
  EXPECT_EQ(wait_exit(peer, 10.0), 0);
  const std::string log = read_file(path("flowsteer.log"));
  EXPECT_EQ(status, 1) << log;
  EXPECT_NE(log.find("image encoding 'bayer_rggb8' cannot be read (rgb8, bgr8, mono8"),
            std::string::npos)
      << log;
  EXPECT_TRUE(read_record(path("peer.csv")).commands.empty()) << "a command was sent";
}

INSTANTIATE_TEST_SUITE_P(Peers, Ros2Robot,
                         ::testing::Values(Peer{"cyclonedds", FLOWSTEER_CYCLONE_PEER},
                                           Peer{"fastdds", FLOWSTEER_FASTDDS_PEER}),
                         [](const ::testing::TestParamInfo<Peer>& info) {
                           return std::string(info.param.name);
                         });

}  // namespace
