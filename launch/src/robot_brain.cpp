#include "flowsteer/launch/robot_brain.hpp"

#include <chrono>
#include <iomanip>

#include "flowsteer/launch/agent_pipeline.hpp"

namespace flowsteer::launch {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

PerceptionOptions perception_options(const PerceptionSection& section) {
  PerceptionOptions options;
  options.flow = section.flow;
  options.segmentation = section.segmentation;
  options.dark_regions = section.dark_regions;
  options.use_depth = false;
  // Without a mount there is no drive, so the speed is zero and the ground test is skipped.
  options.mount = section.mount.value_or(base::CameraMount{});
  return options;
}

PerceptionBrain::PerceptionBrain(const base::CameraIntrinsics& intrinsics,
                                 const PerceptionSection& perception,
                                 const ControllerSection& controller, std::ostream& log,
                                 std::ostream* frame_log)
    : perception_(intrinsics, perception_options(perception)),
      controller_(make_controller(controller.spec, controller.robot_width_m,
                                  controller.preferred_speed_mps)),
      max_accel_mps2_(controller.spec.max_accel_mps2),
      log_(log),
      frame_log_(frame_log) {}

base::Command PerceptionBrain::step(const LoopInput& input) {
  const auto start = Clock::now();
  times_ = {};
  const double speed_mps = input.measured.speed_mps;
  const servo::FlowStatus status =
      perception_.process(input.frame, speed_mps, input.measured.turn_rate, times_);
  const auto control_start = Clock::now();
  percept_ = servo::Percept{perception_.objects(), input.goal_bearing_rad, input.goal_distance_m,
                            std::nullopt};
  controller_.step(percept_, {speed_mps}, output_);
  if (status != servo::FlowStatus::ok) {
    // A blind frame has no objects, so only the goal term turns; the speed term's acceleration
    // gives way to braking, only while moving: the drive never backs up, and a stopped robot
    // stays put.
    output_.command.accel_mps2 = speed_mps > 0.0 ? -max_accel_mps2_ : 0.0;
  }
  const auto end = Clock::now();
  times_.control = std::chrono::duration<double, std::milli>(end - control_start).count();
  times_.total = std::chrono::duration<double, std::milli>(end - start).count();

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
                << perception_.objects().size() << " accel_mps2 " << output_.command.accel_mps2
                << " turn_rate " << output_.command.turn_rate << std::defaultfloat << "\n";
  }
  return output_.command;
}

}  // namespace flowsteer::launch
