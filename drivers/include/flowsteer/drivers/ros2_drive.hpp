#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/drivers/drive.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::ros2_dds {
class Participant;
template <typename Message>
class Publisher;
template <typename Message>
class Subscription;
struct TwistStamped;
}  // namespace flowsteer::ros2_dds

namespace flowsteer::drivers {

// A ROS 2 robot's base controller (ros2_control's diff_drive_controller, or any node that takes
// geometry_msgs/Twist and publishes nav_msgs/Odometry), reached over DDS as a ROS 2 node would.
struct Ros2DriveConfig {
  int domain_id = 0;
  std::string cmd_vel_topic = "/cmd_vel";
  // geometry_msgs/msg/TwistStamped instead of Twist (diff_drive_controller's use_stamped_vel).
  bool stamped = false;
  std::string frame_id = "base_link";  // TwistStamped's header.frame_id
  std::string odom_topic = "/odom";
  // Odometry silent this long stops the base and fails the run, as a lost ODrive heartbeat.
  double timeout_s = 0.5;
  // configure() waits this long for the controller: a subscriber on cmd_vel and a first
  // odometry message (DDS discovery takes a fraction of a second on one host).
  double connect_timeout_s = 5.0;
  // Wheel speeds from the command stage become a body velocity again with the stage's geometry
  // (an exact round trip); the controller's own geometry turns it into its wheels.
  WheelGeometry geometry;
};

// Publishes the command stage's velocity as cmd_vel at the loop's rate (zero for a stop, also
// after a failure) and reads the controller's odometry: the measured wheel speeds from its
// twist, the wheel angles from its pose (distance along the heading and yaw change, through the
// geometry). Not thread-safe.
class Ros2Drive final : public Drive {
 public:
  // Throws std::invalid_argument on a bad topic name, domain id, timeout or geometry.
  explicit Ros2Drive(Ros2DriveConfig config);
  ~Ros2Drive() override;

  std::string_view name() const override { return name_; }
  // Joins the domain and waits up to connect_timeout_s, in all, for a subscriber on cmd_vel and
  // a first odometry message; DriveError naming what is missing otherwise.
  void configure() override;
  void activate() override;
  // Publishes zero and waits (up to timeout_s) until the controller acknowledged it.
  void deactivate() override;
  // DriveError when no odometry came for timeout_s.
  DriveState read() override;
  void write(const WheelSpeeds& wheels) override;

 private:
  void publish(const BodyVelocity& body);
  void publish_stop_and_flush();
  void take_odometry();
  void require_configured() const;

  Ros2DriveConfig config_;
  std::string name_;
  bool configured_ = false;
  bool active_ = false;
  std::unique_ptr<ros2_dds::TwistStamped> stamped_command_;  // reused: its frame_id is set once
  std::unique_ptr<ros2_dds::Participant> participant_;
  std::unique_ptr<ros2_dds::Publisher<recording::ros2::Twist>> twist_;
  std::unique_ptr<ros2_dds::Publisher<ros2_dds::TwistStamped>> twist_stamped_;
  std::unique_ptr<ros2_dds::Subscription<recording::ros2::Odometry>> odometry_;
  recording::ros2::Odometry message_;  // reused for every take
  std::optional<double> last_odometry_s_;
  std::optional<recording::ros2::Pose> last_pose_;
  DriveState state_;
};

}  // namespace flowsteer::drivers
