#include "recorded_camera.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/command.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
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

// The camera's mount from the static transforms: the chain from the image's frame up to the
// base (`base_link` or `base_footprint`, under a namespace or not) composed, its optical centre's
// height and the pitch of its optical axis (the camera's z) below the horizon; a roll about that
// axis is not a flowsteer mount's and is left out. None when the chain does not reach the base.
std::optional<base::CameraMount> mount_of(
    const std::map<std::string, ros2::TransformStamped>& by_child, std::string frame,
    const std::string& file) {
  Eigen::Isometry3d base_from_camera = Eigen::Isometry3d::Identity();
  const auto is_base = [](const std::string& f) {
    for (const char* base : {"base_link", "base_footprint"}) {
      const std::string b = base;
      if (f == b || (f.size() > b.size() && f.ends_with("/" + b))) {
        return true;
      }
    }
    return false;
  };
  for (int hop = 0; hop < 16 && !is_base(frame); ++hop) {
    const auto t = by_child.find(frame);
    if (t == by_child.end()) {
      return std::nullopt;
    }
    const ros2::TransformStamped& link = t->second;
    Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
    parent_from_child.translate(
        Eigen::Vector3d(link.translation.x, link.translation.y, link.translation.z));
    parent_from_child.rotate(
        Eigen::Quaterniond(link.rotation.w, link.rotation.x, link.rotation.y, link.rotation.z)
            .normalized());
    base_from_camera = parent_from_child * base_from_camera;
    frame = link.header.frame_id;
  }
  if (!is_base(frame)) {
    return std::nullopt;
  }
  const Eigen::Vector3d axis = base_from_camera.linear() * Eigen::Vector3d::UnitZ();
  const base::CameraMount mount{base_from_camera.translation().z(),
                                std::atan2(-axis.z(), std::hypot(axis.x(), axis.y()))};
  try {
    mount.validate();
  } catch (const std::invalid_argument& e) {
    throw RecordingError(file + ": the camera's mount from /tf_static (" + frame +
                         " to the image's frame): " + e.what());
  }
  return mount;
}

camera_io::CameraModel camera_model(const ros2::CameraInfo& info, const std::string& where) {
  try {
    return camera_io::camera_model_of(info);
  } catch (const std::invalid_argument& e) {
    throw RecordingError(where + ": " + e.what());
  }
}

// The size a PNG's or a JPEG's header states, read before decoding: hostile bytes must not make
// the decoder allocate gigabytes. None for other formats, or a header cut short.
std::optional<cv::Size> compressed_size(std::span<const std::uint8_t> data) {
  const auto be16 = [&](std::size_t at) { return (data[at] << 8) | data[at + 1]; };
  const auto be32 = [&](std::size_t at) {
    return static_cast<std::int64_t>((std::uint32_t{data[at]} << 24) |
                                     (std::uint32_t{data[at + 1]} << 16) |
                                     (std::uint32_t{data[at + 2]} << 8) | data[at + 3]);
  };
  const auto clamp = [](std::int64_t v) {
    return static_cast<int>(std::min<std::int64_t>(v, 1 << 30));
  };
  if (data.size() >= 24 && data[0] == 0x89 && data[1] == 'P' && data[12] == 'I' &&
      data[13] == 'H') {
    return cv::Size(clamp(be32(16)), clamp(be32(20)));  // IHDR, the first chunk
  }
  if (data.size() < 4 || data[0] != 0xFF || data[1] != 0xD8) {
    return std::nullopt;
  }
  // JPEG: segments after SOI until a start of frame (C0–CF but C4, C8, CC) holds the size.
  for (std::size_t at = 2; at + 9 <= data.size() && data[at] == 0xFF;) {
    const std::uint8_t marker = data[at + 1];
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      return cv::Size(be16(at + 7), be16(at + 5));
    }
    at += 2 + static_cast<std::size_t>(be16(at + 2));
  }
  return std::nullopt;
}

bool within_image_bounds(const cv::Size& size) {
  const auto& side = base::bounds::kImageSide_px;
  return size.width >= side.min && size.width <= side.max && size.height >= side.min &&
         size.height <= side.max;
}

