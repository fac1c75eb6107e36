#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/lens.hpp"
#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/recording/mcap_reader.hpp"

namespace flowsteer::robot {

// Which channels of an MCAP recording a replay takes; empty: the one channel of the type.
struct RecordedTopics {
  std::string image;     // sensor_msgs/msg/Image or CompressedImage
  std::string odometry;  // nav_msgs/msg/Odometry
};

// The camera and the odometry of an MCAP recording (a robot's `ros2 bag`, or flowsteer's own), for
// `flowsteer replay`: each image with its header's stamp, undistorted by the recording's
// CameraInfo (unless the lens is given), the base's speed and turn rate from the last odometry
// at or before it, and the camera's mount from /tf_static (base_link → the image's frame) where
// the recording has it. A first pass over the file reads the odometry, the CameraInfo and the
// mount; the images are decoded in a second, one at a time. A missing or ambiguous channel, or a
// message that is not what its channel says, throws recording::RecordingError naming the topic
// and the message's index.
class RecordedCamera {
 public:
  // lens: the user's lens (--camera-info, --hfov-deg), in place of the recording's CameraInfo.
  RecordedCamera(const std::filesystem::path& path, const RecordedTopics& topics,
                 const std::optional<camera_io::LensOptions>& lens);

  const base::CameraIntrinsics& intrinsics() const { return lens_->intrinsics(); }
  const std::optional<base::CameraMount>& mount() const { return mount_; }
  bool has_odometry() const { return !odometry_.empty(); }
  const std::string& image_topic() const { return image_topic_; }
  const std::string& odometry_topic() const { return odometry_topic_; }
  // The images' mean rate over the recording (30 when it holds a single image).
  double frame_rate_hz() const { return frame_rate_hz_; }

  // The next image and the base's motion at its stamp; false after the last.
  bool read(camera_io::Frame& frame, drivers::BodyVelocity& measured);

 private:
  void index(const RecordedTopics& topics, const std::optional<camera_io::LensOptions>& lens);

  std::filesystem::path path_;
  std::string image_topic_;
  std::string odometry_topic_;
  std::string image_frame_;
  double frame_rate_hz_ = 30.0;
  std::optional<camera_io::Lens> lens_;
  std::optional<base::CameraMount> mount_;
  std::vector<std::pair<std::uint64_t, drivers::BodyVelocity>> odometry_;  // by stamp
  recording::McapReader images_;
  std::uint64_t sequence_ = 0;
};

}  // namespace flowsteer::robot
