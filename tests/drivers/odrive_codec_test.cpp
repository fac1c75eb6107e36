#include <array>
#include <chrono>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "flowsteer/drivers/odrive_can.hpp"

namespace flowsteer::drivers {
namespace {

std::array<std::uint8_t, 8> bytes(const can_frame& f) {
  std::array<std::uint8_t, 8> out{};
  std::memcpy(out.data(), f.data, 8);
  return out;
}

TEST(OdriveCodec, FrameIdsAndPayloadsFollowCanSimple) {
  const can_frame state = odrive::set_axis_requested_state(3, odrive::kAxisStateClosedLoop);
  EXPECT_EQ(state.can_id, 0x067u);  // 3 << 5 | 0x07
  EXPECT_EQ(state.can_dlc, 4);
  EXPECT_EQ(bytes(state), (std::array<std::uint8_t, 8>{8, 0, 0, 0, 0, 0, 0, 0}));

  const can_frame modes = odrive::set_controller_modes(5, 2, 1);
  EXPECT_EQ(modes.can_id, 0x0abu);  // 5 << 5 | 0x0b
  EXPECT_EQ(bytes(modes), (std::array<std::uint8_t, 8>{2, 0, 0, 0, 1, 0, 0, 0}));

  const can_frame vel = odrive::set_input_vel(63, 1.5f, -2.0f);
  EXPECT_EQ(vel.can_id, 0x7edu);  // 63 << 5 | 0x0d
  // IEEE 754 little-endian: 1.5 = 0x3fc00000, −2 = 0xc0000000.
  EXPECT_EQ(bytes(vel), (std::array<std::uint8_t, 8>{0, 0, 0xc0, 0x3f, 0, 0, 0, 0xc0}));

  const can_frame rtr = odrive::get_encoder_estimates(1);
  EXPECT_EQ(rtr.can_id, 0x029u | CAN_RTR_FLAG);
}

TEST(OdriveCodec, ParsesHeartbeatsAndEstimates) {
  can_frame hb{};
  hb.can_id = 0x021;
  hb.can_dlc = 8;
  const std::uint8_t payload[8] = {0x00, 0x08, 0x00, 0x00, 8, 0, 1, 0x80};
  std::memcpy(hb.data, payload, 8);
  const auto parsed = odrive::parse_heartbeat(hb);
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->axis_error, 0x800u);
  EXPECT_EQ(parsed->axis_state, 8);
  EXPECT_FALSE(parsed->motor_error);
  EXPECT_TRUE(parsed->encoder_error);
  EXPECT_FALSE(parsed->controller_error);  // bit 7 is "trajectory done"
  hb.can_dlc = 4;
  EXPECT_FALSE(odrive::parse_heartbeat(hb));  // too short

  const can_frame est = odrive::encoder_estimates_frame(2, {12.25f, -0.5f});
  const auto e = odrive::parse_encoder_estimates(est);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->pos_turns, 12.25f);
  EXPECT_EQ(e->vel_turns_per_s, -0.5f);
}

TEST(OdriveCodec, NamesAxisErrors) {
  EXPECT_EQ(odrive::describe_axis_error(0x800), "0x00000800 (WATCHDOG_TIMER_EXPIRED)");
  EXPECT_EQ(odrive::describe_axis_error(0x201), "0x00000201 (INVALID_STATE | CONTROLLER_FAILED)");
  EXPECT_EQ(odrive::describe_axis_error(0x10000000), "0x10000000 (0x10000000)");
}

TEST(OdriveCanDrive, MissingInterfaceIsAClearErrorAndDoesNotHang) {
  OdriveCanConfig config;
  config.interface = "flowsteer9";
  OdriveCanDrive drive(config);
  const auto start = std::chrono::steady_clock::now();
  try {
    drive.configure();
    FAIL() << "configure did not throw";
  } catch (const DriveError& e) {
    // "not found: No such device", or where the kernel lacks CAN, the socket() failure.
    EXPECT_NE(std::string(e.what()).find("CAN interface flowsteer9"), std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
  EXPECT_THROW(drive.write({}), DriveError);
}

TEST(OdriveCanDrive, RejectsBadConfiguration) {
  OdriveCanConfig config;
  config.right.node_id = config.left.node_id;
  EXPECT_THROW(OdriveCanDrive{config}, std::invalid_argument);
  config = {};
  config.left.node_id = 64;
  EXPECT_THROW(OdriveCanDrive{config}, std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::drivers
