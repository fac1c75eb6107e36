#include "flowsteer/drivers/serial_drives.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::drivers {

namespace {

// Wheel rad/s → encoder ticks per `period_s`, rounded to the integer the firmware takes.
std::int64_t ticks(double wheel_radps, double ticks_per_rev, double per_s) {
  const double value = std::round(wheel_radps / (2.0 * std::numbers::pi) * ticks_per_rev / per_s);
  if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<std::int32_t>::max()) {
    throw DriveError("wheel speed " + std::to_string(wheel_radps) + " rad/s out of range");
  }
  return static_cast<std::int64_t>(value);
}

void require_positive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(what) + " must be positive and finite");
  }
}

std::string printable(std::string_view text) {
  std::string out;
  for (const char c : text) {
    out += c == '\r' ? std::string("\\r") : c == '\n' ? std::string("\\n") : std::string(1, c);
  }
  return out;
}

}  // namespace

void EncoderOdometry::reset(std::int64_t left_ticks, std::int64_t right_ticks, double now_s) {
  left_ticks_ = left_ticks;
  right_ticks_ = right_ticks;
  last_s_ = now_s;
  odometry_ = {};
  speeds_ = {};
}

void EncoderOdometry::update(std::int64_t left_ticks, std::int64_t right_ticks, double now_s) {
  auto delta = [](std::int64_t now, std::int64_t before) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(now) -
                                     static_cast<std::uint32_t>(before));
  };
  const double rad_per_tick = 2.0 * std::numbers::pi / ticks_per_rev_;
  const double left_rad = delta(left_ticks, left_ticks_) * rad_per_tick;
  const double right_rad = delta(right_ticks, right_ticks_) * rad_per_tick;
  odometry_.left_rad += left_rad;
  odometry_.right_rad += right_rad;
  const double dt_s = now_s - last_s_;
  if (dt_s > 0.0) {
    speeds_ = {left_rad / dt_s, right_rad / dt_s};
  }
  left_ticks_ = left_ticks;
  right_ticks_ = right_ticks;
  last_s_ = now_s;
}

// ---------------------------------------------------------------------------------------------
// ros_arduino_bridge

ArduinoBridgeDrive::ArduinoBridgeDrive(ArduinoBridgeConfig config)
    : config_(std::move(config)),
      name_("arduino_bridge " + config_.serial.device),
      odometry_(config_.ticks_per_wheel_rev) {
  require_positive(config_.ticks_per_wheel_rev, "arduino_bridge: ticks_per_wheel_rev");
  require_positive(config_.pid_rate_hz, "arduino_bridge: pid_rate_hz");
}

SerialPort& ArduinoBridgeDrive::port() {
  if (!port_) {
    throw DriveError(name_ + ": not configured");
  }
  return *port_;
}

void ArduinoBridgeDrive::configure() {
  port_.reset();
  port_.emplace(config_.serial);
  if (config_.boot_wait_s > 0.0) {
    std::this_thread::sleep_for(std::chrono::duration<double>(config_.boot_wait_s));
    port_->discard_input();
  }
  // The encoder read doubles as the check that a ros_arduino_bridge board is listening.
  const auto [left, right] = read_encoders();
  odometry_.reset(left, right, base::monotonic_now_s());
}

void ArduinoBridgeDrive::activate() {
  send_speeds(0, 0);
}

void ArduinoBridgeDrive::deactivate() {
  send_speeds(0, 0);
}

void ArduinoBridgeDrive::write(const WheelSpeeds& wheels) {
  send_speeds(ticks(wheels.left_radps, config_.ticks_per_wheel_rev, config_.pid_rate_hz),
              ticks(wheels.right_radps, config_.ticks_per_wheel_rev, config_.pid_rate_hz));
}

DriveState ArduinoBridgeDrive::read() {
  const auto [left, right] = read_encoders();
  odometry_.update(left, right, base::monotonic_now_s());
  return {odometry_.speeds(), odometry_.odometry(), {}};
}

void ArduinoBridgeDrive::send_speeds(std::int64_t left, std::int64_t right) {
  SerialPort& serial = port();
  serial.discard_input();
  serial.write_all("m " + std::to_string(left) + " " + std::to_string(right) + "\r");
  const std::string reply = serial.read_line('\n', 64);
  if (reply != "OK\r\n") {
    throw DriveError(name_ + ": garbled reply to m: expected \"OK\\r\\n\", got \"" +
                     printable(reply) + "\"");
  }
}

std::optional<std::pair<std::int64_t, std::int64_t>> arduino_bridge::parse_encoder_reply(
    std::string_view reply) {
  if (reply.size() < 2 || !reply.ends_with("\r\n")) {
    return std::nullopt;
  }
  std::int64_t values[2] = {0, 0};
  const char* p = reply.data();
  const char* const end = reply.data() + reply.size() - 2;
  for (int i = 0; i < 2; ++i) {
    const auto [next, ec] = std::from_chars(p, end, values[i]);
    if (ec != std::errc() || (i == 0 ? !(next < end && *next == ' ') : next != end)) {
      return std::nullopt;
    }
    p = next + 1;
  }
  return std::pair{values[0], values[1]};
}

std::pair<std::int64_t, std::int64_t> ArduinoBridgeDrive::read_encoders() {
  SerialPort& serial = port();
  serial.discard_input();
  serial.write_all(std::string("e\r"));
  const std::string reply = serial.read_line('\n', 64);
  const auto values = arduino_bridge::parse_encoder_reply(reply);
  if (!values) {
    throw DriveError(name_ + ": garbled reply to e: expected \"<left> <right>\\r\\n\", got \"" +
                     printable(reply) + "\"");
  }
  return *values;
}

