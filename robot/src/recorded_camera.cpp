#include "recorded_camera.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/command.hpp"
#include "flowsteer/recording/recording_error.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::robot {

namespace ros2 = recording::ros2;
using recording::RecordingError;

namespace {

using Image = ros2::MessageType<ros2::Image>;
using CompressedImage = ros2::MessageType<ros2::CompressedImage>;
using Odometry = ros2::MessageType<ros2::Odometry>;
using CameraInfo = ros2::MessageType<ros2::CameraInfo>;
using TFMessage = ros2::MessageType<ros2::TFMessage>;

std::string schema_of(const recording::McapChannel& channel) {
  return channel.schema != nullptr ? channel.schema->name : std::string();
}

bool is_image(const recording::McapChannel& channel) {
  const std::string schema = schema_of(channel);
  return schema == Image::name() || schema == CompressedImage::name();
}

// Decodes a message as its channel's type; a failure names the file, the topic and the index.
template <typename Type>
auto decode(const recording::McapMessage& m, const std::string& file) {
  try {
    return Type::decode(m.data);
  } catch (const RecordingError& e) {
    throw RecordingError(file + ": " + m.channel->topic + " message " + std::to_string(m.index) +
                         ": " + e.what());
  }
}

// The one channel `wanted` names, or the one channel `fits` (none when `optional` and there is
// none); the error lists what the file has.
const recording::McapChannel* choose(
    const std::map<std::uint16_t, recording::McapChannel>& channels, const std::string& wanted,
    bool (*fits)(const recording::McapChannel&), const char* what, const char* option,
    bool optional, const std::string& file) {
  std::vector<const recording::McapChannel*> found;
  std::string topics;
  for (const auto& [id, channel] : channels) {
    if (fits(channel)) {
      topics += (topics.empty() ? "" : ", ") + channel.topic;
      if (wanted.empty() || channel.topic == wanted) {
        found.push_back(&channel);
      }
    }
  }
  if (found.size() == 1) {
    return found.front();
  }
  if (found.empty() && optional && wanted.empty()) {
    return nullptr;
  }
  if (found.empty()) {
    throw RecordingError(file + ": no " + what + " channel" +
                         (wanted.empty() ? std::string() : " on topic " + wanted) +
                         (topics.empty() ? std::string() : " (the file has " + topics + ")"));
  }
  throw RecordingError(file + ": " + std::to_string(found.size()) + " " + what + " channels (" +
                       topics + "): choose one with " + option);
}

// The mount a base → camera transform gives: the optical centre's height, and the pitch of the
// optical axis (the camera's z) below the horizon.
base::CameraMount mount_of(const ros2::TransformStamped& t) {
  const Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  const Eigen::Vector3d axis = q.normalized() * Eigen::Vector3d::UnitZ();
  return {t.translation.z, std::atan2(-axis.z(), std::hypot(axis.x(), axis.y()))};
}

camera_io::CameraModel camera_model(const ros2::CameraInfo& info, const std::string& where) {
  camera_io::CameraModel model;
  model.width_px = static_cast<int>(info.width);
  model.height_px = static_cast<int>(info.height);
  model.fx = info.k[0];
  model.cx = info.k[2];
  model.fy = info.k[4];
  model.cy = info.k[5];
  const bool no_distortion =
      std::all_of(info.d.begin(), info.d.end(), [](double d) { return d == 0.0; });
  const auto distortion = camera_io::distortion_model_from_name(info.distortion_model);
  if (!no_distortion && !distortion) {
    throw RecordingError(where + ": distortion model '" + info.distortion_model +
                         "' (known: plumb_bob, rational_polynomial, equidistant)");
  }
  if (!no_distortion) {
    model.distortion = *distortion;
    model.coefficients = info.d;
    model.coefficients.resize(camera_io::distortion_coefficient_count(*distortion), 0.0);
  }
  try {
    model.validate();
  } catch (const std::invalid_argument& e) {
    throw RecordingError(where + ": " + e.what());
  }
  return model;
}

// A BGR image from an Image message's pixels.
cv::Mat bgr_of(const ros2::Image& image, const std::string& where) {
  const std::map<std::string, std::pair<int, int>> formats = {
      {"rgb8", {CV_8UC3, cv::COLOR_RGB2BGR}},
      {"bgr8", {CV_8UC3, -1}},
      {"mono8", {CV_8UC1, cv::COLOR_GRAY2BGR}},
      {"yuv422", {CV_8UC2, cv::COLOR_YUV2BGR_UYVY}},
      {"yuv422_yuy2", {CV_8UC2, cv::COLOR_YUV2BGR_YUY2}}};
  const auto format = formats.find(image.encoding);
  if (format == formats.end()) {
    throw RecordingError(where + ": encoding '" + image.encoding +
                         "' (known: rgb8, bgr8, mono8, yuv422, yuv422_yuy2)");
  }
  const auto [type, conversion] = format->second;
  const std::size_t row_bytes = image.width * static_cast<std::size_t>(CV_ELEM_SIZE(type));
  if (image.width == 0 || image.height == 0 || image.step < row_bytes ||
      image.data.size() < std::size_t{image.step} * image.height) {
    throw RecordingError(where + ": " + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + " pixels of " + image.encoding +
                         " with step " + std::to_string(image.step) + " do not fit its " +
                         std::to_string(image.data.size()) + " bytes");
  }
  const cv::Mat pixels(static_cast<int>(image.height), static_cast<int>(image.width), type,
                       const_cast<std::uint8_t*>(image.data.data()), image.step);
  cv::Mat bgr;
  if (conversion < 0) {
    pixels.copyTo(bgr);
  } else {
    cv::cvtColor(pixels, bgr, conversion);
  }
  return bgr;
}

// An Image or CompressedImage message's picture, BGR, and its header.
cv::Mat decode_image(const recording::McapMessage& m, const std::string& file,
                     ros2::Header& header) {
  const std::string where = file + ": " + m.channel->topic + " message " + std::to_string(m.index);
  if (schema_of(*m.channel) == Image::name()) {
    const ros2::Image image = decode<Image>(m, file);
    header = image.header;
    return bgr_of(image, where);
  }
  const ros2::CompressedImage image = decode<CompressedImage>(m, file);
  header = image.header;
  cv::Mat bgr = cv::imdecode(image.data, cv::IMREAD_COLOR);
  if (bgr.empty()) {
    throw RecordingError(where + ": cannot decode its " + std::to_string(image.data.size()) +
                         " bytes of format '" + image.format + "'");
  }
  return bgr;
}

// What the first pass learns of an image channel: its first image's frame and size, and its
// message count and first and last log times (the frame rate).
struct ImageChannel {
  std::string frame_id;
  cv::Size size;
  std::uint64_t count = 0;
  std::uint64_t first_ns = 0;
  std::uint64_t last_ns = 0;

