#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace flowsteer::recording::ros2 {

// The ROS 2 messages a recording holds, as ROS 2's common_interfaces define them (field for
// field, in order), with their CDR encoding and their schema.
// Frames follow REP 103 (x forward, y left, z up; yaw positive to the left) and REP 105.

struct Time {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  // Throws std::invalid_argument past 2^31 s.
  static Time from_ns(std::uint64_t t_ns);
  std::uint64_t ns() const;
};

struct Header {
  Time stamp;
  std::string frame_id;
};

struct Vector3 {
  double x = 0.0, y = 0.0, z = 0.0;
};

struct Quaternion {
  double x = 0.0, y = 0.0, z = 0.0, w = 1.0;
  static Quaternion from_yaw(double yaw_rad);
  // The rotation's yaw about z (REP 103), whatever its roll and pitch.
  double yaw_rad() const;
};

struct Twist {
  Vector3 linear;
  Vector3 angular;
};

struct Pose {
  Vector3 position;  // geometry_msgs/Point has the Vector3's fields
  Quaternion orientation;
};

struct Odometry {
  Header header;
  std::string child_frame_id;
  Pose pose;
  std::array<double, 36> pose_covariance{};
  Twist twist;
  std::array<double, 36> twist_covariance{};
};

struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Vector3 translation;
  Quaternion rotation;
};

struct TFMessage {
  std::vector<TransformStamped> transforms;
};

struct CompressedImage {
  Header header;
  std::string format;  // "png", "jpeg", ...
  std::vector<std::uint8_t> data;
};

struct Image {
  Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;  // "rgb8", "bgr8", "mono8", ...
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;  // bytes per row
  std::vector<std::uint8_t> data;
};

struct RegionOfInterest {
  std::uint32_t x_offset = 0;
  std::uint32_t y_offset = 0;
  std::uint32_t height = 0;  // 0 with width 0: the whole image
  std::uint32_t width = 0;
  bool do_rectify = false;
};

struct CameraInfo {
  Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string distortion_model = "plumb_bob";
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
  std::uint32_t binning_x = 0;  // 0 or 1: none
  std::uint32_t binning_y = 0;
  RegionOfInterest roi;
};

// The ros2msg schema text MCAP stores for "package/Type": the type's fields, then each type it
// uses after a line of 80 '=' and "MSG: package/Type", as rosbag2 records them.
const std::string& ros2msg_schema(const std::string& package_type);

// Every type: its ROS 2 name, its schema, and the functions that encode it into `out` (cleared
// first) and decode it. Decoding throws RecordingError naming the field where the bytes end or
// disagree.
template <typename Message>
struct MessageType;

#define FLOWSTEER_ROS2_MESSAGE(Type, package)                                        \
  template <>                                                                        \
  struct MessageType<Type> {                                                         \
    static constexpr const char* name() { return package "/msg/" #Type; }            \
    static const std::string& schema() { return ros2msg_schema(package "/" #Type); } \
    static void encode(const Type& message, std::vector<std::uint8_t>& out);         \
    static Type decode(std::span<const std::uint8_t> data);                          \
  };
FLOWSTEER_ROS2_MESSAGE(Twist, "geometry_msgs")
FLOWSTEER_ROS2_MESSAGE(Odometry, "nav_msgs")
FLOWSTEER_ROS2_MESSAGE(TFMessage, "tf2_msgs")
FLOWSTEER_ROS2_MESSAGE(CompressedImage, "sensor_msgs")
FLOWSTEER_ROS2_MESSAGE(Image, "sensor_msgs")
FLOWSTEER_ROS2_MESSAGE(CameraInfo, "sensor_msgs")
#undef FLOWSTEER_ROS2_MESSAGE

}  // namespace flowsteer::recording::ros2
