// The robot loop and its launch files: the shipped launch files parse, bad ones name the line
// and field, the goal is tracked by odometry, and however the loop ends (recording over,
// camera silent, stop requested, an error) the base is left stopped and deactivated.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/videoio.hpp>

#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/robot/robot_loop.hpp"
#include "robot_launch_errors.hpp"

namespace {

namespace fs = std::filesystem;
using namespace flowsteer;
using config::parse_robot_launch;

using robot::test_support::error_of;

TEST(RobotLaunch, ShippedLaunchFilesParse) {
  for (const char* name :
       {"v4l2_sim_base.yaml", "v4l2_odrive.yaml", "replay.yaml", "ros2_diff_drive.yaml"}) {
    SCOPED_TRACE(name);
    const config::RobotLaunch l =
        config::read_robot_launch(std::string(FLOWSTEER_LAUNCH_FILES_DIR) + "/" + name);
    EXPECT_TRUE(l.goal.has_value());
    EXPECT_EQ(l.drive.has_value(), std::string(name) != "replay.yaml");
  }
  const config::RobotLaunch replay =
      config::read_robot_launch(std::string(FLOWSTEER_LAUNCH_FILES_DIR) + "/replay.yaml");
  // Relative recordings are found beside the launch file.
  EXPECT_EQ(std::get<camera_io::ReplayOptions>(replay.camera.source).path,
            std::string(FLOWSTEER_LAUNCH_FILES_DIR) + "/run.mp4");
  const config::RobotLaunch v4l2 =
      config::read_robot_launch(std::string(FLOWSTEER_LAUNCH_FILES_DIR) + "/v4l2_odrive.yaml");
  const auto& o = std::get<camera_io::V4l2Options>(v4l2.camera.source);
  EXPECT_EQ(o.format, camera_io::PixelFormat::mjpeg);
  EXPECT_DOUBLE_EQ(v4l2.camera.timeout_s, 0.3);
  const config::RobotLaunch ros2 =
      config::read_robot_launch(std::string(FLOWSTEER_LAUNCH_FILES_DIR) + "/ros2_diff_drive.yaml");
  const auto& camera = std::get<camera_io::Ros2CameraOptions>(ros2.camera.source);
  EXPECT_EQ(camera.camera_info_topic, "/camera/camera_info");
  const auto& drive = std::get<drivers::Ros2DriveConfig>(ros2.drive->drive);
  EXPECT_TRUE(drive.stamped);
  EXPECT_EQ(drive.cmd_vel_topic, "/diff_drive_controller/cmd_vel");
  EXPECT_EQ(drive.odom_topic, "/diff_drive_controller/odom");
}

TEST(RobotLaunch, BadFilesNameTheLineAndField) {
  EXPECT_EQ(error_of("camera:\n  type: v4l2\n  v4l2:\n    devce: /dev/video0\n"),
            "bad.yaml:4:5: camera.v4l2.devce: unknown key (expected one of: device, width_px, "
            "height_px, frame_rate_hz, pixel_format, buffer_count)");
  EXPECT_EQ(error_of("camera:\n  timeout_s: 1\n"),
            "bad.yaml:2:3: camera.type: missing: v4l2, libcamera, replay or ros2");
  EXPECT_EQ(error_of("camera:\n  type: ros2\n  horizontal_fov_rad: 1\n  ros2:\n"
                     "    camera_info: {topic: /cam/info}\n"),
            "bad.yaml:5:18: camera.ros2.camera_info: give camera.horizontal_fov_rad or a "
            "camera_info topic, not both");
  EXPECT_EQ(error_of("camera:\n  type: ros2\n  ros2:\n    image: {type: "
                     "sensor_msgs/CompressedImage, encoding: rgb8}\n"),
            "bad.yaml:4:58: camera.ros2.image.encoding: only a sensor_msgs/msg/Image has an "
            "encoding");
  EXPECT_EQ(error_of("camera:\n  type: replay\n  v4l2: {device: /dev/video1}\n"),
            "bad.yaml:3:9: camera.v4l2: settings for another camera than type 'replay'");
  EXPECT_EQ(error_of("camera:\n  type: v4l2\n  v4l2: {pixel_format: RGB3}\n"),
            "bad.yaml:3:24: camera.v4l2.pixel_format: expected one of: YUYV, MJPG, MJPEG, GREY; "
            "got 'RGB3'");
  EXPECT_EQ(error_of("camera:\n  type: replay\n"),
            "bad.yaml:1:1: camera.replay.path: missing: the video file or image pattern to "
            "replay");
  EXPECT_EQ(error_of("camera: {type: replay, replay: {path: a.mp4}}\ngoal: {bearing_rad: 0.1}\n"),
            "bad.yaml:2:7: goal.distance_m: missing: how far the goal is");
  EXPECT_EQ(error_of("camera: {type: replay, replay: {path: a.mp4}}\ngoal: {distance_m: -1}\n"),
            "bad.yaml:2:20: goal.distance_m: must be from 0.01 to 1000 m, got -1");
  EXPECT_EQ(error_of("camera: {type: v4l2, timeout_s: 0.01}\ndrive: {type: sim, loop_rate_hz: "
                     "50}\n"),
            "bad.yaml:2:34: drive.loop_rate_hz: one loop period must be shorter than "
            "camera.timeout_s");
  EXPECT_EQ(error_of("camera: {type: v4l2}\nmotors: {}\n"),
            "bad.yaml:2:1: motors: unknown key (expected one of: camera, drive, goal, perception, "
            "controller)");
  EXPECT_EQ(error_of("camera: {type: v4l2, calibration: /nonexistent/cam.yaml}\n").substr(0, 24),
            "/nonexistent/cam.yaml: c");
}

TEST(GoalTracker, StraightAheadComesCloser) {
  robot::GoalTracker goal({0.0, 5.0});
  for (int i = 0; i < 100; ++i) {
    goal.advance({1.0, 0.0}, 0.02);
  }
  EXPECT_NEAR(goal.distance_m(), 3.0, 1e-9);
  EXPECT_NEAR(goal.bearing_rad(), 0.0, 1e-9);
}

TEST(GoalTracker, TurningRightTowardsAGoalOnTheRightCentresIt) {
  robot::GoalTracker goal({std::numbers::pi / 2, 2.0});  // 2 m to the right
  EXPECT_NEAR(goal.bearing_rad(), std::numbers::pi / 2, 1e-9);
  for (int i = 0; i < 50; ++i) {
    goal.advance({0.0, std::numbers::pi / 2}, 0.02);  // a right turn of 90° in 1 s, in place
  }
  EXPECT_NEAR(goal.bearing_rad(), 0.0, 1e-9);
  EXPECT_NEAR(goal.distance_m(), 2.0, 1e-9);
  goal.advance({0.0, -std::numbers::pi}, 1.0);  // half a turn left: the goal is behind, right
  EXPECT_NEAR(std::abs(goal.bearing_rad()), std::numbers::pi, 1e-9);
}

// Accelerates and, like a real pipeline, takes time over each frame.
class ForwardBrain : public robot::FrameHandler {
 public:
  base::Command step(const robot::LoopInput& input) override {
    ++frames;
    last_goal_distance_m = input.goal_distance_m;
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
    return {1.0, 0.0};
  }
  int frames = 0;
  std::optional<double> last_goal_distance_m;
};

// A camera that delivers `frames` frames 20 ms apart, each a new picture (or all one picture, as
// a frozen source gives), then nothing, or throws.
class StallingCamera : public camera_io::FrameSource {
 public:
  StallingCamera(int frames, bool throw_after, bool one_picture = false)
      : frames_(frames), throw_after_(throw_after), one_picture_(one_picture) {
    intrinsics_ = base::CameraIntrinsics::from_horizontal_fov(32, 24, 1.0);
  }
  const base::CameraIntrinsics& intrinsics() const override { return intrinsics_; }
  camera_io::ReadStatus read(camera_io::Frame& frame, double timeout_s) override {
    if (delivered_ >= frames_) {
      if (throw_after_) {
        throw std::runtime_error("camera unplugged");
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(timeout_s));
      return camera_io::ReadStatus::timeout;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    frame.image = cv::Mat(24, 32, CV_8UC3, cv::Scalar::all(one_picture_ ? 100 : delivered_ % 250));
    frame.sequence = static_cast<std::uint64_t>(delivered_++);
    return camera_io::ReadStatus::ok;
  }

 private:
  int frames_;
  bool throw_after_;
  bool one_picture_;
  int delivered_ = 0;
  base::CameraIntrinsics intrinsics_;
};

std::unique_ptr<drivers::MobileBase> sim_base() {
  const config::RobotLaunch l = parse_robot_launch(
      "camera: {type: replay, replay: {path: x.avi}}\n"
      "drive: {type: sim, loop_rate_hz: 50, watchdog: {timeout_s: 0.3, ramp_s: 0.1}}\n"
      "perception: {height_m: 0.3}\n",
      "test.yaml", "");
  return config::make_base(*l.drive);
}

TEST(RobotLoop, ReplayEndStopsTheBaseAndSaysSo) {
  const fs::path video = fs::path(::testing::TempDir()) / "robot_loop_replay.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0,
                           {32, 24});
    for (int i = 0; i < 20; ++i) {
      writer.write(cv::Mat(24, 32, CV_8UC3, cv::Scalar::all(10 * i)));
    }
  }
  camera_io::ReplayOptions replay;
  replay.path = video.string();
  camera_io::ReplaySource camera(replay);
  auto base = sim_base();
  ForwardBrain brain;
  robot::RobotLoopOptions options;
  options.camera_name = "replay " + video.string();
  options.goal = config::GoalSection{0.0, 10.0};
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const auto result = robot::run_robot_loop(camera, base.get(), brain, options, stop, log);
  EXPECT_EQ(result.reason, robot::StopReason::end_of_stream);
  EXPECT_EQ(result.frames, 20u);
  EXPECT_EQ(brain.frames, 20);
  EXPECT_GT(result.max_measured_speed_mps, 0.1) << "the base never moved";
  ASSERT_TRUE(brain.last_goal_distance_m.has_value());
  EXPECT_LT(*brain.last_goal_distance_m, 10.0) << "odometry did not bring the goal closer";
  EXPECT_EQ(base->lifecycle(), drivers::Lifecycle::inactive);
  EXPECT_EQ(log.str(),
            "flowsteer run: replay " + video.string() + " ended: base sim_base stopped\n");
  fs::remove(video);
}

