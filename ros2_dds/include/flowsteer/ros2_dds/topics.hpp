#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "flowsteer/recording/ros2_messages.hpp"
#include "flowsteer/ros2_dds/participant.hpp"

namespace flowsteer::ros2_dds {

// The messages this module carries are recording's ROS 2 structs (Twist, Odometry, Image,
// CompressedImage, CameraInfo) and this one, which only a drive publishes.
struct TwistStamped {
  recording::ros2::Header header;
  recording::ros2::Twist twist;
};

// "geometry_msgs/msg/Twist": the ROS 2 type a message struct travels as.
template <typename Message>
std::string ros2_type_name();

// A ROS 2 publisher: a DDS writer on topic "rt" + topic, with ROS 2's DDS type name
// ("geometry_msgs::msg::dds_::Twist_"). Message: Twist or TwistStamped.
template <typename Message>
class Publisher {
 public:
  // Throws DdsError naming the topic when the topic or writer cannot be made, or the name is
  // not a ROS 2 topic name (topic_name_problem).
  Publisher(const Participant& participant, const std::string& topic, const Qos& qos);
  ~Publisher();
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Throws DdsError naming the topic when the write fails.
  void publish(const Message& message);
  // Subscriptions matched now.
  int subscriber_count() const;
  // Waits until a subscription has matched; false after timeout_s without one.
  bool wait_for_subscriber(double timeout_s) const;
  // Waits until every matched reliable subscription acknowledged what was published; false on
  // timeout. What a stop publishes is followed by this, so that it is not lost at exit.
  bool wait_for_acknowledgements(double timeout_s) const;
  const std::string& topic() const { return topic_; }

 private:
  std::string topic_;
  std::int32_t topic_handle_;
  std::int32_t writer_;
};

// A ROS 2 subscription. Message: Odometry, Image, CompressedImage or CameraInfo.
template <typename Message>
class Subscription {
 public:
  Subscription(const Participant& participant, const std::string& topic, const Qos& qos);
  ~Subscription();
  Subscription(const Subscription&) = delete;
  Subscription& operator=(const Subscription&) = delete;

  // Waits up to timeout_s for a message to take; true when one is there.
  bool wait(double timeout_s);
  // Moves the oldest message not yet taken into `message` (reusing its buffers); false, with
  // `message` unchanged, when none is waiting. Throws DdsError naming the topic on a failure.
  bool take(Message& message);
  // Publishers matched now.
  int publisher_count() const;
  const std::string& topic() const { return topic_; }

 private:
  std::string topic_;
  std::int32_t topic_handle_;
  std::int32_t reader_;
  std::int32_t waitset_;
};

}  // namespace flowsteer::ros2_dds
