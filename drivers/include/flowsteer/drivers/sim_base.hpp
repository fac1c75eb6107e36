#pragma once

#include <functional>
#include <optional>
#include <string_view>

#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/drivers/drive.hpp"

namespace flowsteer::drivers {

// Pose of the base in the world frame (REP-103: x forward at start, y left, yaw
// counter-clockwise from x).
struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

struct SimBaseConfig {
  WheelGeometry geometry;
  // First-order lag of each wheel's speed behind its command; 0 follows at once.
  double wheel_time_constant_s = 0.0;
  Pose2 start;
  // The simulation's clock in seconds. Empty: the monotonic clock.
  std::function<double()> clock;
};

// The unicycle the simulator drives, behind the same Drive interface as the hardware: wheel
// speeds in, the body moves, wheel odometry and measured speeds out.
class SimBase final : public Drive {
 public:
  // Throws std::invalid_argument on a bad geometry or a negative time constant.
  explicit SimBase(SimBaseConfig config);

  std::string_view name() const override { return "sim_base"; }
  void configure() override;
  void activate() override;
  void deactivate() override;
  DriveState read() override;
  void write(const WheelSpeeds& wheels) override;

  // Advances the model to the clock's now; read() and write() do this themselves.
  void advance();
  const Pose2& pose() const { return pose_; }

 private:
  enum class Phase { unconfigured, inactive, active };
  void require_active(const char* operation) const;

  SimBaseConfig config_;
  Phase phase_ = Phase::unconfigured;
  WheelSpeeds commanded_;
  WheelSpeeds actual_;
  WheelOdometry odometry_;
  Pose2 pose_;
  std::optional<double> last_s_;
};

}  // namespace flowsteer::drivers
