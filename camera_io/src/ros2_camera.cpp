#include "flowsteer/camera_io/ros2_camera.hpp"

#include <array>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/bounds.hpp"
#include "flowsteer/base/clock.hpp"
#include "flowsteer/ros2_dds/participant.hpp"
#include "flowsteer/ros2_dds/topics.hpp"

namespace flowsteer::camera_io {

namespace ros2 = recording::ros2;

namespace {

// A readable encoding: bytes per pixel, and the conversion to BGR (-1: a copy).
struct Encoding {
  std::string_view name;
  int channels;
  int to_bgr;
};

constexpr std::array kEncodings = {
    Encoding{"rgb8", 3, cv::COLOR_RGB2BGR},
    Encoding{"bgr8", 3, -1},
    Encoding{"mono8", 1, cv::COLOR_GRAY2BGR},
    Encoding{"yuv422", 2, cv::COLOR_YUV2BGR_UYVY},
    Encoding{"yuv422_yuy2", 2, cv::COLOR_YUV2BGR_YUY2},
};

const Encoding* find_encoding(std::string_view name) {
  for (const Encoding& encoding : kEncodings) {
    if (encoding.name == name) {
      return &encoding;
    }
  }
  return nullptr;
}

// A header stamp more than this old is not taken for the capture time (a publisher that does
// not stamp, or another host's clock): the reception time is.
constexpr double kMaxStampAge_s = 1.0;

}  // namespace

std::string ros2_image_type_name(Ros2ImageType type) {
  return type == Ros2ImageType::image ? ros2_dds::ros2_type_name<ros2::Image>()
                                      : ros2_dds::ros2_type_name<ros2::CompressedImage>();
}

std::optional<Ros2ImageType> ros2_image_type_from_name(std::string_view name) {
  for (Ros2ImageType type : {Ros2ImageType::image, Ros2ImageType::compressed_image}) {
    if (name == ros2_image_type_name(type)) {
      return type;
    }
  }
  return std::nullopt;
}

std::string ros2_image_encoding_names() {
  std::string names;
  for (const Encoding& encoding : kEncodings) {
    names += (names.empty() ? "" : ", ") + std::string(encoding.name);
  }
  return names;
}

bool is_readable_ros2_image_encoding(std::string_view encoding) {
  return find_encoding(encoding) != nullptr;
}

Ros2Camera::Ros2Camera(const Ros2CameraOptions& options)
    : name_("ros2 camera " + options.image_topic + " (domain " + std::to_string(options.domain_id) +
            ")"),
      encoding_(options.encoding) {
  if (!encoding_.empty() && !is_readable_ros2_image_encoding(encoding_)) {
    throw std::runtime_error(name_ + ": encoding '" + encoding_ + "' cannot be read (" +
                             ros2_image_encoding_names() + ")");
  }
  // Both subscriptions from the start, so that a CameraInfo published while the first image is
  // awaited is not missed; one deadline for both.
  const double deadline_s = base::monotonic_now_s() + options.connect_timeout_s;
  const auto left_s = [&] { return std::max(0.0, deadline_s - base::monotonic_now_s()); };
  const std::string within = " within " + base::format_number(options.connect_timeout_s) + " s";
  std::unique_ptr<ros2_dds::Subscription<ros2::CameraInfo>> infos;
  bool arrived = false;
  try {
    participant_ = std::make_unique<ros2_dds::Participant>(options.domain_id);
    const ros2_dds::Qos qos{ros2_dds::Reliability::best_effort, 2};
    if (options.image_type == Ros2ImageType::image) {
      images_ = std::make_unique<ros2_dds::Subscription<ros2::Image>>(*participant_,
                                                                      options.image_topic, qos);
    } else {
      compressed_ = std::make_unique<ros2_dds::Subscription<ros2::CompressedImage>>(
          *participant_, options.image_topic, qos);
    }
    if (!options.camera_info_topic.empty()) {
      infos = std::make_unique<ros2_dds::Subscription<ros2::CameraInfo>>(
          *participant_, options.camera_info_topic, qos);
    }
    while (!arrived && (images_ ? images_->wait(left_s()) : compressed_->wait(left_s()))) {
      arrived = take_newest();
    }
  } catch (const ros2_dds::DdsError& error) {
    throw std::runtime_error(name_ + ": " + error.what());
  }
  if (!arrived) {
    throw std::runtime_error(name_ + ": no " + ros2_image_type_name(options.image_type) + within +
                             ": is the camera driver running, on this domain?");
  }
  decode();
  if (infos) {
    use_camera_info(*infos, left_s(), name_ + ", camera_info " + options.camera_info_topic, within);
  } else {
    lens_.emplace(options.lens, bgr_.cols, bgr_.rows, name_);
  }
}

Ros2Camera::~Ros2Camera() = default;

void Ros2Camera::use_camera_info(ros2_dds::Subscription<ros2::CameraInfo>& infos, double timeout_s,
                                 const std::string& source, const std::string& within) {
  ros2::CameraInfo info;
  bool received = false;
  try {
    received = infos.wait(timeout_s) && infos.take(info);
  } catch (const ros2_dds::DdsError& error) {
    throw std::runtime_error(source + ": " + error.what());
  }
  if (!received) {
    throw std::runtime_error(source + ": no CameraInfo" + within);
  }
  LensOptions lens;
  try {
    lens.model = camera_model_of(info);
  } catch (const std::invalid_argument& error) {
    throw std::runtime_error(source + ": " + error.what());
  }
  try {
    lens_.emplace(lens, bgr_.cols, bgr_.rows, source);
  } catch (const std::invalid_argument& error) {
    throw std::runtime_error(error.what());  // Lens names `source`: another size than the images'
  }
}

bool Ros2Camera::take_newest() {
  bool took = false;
  if (images_) {
    while (images_->take(image_)) {
      took = true;
    }
  } else {
    while (compressed_->take(compressed_image_)) {
      took = true;
    }
  }
  if (took) {
    header_ = images_ ? image_.header : compressed_image_.header;
    received_s_ = base::monotonic_now_s();
  }
  return took;
}

void Ros2Camera::decode() {
  const int rows = bgr_.empty() ? -1 : bgr_.rows;
  const int cols = bgr_.empty() ? -1 : bgr_.cols;
  if (compressed_) {
    // imdecode leaves its output as it was when it fails: decode into a Mat of its own.
    const cv::Mat decoded = compressed_image_.data.empty()
                                ? cv::Mat()
                                : cv::imdecode(compressed_image_.data, cv::IMREAD_COLOR);
    if (decoded.empty()) {
      throw std::runtime_error(
          name_ + ": a CompressedImage in format '" + compressed_image_.format + "' of " +
          std::to_string(compressed_image_.data.size()) + " bytes could not be decoded");
    }
    bgr_ = decoded;
  } else {
    const ros2::Image& image = image_;
    const Encoding* encoding = find_encoding(image.encoding);
    if (encoding == nullptr || (!encoding_.empty() && image.encoding != encoding_)) {
      throw std::runtime_error(name_ + ": image encoding '" + image.encoding + "' " +
                               (encoding == nullptr
                                    ? "cannot be read (" + ros2_image_encoding_names() + ")"
                                    : "is not the encoding asked for, '" + encoding_ + "'"));
    }
    const std::size_t row_bytes = static_cast<std::size_t>(image.width) * encoding->channels;
    if (image.width == 0 || image.height == 0 || image.step < row_bytes ||
        image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
      throw std::runtime_error(name_ + ": a " + std::to_string(image.width) + "x" +
                               std::to_string(image.height) + " " + image.encoding +
                               " image with step " + std::to_string(image.step) + " and " +
                               std::to_string(image.data.size()) + " bytes is not whole");
    }
    const cv::Mat wrapped(static_cast<int>(image.height), static_cast<int>(image.width),
                          CV_8UC(encoding->channels), const_cast<std::uint8_t*>(image.data.data()),
                          image.step);
    if (encoding->to_bgr < 0) {
      wrapped.copyTo(bgr_);
    } else {
      cv::cvtColor(wrapped, bgr_, encoding->to_bgr);
    }
  }
  if (rows >= 0 && (bgr_.rows != rows || bgr_.cols != cols)) {
    throw std::runtime_error(name_ + ": the images changed size from " + std::to_string(cols) +
                             "x" + std::to_string(rows) + " to " + std::to_string(bgr_.cols) + "x" +
                             std::to_string(bgr_.rows));
  }
}

ReadStatus Ros2Camera::read(Frame& frame, double timeout_s) {
  try {
    // The image the constructor waited for goes out first, unless a newer one came meanwhile.
    const bool newer =
        first_pending_
            ? take_newest()
            : (images_ ? images_->wait(timeout_s) : compressed_->wait(timeout_s)) && take_newest();
    if (!newer && !first_pending_) {
      return ReadStatus::timeout;
    }
    if (newer) {
      decode();
    }
  } catch (const ros2_dds::DdsError& error) {
    throw std::runtime_error(name_ + ": " + error.what());
  }
  first_pending_ = false;
  double timestamp_s =
      base::monotonic_of_realtime_s(header_.stamp.sec, header_.stamp.nanosec, kMaxStampAge_s)
          .value_or(received_s_);
  if (!(timestamp_s > last_timestamp_s_)) {
    // Frame times only increase.
    timestamp_s = std::max(received_s_, last_timestamp_s_ + 1e-6);
  }
  last_timestamp_s_ = timestamp_s;
  frame.image = lens_->apply(bgr_);
  frame.timestamp_s = timestamp_s;
  frame.sequence = sequence_++;
  frame.sim.reset();
  return ReadStatus::ok;
}

}  // namespace flowsteer::camera_io