// ---------------------------------------------------------------------------------------------
// RoboClaw

std::uint16_t roboclaw::crc16(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0;
  for (const std::uint8_t byte : bytes) {
    crc ^= static_cast<std::uint16_t>(byte << 8);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000) != 0 ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021)
                                : static_cast<std::uint16_t>(crc << 1);
    }
  }
  return crc;
}

namespace {

void put_be32(std::vector<std::uint8_t>& out, std::int64_t value) {
  const auto u = static_cast<std::uint32_t>(static_cast<std::int32_t>(value));
  for (int shift = 24; shift >= 0; shift -= 8) {
    out.push_back(static_cast<std::uint8_t>(u >> shift));
  }
}

std::uint32_t get_be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

}  // namespace

RoboClawDrive::RoboClawDrive(RoboClawConfig config)
    : config_(std::move(config)),
      name_("roboclaw " + config_.serial.device),
      odometry_(config_.ticks_per_wheel_rev) {
  require_positive(config_.ticks_per_wheel_rev, "roboclaw: ticks_per_wheel_rev");
  if (!(config_.board_timeout_s >= 0.1 && config_.board_timeout_s <= 25.5)) {
    throw std::invalid_argument("roboclaw: board_timeout_s must lie in [0.1, 25.5]");
  }
}

SerialPort& RoboClawDrive::port() {
  if (!port_) {
    throw DriveError(name_ + ": not configured");
  }
  return *port_;
}

void RoboClawDrive::send_acked(std::uint8_t command, std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> packet = {config_.address, command};
  packet.insert(packet.end(), data.begin(), data.end());
  const std::uint16_t crc = roboclaw::crc16(packet);
  packet.push_back(static_cast<std::uint8_t>(crc >> 8));
  packet.push_back(static_cast<std::uint8_t>(crc & 0xff));
  SerialPort& serial = port();
  serial.discard_input();
  serial.write_all(packet);
  const std::vector<std::uint8_t> reply = serial.read_exact(1);
  if (reply[0] != roboclaw::kAck) {
    throw DriveError(name_ + ": garbled reply to command " + std::to_string(command) +
                     ": expected ack 0xff, got " + hex_bytes(reply) +
                     " (a board that finds a CRC mismatch in the packet does not ack)");
  }
}

std::optional<roboclaw::EncoderCounts> roboclaw::parse_encoder_reply(
    std::uint8_t address, std::span<const std::uint8_t> reply, std::string& why) {
  if (reply.size() != 10) {
    why = "encoder reply of " + std::to_string(reply.size()) + " bytes, expected 10";
    return std::nullopt;
  }
  // The reply's CRC covers the request's address and command too.
  std::array<std::uint8_t, 10> covered = {address, kReadEncoders};
  std::copy(reply.begin(), reply.begin() + 8, covered.begin() + 2);
  const std::uint16_t computed = crc16(covered);
  const auto received = static_cast<std::uint16_t>((reply[8] << 8) | reply[9]);
  if (computed != received) {
    char buf[80];
    std::snprintf(buf, sizeof buf, "CRC mismatch in encoder reply: computed 0x%04x, got 0x%04x",
                  computed, received);
    why = buf;
    return std::nullopt;
  }
  return EncoderCounts{static_cast<std::int32_t>(get_be32(reply.data())),
                       static_cast<std::int32_t>(get_be32(reply.data() + 4))};
}

std::pair<std::int64_t, std::int64_t> RoboClawDrive::read_encoders() {
  const std::uint8_t request[2] = {config_.address, roboclaw::kReadEncoders};
  SerialPort& serial = port();
  serial.discard_input();
  serial.write_all(request);
  const std::vector<std::uint8_t> reply = serial.read_exact(10);
  std::string why;
  const auto counts = roboclaw::parse_encoder_reply(config_.address, reply, why);
  if (!counts) {
    throw DriveError(name_ + ": " + why + " (" + hex_bytes(reply) + ")");
  }
  return config_.left_is_m1 ? std::pair<std::int64_t, std::int64_t>{counts->m1, counts->m2}
                            : std::pair<std::int64_t, std::int64_t>{counts->m2, counts->m1};
}

void RoboClawDrive::configure() {
  port_.reset();
  port_.emplace(config_.serial);
  const std::uint8_t tenths =
      static_cast<std::uint8_t>(std::lround(config_.board_timeout_s * 10.0));
  send_acked(roboclaw::kSetSerialTimeout, std::span(&tenths, 1));
  const auto [left, right] = read_encoders();
  odometry_.reset(left, right, base::monotonic_now_s());
}

void RoboClawDrive::activate() {
  write({});
}

void RoboClawDrive::deactivate() {
  write({});
}

void RoboClawDrive::write(const WheelSpeeds& wheels) {
  const std::int64_t left = ticks(wheels.left_radps, config_.ticks_per_wheel_rev, 1.0);
  const std::int64_t right = ticks(wheels.right_radps, config_.ticks_per_wheel_rev, 1.0);
  std::vector<std::uint8_t> data;
  put_be32(data, config_.left_is_m1 ? left : right);
  put_be32(data, config_.left_is_m1 ? right : left);
  send_acked(roboclaw::kMixedSpeed, data);
}

DriveState RoboClawDrive::read() {
  const auto [left, right] = read_encoders();
  odometry_.update(left, right, base::monotonic_now_s());
  return {odometry_.speeds(), odometry_.odometry(), {}};
}

}  // namespace flowsteer::drivers
