#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "flowsteer/base/unique_fd.hpp"

namespace flowsteer::drivers {

struct SerialConfig {
  std::string device;  // e.g. /dev/ttyACM0
  int baud = 115200;
  // Longest wait for the device to accept a write or deliver the expected reply.
  double timeout_s = 0.1;
};

// A serial device in raw 8N1 mode through termios. Every read and write waits at most
// timeout_s (poll) and throws DriveError naming the device on failure or timeout.
class SerialPort {
 public:
  // Opens and configures the device; throws DriveError (with errno text) when it is missing, is
  // not a terminal or the baud rate is not one termios knows.
  explicit SerialPort(const SerialConfig& config);

  void write_all(std::span<const std::uint8_t> bytes);
  void write_all(const std::string& text);
  // Exactly n bytes, or DriveError on timeout (what arrived is shown in the message).
  std::vector<std::uint8_t> read_exact(std::size_t n);
  // Bytes up to and including `terminator`; DriveError on timeout or past max_bytes.
  std::string read_line(char terminator, std::size_t max_bytes);
  // Drops unread input, so a late reply to an earlier request cannot pass for the next one.
  void discard_input();

  const std::string& device() const { return config_.device; }

 private:
  // Waits for `events` on the descriptor until the deadline; false on timeout.
  bool wait(short events, double deadline_s, const char* operation);

  SerialConfig config_;
  base::UniqueFd fd_;
};

// "0x01 0xff ...": bytes for error messages.
std::string hex_bytes(std::span<const std::uint8_t> bytes);

}  // namespace flowsteer::drivers
