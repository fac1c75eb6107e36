#include "flowsteer/config/drive_config.hpp"

#include <gtest/gtest.h>

#include "flowsteer/base/config_error.hpp"

namespace flowsteer::config {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_drive_section(yaml, "robot.yaml");
  } catch (const base::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return "";
}

TEST(DriveSection, OdriveSectionIsRead) {
  const DriveSection s = parse_drive_section(R"(
drive:
  type: odrive_can
  loop_rate_hz: 100
  geometry: {wheel_separation_m: 0.5, wheel_radius_m: 0.08}
  limits: {max_speed_mps: 0.8, max_turn_rate: 1.2}
  watchdog: {timeout_s: 0.3, ramp_s: 0.1}
  odrive:
    can_interface: vcan0
    left: {node_id: 3, direction: 1}
    right: {node_id: 4, direction: -1}
    motor_turns_per_wheel_turn: 2.0
)",
                                             "robot.yaml");
  EXPECT_DOUBLE_EQ(s.loop_rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(s.stage.geometry.wheel_separation_m, 0.5);
  EXPECT_DOUBLE_EQ(s.stage.limits.max_speed_mps, 0.8);
  EXPECT_DOUBLE_EQ(s.stage.watchdog.timeout_s, 0.3);
  const auto& c = std::get<drivers::OdriveCanConfig>(s.drive);
  EXPECT_EQ(c.interface, "vcan0");
  EXPECT_EQ(c.left.node_id, 3);
  EXPECT_EQ(c.right.direction, -1.0);
  EXPECT_DOUBLE_EQ(c.motor_turns_per_wheel_turn, 2.0);
}

TEST(DriveSection, SerialSectionsAreRead) {
  const DriveSection arduino = parse_drive_section(
      "drive:\n  type: arduino_bridge\n  arduino_bridge: {device: /dev/ttyACM0, "
      "ticks_per_wheel_rev: 1200}\n",
      "robot.yaml");
  const auto& a = std::get<drivers::ArduinoBridgeConfig>(arduino.drive);
  EXPECT_EQ(a.serial.device, "/dev/ttyACM0");
  EXPECT_EQ(a.serial.baud, 57600);
  const DriveSection claw = parse_drive_section(
      "drive:\n  type: roboclaw\n  roboclaw: {device: /dev/ttyS1, address: 0x81, "
      "ticks_per_wheel_rev: 4096, left_is_m1: false}\n",
      "robot.yaml");
  const auto& c = std::get<drivers::RoboClawConfig>(claw.drive);
  EXPECT_EQ(c.address, 0x81);
  EXPECT_FALSE(c.left_is_m1);
}

TEST(DriveSection, SimBaseDrivesAndStops) {
  const DriveSection s = parse_drive_section(
      "drive: {type: sim, watchdog: {timeout_s: 0.2, ramp_s: 0.1}}\n", "r.yaml");
  auto base = make_base(s);
  base->configure();
  base->activate(0.0);
  base->command({0.5, 0.0}, 0.0);
  double t = 0.0;
  for (; t < 0.15; t += 0.02) {
    base->update(t);
  }
  EXPECT_GT(base->update(t).measured.speed_mps, 0.0);
  // No fresh command: the watchdog brings it to rest.
  for (; t < 0.6; t += 0.02) {
    base->update(t);
  }
  EXPECT_NEAR(base->update(t).measured.speed_mps, 0.0, 1e-9);
  base->deactivate();
}

// Found by fuzz/robot_launch_yaml (tests/fuzz/regressions/robot_launch_yaml/scalar_serial.yaml):
// a serial drive's settings given as a scalar threw yaml-cpp's BadSubscript, which names no file.
TEST(DriveSection, SerialSettingsThatAreNoMappingAreAnError) {
  EXPECT_NE(error_of("drive:\n  type: roboclaw\n  roboclaw:  0.4}\n")
                .find("robot.yaml:3:14: drive.roboclaw: expected a mapping"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: arduino_bridge, arduino_bridge: [1]}\n")
                .find("drive.arduino_bridge: expected a mapping"),
            std::string::npos);
}