TEST(RobotLoop, ACameraTimeoutStopsTheMovingBaseWithinTheTimeout) {
  StallingCamera camera(15, false);
  auto base = sim_base();
  ForwardBrain brain;
  robot::RobotLoopOptions options;
  options.camera_timeout_s = 0.2;
  options.camera_name = "camera /dev/video0";
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const auto start = std::chrono::steady_clock::now();
  const auto result = robot::run_robot_loop(camera, base.get(), brain, options, stop, log);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(result.reason, robot::StopReason::camera_timeout);
  EXPECT_EQ(result.frames, 15u);
  EXPECT_GT(result.max_measured_speed_mps, 0.1);
  EXPECT_EQ(base->lifecycle(), drivers::Lifecycle::inactive);
  EXPECT_TRUE(base->stage().emergency_stopped());
  // 15 frames of 20 ms plus 15 ms each, then the timeout and at most a drive period more.
  EXPECT_LT(elapsed_s, 15 * 0.035 + 0.2 + 0.1);
  EXPECT_NE(log.str().find("flowsteer run: camera /dev/video0 delivered no frame for 0.2"),
            std::string::npos)
      << log.str();
  EXPECT_NE(log.str().find("(timeout 0.20 s): base sim_base stopped"), std::string::npos)
      << log.str();
}

