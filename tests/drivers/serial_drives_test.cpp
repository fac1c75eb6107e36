#include "flowsteer/drivers/serial_drives.hpp"

#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/drivers/mobile_base.hpp"
#include "pty_board.hpp"

namespace flowsteer::drivers {
namespace {

using testing::Board;
using testing::Pty;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Expects `call` to throw DriveError whose message contains `needle`, within `limit_s`.
template <typename Call>
void expect_error(Call call, const std::string& needle, double limit_s = 1.0) {
  const double start_s = now_s();
  try {
    call();
    ADD_FAILURE() << "no DriveError; expected one containing \"" << needle << "\"";
  } catch (const DriveError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
  EXPECT_LT(now_s() - start_s, limit_s) << "took too long: something waited without a timeout";
}

CommandStageConfig stage_config() {
  CommandStageConfig c;
  c.geometry = {0.4, 0.05};
  c.watchdog = {0.5, 0.2};
  return c;
}

// Drives `base` until its board's port goes away (the adapter pulled: the pty's other end
// closed), then expects the next update to fail at once, saying the port hung up and that the
// stop could not be sent, and the base to be left failed. Prints the time from the hang-up to
// the error.
void expect_hang_up_fails_the_base(MobileBase& base, Board& board, Pty& pty,
                                   const std::string& port) {
  base.configure();
  base.activate(now_s());
  base.command({0.2, 0.3}, now_s());
  base.update(now_s());
  board.stop();
  pty.hang_up();
  const double hung_up_s = now_s();
  base.command({0.2, 0.3}, now_s());
  try {
    base.update(now_s());
    ADD_FAILURE() << "no DriveError after the port hung up";
  } catch (const DriveError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("update failed, the stop could not be sent either"), std::string::npos)
        << message;
    EXPECT_NE(message.find("serial " + port + ": "), std::string::npos) << message;
    EXPECT_NE(message.find("Input/output error"), std::string::npos) << message;
  }
  const double error_after_s = now_s() - hung_up_s;
  std::printf("time from hang-up to the error: %.3f ms\n", 1e3 * error_after_s);
  EXPECT_LT(error_after_s, 0.5) << "the drive waited on a port that is gone";
  EXPECT_EQ(base.lifecycle(), Lifecycle::failed);
}

// ---------------------------------------------------------------------------------------------
// ros_arduino_bridge

class ArduinoBoard final : public Board {
 public:
  enum class Mode { normal, garble_motion, short_reply, silent };
  using Board::Board;

  std::atomic<Mode> mode{Mode::normal};
  std::vector<std::string> lines() {
    std::lock_guard lock(mutex_);
    return lines_;
  }

 private:
  void serve() override {
    std::string line;
    for (std::uint8_t b = read_byte(); b != '\r'; b = read_byte()) {
      line += static_cast<char>(b);
    }
    {
      std::lock_guard lock(mutex_);
      lines_.push_back(line);
    }
    if (mode == Mode::silent) {
      return;
    }
    if (line == "e") {
      send(mode == Mode::short_reply
               ? "12"
               : std::to_string(left_) + " " + std::to_string(right_) + "\r\n");
      left_ += 300;  // a quarter turn of the left wheel between reads
      right_ -= 600;
      return;
    }
    std::int64_t speeds[2] = {0, 0};
    const char* p = line.data() + 2;
    const char* end = line.data() + line.size();
    bool ok = line.starts_with("m ");
    for (int i = 0; ok && i < 2; ++i) {
      const auto [next, ec] = std::from_chars(p, end, speeds[i]);
      ok = ec == std::errc() && (i == 0 ? next < end && *next == ' ' : next == end);
      p = next + 1;
    }
    if (!ok) {
      error("unexpected line \"" + line + "\"");
      return;
    }
    if (mode == Mode::garble_motion && (speeds[0] != 0 || speeds[1] != 0)) {
      send("O\x7fK?\r\n");
    } else if (mode == Mode::short_reply) {
      send("O");
    } else {
      send("OK\r\n");
    }
  }

