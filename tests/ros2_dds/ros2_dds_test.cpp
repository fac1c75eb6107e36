// ROS 2 topics over Cyclone DDS (ros2_dds): names and domain ids as ROS 2 takes them, and each
// message through a publisher and a subscription on loopback, field for field.

#include <gtest/gtest.h>

#include <cstdlib>

#include "flowsteer/ros2_dds/participant.hpp"
#include "flowsteer/ros2_dds/topics.hpp"
#include "loopback_dds.hpp"

namespace {

using namespace flowsteer;
namespace ros2 = recording::ros2;

constexpr int kDomain = 117;

TEST(Ros2Names, TopicNamesAsRos2TakesThem) {
  EXPECT_FALSE(ros2_dds::topic_name_problem("/cmd_vel"));
  EXPECT_FALSE(ros2_dds::topic_name_problem("/robot_1/camera/image_raw"));
  EXPECT_TRUE(ros2_dds::topic_name_problem("cmd_vel"));
  EXPECT_TRUE(ros2_dds::topic_name_problem("/"));
  EXPECT_TRUE(ros2_dds::topic_name_problem("/cmd_vel/"));
  EXPECT_TRUE(ros2_dds::topic_name_problem("/a//b"));
  EXPECT_TRUE(ros2_dds::topic_name_problem("/2d/odom"));
  EXPECT_NE(ros2_dds::topic_name_problem("/cmd-vel")->find("'-'"), std::string::npos);
}

TEST(Ros2Names, DomainIdFromTheEnvironment) {
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(ros2_dds::domain_id_from_environment(), 0);
  ::setenv("ROS_DOMAIN_ID", "42", 1);
  EXPECT_EQ(ros2_dds::domain_id_from_environment(), 42);
  for (const char* bad : {"233", "-1", "seven", "4 2"}) {
    ::setenv("ROS_DOMAIN_ID", bad, 1);
    try {
      ros2_dds::domain_id_from_environment();
      ADD_FAILURE() << bad << " accepted";
    } catch (const ros2_dds::DdsError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("ROS_DOMAIN_ID='") + bad + "'"),
                std::string::npos)
          << e.what();
    }
  }
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_THROW(ros2_dds::Participant(233), ros2_dds::DdsError);
}

TEST(Ros2Names, TypeNamesAreRos2s) {
  EXPECT_EQ(ros2_dds::ros2_type_name<ros2::Twist>(), "geometry_msgs/msg/Twist");
  EXPECT_EQ(ros2_dds::ros2_type_name<ros2::Odometry>(), "nav_msgs/msg/Odometry");
  EXPECT_EQ(ros2_dds::ros2_type_name<ros2::CompressedImage>(), "sensor_msgs/msg/CompressedImage");
}

// One message from a publisher of one participant to a subscription of another.
template <typename Message>
Message round_trip(const Message& sent, const std::string& topic,
                   ros2_dds::Qos qos = ros2_dds::Qos{}) {
  flowsteer::ros2_dds_test::use_loopback_dds();
  const ros2_dds::Participant robot(kDomain);
  const ros2_dds::Participant node(kDomain);
  ros2_dds::Subscription<Message> subscription(node, topic, qos);
  ros2_dds::Publisher<Message> publisher(robot, topic, ros2_dds::Qos{});
  EXPECT_TRUE(publisher.wait_for_subscriber(10.0)) << topic;
  EXPECT_EQ(subscription.publisher_count(), 1);
  publisher.publish(sent);
  EXPECT_TRUE(publisher.wait_for_acknowledgements(5.0) ||
              qos.reliability != ros2_dds::Reliability::reliable);
  Message received;
  EXPECT_TRUE(subscription.wait(5.0)) << topic;
  EXPECT_TRUE(subscription.take(received)) << topic;
  EXPECT_FALSE(subscription.take(received)) << "one message sent, two taken";
  return received;
}