// A BGR image from an Image message's pixels.
cv::Mat bgr_of(const ros2::Image& image, const std::string& where) {
  static const std::map<std::string, std::pair<int, int>> formats = {
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
  if (!within_image_bounds({static_cast<int>(std::min<std::uint32_t>(image.width, 1 << 30)),
                            static_cast<int>(std::min<std::uint32_t>(image.height, 1 << 30))}) ||
      image.step < row_bytes || image.data.size() < std::size_t{image.step} * image.height) {
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
  if (const auto size = compressed_size(image.data); size && !within_image_bounds(*size)) {
    throw RecordingError(where + ": a " + std::to_string(size->width) + "x" +
                         std::to_string(size->height) + " " + image.format +
                         " image, outside a camera's sides " +
                         base::bounds::kImageSide_px.describe());
  }
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

  std::optional<double> frame_rate_hz() const {
    if (count < 2 || last_ns <= first_ns) {
      return std::nullopt;
    }
    return static_cast<double>(count - 1) / (static_cast<double>(last_ns - first_ns) * 1e-9);
  }
};

// What the first pass over a recording gathers: every odometry channel's motion by stamp, the
// first CameraInfo of each frame, each image channel, the static transforms by child frame.
struct RecordingIndex {
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, drivers::BodyVelocity>>> odometry;
  std::map<std::string, ros2::CameraInfo> camera_infos;
  std::map<std::uint16_t, ImageChannel> image_channels;
  std::map<std::string, ros2::TransformStamped> static_transforms;

  void add(const recording::McapMessage& m, const std::string& file) {
    const std::string schema = schema_of(*m.channel);
    if (schema == Odometry::name()) {
      const ros2::Odometry o = decode<Odometry>(m, file);
      odometry[m.channel->id].emplace_back(
          o.header.stamp.ns(),
          drivers::BodyVelocity{o.twist.linear.x, base::turn_rate_of(o.twist.angular.z)});
    } else if (schema == CameraInfo::name()) {
      const ros2::CameraInfo info = decode<CameraInfo>(m, file);
      camera_infos.try_emplace(info.header.frame_id, info);
    } else if (m.channel->topic == "/tf_static" && schema == TFMessage::name()) {
      ros2::TFMessage tf = decode<TFMessage>(m, file);
      for (ros2::TransformStamped& t : tf.transforms) {
        static_transforms[t.child_frame_id] = std::move(t);
      }
    } else if (is_image(*m.channel)) {
      image_channels[m.channel->id].add(m, file);
    }
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
  RecordingIndex found;
  while (const auto m = reader.next()) {
    found.add(*m, file);
  }
  const recording::McapChannel* image =
      choose(reader.channels(), topics.image, is_image, "image", "--image-topic", false, file);
  image_topic_ = image->topic;
  const auto images = found.image_channels.find(image->id);
  if (images == found.image_channels.end()) {
    throw RecordingError(file + ": no images on " + image_topic_ +
                         " (a recording made with --mcap-images 0 has none)");
  }
  image_frame_ = images->second.frame_id;
  frame_rate_hz_ = images->second.frame_rate_hz().value_or(frame_rate_hz_);
  const recording::McapChannel* odom = choose(
      reader.channels(), topics.odometry,
      [](const recording::McapChannel& c) { return schema_of(c) == Odometry::name(); }, "odometry",
      "--odom-topic", true, file);
  if (odom != nullptr) {
    odometry_topic_ = odom->topic;
    odometry_ = std::move(found.odometry[odom->id]);
    std::stable_sort(odometry_.begin(), odometry_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  mount_ = mount_of(found.static_transforms, image_frame_, file);
  camera_io::LensOptions options;
  if (lens) {
    options = *lens;
  } else {
    const auto info = found.camera_infos.find(image_frame_);
    if (info == found.camera_infos.end()) {
      throw RecordingError(file + ": no CameraInfo for the frame '" + image_frame_ + "' of " +
                           image_topic_ + ": give --camera-info or --hfov-deg");
    }
    options.model = camera_model(info->second, file + ": CameraInfo of " + image_frame_);
  }
  const cv::Size size = images->second.size;
  lens_.emplace(options, size.width, size.height, file + ": " + image_topic_);
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