TEST(DriveSection, Ros2SectionIsRead) {
  ::unsetenv("ROS_DOMAIN_ID");
  const DriveSection plain = parse_drive_section(
      "drive: {type: ros2, geometry: {wheel_separation_m: 0.3, wheel_radius_m: 0.04}}\n",
      "robot.yaml");
  const auto& defaults = std::get<drivers::Ros2DriveConfig>(plain.drive);
  EXPECT_EQ(defaults.domain_id, 0);
  EXPECT_EQ(defaults.cmd_vel_topic, "/cmd_vel");
  EXPECT_FALSE(defaults.stamped);
  EXPECT_EQ(defaults.odom_topic, "/odom");
  EXPECT_EQ(defaults.geometry.wheel_radius_m, 0.04);  // the stage's, for the round trip

  ::setenv("ROS_DOMAIN_ID", "17", 1);
  const DriveSection s = parse_drive_section(R"(
drive:
  type: ros2
  ros2:
    cmd_vel: {topic: /diff_cont/cmd_vel, type: geometry_msgs/TwistStamped, frame_id: base}
    odom: {topic: /diff_cont/odom, type: nav_msgs/msg/Odometry}
    timeout_s: 0.3
    connect_timeout_s: 12
)",
                                             "robot.yaml");
  ::unsetenv("ROS_DOMAIN_ID");
  const auto& c = std::get<drivers::Ros2DriveConfig>(s.drive);
  EXPECT_EQ(c.domain_id, 17);
  EXPECT_EQ(c.cmd_vel_topic, "/diff_cont/cmd_vel");
  EXPECT_TRUE(c.stamped);
  EXPECT_EQ(c.frame_id, "base");
  EXPECT_EQ(c.odom_topic, "/diff_cont/odom");
  EXPECT_EQ(c.timeout_s, 0.3);
  EXPECT_EQ(c.connect_timeout_s, 12.0);
}

TEST(DriveSection, Ros2ErrorsNameTheFieldAndValue) {
  EXPECT_NE(error_of("drive: {type: ros2, ros2: {cmd_vel: {type: geometry_msgs/msg/Twist, "
                     "frame_id: base}}}\n")
                .find("drive.ros2.cmd_vel.frame_id: only a geometry_msgs/msg/TwistStamped"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: ros2, ros2: {cmd_vel: {type: std_msgs/String}}}\n")
                .find("drive.ros2.cmd_vel.type: 'std_msgs/String' is not a type flowsteer reads "
                      "or writes here (geometry_msgs/msg/Twist, geometry_msgs/msg/TwistStamped)"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: ros2, ros2: {odom: {topic: odom}}}\n")
                .find("drive.ros2.odom.topic: 'odom': a topic name starts with '/'"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: ros2, ros2: {domain_id: 233}}\n")
                .find("drive.ros2.domain_id: must be from 0 to 232, got 233"),
            std::string::npos);
  EXPECT_NE(
      error_of("drive: {type: ros2, ros2: {qos: reliable}}\n").find("drive.ros2.qos: unknown key"),
      std::string::npos);
}

TEST(DriveSection, ErrorsNameTheField) {
  EXPECT_NE(error_of("drive: {type: tank}\n").find("robot.yaml:1:15: drive.type: expected one of"),
            std::string::npos);
  EXPECT_NE(error_of("camera: {}\n").find("drive: missing"), std::string::npos);
  EXPECT_NE(error_of("drive: {type: sim, odrive: {can_interface: can0}}\n")
                .find("drive.odrive: settings for another drive"),
            std::string::npos);
  EXPECT_NE(error_of("drive:\n  type: odrive_can\n  odrive: {left: {node_id: 2}, right: "
                     "{node_id: 2}}\n")
                .find("different node ids"),
            std::string::npos);
  EXPECT_NE(error_of("drive:\n  type: odrive_can\n  odrive: {left: {node_id: 70}}\n")
                .find("drive.odrive.left.node_id: must be from 0 to 63, got 70"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: sim, watchdog: {timeout_s: 0.2, ramp_s: 0.5}}\n")
                .find("drive.watchdog.ramp_s"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: sim, loop_rate_hz: 2}\n").find("drive.loop_rate_hz"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: roboclaw}\n").find("drive.roboclaw: missing"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: roboclaw, roboclaw: {device: /dev/ttyS0}}\n")
                .find("drive.roboclaw.ticks_per_wheel_rev: missing"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: roboclaw, roboclaw: {ticks_per_wheel_rev: 10}}\n")
                .find("drive.roboclaw.device: missing"),
            std::string::npos);
  EXPECT_NE(error_of("drive: {type: sim, limits: {top_speed: 3}}\n")
                .find("drive.limits.top_speed: unknown key"),
            std::string::npos);
}

}  // namespace
}  // namespace flowsteer::config
