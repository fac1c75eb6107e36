#pragma once

#include <dds/dds.h>

#include "flowsteer/recording/ros2_messages.hpp"
#include "flowsteer/ros2_dds/topics.hpp"
#include "geometry_msgs/msg/Twist.h"
#include "geometry_msgs/msg/TwistStamped.h"
#include "nav_msgs/msg/Odometry.h"
#include "sensor_msgs/msg/CameraInfo.h"
#include "sensor_msgs/msg/CompressedImage.h"
#include "sensor_msgs/msg/Image.h"

namespace flowsteer::ros2_dds::detail {

// For each message struct: the C type idlc generated from ROS 2's definition, its descriptor,
// its ROS 2 name, and the conversions. to_wire points the C type's strings and sequences into
// the message (no copy: the message must outlive the write); from_wire copies, reusing the
// message's buffers.
template <typename Message>
struct Wire;

#define FLOWSTEER_ROS2_WIRE(Message, CType, ros2_name)                         \
  template <>                                                                  \
  struct Wire<Message> {                                                       \
    using C = CType;                                                           \
    static const dds_topic_descriptor_t& descriptor() { return CType##_desc; } \
    static constexpr const char* kRos2Name = ros2_name;                        \
    static void to_wire(const Message& message, C& wire);                      \
    static void from_wire(const C& wire, Message& message);                    \
  }

FLOWSTEER_ROS2_WIRE(recording::ros2::Twist, geometry_msgs_msg_dds__Twist_,
                    "geometry_msgs/msg/Twist");
FLOWSTEER_ROS2_WIRE(TwistStamped, geometry_msgs_msg_dds__TwistStamped_,
                    "geometry_msgs/msg/TwistStamped");
FLOWSTEER_ROS2_WIRE(recording::ros2::Odometry, nav_msgs_msg_dds__Odometry_,
                    "nav_msgs/msg/Odometry");
FLOWSTEER_ROS2_WIRE(recording::ros2::Image, sensor_msgs_msg_dds__Image_, "sensor_msgs/msg/Image");
FLOWSTEER_ROS2_WIRE(recording::ros2::CompressedImage, sensor_msgs_msg_dds__CompressedImage_,
                    "sensor_msgs/msg/CompressedImage");
FLOWSTEER_ROS2_WIRE(recording::ros2::CameraInfo, sensor_msgs_msg_dds__CameraInfo_,
                    "sensor_msgs/msg/CameraInfo");

#undef FLOWSTEER_ROS2_WIRE

}  // namespace flowsteer::ros2_dds::detail
