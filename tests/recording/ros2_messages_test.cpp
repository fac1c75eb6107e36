#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "flowsteer/recording/recording_error.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::recording::ros2 {
namespace {

template <typename M>
M round_trip(const M& message) {
  std::vector<std::uint8_t> bytes;
  MessageType<M>::encode(message, bytes);
  return MessageType<M>::decode(bytes);
}

TEST(Ros2Messages, TwistIsItsSixDoublesAfterTheHeader) {
  std::vector<std::uint8_t> bytes;
  MessageType<Twist>::encode({{0.5, 0.0, 0.0}, {0.0, 0.0, -0.25}}, bytes);
  ASSERT_EQ(bytes.size(), 4u + 6 * 8);
  EXPECT_EQ(bytes[0], 0x00);
  EXPECT_EQ(bytes[1], 0x01);
  const Twist back = MessageType<Twist>::decode(bytes);
  EXPECT_EQ(back.linear.x, 0.5);
  EXPECT_EQ(back.angular.z, -0.25);
}

TEST(Ros2Messages, OdometryAlignsItsDoublesAfterTheStrings) {
  Odometry odom;
  odom.header = {Time::from_ns(12'345'678'901), "odom"};
  odom.child_frame_id = "base_link";  // 10 bytes with its NUL: the next double needs padding
  odom.pose.position = {1.25, -2.5, 0.0};
  odom.pose.orientation = Quaternion::from_yaw(0.3);
  odom.twist.linear.x = 0.7;
  odom.twist.angular.z = 0.1;
  const Odometry back = round_trip(odom);
  EXPECT_EQ(back.header.stamp.sec, 12);
  EXPECT_EQ(back.header.stamp.nanosec, 345'678'901u);
  EXPECT_EQ(back.header.frame_id, "odom");
  EXPECT_EQ(back.child_frame_id, "base_link");
  EXPECT_EQ(back.pose.position.y, -2.5);
  const ros2::Quaternion& q = back.pose.orientation;
  EXPECT_NEAR(2.0 * std::atan2(q.z, q.w), 0.3, 1e-15);
  EXPECT_EQ(back.twist.linear.x, 0.7);
  EXPECT_EQ(back.twist.angular.z, 0.1);
}

TEST(Ros2Messages, CameraInfoAndImagesRoundTrip) {
  CameraInfo info;
  info.header.frame_id = "camera_optical";
  info.width = 320;
  info.height = 240;
  info.d = {0.1, -0.02, 0.0, 0.0, 0.0};
  info.k = {200, 0, 159.5, 0, 200, 119.5, 0, 0, 1};
  const CameraInfo back = round_trip(info);
  EXPECT_EQ(back.width, 320u);
  EXPECT_EQ(back.d, info.d);
  EXPECT_EQ(back.k, info.k);

  CompressedImage image;
  image.format = "png";
  image.data = {0x89, 'P', 'N', 'G', 1, 2, 3};
  EXPECT_EQ(round_trip(image).data, image.data);
}

TEST(Ros2Messages, TransformsKeepTheirOrder) {
  TFMessage tf;
  tf.transforms.push_back({{Time::from_ns(1), "world"}, "a/base_link", {1, 2, 0}, {}});
  tf.transforms.push_back({{Time::from_ns(1), "world"}, "b/base_link", {3, 4, 0}, {}});
  const TFMessage back = round_trip(tf);
  ASSERT_EQ(back.transforms.size(), 2u);
  EXPECT_EQ(back.transforms[1].child_frame_id, "b/base_link");
  EXPECT_EQ(back.transforms[1].translation.y, 4.0);
}

TEST(Ros2Messages, AStampThatIsNoTimeIsRefused) {
  for (const Time stamp : {Time{-1, 0}, Time{1, 1'000'000'000}}) {
    CompressedImage image;
    image.header.stamp = stamp;
    std::vector<std::uint8_t> bytes;
    MessageType<CompressedImage>::encode(image, bytes);
    EXPECT_THROW(MessageType<CompressedImage>::decode(bytes), RecordingError);
  }
  EXPECT_THROW(Time::from_ns(std::uint64_t{1} << 62), std::invalid_argument);
}

TEST(Ros2Messages, ShortOrMalformedBytesNameTheField) {
  std::vector<std::uint8_t> bytes;
  Odometry odom;
  odom.child_frame_id = "base_link";
  MessageType<Odometry>::encode(odom, bytes);
  bytes.resize(40);
  try {
    MessageType<Odometry>::decode(bytes);
    FAIL();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("CDR field pose.pose.position"), std::string::npos)
        << e.what();
  }
  const std::vector<std::uint8_t> big_endian = {0x00, 0x00, 0x00, 0x00, 0, 0, 0, 0};
  EXPECT_THROW(MessageType<Twist>::decode(big_endian), RecordingError);
  // A sequence whose count exceeds what the message holds.
  const std::vector<std::uint8_t> huge = {0x00, 0x01, 0x00, 0x00, 0xff, 0xff, 0xff, 0x7f};
  EXPECT_THROW(MessageType<TFMessage>::decode(huge), RecordingError);
}

TEST(Ros2Messages, SchemasCarryTheirDependenciesOnce) {
  const std::string& odom = MessageType<Odometry>::schema();
  EXPECT_EQ(odom.find("std_msgs/Header header\n"), 0u);
  for (const char* type : {"MSG: std_msgs/Header\n", "MSG: builtin_interfaces/Time\n",
                           "MSG: geometry_msgs/Pose\n", "MSG: geometry_msgs/Vector3\n"}) {
    const auto at = odom.find(type);
    ASSERT_NE(at, std::string::npos) << type;
    EXPECT_EQ(odom.find(type, at + 1), std::string::npos) << type << " twice";
  }
  EXPECT_STREQ(MessageType<TFMessage>::name(), "tf2_msgs/msg/TFMessage");
}

}  // namespace
}  // namespace flowsteer::recording::ros2
