#include "message_conversions.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace flowsteer::ros2_dds::detail {

namespace ros2 = recording::ros2;

namespace {

// A string or sequence the writer only reads: the C types are not const-correct.
char* borrow(const std::string& text) {
  return const_cast<char*>(text.c_str());
}

template <typename Sequence, typename T>
Sequence borrow(const std::vector<T>& values) {
  Sequence sequence{};
  sequence._maximum = sequence._length = static_cast<std::uint32_t>(values.size());
  sequence._buffer = const_cast<T*>(values.data());
  sequence._release = false;
  return sequence;
}

void copy_string(const char* wire, std::string& text) {
  text.assign(wire != nullptr ? wire : "");
}

template <typename Sequence, typename T>
void copy_sequence(const Sequence& wire, std::vector<T>& values) {
  values.assign(wire._buffer, wire._buffer + (wire._buffer != nullptr ? wire._length : 0));
}

void header_to_wire(const ros2::Header& header, std_msgs_msg_dds__Header_& wire) {
  wire.stamp.sec = header.stamp.sec;
  wire.stamp.nanosec = header.stamp.nanosec;
  wire.frame_id = borrow(header.frame_id);
}

void header_from_wire(const std_msgs_msg_dds__Header_& wire, ros2::Header& header) {
  header.stamp.sec = wire.stamp.sec;
  header.stamp.nanosec = wire.stamp.nanosec;
  copy_string(wire.frame_id, header.frame_id);
}

template <typename CVector>
void vector_to_wire(const ros2::Vector3& v, CVector& wire) {
  wire.x = v.x;
  wire.y = v.y;
  wire.z = v.z;
}

template <typename CVector>
ros2::Vector3 vector_from_wire(const CVector& wire) {
  return {wire.x, wire.y, wire.z};
}

void twist_to_wire(const ros2::Twist& twist, geometry_msgs_msg_dds__Twist_& wire) {
  vector_to_wire(twist.linear, wire.linear);
  vector_to_wire(twist.angular, wire.angular);
}

void twist_from_wire(const geometry_msgs_msg_dds__Twist_& wire, ros2::Twist& twist) {
  twist.linear = vector_from_wire(wire.linear);
  twist.angular = vector_from_wire(wire.angular);
}

}  // namespace

void Wire<ros2::Twist>::to_wire(const ros2::Twist& message, C& wire) {
  twist_to_wire(message, wire);
}
void Wire<ros2::Twist>::from_wire(const C& wire, ros2::Twist& message) {
  twist_from_wire(wire, message);
}

void Wire<TwistStamped>::to_wire(const TwistStamped& message, C& wire) {
  header_to_wire(message.header, wire.header);
  twist_to_wire(message.twist, wire.twist);
}
void Wire<TwistStamped>::from_wire(const C& wire, TwistStamped& message) {
  header_from_wire(wire.header, message.header);
  twist_from_wire(wire.twist, message.twist);
}

void Wire<ros2::Odometry>::to_wire(const ros2::Odometry& message, C& wire) {
  header_to_wire(message.header, wire.header);
  wire.child_frame_id = borrow(message.child_frame_id);
  vector_to_wire(message.pose.position, wire.pose.pose.position);
  const ros2::Quaternion& q = message.pose.orientation;
  wire.pose.pose.orientation = {q.x, q.y, q.z, q.w};
  std::copy(message.pose_covariance.begin(), message.pose_covariance.end(), wire.pose.covariance);
  twist_to_wire(message.twist, wire.twist.twist);
  std::copy(message.twist_covariance.begin(), message.twist_covariance.end(),
            wire.twist.covariance);
}
void Wire<ros2::Odometry>::from_wire(const C& wire, ros2::Odometry& message) {
  header_from_wire(wire.header, message.header);
  copy_string(wire.child_frame_id, message.child_frame_id);
  message.pose.position = vector_from_wire(wire.pose.pose.position);
  const auto& q = wire.pose.pose.orientation;
  message.pose.orientation = {q.x, q.y, q.z, q.w};
  std::copy(std::begin(wire.pose.covariance), std::end(wire.pose.covariance),
            message.pose_covariance.begin());
  twist_from_wire(wire.twist.twist, message.twist);
  std::copy(std::begin(wire.twist.covariance), std::end(wire.twist.covariance),
            message.twist_covariance.begin());
}

void Wire<ros2::Image>::to_wire(const ros2::Image& message, C& wire) {
  header_to_wire(message.header, wire.header);
  wire.height = message.height;
  wire.width = message.width;
  wire.encoding = borrow(message.encoding);
  wire.is_bigendian = message.is_bigendian;
  wire.step = message.step;
  wire.data = borrow<dds_sequence_uint8>(message.data);
}
void Wire<ros2::Image>::from_wire(const C& wire, ros2::Image& message) {
  header_from_wire(wire.header, message.header);
  message.height = wire.height;
  message.width = wire.width;
  copy_string(wire.encoding, message.encoding);
  message.is_bigendian = wire.is_bigendian;
  message.step = wire.step;
  copy_sequence(wire.data, message.data);
}

void Wire<ros2::CompressedImage>::to_wire(const ros2::CompressedImage& message, C& wire) {
  header_to_wire(message.header, wire.header);
  wire.format = borrow(message.format);
  wire.data = borrow<dds_sequence_uint8>(message.data);
}
void Wire<ros2::CompressedImage>::from_wire(const C& wire, ros2::CompressedImage& message) {
  header_from_wire(wire.header, message.header);
  copy_string(wire.format, message.format);
  copy_sequence(wire.data, message.data);
}

void Wire<ros2::CameraInfo>::to_wire(const ros2::CameraInfo& message, C& wire) {
  header_to_wire(message.header, wire.header);
  wire.height = message.height;
  wire.width = message.width;
  wire.distortion_model = borrow(message.distortion_model);
  wire.d = borrow<dds_sequence_double>(message.d);
  std::copy(message.k.begin(), message.k.end(), wire.k);
  std::copy(message.r.begin(), message.r.end(), wire.r);
  std::copy(message.p.begin(), message.p.end(), wire.p);
  wire.binning_x = message.binning_x;
  wire.binning_y = message.binning_y;
  const ros2::RegionOfInterest& roi = message.roi;
  wire.roi = {roi.x_offset, roi.y_offset, roi.height, roi.width, roi.do_rectify};
}
void Wire<ros2::CameraInfo>::from_wire(const C& wire, ros2::CameraInfo& message) {
  header_from_wire(wire.header, message.header);
  message.height = wire.height;
  message.width = wire.width;
  copy_string(wire.distortion_model, message.distortion_model);
  copy_sequence(wire.d, message.d);
  std::copy(std::begin(wire.k), std::end(wire.k), message.k.begin());
  std::copy(std::begin(wire.r), std::end(wire.r), message.r.begin());
  std::copy(std::begin(wire.p), std::end(wire.p), message.p.begin());
  message.binning_x = wire.binning_x;
  message.binning_y = wire.binning_y;
  const auto& roi = wire.roi;
  message.roi = {roi.x_offset, roi.y_offset, roi.height, roi.width, roi.do_rectify};
}

}  // namespace flowsteer::ros2_dds::detail
