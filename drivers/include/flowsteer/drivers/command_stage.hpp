#pragma once

#include <optional>
#include <string>

#include "flowsteer/base/command.hpp"
#include "flowsteer/drivers/drive.hpp"

namespace flowsteer::drivers {

struct WheelGeometry {
  double wheel_separation_m = 0.4;  // between the wheels' contact points
  double wheel_radius_m = 0.05;
};

// Body velocity of the base in the controller's terms: forward speed and the turn rate ω about
// the camera's y axis, positive to the right (docs/CONVENTIONS.md).
struct BodyVelocity {
  double speed_mps = 0.0;
  double turn_rate = 0.0;  // rad/s, positive turns right
};

// The only place where the controller's turn rate meets the robot's yaw rate: ω_z = −ω_cy
// (REP-103 z points up, the camera's y points down). Both directions go through these two.
WheelSpeeds to_wheels(const BodyVelocity& body, const WheelGeometry& geometry);
BodyVelocity from_wheels(const WheelSpeeds& wheels, const WheelGeometry& geometry);

struct CommandLimits {
  double max_speed_mps = 1.0;
  double max_reverse_speed_mps = 0.0;  // the papers' agents never back up
  double max_accel_mps2 = 1.0;         // |a_c| is clamped to this
  double max_turn_rate = 1.0;          // rad/s
  // When either wheel would exceed this, both are scaled down together, which keeps the
  // curvature of the path.
  double max_wheel_speed_radps = 40.0;
};

struct WatchdogConfig {
  // A command older than this is not obeyed: by then the wheels are commanded zero.
  double timeout_s = 0.5;
  // The last stretch of the timeout during which speed and turn rate ramp linearly to zero,
  // so a stale command ends in a controlled stop rather than a jolt. 0 stops in one step.
  double ramp_s = 0.2;
};

struct CommandStageConfig {
  WheelGeometry geometry;
  CommandLimits limits;
  WatchdogConfig watchdog;
};

// What the stage decided in one update().
struct StageOutput {
  BodyVelocity body;               // after limits, watchdog and e-stop
  WheelSpeeds wheels;              // what to send to the drive
  bool watchdog_tripped = false;   // no fresh command within the timeout: wheels at zero
  bool watchdog_ramping = false;   // the command is stale and the ramp to zero is under way
  bool emergency_stopped = false;  // latched until clear_emergency_stop()
};

// Turns the controller's (a_c, ω) into wheel speeds, safely. Not thread-safe; time is the
// caller's monotonic clock in seconds, so tests can drive it with a fake clock.
class CommandStage {
 public:
  // Throws std::invalid_argument on a non-positive geometry, limit or timeout, or a ramp longer
  // than the timeout.
  explicit CommandStage(const CommandStageConfig& config);

  // Takes a fresh command. A command with NaN or Inf is rejected: it does not refresh the
  // watchdog, and the reason is returned (and kept in last_rejection()). Commands are also
  // rejected while the emergency stop holds. Returns std::nullopt when accepted.
  std::optional<std::string> command(const base::Command& command, double now_s);

  // Advances to now_s: integrates a_c into the speed, applies the limits and the watchdog and
  // maps to wheel speeds. Call it at the drive's loop rate, commands or not.
  StageOutput update(double now_s);

  void emergency_stop();
  // Releases the stop. The base stays at rest until a fresh command arrives.
  void clear_emergency_stop();
  bool emergency_stopped() const { return estopped_; }

  // Forgets speed and command, e.g. when the drive is (re)activated.
  void reset(double now_s);

  const std::optional<std::string>& last_rejection() const { return last_rejection_; }
  const CommandStageConfig& config() const { return config_; }

 private:
  CommandStageConfig config_;
  base::Command last_command_;
  std::optional<double> last_command_s_;  // none: no fresh command since reset
  std::optional<double> last_update_s_;
  double speed_mps_ = 0.0;
  double turn_rate_ = 0.0;
  // Body velocity when the watchdog's ramp began; the ramp scales it down linearly.
  std::optional<BodyVelocity> ramp_from_;
  bool estopped_ = false;
  std::optional<std::string> last_rejection_;
};

}  // namespace flowsteer::drivers