  void add(const recording::McapMessage& m, const std::string& file) {
    if (count++ == 0) {
      ros2::Header header;
      size = decode_image(m, file, header).size();
      frame_id = header.frame_id;
      first_ns = m.log_time_ns;
    }
    last_ns = m.log_time_ns;
  }
};

}  // namespace

RecordedCamera::RecordedCamera(const std::filesystem::path& path, const RecordedTopics& topics,
                               const std::optional<camera_io::LensOptions>& lens)
    : path_(path), images_(path) {
  index(topics, lens);
}

void RecordedCamera::index(const RecordedTopics& topics,
                           const std::optional<camera_io::LensOptions>& lens) {
  const std::string file = path_.string();
  recording::McapReader reader(path_);
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, drivers::BodyVelocity>>> odometry;
  std::map<std::string, ros2::CameraInfo> camera_infos;  // the first of each frame
  std::map<std::uint16_t, ImageChannel> image_channels;
  std::vector<ros2::TransformStamped> mounts;
  while (const auto m = reader.next()) {
    const std::string schema = schema_of(*m->channel);
    if (schema == Odometry::name()) {
      const ros2::Odometry o = decode<Odometry>(*m, file);
      odometry[m->channel->id].emplace_back(
          o.header.stamp.ns(),
          drivers::BodyVelocity{o.twist.linear.x, base::turn_rate_of(o.twist.angular.z)});
    } else if (schema == CameraInfo::name()) {
      const ros2::CameraInfo info = decode<CameraInfo>(*m, file);
      camera_infos.try_emplace(info.header.frame_id, info);
    } else if (m->channel->topic == "/tf_static" && schema == TFMessage::name()) {
      const ros2::TFMessage tf = decode<TFMessage>(*m, file);
      mounts.insert(mounts.end(), tf.transforms.begin(), tf.transforms.end());
    } else if (is_image(*m->channel)) {
      image_channels[m->channel->id].add(*m, file);
    }
  }
  const recording::McapChannel* image =
      choose(reader.channels(), topics.image, is_image, "image", "--image-topic", false, file);
  image_topic_ = image->topic;
  const ImageChannel& images = image_channels.at(image->id);
  image_frame_ = images.frame_id;
  if (images.count > 1 && images.last_ns > images.first_ns) {
    frame_rate_hz_ = static_cast<double>(images.count - 1) /
                     (static_cast<double>(images.last_ns - images.first_ns) * 1e-9);
  }
  const recording::McapChannel* odom = choose(
      reader.channels(), topics.odometry,
      [](const recording::McapChannel& c) { return schema_of(c) == Odometry::name(); }, "odometry",
      "--odom-topic", true, file);
  if (odom != nullptr) {
    odometry_topic_ = odom->topic;
    odometry_ = std::move(odometry[odom->id]);
    std::stable_sort(odometry_.begin(), odometry_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  for (const ros2::TransformStamped& t : mounts) {
    if (t.child_frame_id == image_frame_) {
      mount_ = mount_of(t);
    }
  }
  camera_io::LensOptions options;
  if (lens) {
    options = *lens;
  } else {
    const auto info = camera_infos.find(image_frame_);
    if (info == camera_infos.end()) {
      throw RecordingError(file + ": no CameraInfo for the frame '" + image_frame_ + "' of " +
                           image_topic_ + ": give --camera-info or --hfov-deg");
    }
    options.model = camera_model(info->second, file + ": CameraInfo of " + image_frame_);
  }
  lens_.emplace(options, images.size.width, images.size.height, file + ": " + image_topic_);
}

bool RecordedCamera::read(camera_io::Frame& frame, drivers::BodyVelocity& measured) {
  while (const auto m = images_.next()) {
    if (m->channel->topic != image_topic_) {
      continue;
    }
    ros2::Header header;
    const cv::Mat bgr = decode_image(*m, path_.string(), header);
    const base::CameraIntrinsics& k = lens_->intrinsics();
    if (bgr.cols != k.width_px || bgr.rows != k.height_px) {
      throw RecordingError(path_.string() + ": " + image_topic_ + " message " +
                           std::to_string(m->index) + ": a " + std::to_string(bgr.cols) + "x" +
                           std::to_string(bgr.rows) + " image, the camera's are " +
                           std::to_string(k.width_px) + "x" + std::to_string(k.height_px));
    }
    lens_->apply(bgr).copyTo(frame.image);
    frame.timestamp_s = static_cast<double>(header.stamp.ns()) * 1e-9;
    frame.sequence = sequence_++;
    frame.sim.reset();
    const std::uint64_t stamp = header.stamp.ns();
    const auto after =
        std::upper_bound(odometry_.begin(), odometry_.end(), stamp,
                         [](std::uint64_t t, const auto& entry) { return t < entry.first; });
    measured = after == odometry_.begin() ? drivers::BodyVelocity{} : std::prev(after)->second;
    return true;
  }
  return false;
}

}  // namespace flowsteer::robot
