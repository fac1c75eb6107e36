#include "flowsteer/drivers/command_stage.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flowsteer/base/command.hpp"

namespace flowsteer::drivers {

namespace {

void require_positive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("command stage: ") + what +
                                " must be positive and finite, got " + std::to_string(value));
  }
}

}  // namespace

WheelSpeeds to_wheels(const BodyVelocity& body, const WheelGeometry& geometry) {
  const double yaw_rate_radps = base::yaw_rate_of(body.turn_rate);
  const double half_track_m = 0.5 * geometry.wheel_separation_m;
  // A positive yaw rate (counter-clockwise seen from above) makes the right wheel roll faster.
  return {(body.speed_mps - yaw_rate_radps * half_track_m) / geometry.wheel_radius_m,
          (body.speed_mps + yaw_rate_radps * half_track_m) / geometry.wheel_radius_m};
}

BodyVelocity from_wheels(const WheelSpeeds& wheels, const WheelGeometry& geometry) {
  const double left_mps = wheels.left_radps * geometry.wheel_radius_m;
  const double right_mps = wheels.right_radps * geometry.wheel_radius_m;
  const double yaw_rate_radps = (right_mps - left_mps) / geometry.wheel_separation_m;
  return {0.5 * (left_mps + right_mps), base::turn_rate_of(yaw_rate_radps)};
}

CommandStage::CommandStage(const CommandStageConfig& config) : config_(config) {
  require_positive(config.geometry.wheel_separation_m, "wheel_separation_m");
  require_positive(config.geometry.wheel_radius_m, "wheel_radius_m");
  require_positive(config.limits.max_speed_mps, "max_speed_mps");
  require_positive(config.limits.max_accel_mps2, "max_accel_mps2");
  require_positive(config.limits.max_turn_rate, "max_turn_rate");
  require_positive(config.limits.max_wheel_speed_radps, "max_wheel_speed_radps");
  require_positive(config.watchdog.timeout_s, "watchdog timeout_s");
  if (!(config.limits.max_reverse_speed_mps >= 0.0) ||
      !std::isfinite(config.limits.max_reverse_speed_mps)) {
    throw std::invalid_argument("command stage: max_reverse_speed_mps must be >= 0 and finite");
  }
  if (!(config.watchdog.ramp_s >= 0.0) || config.watchdog.ramp_s > config.watchdog.timeout_s) {
    throw std::invalid_argument("command stage: watchdog ramp_s must lie in [0, timeout_s]");
  }
}

std::optional<std::string> CommandStage::command(const base::Command& command, double now_s) {
  if (estopped_) {
    last_rejection_ = "command rejected: emergency stop holds until cleared";
  } else if (!std::isfinite(command.accel_mps2) || !std::isfinite(command.turn_rate)) {
    last_rejection_ = "command rejected: not finite (accel_mps2 " +
                      std::to_string(command.accel_mps2) + ", turn_rate " +
                      std::to_string(command.turn_rate) + ")";
  } else if (!std::isfinite(now_s)) {
    last_rejection_ = "command rejected: time stamp not finite";
  } else {
    last_command_ = command;
    last_command_s_ = now_s;
    ramp_from_.reset();
    return std::nullopt;
  }
  return last_rejection_;
}

StageOutput CommandStage::update(double now_s) {
  const double dt_s = last_update_s_ ? std::max(0.0, now_s - *last_update_s_) : 0.0;
  last_update_s_ = now_s;
  const CommandLimits& limits = config_.limits;
  const WatchdogConfig& watchdog = config_.watchdog;

  StageOutput out;
  out.emergency_stopped = estopped_;
  const double age_s = last_command_s_ ? now_s - *last_command_s_ : watchdog.timeout_s;
  if (estopped_ || age_s >= watchdog.timeout_s) {
    speed_mps_ = 0.0;
    turn_rate_ = 0.0;
    ramp_from_.reset();
    out.watchdog_tripped = !estopped_;
  } else if (age_s >= watchdog.timeout_s - watchdog.ramp_s) {
    // The ramp reaches zero exactly at the timeout, whatever the acceleration limit says:
    // stopping in time matters more than stopping gently.
    if (!ramp_from_) {
      ramp_from_ = BodyVelocity{speed_mps_, turn_rate_};
    }
    const double fraction = (watchdog.timeout_s - age_s) / watchdog.ramp_s;
    speed_mps_ = ramp_from_->speed_mps * fraction;
    turn_rate_ = ramp_from_->turn_rate * fraction;
    out.watchdog_ramping = true;
  } else {
    const double accel_mps2 =
        std::clamp(last_command_.accel_mps2, -limits.max_accel_mps2, limits.max_accel_mps2);
    speed_mps_ = std::clamp(speed_mps_ + accel_mps2 * dt_s, -limits.max_reverse_speed_mps,
                            limits.max_speed_mps);
    turn_rate_ = std::clamp(last_command_.turn_rate, -limits.max_turn_rate, limits.max_turn_rate);
  }

  out.wheels = to_wheels({speed_mps_, turn_rate_}, config_.geometry);
  const double fastest_radps =
      std::max(std::abs(out.wheels.left_radps), std::abs(out.wheels.right_radps));
  if (fastest_radps > limits.max_wheel_speed_radps) {
    const double scale = limits.max_wheel_speed_radps / fastest_radps;
    out.wheels.left_radps *= scale;
    out.wheels.right_radps *= scale;
    // Keep the integrator at what the wheels can do, or it winds up past the limit.
    speed_mps_ *= scale;
  }
  out.body = from_wheels(out.wheels, config_.geometry);
  return out;
}

void CommandStage::emergency_stop() {
  estopped_ = true;
  speed_mps_ = 0.0;
  turn_rate_ = 0.0;
  last_command_s_.reset();
  ramp_from_.reset();
}

void CommandStage::clear_emergency_stop() {
  estopped_ = false;
}

void CommandStage::reset(double now_s) {
  speed_mps_ = 0.0;
  turn_rate_ = 0.0;
  last_command_ = {};
  last_command_s_.reset();
  last_update_s_ = now_s;
  ramp_from_.reset();
}

}  // namespace flowsteer::drivers