TEST(RobotLoop, ARepeatedPictureIsNotSeenAgainAndAFrozenOneStopsTheBase) {
  StallingCamera camera(1000, false, true);
  auto base = sim_base();
  ForwardBrain brain;
  robot::RobotLoopOptions options;
  options.camera_timeout_s = 0.2;
  options.camera_name = "camera /dev/video0";
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const auto result = robot::run_robot_loop(camera, base.get(), brain, options, stop, log);
  EXPECT_EQ(result.reason, robot::StopReason::camera_timeout);
  // The brain sees the picture until the base moves, then no more.
  EXPECT_LT(brain.frames, 5);
  EXPECT_GE(result.frames, 9u);
  EXPECT_EQ(result.repeated_frames, result.frames - static_cast<std::size_t>(brain.frames));
  EXPECT_TRUE(base->stage().emergency_stopped());
  EXPECT_NE(log.str().find("flowsteer run: camera /dev/video0 repeated one picture for 0.2"),
            std::string::npos)
      << log.str();
}

TEST(RobotLoop, AStopRequestStopsTheBase) {
  StallingCamera camera(1000, false);
  auto base = sim_base();
  ForwardBrain brain;
  std::atomic<bool> stop{false};
  std::ostringstream log;
  std::thread signaller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    stop = true;
  });
  const auto result = robot::run_robot_loop(camera, base.get(), brain, {}, stop, log);
  signaller.join();
  EXPECT_EQ(result.reason, robot::StopReason::stop_requested);
  EXPECT_GT(result.max_measured_speed_mps, 0.1);
  EXPECT_EQ(base->lifecycle(), drivers::Lifecycle::inactive);
  EXPECT_EQ(log.str(), "flowsteer run: stop requested: base sim_base stopped\n");
}

TEST(RobotLoop, ACameraErrorStopsTheBaseBeforeItIsReported) {
  StallingCamera camera(10, true);
  auto base = sim_base();
  ForwardBrain brain;
  std::atomic<bool> stop{false};
  std::ostringstream log;
  EXPECT_THROW(robot::run_robot_loop(camera, base.get(), brain, {}, stop, log), std::runtime_error);
  EXPECT_EQ(base->lifecycle(), drivers::Lifecycle::inactive);
  EXPECT_TRUE(base->stage().emergency_stopped());
}

}  // namespace
