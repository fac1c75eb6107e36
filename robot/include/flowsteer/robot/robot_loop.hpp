#pragma once

#include <atomic>
#include <cstddef>
#include <optional>
#include <ostream>
#include <string>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/drivers/mobile_base.hpp"
#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/servo/control.hpp"

namespace flowsteer::robot {

// The base's pose in the frame of its start (REP-103: x forward, y left, yaw positive left),
// integrated from its wheel odometry as a unicycle; wheel slip accumulates, as with any odometry.
class Odometer {
 public:
  // Moves the robot by its mean speed and turn rate (positive right) over dt_s.
  void advance(const drivers::BodyVelocity& measured, double dt_s);
  double x_m() const { return x_m_; }
  double y_m() const { return y_m_; }
  double yaw_rad() const { return yaw_rad_; }

 private:
  double x_m_ = 0.0;
  double y_m_ = 0.0;
  double yaw_rad_ = 0.0;
};

// Where the goal lies now, tracked from its bearing and distance at the start by the odometer.
class GoalTracker {
 public:
  explicit GoalTracker(const config::GoalSection& goal);
  void advance(const drivers::BodyVelocity& measured, double dt_s) {
    odometer_.advance(measured, dt_s);
  }
  // Bearing from the robot's heading, positive to the right, in (-π, π].
  double bearing_rad() const;
  double distance_m() const;

 private:
  // The goal in the start pose's frame.
  double goal_x_m_;
  double goal_y_m_;
  Odometer odometer_;
};

// What the loop gives the perception and control stages for one frame.
struct LoopInput {
  const camera_io::Frame& frame;
  drivers::BodyVelocity measured;  // from the base; zero without one
  std::optional<double> goal_bearing_rad;
  std::optional<double> goal_distance_m;
};

// Turns a frame into a command: the robot's pipeline::Brain (RobotBrain), or a test's stand-in
// for it.
class FrameHandler {
 public:
  virtual ~FrameHandler() = default;
  virtual base::Command step(const LoopInput& input) = 0;
};

enum class StopReason { end_of_stream, camera_timeout, stop_requested, frame_limit };
const char* stop_reason_name(StopReason reason);

struct RobotLoopOptions {
  double camera_timeout_s = 0.5;
  // How often the base is updated while waiting for frames (the drive's loop rate).
  double drive_period_s = 0.02;
  std::optional<config::GoalSection> goal;
  std::size_t max_frames = 0;          // 0: no limit
  std::string camera_name = "camera";  // for the log
  // Where the loop records /cmd_vel (the wheel speeds written to the drive, as the body's
  // velocity) and /odom at every update of the base; none: nothing recorded.
  pipeline::RunRecorder* recorder = nullptr;
};

struct RobotLoopResult {
  StopReason reason = StopReason::end_of_stream;
  std::size_t frames = 0;
  // Frames equal to the one before to the last byte while the base moves: a capture device
  // faster than its source (an HDMI grabber, vivid's loop) repeats a picture, which carries no
  // motion, so the brain does not see it; the last command stands until a new picture comes. (On
  // a base at rest in a still scene the same picture is the truth, and the brain sees it.)
  std::size_t repeated_frames = 0;
  double duration_s = 0.0;
  double max_measured_speed_mps = 0.0;  // the fastest the base was measured to go
};

// The robot's loop: camera → brain → base, at the camera's rate, with the base updated at the
// drive's rate in between (its stream and watchdog need that). The base (may be null) is
// configured and activated here and is always left stopped and deactivated: at the end of the
// recording, when the camera delivers nothing for camera_timeout_s, when stop_requested
// becomes true (a signal handler sets it), and when anything throws (the exception then
// reaches the caller after the stop). Each stop is logged with its reason.
RobotLoopResult run_robot_loop(camera_io::FrameSource& camera, drivers::MobileBase* robot_base,
                               FrameHandler& brain, const RobotLoopOptions& options,
                               const std::atomic<bool>& stop_requested, std::ostream& log);

}  // namespace flowsteer::robot
