#include "flowsteer/robot/robot_loop.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <iomanip>
#include <sstream>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/command.hpp"
#include "flowsteer/pipeline/brain.hpp"

namespace flowsteer::robot {
namespace {

bool same_picture(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

// Above an encoder's noise at rest.
bool moving(const drivers::BodyVelocity& measured) {
  return std::abs(measured.speed_mps) > 0.01 || std::abs(measured.turn_rate) > 0.01;
}

// Records the zero a stop wrote to the drive. A recording that cannot be written (a full disk)
// must not keep the base from being stopped and deactivated: its failure is logged, not thrown.
void record_stop(pipeline::RunRecorder* recorder, std::ostream& log) noexcept {
  if (recorder == nullptr) {
    return;
  }
  try {
    recorder->command(0, recording::nanoseconds(base::monotonic_now_s()), 0.0, 0.0);
  } catch (const std::exception& e) {
    log << "flowsteer run: recording the stop failed: " << e.what() << "\n";
  }
}

// Leaves the base stopped and deactivated however the loop ends; when an error ends it (the
// camera gone, a perception failure) the log says the base was stopped before the error shows.
class BaseStopper {
 public:
  BaseStopper(drivers::MobileBase* robot_base, pipeline::RunRecorder* recorder, std::ostream& log)
      : base_(robot_base),
        recorder_(recorder),
        log_(log),
        exceptions_(std::uncaught_exceptions()) {}
  ~BaseStopper() {
    if (base_ == nullptr || base_->lifecycle() != drivers::Lifecycle::active) {
      return;
    }
    try {
      base_->emergency_stop();
      base_->deactivate();
      record_stop(recorder_, log_);
      if (std::uncaught_exceptions() > exceptions_) {
        log_ << "flowsteer run: the run failed: base " << base_->drive().name() << " stopped\n";
      }
    } catch (const std::exception& e) {
      log_ << "flowsteer run: stopping " << base_->drive().name() << " failed: " << e.what()
           << "\n";
    }
  }
  BaseStopper(const BaseStopper&) = delete;
  BaseStopper& operator=(const BaseStopper&) = delete;

 private:
  drivers::MobileBase* base_;
  pipeline::RunRecorder* recorder_;
  std::ostream& log_;
  int exceptions_;
};

// The mean motion between two odometry readings dt_s apart. The wheels' angles, not their speeds
// at the readings: a command that changed between them would turn the tracked heading away from
// the robot's, most in the quick back-and-forth of avoidance.
drivers::BodyVelocity travelled(const drivers::WheelOdometry& from,
                                const drivers::WheelOdometry& to, double dt_s,
                                const drivers::WheelGeometry& geometry) {
  return drivers::from_wheels(
      {(to.left_rad - from.left_rad) / dt_s, (to.right_rad - from.right_rad) / dt_s}, geometry);
}

// What the drive was just sent, as the body's velocity from the wheel speeds on the wire (after
// every limit, the watchdog and a stop), and where the odometry puts the base.
void record_update(pipeline::RunRecorder& recorder, double t_s, const drivers::BaseState& state,
                   const drivers::WheelGeometry& geometry, const Odometer& odometer) {
  const std::uint64_t t_ns = recording::nanoseconds(t_s);
  const drivers::BodyVelocity sent = drivers::from_wheels(state.sent.wheels, geometry);
  recorder.command(0, t_ns, sent.speed_mps, sent.turn_rate);
  recorder.odometry(0, t_ns, odometer.x_m(), odometer.y_m(), odometer.yaw_rad(),
                    state.measured.speed_mps, state.measured.turn_rate);
  recorder.write_transforms(t_ns);
}

}  // namespace

void Odometer::advance(const drivers::BodyVelocity& measured, double dt_s) {
  const double yaw_rate = base::yaw_rate_of(measured.turn_rate);
  const double mid_yaw = yaw_rad_ + 0.5 * yaw_rate * dt_s;
  x_m_ += measured.speed_mps * std::cos(mid_yaw) * dt_s;
  y_m_ += measured.speed_mps * std::sin(mid_yaw) * dt_s;
  yaw_rad_ += yaw_rate * dt_s;
}

GoalTracker::GoalTracker(const config::GoalSection& goal)
    : goal_x_m_(goal.distance_m * std::cos(goal.bearing_rad)),
      goal_y_m_(-goal.distance_m * std::sin(goal.bearing_rad)) {}

double GoalTracker::bearing_rad() const {
  return pipeline::goal_bearing_rad(goal_x_m_ - odometer_.x_m(), goal_y_m_ - odometer_.y_m(),
                                    odometer_.yaw_rad());
}

double GoalTracker::distance_m() const {
  return std::hypot(goal_x_m_ - odometer_.x_m(), goal_y_m_ - odometer_.y_m());
}

const char* stop_reason_name(StopReason reason) {
  switch (reason) {
    case StopReason::end_of_stream:
      return "end of stream";
    case StopReason::camera_timeout:
      return "camera timeout";
    case StopReason::stop_requested:
      return "stop requested";
    case StopReason::frame_limit:
      return "frame limit";
  }
  return "?";
}

RobotLoopResult run_robot_loop(camera_io::FrameSource& camera, drivers::MobileBase* robot_base,
                               FrameHandler& brain, const RobotLoopOptions& options,
                               const std::atomic<bool>& stop_requested, std::ostream& log) {
  RobotLoopResult result;
  const double start_s = base::monotonic_now_s();
  std::optional<GoalTracker> goal;
  if (options.goal) {
    goal.emplace(*options.goal);
  }
  BaseStopper stopper(robot_base, options.recorder, log);
  if (robot_base != nullptr) {
    robot_base->configure();
    robot_base->activate(base::monotonic_now_s());
  }
  drivers::BodyVelocity measured;
  double last_frame_s = base::monotonic_now_s();
  double last_update_s = last_frame_s;
  drivers::WheelOdometry last_odometry;  // since configure(): zero
  Odometer odometer;
  camera_io::Frame frame;
  cv::Mat last_picture;  // the last frame the brain saw
  const auto stop = [&](StopReason reason, const std::string& why) {
    result.reason = reason;
    log << "flowsteer run: " << why;
    if (robot_base != nullptr) {
      // The stopper deactivates; latching the stop first makes the zero immediate.
      robot_base->emergency_stop();
      record_stop(options.recorder, log);
      log << ": base " << robot_base->drive().name() << " stopped";
    }
    log << "\n";
  };
  for (;;) {
    if (stop_requested.load()) {
      stop(StopReason::stop_requested, "stop requested");
      break;
    }
    const double now_s = base::monotonic_now_s();
    const double left_s = options.camera_timeout_s - (now_s - last_frame_s);
    // Without a base nothing needs a steady rate: wait for the frame up to the timeout.
    const double wait_s =
        std::max(0.0, robot_base != nullptr ? std::min(options.drive_period_s, left_s) : left_s);
    const camera_io::ReadStatus status = camera.read(frame, wait_s);
    const double after_s = base::monotonic_now_s();
    if (status == camera_io::ReadStatus::end_of_stream) {
      stop(StopReason::end_of_stream, options.camera_name + " ended");
      break;
    }
    bool repeated = false;
    if (status == camera_io::ReadStatus::ok) {
      ++result.frames;
      repeated = moving(measured) && same_picture(frame.image, last_picture);
      result.repeated_frames += repeated ? 1 : 0;
      if (!repeated) {
        last_frame_s = after_s;
        frame.image.copyTo(last_picture);
        LoopInput input{frame, measured, std::nullopt, std::nullopt};
        if (goal) {
          input.goal_bearing_rad = goal->bearing_rad();
          input.goal_distance_m = goal->distance_m();
        }
        const base::Command command = brain.step(input);
        if (robot_base != nullptr) {
          if (const auto rejected = robot_base->command(command, base::monotonic_now_s())) {
            log << "flowsteer run: frame " << frame.sequence << ": command rejected: " << *rejected
                << "\n";
          }
        }
      }
    }
    // A picture repeated for as long while the base moves counts as none: a frozen source must
    // not keep the robot on its last command.
    if (after_s - last_frame_s >= options.camera_timeout_s) {
      std::ostringstream why;
      why << options.camera_name
          << (repeated ? " repeated one picture for " : " delivered no frame for ") << std::fixed
          << std::setprecision(2) << after_s - last_frame_s << " s (timeout "
          << options.camera_timeout_s << " s)";
      stop(StopReason::camera_timeout, why.str());
      break;
    }
    if (robot_base != nullptr) {
      const double update_s = base::monotonic_now_s();
      const drivers::BaseState state = robot_base->update(update_s);
      measured = state.measured;
      result.max_measured_speed_mps = std::max(result.max_measured_speed_mps, measured.speed_mps);
      const drivers::WheelGeometry& geometry = robot_base->stage().config().geometry;
      if (update_s > last_update_s) {
        const double dt_s = update_s - last_update_s;
        const drivers::BodyVelocity moved =
            travelled(last_odometry, state.drive.odometry, dt_s, geometry);
        odometer.advance(moved, dt_s);
        if (goal) {
          goal->advance(moved, dt_s);
        }
      }
      last_update_s = update_s;
      last_odometry = state.drive.odometry;
      if (options.recorder != nullptr) {
        record_update(*options.recorder, update_s, state, geometry, odometer);
      }
    }
    if (options.max_frames > 0 && result.frames >= options.max_frames) {
      stop(StopReason::frame_limit, "frame limit reached");
      break;
    }
  }
  result.duration_s = base::monotonic_now_s() - start_s;
  return result;
}

}  // namespace flowsteer::robot
