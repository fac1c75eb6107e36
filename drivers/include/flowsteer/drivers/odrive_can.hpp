#pragma once

#include <linux/can.h>

#include <array>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>

#include "flowsteer/base/unique_fd.hpp"
#include "flowsteer/drivers/drive.hpp"

namespace flowsteer::drivers {

// ODrive's CAN Simple protocol as of firmware 0.5.x: 11-bit ids node_id << 5 | cmd_id,
// little-endian payloads.
namespace odrive {

inline constexpr std::uint32_t kHeartbeat = 0x01;
inline constexpr std::uint32_t kSetAxisRequestedState = 0x07;
inline constexpr std::uint32_t kGetEncoderEstimates = 0x09;
inline constexpr std::uint32_t kSetControllerModes = 0x0b;
inline constexpr std::uint32_t kSetInputVel = 0x0d;

inline constexpr std::uint32_t kAxisStateIdle = 1;
inline constexpr std::uint32_t kAxisStateClosedLoop = 8;
inline constexpr std::int32_t kControlModeVelocity = 2;
// The command stage already limits acceleration, so the ODrive takes the input as it is.
inline constexpr std::int32_t kInputModePassthrough = 1;

inline constexpr std::uint8_t kMaxNodeId = 0x3f;

std::uint32_t frame_id(std::uint8_t node_id, std::uint32_t cmd_id);
std::uint8_t node_of(canid_t id);
std::uint32_t cmd_of(canid_t id);

can_frame set_axis_requested_state(std::uint8_t node_id, std::uint32_t state);
can_frame set_controller_modes(std::uint8_t node_id, std::int32_t control_mode,
                               std::int32_t input_mode);
can_frame set_input_vel(std::uint8_t node_id, float vel_turns_per_s, float torque_ff_nm);
// A remote (RTR) frame: the axis answers with its position and velocity estimates.
can_frame get_encoder_estimates(std::uint8_t node_id);

struct Heartbeat {
  std::uint32_t axis_error = 0;
  std::uint8_t axis_state = 0;
  bool motor_error = false;
  bool encoder_error = false;
  bool controller_error = false;
};
can_frame heartbeat_frame(std::uint8_t node_id, const Heartbeat& heartbeat);
// std::nullopt when the frame is too short to be one.
std::optional<Heartbeat> parse_heartbeat(const can_frame& frame);

struct EncoderEstimates {
  float pos_turns = 0.0f;
  float vel_turns_per_s = 0.0f;
};
can_frame encoder_estimates_frame(std::uint8_t node_id, const EncoderEstimates& estimates);
std::optional<EncoderEstimates> parse_encoder_estimates(const can_frame& frame);

// "0x00000800 (WATCHDOG_TIMER_EXPIRED)"; bits without a 0.5.x name are shown as hex.
std::string describe_axis_error(std::uint32_t axis_error);

}  // namespace odrive

// A frame and when the kernel received it, on base::monotonic_now_s()'s clock.
struct ReceivedCanFrame {
  can_frame frame;
  double received_s;
};

// A raw SocketCAN socket bound to one interface, non-blocking, with deadlines on every wait.
// Frames carry the kernel's receive time, so a loop that reads once a period still dates each
// to when it came, not to when the loop got to it.
class CanSocket {
 public:
  // Throws DriveError naming the interface when it does not exist or the socket fails.
  explicit CanSocket(const std::string& interface);
  // Only frames whose id matches one of these (id & mask) are received; none: all.
  void set_filters(const can_filter* filters, std::size_t count);
  void send(const can_frame& frame, double timeout_s);
  // The next frame, or std::nullopt when none arrives within timeout_s (0: only what waits).
  std::optional<ReceivedCanFrame> receive(double timeout_s);
  const std::string& interface() const { return interface_; }

 private:
  std::string interface_;
  base::UniqueFd fd_;
};

struct OdriveAxisConfig {
  std::uint8_t node_id = 0;
  // +1 when the motor turning forward rolls the wheel forward; −1 for the mirrored side.
  double direction = 1.0;
};

struct OdriveCanConfig {
  std::string interface = "can0";
  OdriveAxisConfig left{0, 1.0};
  OdriveAxisConfig right{1, -1.0};
  double motor_turns_per_wheel_turn = 1.0;  // gear ratio
  // Wheel radians per motor turn of `axis` (gear ratio and direction): an axis's turns or
  // turns/s times this are its wheel's, positive rolling forward.
  double wheel_rad_per_turn(const OdriveAxisConfig& axis) const {
    return 2.0 * std::numbers::pi / motor_turns_per_wheel_turn * axis.direction;
  }
  // Longest wait for a heartbeat, an answer or a state change; also how old the last
  // heartbeat may be before the link counts as lost.
  double timeout_s = 0.5;
};

// Two ODrive axes (one per wheel) over SocketCAN. configure() waits for both heartbeats and
// reads the encoders; activate() sets velocity control and requests closed-loop control and
// waits for it; write() streams Set_Input_Vel to both axes (the ODrive's own watchdog wants a
// steady stream) and asks for encoder estimates; read() collects heartbeats and estimates;
// deactivate() commands zero, requests idle and waits for both axes to report it.
// An axis error in a heartbeat, a lost heartbeat or an axis that leaves closed-loop control
// stops both axes (zero velocity, then idle) and throws DriveError naming the node.
class OdriveCanDrive final : public Drive {
 public:
  // Throws std::invalid_argument on bad node ids, directions, gear ratio or timeout.
  explicit OdriveCanDrive(OdriveCanConfig config);

  std::string_view name() const override { return name_; }
  void configure() override;
  void activate() override;
  void deactivate() override;
  DriveState read() override;
  void write(const WheelSpeeds& wheels) override;

 private:
  struct Axis {
    OdriveAxisConfig config;
    const char* side;
    std::optional<double> heartbeat_s;  // monotonic time of the last heartbeat
    odrive::Heartbeat heartbeat;
    std::optional<double> estimates_s;
    odrive::EncoderEstimates estimates;
    double start_pos_turns = 0.0;
  };

  CanSocket& socket();
  // Takes every frame waiting (or, with a deadline, waits for one more) and files it.
  void drain(double wait_s);
  // Throw (after stopping the axes) when an axis reports an error; check_errors also when a
  // heartbeat is missing or late, or an axis that should be in closed-loop control is not.
  void check_axis_error(const Axis& axis);
  void check_errors(bool need_closed_loop);
  // Waits until `done` holds for both axes or the timeout passes; throws naming the laggard.
  // An axis error met meanwhile fails at once, unless `errors` says to ignore it.
  enum class AxisErrors { fail, ignore };
  template <typename Done>
  void wait_for(Done done, const std::string& what, AxisErrors errors = AxisErrors::fail);
  void stop_axes() noexcept;
  [[noreturn]] void fail(const std::string& message);
  std::string axis_name(const Axis& axis) const;

  OdriveCanConfig config_;
  std::string name_;
  std::optional<CanSocket> socket_;
  std::array<Axis, 2> axes_;
  bool active_ = false;
};

}  // namespace flowsteer::drivers