TEST(Ros2Topics, OdometryFieldForField) {
  ros2::Odometry sent;
  sent.header = {{1'700'000'000, 123'456'789}, "odom"};
  sent.child_frame_id = "base_link";
  sent.pose.position = {1.5, -2.25, 0.0};
  sent.pose.orientation = ros2::Quaternion::from_yaw(0.7);
  sent.twist.linear = {0.4, 0.0, 0.0};
  sent.twist.angular = {0.0, 0.0, -0.3};
  for (int i = 0; i < 36; ++i) {
    sent.pose_covariance[i] = 0.01 * i;
    sent.twist_covariance[i] = -0.02 * i;
  }
  const ros2::Odometry got = round_trip(sent, "/odom");
  EXPECT_EQ(got.header.stamp.sec, sent.header.stamp.sec);
  EXPECT_EQ(got.header.stamp.nanosec, sent.header.stamp.nanosec);
  EXPECT_EQ(got.header.frame_id, "odom");
  EXPECT_EQ(got.child_frame_id, "base_link");
  EXPECT_EQ(got.pose.position.y, -2.25);
  EXPECT_EQ(got.pose.orientation.z, sent.pose.orientation.z);
  EXPECT_EQ(got.pose.orientation.w, sent.pose.orientation.w);
  EXPECT_EQ(got.twist.linear.x, 0.4);
  EXPECT_EQ(got.twist.angular.z, -0.3);
  EXPECT_EQ(got.pose_covariance, sent.pose_covariance);
  EXPECT_EQ(got.twist_covariance, sent.twist_covariance);
}

TEST(Ros2Topics, ImageAndCameraInfoFieldForField) {
  ros2::Image image;
  image.header = {{12, 34}, "camera_optical"};
  image.height = 2;
  image.width = 3;
  image.encoding = "rgb8";
  image.step = 10;  // padded rows
  image.data = {1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 11, 12, 13, 14, 15, 16, 17, 18, 19, 0};
  // A camera's subscription is best effort: it matches a reliable publisher.
  const ros2::Image got_image =
      round_trip(image, "/camera/image_raw", {ros2_dds::Reliability::best_effort, 2});
  EXPECT_EQ(got_image.data, image.data);
  EXPECT_EQ(got_image.step, 10u);
  EXPECT_EQ(got_image.encoding, "rgb8");
  EXPECT_EQ(got_image.header.frame_id, "camera_optical");

  ros2::CameraInfo info;
  info.height = 240;
  info.width = 320;
  info.distortion_model = "plumb_bob";
  info.d = {0.1, -0.2, 0.001, 0.002, 0.03};
  info.k = {200, 0, 160.5, 0, 201, 119.5, 0, 0, 1};
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.p = {200, 0, 160.5, 0, 0, 201, 119.5, 0, 0, 0, 1, 0};
  const ros2::CameraInfo got_info = round_trip(info, "/camera/camera_info");
  EXPECT_EQ(got_info.d, info.d);
  EXPECT_EQ(got_info.k, info.k);
  EXPECT_EQ(got_info.p, info.p);
  EXPECT_EQ(got_info.width, 320u);
}

TEST(Ros2Topics, TwistAndTwistStamped) {
  ros2::Twist twist;
  twist.linear.x = 0.25;
  twist.angular.z = 0.5;
  const ros2::Twist got = round_trip(twist, "/cmd_vel");
  EXPECT_EQ(got.linear.x, 0.25);
  EXPECT_EQ(got.angular.z, 0.5);
  const ros2_dds::TwistStamped stamped{{{5, 6}, "base_link"}, twist};
  const ros2_dds::TwistStamped got_stamped = round_trip(stamped, "/robot/cmd_vel");
  EXPECT_EQ(got_stamped.header.frame_id, "base_link");
  EXPECT_EQ(got_stamped.twist.angular.z, 0.5);
}

TEST(Ros2Topics, NothingToTakeWithoutAPublisher) {
  flowsteer::ros2_dds_test::use_loopback_dds();
  const ros2_dds::Participant node(kDomain);
  ros2_dds::Subscription<ros2::Odometry> odometry(node, "/lonely/odom", ros2_dds::Qos{});
  EXPECT_FALSE(odometry.wait(0.05));
  ros2::Odometry message;
  EXPECT_FALSE(odometry.take(message));
  ros2_dds::Publisher<ros2::Twist> commands(node, "/lonely/cmd_vel", ros2_dds::Qos{});
  EXPECT_FALSE(commands.wait_for_subscriber(0.05));
  EXPECT_THROW(ros2_dds::Publisher<ros2::Twist>(node, "cmd_vel", ros2_dds::Qos{}),
               ros2_dds::DdsError);
}

}  // namespace
