#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "flowsteer/drivers/drive.hpp"
#include "flowsteer/drivers/serial_port.hpp"

namespace flowsteer::drivers {

// Turns encoder counts into wheel odometry and measured wheel speeds.
class EncoderOdometry {
 public:
  explicit EncoderOdometry(double ticks_per_wheel_rev) : ticks_per_rev_(ticks_per_wheel_rev) {}
  // Sets the zero of the odometry.
  void reset(std::int64_t left_ticks, std::int64_t right_ticks, double now_s);
  // Differences of 32-bit counters are taken modulo 2³², so a counter that wraps does not
  // look like a jump.
  void update(std::int64_t left_ticks, std::int64_t right_ticks, double now_s);
  const WheelOdometry& odometry() const { return odometry_; }
  const WheelSpeeds& speeds() const { return speeds_; }

 private:
  double ticks_per_rev_;
  std::int64_t left_ticks_ = 0;
  std::int64_t right_ticks_ = 0;
  double last_s_ = 0.0;
  WheelOdometry odometry_;
  WheelSpeeds speeds_;
};

// ros_arduino_bridge's firmware (ASCII, one command per line ending in '\r'):
// `m <left> <right>` sets wheel speeds in encoder ticks per PID period and answers "OK";
// `e` answers "<left ticks> <right ticks>". Its firmware stops the motors on its own when no
// `m` arrives for AUTO_STOP_INTERVAL.
struct ArduinoBridgeConfig {
  SerialConfig serial;
  double ticks_per_wheel_rev = 0.0;  // encoder ticks per wheel revolution
  double pid_rate_hz = 30.0;         // the firmware's PID_RATE: `m` speeds are per PID period
  // Boards that reset when the port opens (DTR) need about 2 s before they listen.
  double boot_wait_s = 0.0;
};

namespace arduino_bridge {
// The reply to `e`: exactly "<left ticks> <right ticks>\r\n" (decimal, optionally negative);
// std::nullopt for anything else, which means a garbled line or another device.
std::optional<std::pair<std::int64_t, std::int64_t>> parse_encoder_reply(std::string_view reply);
}  // namespace arduino_bridge

class ArduinoBridgeDrive final : public Drive {
 public:
  // Throws std::invalid_argument on a non-positive ticks_per_wheel_rev or pid_rate_hz.
  explicit ArduinoBridgeDrive(ArduinoBridgeConfig config);

  std::string_view name() const override { return name_; }
  void configure() override;
  void activate() override;
  void deactivate() override;
  DriveState read() override;
  void write(const WheelSpeeds& wheels) override;

 private:
  SerialPort& port();
  void send_speeds(std::int64_t left, std::int64_t right);
  std::pair<std::int64_t, std::int64_t> read_encoders();

  ArduinoBridgeConfig config_;
  std::string name_;
  std::optional<SerialPort> port_;
  EncoderOdometry odometry_;
};

// RoboClaw packet serial: [address, command, data (big-endian), CRC-16/CCITT of all before,
// big-endian]. Writes are acknowledged with 0xff; reads answer data and a CRC over
// address, command and data.
struct RoboClawConfig {
  SerialConfig serial;
  std::uint8_t address = 0x80;
  double ticks_per_wheel_rev = 0.0;  // quadrature counts per wheel revolution
  // The board's own serial timeout (command 14): it stops the motors when packets stop for
  // this long. Sent in tenths of a second, 0.1 to 25.5 s.
  double board_timeout_s = 0.5;
  bool left_is_m1 = true;
};

namespace roboclaw {
inline constexpr std::uint8_t kSetSerialTimeout = 14;
inline constexpr std::uint8_t kMixedSpeed = 37;  // signed speed of M1 and M2, counts/s
inline constexpr std::uint8_t kReadEncoders = 78;
inline constexpr std::uint8_t kAck = 0xff;
// CRC-16/CCITT as RoboClaw uses it: polynomial 0x1021, initial value 0, no reflection.
std::uint16_t crc16(std::span<const std::uint8_t> bytes);

struct EncoderCounts {
  std::int32_t m1 = 0;
  std::int32_t m2 = 0;
};
// The reply to kReadEncoders from the board at `address`: M1 and M2 counts (big-endian) and a
// CRC over the request's address and command and the counts. std::nullopt, with the reason in
// `why`, for a reply that is not 10 bytes long or whose CRC does not match.
std::optional<EncoderCounts> parse_encoder_reply(std::uint8_t address,
                                                 std::span<const std::uint8_t> reply,
                                                 std::string& why);
}  // namespace roboclaw

class RoboClawDrive final : public Drive {
 public:
  // Throws std::invalid_argument on a bad ticks_per_wheel_rev or board_timeout_s.
  explicit RoboClawDrive(RoboClawConfig config);

  std::string_view name() const override { return name_; }
  void configure() override;
  void activate() override;
  void deactivate() override;
  DriveState read() override;
  void write(const WheelSpeeds& wheels) override;

 private:
  SerialPort& port();
  // Sends a packet (CRC appended) and checks the one-byte acknowledgement.
  void send_acked(std::uint8_t command, std::span<const std::uint8_t> data);
  std::pair<std::int64_t, std::int64_t> read_encoders();

  RoboClawConfig config_;
  std::string name_;
  std::optional<SerialPort> port_;
  EncoderOdometry odometry_;
};

}  // namespace flowsteer::drivers
