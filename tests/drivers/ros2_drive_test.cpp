// The ros2 drive against a base controller played in this process with ros2_dds (a Twist
// subscription and an Odometry publisher on another participant, loopback only).

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>

#include "../ros2_dds/loopback_dds.hpp"
#include "flowsteer/drivers/ros2_drive.hpp"
#include "flowsteer/ros2_dds/participant.hpp"
#include "flowsteer/ros2_dds/topics.hpp"

namespace {

using namespace flowsteer;
namespace ros2 = recording::ros2;

constexpr int kDomain = 131;

drivers::Ros2DriveConfig config(const std::string& prefix) {
  drivers::Ros2DriveConfig c;
  c.domain_id = kDomain;
  c.cmd_vel_topic = prefix + "/cmd_vel";
  c.odom_topic = prefix + "/odom";
  c.timeout_s = 0.3;
  c.connect_timeout_s = 10.0;
  c.geometry = {0.4, 0.05};
  return c;
}

// A controller: takes Twist, publishes Odometry with the pose it is given.
class Controller {
 public:
  explicit Controller(const std::string& prefix)
      : participant_(kDomain),
        commands_(participant_, prefix + "/cmd_vel", ros2_dds::Qos{}),
        odometry_(participant_, prefix + "/odom", ros2_dds::Qos{}) {}

  void publish(double x, double y, double yaw, double speed, double yaw_rate) {
    ros2::Odometry odom;
    odom.pose.position = {x, y, 0.0};
    odom.pose.orientation = ros2::Quaternion::from_yaw(yaw);
    odom.twist.linear.x = speed;
    odom.twist.angular.z = yaw_rate;
    ASSERT_TRUE(odometry_.wait_for_subscriber(10.0));  // volatile: nothing is kept for later
    odometry_.publish(odom);
    ASSERT_TRUE(odometry_.wait_for_acknowledgements(5.0));
  }

  // The newest command within timeout_s.
  std::optional<ros2::Twist> command(double timeout_s) {
    std::optional<ros2::Twist> newest;
    ros2::Twist twist;
    if (commands_.wait(timeout_s)) {
      while (commands_.take(twist)) {
        newest = twist;
      }
    }
    return newest;
  }

 private:
  ros2_dds::Participant participant_;
  ros2_dds::Subscription<ros2::Twist> commands_;
  ros2_dds::Publisher<ros2::Odometry> odometry_;
};

TEST(Ros2Drive, WithoutAControllerConfigureSaysWhatIsMissing) {
  flowsteer::ros2_dds_test::use_loopback_dds();
  drivers::Ros2DriveConfig c = config("/nobody");
  c.connect_timeout_s = 0.2;
  drivers::Ros2Drive drive(c);
  try {
    drive.configure();
    FAIL() << "configured without a controller";
  } catch (const drivers::DriveError& e) {
    EXPECT_NE(std::string(e.what()).find("no subscriber on /nobody/cmd_vel"), std::string::npos)
        << e.what();
  }
}

TEST(Ros2Drive, BadSettingsAreRefused) {
  drivers::Ros2DriveConfig c = config("/x");
  c.cmd_vel_topic = "cmd_vel";
  EXPECT_THROW(drivers::Ros2Drive{c}, std::invalid_argument);
  c = config("/x");
  c.domain_id = 233;
  EXPECT_THROW(drivers::Ros2Drive{c}, std::invalid_argument);
}

TEST(Ros2Drive, CommandsOdometryAndSilence) {
  flowsteer::ros2_dds_test::use_loopback_dds();
  Controller controller("/base");
  const drivers::Ros2DriveConfig c = config("/base");
  drivers::Ros2Drive drive(c);
  std::thread first_odometry([&] { controller.publish(1.0, 2.0, 0.3, 0.0, 0.0); });
  drive.configure();
  first_odometry.join();
  drive.activate();

  // Wheel speeds out are the body velocity of the command stage's geometry, ω as a yaw rate.
  const drivers::BodyVelocity body{0.4, 0.25};  // turning right: yaw rate −0.25 rad/s
  drive.write(drivers::to_wheels(body, c.geometry));
  const auto sent = controller.command(5.0);
  ASSERT_TRUE(sent);
  EXPECT_NEAR(sent->linear.x, 0.4, 1e-12);
  EXPECT_NEAR(sent->angular.z, -0.25, 1e-12);

  // An arc of radius 2 m to the left, a quarter turn, from (1, 2) heading 0.3 rad: the outer
  // (right) wheel rolls (2 + 0.2) π/2, the inner (2 − 0.2) π/2.
  const double r_m = 2.0;
  const double cx = 1.0 - r_m * std::sin(0.3);
  const double cy = 2.0 + r_m * std::cos(0.3);
  const int steps = 50;
  drivers::DriveState state;
  for (int i = 1; i <= steps; ++i) {
    const double yaw = 0.3 + 0.5 * std::numbers::pi * i / steps;
    controller.publish(cx + r_m * std::sin(yaw), cy - r_m * std::cos(yaw), yaw, 0.5, 0.25);
    state = drive.read();
  }
  const double quarter = 0.5 * std::numbers::pi;
  EXPECT_NEAR(state.odometry.left_rad * 0.05, (r_m - 0.2) * quarter, 1e-9);
  EXPECT_NEAR(state.odometry.right_rad * 0.05, (r_m + 0.2) * quarter, 1e-9);
  const drivers::BodyVelocity measured = drivers::from_wheels(state.measured, c.geometry);
  EXPECT_NEAR(measured.speed_mps, 0.5, 1e-12);
  EXPECT_NEAR(base::yaw_rate_of(measured.turn_rate), 0.25, 1e-12);

  // Odometry silent for the timeout: the read fails naming it, and a stop went out.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  try {
    drive.read();
    FAIL() << "odometry silent, read() went on";
  } catch (const drivers::DriveError& e) {
    EXPECT_NE(std::string(e.what()).find("no odometry on /base/odom for"), std::string::npos)
        << e.what();
  }
  const auto stop = controller.command(5.0);
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->linear.x, 0.0);
  EXPECT_EQ(stop->angular.z, 0.0);
  EXPECT_THROW(drive.write(drivers::to_wheels(body, c.geometry)), drivers::DriveError);
  drive.deactivate();
}

}  // namespace
