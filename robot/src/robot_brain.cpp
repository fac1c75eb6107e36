#include "flowsteer/robot/robot_brain.hpp"

#include <iomanip>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::robot {

pipeline::BrainConfig robot_brain_config(const config::PerceptionSection& perception,
                                         const config::ControllerSection& controller) {
  pipeline::BrainConfig config;
  config.controller = controller.spec;
  // Without a mount there is no drive, so the speed is zero and the ground test is skipped, and
  // nothing says where the ground is: no depth from it either. Dark regions follow
  // controller.delta > 0, as in the simulator; the reader has checked that
  // perception.dark_regions says the same.
  config.controller.use_depth = controller.spec.use_depth && perception.mount.has_value();
  servo::PerceptionConfig methods{perception.flow, perception.segmentation};
  methods.obstacle_memory = perception.obstacle_memory;
  config.perception = pipeline::perception_options(methods, config.controller,
                                                   perception.mount.value_or(base::CameraMount{}));
  config.agent_width_m = controller.robot_width_m;
  config.preferred_speed_mps = controller.preferred_speed_mps;
  return config;
}

RobotBrain::RobotBrain(const base::CameraIntrinsics& intrinsics,
                       const pipeline::BrainConfig& config, std::ostream& log,
                       std::ostream* frame_log, bool live_camera)
    : brain_(intrinsics, config), log_(log), frame_log_(frame_log), live_camera_(live_camera) {}

base::Command RobotBrain::step(const LoopInput& input) {
  const servo::ControlOutput& output = brain_.step(
      {input.frame, input.measured.speed_mps, input.measured.turn_rate, input.goal_bearing_rad,
       input.goal_distance_m, std::nullopt, std::nullopt, false});
  const servo::FlowStatus status = brain_.status();
  if (logged_status_ != status) {
    log_ << "flowsteer run: frame " << input.frame.sequence << ": ";
    if (status == servo::FlowStatus::ok) {
      log_ << "flow ok, steering by the features";
    } else {
      log_ << "blind (" << servo::to_string(status)
           << "): braking to a stop, holding the goal heading, no avoidance";
    }
    log_ << "\n";
    logged_status_ = status;
  }
  if (frame_log_ != nullptr) {
    *frame_log_ << "frame " << input.frame.sequence << " t_s " << std::fixed << std::setprecision(3)
                << input.frame.timestamp_s << " " << servo::to_string(status) << " objects "
                << brain_.objects().size() << " accel_mps2 " << output.command.accel_mps2
                << " turn_rate " << output.command.turn_rate;
    if (live_camera_) {
      *frame_log_ << " latency_ms " << 1e3 * (base::monotonic_now_s() - input.frame.timestamp_s);
    }
    *frame_log_ << std::defaultfloat << "\n";
  }
  if (recorder_ != nullptr) {
    recorder_->percept(0, recording::nanoseconds(input.frame.timestamp_s), brain_,
                       input.frame.image);
  }
  return output.command;
}

}  // namespace flowsteer::robot
