#include "flowsteer/drivers/sim_base.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::drivers {

SimBase::SimBase(SimBaseConfig config) : config_(std::move(config)), pose_(config_.start) {
  if (!(config_.geometry.wheel_radius_m > 0.0) || !(config_.geometry.wheel_separation_m > 0.0)) {
    throw std::invalid_argument("sim_base: wheel_radius_m and wheel_separation_m must be > 0");
  }
  if (!(config_.wheel_time_constant_s >= 0.0)) {
    throw std::invalid_argument("sim_base: wheel_time_constant_s must be >= 0");
  }
  if (!config_.clock) {
    config_.clock = base::monotonic_now_s;
  }
}

void SimBase::require_active(const char* operation) const {
  if (phase_ != Phase::active) {
    throw DriveError(std::string("sim_base: ") + operation + " while not active");
  }
}

void SimBase::configure() {
  phase_ = Phase::inactive;
  odometry_ = {};
  commanded_ = {};
  actual_ = {};
  last_s_ = config_.clock();
}

void SimBase::activate() {
  if (phase_ == Phase::unconfigured) {
    throw DriveError("sim_base: activate before configure");
  }
  advance();
  commanded_ = {};
  phase_ = Phase::active;
}

void SimBase::deactivate() {
  advance();
  commanded_ = {};
  if (phase_ == Phase::active) {
    phase_ = Phase::inactive;
  }
}

void SimBase::write(const WheelSpeeds& wheels) {
  if (phase_ != Phase::unconfigured && wheels.left_radps == 0.0 && wheels.right_radps == 0.0) {
    advance();
    commanded_ = {};  // a stop, taken in any phase
    return;
  }
  require_active("write");
  if (!std::isfinite(wheels.left_radps) || !std::isfinite(wheels.right_radps)) {
    throw DriveError("sim_base: wheel speeds not finite");
  }
  advance();
  commanded_ = wheels;
}

DriveState SimBase::read() {
  if (phase_ == Phase::unconfigured) {
    throw DriveError("sim_base: read before configure");
  }
  advance();
  DriveState state;
  state.measured = actual_;
  state.odometry = odometry_;
  return state;
}

void SimBase::advance() {
  const double now_s = config_.clock();
  const double dt_s = last_s_ ? now_s - *last_s_ : 0.0;
  last_s_ = now_s;
  if (!(dt_s > 0.0)) {
    return;
  }
  // Exact solution of the first-order lag over dt with the command held; the odometry and the
  // pose use the mean wheel speed over the step.
  const double tau_s = config_.wheel_time_constant_s;
  const double keep = tau_s > 0.0 ? std::exp(-dt_s / tau_s) : 0.0;
  const double mean_factor = tau_s > 0.0 ? tau_s / dt_s * (1.0 - keep) : 0.0;
  auto step = [&](double& actual, double commanded) {
    const double mean = commanded + (actual - commanded) * mean_factor;
    actual = commanded + (actual - commanded) * keep;
    return mean;
  };
  const WheelSpeeds mean{step(actual_.left_radps, commanded_.left_radps),
                         step(actual_.right_radps, commanded_.right_radps)};
  odometry_.left_rad += mean.left_radps * dt_s;
  odometry_.right_rad += mean.right_radps * dt_s;

  const double r = config_.geometry.wheel_radius_m;
  const double speed_mps = 0.5 * r * (mean.left_radps + mean.right_radps);
  const double yaw_rate_radps =
      r * (mean.right_radps - mean.left_radps) / config_.geometry.wheel_separation_m;
  // Integrate along the arc (exact for constant speeds); fall back to a straight line when
  // the yaw rate is negligible.
  const double dyaw = yaw_rate_radps * dt_s;
  if (std::abs(dyaw) < 1e-9) {
    pose_.x_m += speed_mps * dt_s * std::cos(pose_.yaw_rad);
    pose_.y_m += speed_mps * dt_s * std::sin(pose_.yaw_rad);
  } else {
    const double radius_m = speed_mps / yaw_rate_radps;
    pose_.x_m += radius_m * (std::sin(pose_.yaw_rad + dyaw) - std::sin(pose_.yaw_rad));
    pose_.y_m -= radius_m * (std::cos(pose_.yaw_rad + dyaw) - std::cos(pose_.yaw_rad));
  }
  pose_.yaw_rad = std::remainder(pose_.yaw_rad + dyaw, 2.0 * std::numbers::pi);
}

}  // namespace flowsteer::drivers