  std::vector<std::string> lines_;
  std::int64_t left_ = 1000;
  std::int64_t right_ = -50;
};

ArduinoBridgeConfig arduino_config(const Pty& pty) {
  ArduinoBridgeConfig c;
  c.serial = {pty.slave_path(), 57600, 0.1};
  c.ticks_per_wheel_rev = 1200;
  c.pid_rate_hz = 30;
  return c;
}

TEST(ArduinoBridge, SpeaksTheProtocolAndReadsOdometry) {
  Pty pty;
  ArduinoBoard board(pty);
  board.start();
  ArduinoBridgeDrive drive(arduino_config(pty));
  drive.configure();
  drive.activate();
  // 3 rev/s = 3600 ticks/s = 120 ticks per 1/30 s PID period.
  drive.write({2.0 * std::numbers::pi * 3.0, -2.0 * std::numbers::pi * 1.5});
  const DriveState state = drive.read();
  drive.deactivate();
  board.stop();
  EXPECT_EQ(board.lines(), (std::vector<std::string>{"e", "m 0 0", "m 120 -60", "e", "m 0 0"}));
  EXPECT_TRUE(board.errors().empty()) << board.errors().front();
  // 300 and −600 ticks of 1200 per revolution since configure().
  EXPECT_NEAR(state.odometry.left_rad, 0.5 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(state.odometry.right_rad, -std::numbers::pi, 1e-12);
  EXPECT_GT(state.measured.left_radps, 0.0);
}

TEST(ArduinoBridge, PositiveTurnRateDrivesTheLeftWheelForward) {
  Pty pty;
  ArduinoBoard board(pty);
  board.start();
  MobileBase base(std::make_unique<ArduinoBridgeDrive>(arduino_config(pty)), stage_config());
  base.configure();
  base.activate(now_s());
  base.command({0.0, 0.5}, now_s());  // turn right on the spot
  base.update(now_s());
  base.deactivate();
  board.stop();
  // ω_z = −0.5 rad/s: left wheel +0.5·0.2/0.05 = 2 rad/s = 12.7 ticks per period.
  const std::vector<std::string> lines = board.lines();
  ASSERT_GE(lines.size(), 4u);
  EXPECT_EQ(lines[2], "m 13 -13");
}

TEST(ArduinoBridge, MissingDeviceIsAClearError) {
  ArduinoBridgeConfig c;
  c.serial = {"/dev/flowsteer-no-such-tty", 115200, 0.1};
  c.ticks_per_wheel_rev = 1000;
  ArduinoBridgeDrive drive(c);
  expect_error([&] { drive.configure(); },
               "serial /dev/flowsteer-no-such-tty: open: No such file or directory");
  expect_error([&] { drive.write({1.0, 1.0}); }, "not configured");
}

TEST(ArduinoBridge, NotATerminalIsAClearError) {
  ArduinoBridgeConfig c;
  c.serial = {"/dev/null", 115200, 0.1};
  c.ticks_per_wheel_rev = 1000;
  ArduinoBridgeDrive drive(c);
  expect_error([&] { drive.configure(); }, "serial /dev/null: not a serial device");
}

TEST(ArduinoBridge, GarbledReplyStopsTheBase) {
  Pty pty;
  ArduinoBoard board(pty);
  board.mode = ArduinoBoard::Mode::garble_motion;
  board.start();
  MobileBase base(std::make_unique<ArduinoBridgeDrive>(arduino_config(pty)), stage_config());
  base.configure();
  base.activate(now_s());
  base.command({0.0, 0.5}, now_s());
  expect_error([&] { base.update(now_s()); },
               "update failed, base stopped: arduino_bridge " + pty.slave_path() +
                   ": garbled reply to m: expected \"OK\\r\\n\", got \"O\x7fK?\\r\\n\"");
  board.stop();
  EXPECT_EQ(base.lifecycle(), Lifecycle::failed);
  EXPECT_EQ(board.lines().back(), "m 0 0");  // the base was told to stop
}

TEST(ArduinoBridge, PortGoneMidRunIsAClearErrorAndFailsTheBase) {
  Pty pty;
  ArduinoBoard board(pty);
  board.start();
  MobileBase base(std::make_unique<ArduinoBridgeDrive>(arduino_config(pty)), stage_config());
  expect_hang_up_fails_the_base(base, board, pty, pty.slave_path());
}

TEST(ArduinoBridge, ShortReplyTimesOut) {
  Pty pty;
  ArduinoBoard board(pty);
  board.mode = ArduinoBoard::Mode::short_reply;
  board.start();
  ArduinoBridgeDrive drive(arduino_config(pty));
  expect_error([&] { drive.configure(); }, "short reply: timed out after 0.1");
}

TEST(ArduinoBridge, SilentBoardTimesOut) {
  Pty pty;
  ArduinoBoard board(pty);
  board.mode = ArduinoBoard::Mode::silent;
  board.start();
  ArduinoBridgeDrive drive(arduino_config(pty));
  expect_error([&] { drive.configure(); }, "timed out after 0.1");
}

// ---------------------------------------------------------------------------------------------
// RoboClaw

// CRC-16/CCITT (0x1021, init 0) from a table, written apart from the drive's bitwise loop so
// the board checks the drive rather than agreeing with it by construction.
std::uint16_t board_crc(const std::vector<std::uint8_t>& bytes) {
  static const std::array<std::uint16_t, 256> table = [] {
    std::array<std::uint16_t, 256> t{};
    for (unsigned i = 0; i < 256; ++i) {
      unsigned v = i << 8;
      for (int k = 0; k < 8; ++k) {
        v = (v & 0x8000) ? ((v << 1) ^ 0x1021) : (v << 1);
      }
      t[i] = static_cast<std::uint16_t>(v);
    }
    return t;
  }();
  std::uint16_t crc = 0;
  for (const std::uint8_t b : bytes) {
    crc = static_cast<std::uint16_t>((crc << 8) ^ table[((crc >> 8) ^ b) & 0xff]);
  }
  return crc;
}

TEST(RoboClawCrc, KnownAnswer) {
  const std::string check = "123456789";  // CRC-16/XMODEM check value 0x31c3
  const std::vector<std::uint8_t> bytes(check.begin(), check.end());
  EXPECT_EQ(roboclaw::crc16(bytes), 0x31c3);
  EXPECT_EQ(board_crc(bytes), 0x31c3);
}

// The decoders the serial drives use and fuzz/ feeds: exactly "<left> <right>\r\n", nothing
// looser.
TEST(ArduinoBridgeReply, OnlyTwoDecimalCountsAndCrLfAreAnEncoderReply) {
  using arduino_bridge::parse_encoder_reply;
  const auto counts = parse_encoder_reply("12 -34\r\n");
  ASSERT_TRUE(counts.has_value());
  EXPECT_EQ(counts->first, 12);
  EXPECT_EQ(counts->second, -34);
  for (const char* garbled :
       {"12 -34\n", "12 -34", "12  -34\r\n", "12\r\n", "\r\n", "", "12 34x\r\n", "+1 2\r\n",
        " 1 2\r\n", "1 2 3\r\n", "99999999999999999999 1\r\n"}) {
    EXPECT_FALSE(parse_encoder_reply(garbled).has_value()) << '"' << garbled << '"';
  }
}

TEST(RoboClawReply, EncoderCountsNeedTenBytesAndTheRequestsCrc) {
  // M1 = 1000, M2 = -2, with the CRC over the request's address and command too.
  std::vector<std::uint8_t> covered = {
      0x81, roboclaw::kReadEncoders, 0, 0, 3, 0xe8, 0xff, 0xff, 0xff, 0xfe};
  const std::uint16_t crc = board_crc(covered);
  std::vector<std::uint8_t> reply(covered.begin() + 2, covered.end());
  reply.push_back(static_cast<std::uint8_t>(crc >> 8));
  reply.push_back(static_cast<std::uint8_t>(crc & 0xff));
  std::string why;
  const auto counts = roboclaw::parse_encoder_reply(0x81, reply, why);
  ASSERT_TRUE(counts.has_value()) << why;
  EXPECT_EQ(counts->m1, 1000);
  EXPECT_EQ(counts->m2, -2);

  // The same bytes from another address: the CRC does not match.
  EXPECT_FALSE(roboclaw::parse_encoder_reply(0x80, reply, why).has_value());
  EXPECT_EQ(why.rfind("CRC mismatch in encoder reply: computed 0x", 0), 0U) << why;
  EXPECT_NE(why.find(", got 0x"), std::string::npos) << why;

  reply.pop_back();
  EXPECT_FALSE(roboclaw::parse_encoder_reply(0x81, reply, why).has_value());
  EXPECT_EQ(why, "encoder reply of 9 bytes, expected 10");
}

struct Packet {
  std::uint8_t command;
  std::vector<std::uint8_t> data;
};

class RoboClawBoard final : public Board {
 public:
  enum class Mode { normal, bad_reply_crc, garbled_ack };
  using Board::Board;

  std::atomic<Mode> mode{Mode::normal};
  std::vector<Packet> packets() {
    std::lock_guard lock(mutex_);
    return packets_;
  }

 private:
  void serve() override {
    std::vector<std::uint8_t> packet = {read_byte()};
    if (packet[0] != 0x80) {
      error("wrong address " + std::to_string(packet[0]));
      return;
    }
    packet.push_back(read_byte());
    const std::uint8_t command = packet[1];
    if (command == 78) {
      {
        std::lock_guard lock(mutex_);
        packets_.push_back({command, {}});
      }
      std::vector<std::uint8_t> reply;
      for (const std::uint32_t count : {m1_, m2_}) {
        for (int shift = 24; shift >= 0; shift -= 8) {
          reply.push_back(static_cast<std::uint8_t>(count >> shift));
        }
      }
      std::vector<std::uint8_t> covered = packet;
      covered.insert(covered.end(), reply.begin(), reply.end());
      std::uint16_t crc = board_crc(covered);
      if (mode == Mode::bad_reply_crc) {
        crc ^= 0x0100;
      }
      reply.push_back(static_cast<std::uint8_t>(crc >> 8));
      reply.push_back(static_cast<std::uint8_t>(crc & 0xff));
      send(reply);
      m1_ += 2048;  // half a turn of M1 between reads
      m2_ -= 1024;
      return;
    }
    std::size_t data_bytes = 0;
    if (command == 14) {
      data_bytes = 1;
    } else if (command == 37) {
      data_bytes = 8;
    } else {
      error("unexpected command " + std::to_string(command));
      return;
    }
    for (std::size_t i = 0; i < data_bytes + 2; ++i) {
      packet.push_back(read_byte());
    }
    const std::vector<std::uint8_t> covered(packet.begin(), packet.end() - 2);
    const std::uint16_t crc =
        static_cast<std::uint16_t>((packet[packet.size() - 2] << 8) | packet[packet.size() - 1]);
    if (crc != board_crc(covered)) {
      error("CRC mismatch in command " + std::to_string(command));
      return;  // a real RoboClaw ignores the packet and does not ack
    }
    {
      std::lock_guard lock(mutex_);
      packets_.push_back({command, std::vector<std::uint8_t>(covered.begin() + 2, covered.end())});
    }
    send(std::vector<std::uint8_t>{mode == Mode::garbled_ack ? std::uint8_t{0x00}
                                                             : std::uint8_t{0xff}});
  }

  std::vector<Packet> packets_;
  std::uint32_t m1_ = static_cast<std::uint32_t>(-100);
  std::uint32_t m2_ = 0x80000100u;  // INT32_MIN + 256: the counter wraps before the second read
};

std::int32_t be32(const std::vector<std::uint8_t>& d, std::size_t at) {
  return static_cast<std::int32_t>((std::uint32_t{d[at]} << 24) | (std::uint32_t{d[at + 1]} << 16) |
                                   (std::uint32_t{d[at + 2]} << 8) | std::uint32_t{d[at + 3]});
}

RoboClawConfig roboclaw_config(const Pty& pty) {
  RoboClawConfig c;
  c.serial = {pty.slave_path(), 38400, 0.1};
  c.ticks_per_wheel_rev = 4096;
  c.board_timeout_s = 0.3;
  return c;
}

TEST(RoboClaw, SpeaksPacketSerialAndReadsOdometry) {
  Pty pty;
  RoboClawBoard board(pty);
  board.start();
  RoboClawDrive drive(roboclaw_config(pty));
  drive.configure();
  drive.activate();
  drive.write({2.0 * std::numbers::pi * 2.5, -2.0 * std::numbers::pi * 0.25});
  const DriveState state = drive.read();
  drive.deactivate();
  board.stop();
  ASSERT_TRUE(board.errors().empty()) << board.errors().front();
  const std::vector<Packet> p = board.packets();
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(p[0].command, 14);
  EXPECT_EQ(p[0].data, std::vector<std::uint8_t>{3});  // 0.3 s in tenths
  EXPECT_EQ(p[1].command, 78);
  EXPECT_EQ(p[2].command, 37);
  EXPECT_EQ(p[2].data, std::vector<std::uint8_t>(8, 0));  // activate: zero speeds
  EXPECT_EQ(p[3].command, 37);
  EXPECT_EQ(be32(p[3].data, 0), 10240);  // 2.5 rev/s × 4096 counts
  EXPECT_EQ(be32(p[3].data, 4), -1024);
  EXPECT_EQ(p[4].command, 78);
  EXPECT_EQ(p[5].command, 37);
  EXPECT_EQ(p[5].data, std::vector<std::uint8_t>(8, 0));
  EXPECT_NEAR(state.odometry.left_rad, std::numbers::pi, 1e-12);          // +2048 counts
  EXPECT_NEAR(state.odometry.right_rad, -0.5 * std::numbers::pi, 1e-12);  // −1024, no jump
}

TEST(RoboClaw, ReplyWithBadCrcIsAClearErrorAndStopsTheBase) {
  Pty pty;
  RoboClawBoard board(pty);
  board.start();
  MobileBase base(std::make_unique<RoboClawDrive>(roboclaw_config(pty)), stage_config());
  base.configure();
  base.activate(now_s());
  base.command({0.0, 0.5}, now_s());
  board.mode = RoboClawBoard::Mode::bad_reply_crc;
  expect_error([&] { base.update(now_s()); }, "CRC mismatch in encoder reply: computed 0x");
  board.stop();
  EXPECT_TRUE(board.errors().empty());
  const std::vector<Packet> p = board.packets();
  ASSERT_GE(p.size(), 2u);
  // The turning command, the encoder read with the bad reply, then the stop (written by the
  // base, then by deactivate).
  ASSERT_GE(p.size(), 4u);
  const Packet& turn = p[p.size() - 4];
  EXPECT_EQ(turn.command, 37);
  EXPECT_GT(be32(turn.data, 0), 0);  // left forward: a right turn
  EXPECT_LT(be32(turn.data, 4), 0);
  EXPECT_EQ(p[p.size() - 3].command, 78);
  EXPECT_EQ(p.back().command, 37);
  EXPECT_EQ(p.back().data, std::vector<std::uint8_t>(8, 0));
}

TEST(RoboClaw, PortGoneMidRunIsAClearErrorAndFailsTheBase) {
  Pty pty;
  RoboClawBoard board(pty);
  board.start();
  MobileBase base(std::make_unique<RoboClawDrive>(roboclaw_config(pty)), stage_config());
  expect_hang_up_fails_the_base(base, board, pty, pty.slave_path());
}

TEST(RoboClaw, GarbledAckIsAClearError) {
  Pty pty;
  RoboClawBoard board(pty);
  board.mode = RoboClawBoard::Mode::garbled_ack;
  board.start();
  RoboClawDrive drive(roboclaw_config(pty));
  expect_error([&] { drive.configure(); },
               "garbled reply to command 14: expected ack 0xff, got 0x00");
}

TEST(RoboClaw, NoBoardTimesOut) {
  Pty pty;  // nobody answers on the master side
  RoboClawDrive drive(roboclaw_config(pty));
  expect_error([&] { drive.configure(); }, "short reply: timed out after 0.1");
}

}  // namespace
}  // namespace flowsteer::drivers
