#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/lens.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::ros2_dds {
class Participant;
template <typename Message>
class Subscription;
}  // namespace flowsteer::ros2_dds

namespace flowsteer::camera_io {

enum class Ros2ImageType {
  image,             // sensor_msgs/msg/Image
  compressed_image,  // sensor_msgs/msg/CompressedImage (JPEG, PNG: whatever OpenCV decodes)
};

// "sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage", and back.
std::string ros2_image_type_name(Ros2ImageType type);
std::optional<Ros2ImageType> ros2_image_type_from_name(std::string_view name);

// The Image encodings a Ros2Camera reads ("rgb8, bgr8, ..."), and whether one is among them.
// yuv422 is UYVY, as ROS 2's sensor_msgs/image_encodings.hpp defines it; yuv422_yuy2 is YUYV.
std::string ros2_image_encoding_names();
bool is_readable_ros2_image_encoding(std::string_view encoding);

struct Ros2CameraOptions {
  int domain_id = 0;
  std::string image_topic = "/camera/image_raw";
  Ros2ImageType image_type = Ros2ImageType::image;
  // An Image encoding to insist on (an image in another one is an error); empty takes any
  // readable one.
  std::string encoding;
  // The camera's CameraInfo topic: its K, D and distortion model are the lens, and its size must
  // be the images'. Empty: `lens` (a calibration file or a field of view) instead.
  std::string camera_info_topic;
  LensOptions lens;
  // The constructor waits this long for the first image (and CameraInfo).
  double connect_timeout_s = 5.0;
};

// A ROS 2 camera driver's images, subscribed over DDS as a ROS 2 node would (best effort, keep
// last 2: it matches reliable and best-effort publishers, and a slow loop gets the newest
// image). Each read() delivers the newest image that arrived, converted to BGR and undistorted;
// older ones are skipped. Frame times are the header's stamps moved onto the monotonic clock by
// their age (the time the image was taken from DDS when a stamp is unset, in the future or over
// a second old). Not thread-safe.
class Ros2Camera final : public FrameSource {
 public:
  // Waits connect_timeout_s, in all, for the first image (and CameraInfo). Throws
  // std::runtime_error naming the topic and domain when none comes, the encoding cannot be read, or
  // CameraInfo's size or model does not fit the images.
  explicit Ros2Camera(const Ros2CameraOptions& options);
  ~Ros2Camera() override;
  Ros2Camera(const Ros2Camera&) = delete;
  Ros2Camera& operator=(const Ros2Camera&) = delete;

  const base::CameraIntrinsics& intrinsics() const override { return lens_->intrinsics(); }
  // Throws std::runtime_error naming the topic for an image that cannot be decoded, is in
  // another encoding than asked, or changed size.
  ReadStatus read(Frame& frame, double timeout_s) override;

 private:
  bool take_newest();
  void decode();
  // The lens from the first CameraInfo within timeout_s; `source` and `within` for errors.
  void use_camera_info(ros2_dds::Subscription<recording::ros2::CameraInfo>& infos, double timeout_s,
                       const std::string& source, const std::string& within);

  std::string name_;
  std::string encoding_;
  std::unique_ptr<ros2_dds::Participant> participant_;
  std::unique_ptr<ros2_dds::Subscription<recording::ros2::Image>> images_;
  std::unique_ptr<ros2_dds::Subscription<recording::ros2::CompressedImage>> compressed_;
  recording::ros2::Image image_;  // reused for every take
  recording::ros2::CompressedImage compressed_image_;
  recording::ros2::Header header_;  // of the image taken last
  cv::Mat bgr_;
  std::optional<Lens> lens_;
  bool first_pending_ = true;  // the image the constructor waited for is not delivered yet
  double received_s_ = 0.0;    // when the image taken last was taken from DDS
  double last_timestamp_s_ = 0.0;
  std::uint64_t sequence_ = 0;
};

}  // namespace flowsteer::camera_io
