#include "flowsteer/camera_io/replay_source.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/camera_io/glob.hpp"

namespace flowsteer::camera_io {
namespace {

// Wider than any frame number needs; see check_printf_pattern.
constexpr int kMaxFieldWidth = 32;

bool is_glob(const std::string& path) {
  return path.find_first_of("*?[") != std::string::npos;
}

bool is_printf_pattern(const std::string& path) {
  return path.find('%') != std::string::npos;
}

std::string format_index(const std::string& pattern, std::size_t index) {
  const int length = std::snprintf(nullptr, 0, pattern.c_str(), static_cast<int>(index));
  if (length < 0) {
    throw std::runtime_error("replay: bad printf pattern '" + pattern + "'");
  }
  std::string name(static_cast<std::size_t>(length), '\0');
  std::snprintf(name.data(), name.size() + 1, pattern.c_str(), static_cast<int>(index));
  return name;
}

// A printf pattern takes exactly one integer conversion ("%d", "%05d"), nothing else but "%%".
void check_printf_pattern(const std::string& pattern) {
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < pattern.size() && (std::isdigit(static_cast<unsigned char>(pattern[j])) != 0)) {
      ++j;
    }
    if (j >= pattern.size() || pattern[j] != 'd') {
      throw std::runtime_error("replay: image pattern '" + pattern +
                               "' must number frames with one %d (or %0Nd)");
    }
    // Each name is formatted in full: a field width of millions would allocate gigabytes. The
    // leading zeros are the zero-padding flag, not the width.
    std::size_t k = i + 1;
    while (k < j && pattern[k] == '0') {
      ++k;
    }
    const std::string width = pattern.substr(k, j - k);
    if (width.size() > 2 || (!width.empty() && std::stoi(width) > kMaxFieldWidth)) {
      throw std::runtime_error("replay: image pattern '" + pattern + "': field width " + width +
                               " is more than " + std::to_string(kMaxFieldWidth));
    }
    ++conversions;
    i = j;
  }
  if (conversions != 1) {
    throw std::runtime_error("replay: image pattern '" + pattern +
                             "' must number frames with one %d (or %0Nd)");
  }
}

}  // namespace

bool is_image_sequence_pattern(const std::string& path) {
  return is_glob(path) || is_printf_pattern(path);
}

std::vector<std::string> image_sequence_files(const std::string& pattern) {
  // The C functions below would see the pattern only up to a NUL: a printf pattern cut there
  // names the same file for every index, and the loop below would never end.
  if (pattern.find('\0') != std::string::npos) {
    throw std::runtime_error("replay: image pattern '" + pattern.substr(0, pattern.find('\0')) +
                             "...' contains a NUL character");
  }
  std::vector<std::string> files;
  if (is_glob(pattern)) {
    for (const std::filesystem::path& path : expand_glob(pattern)) {
      files.push_back(path.string());
    }
    return files;
  }
  check_printf_pattern(pattern);
  std::size_t index = 0;
  // Sequences are numbered from 0 or from 1.
  if (!std::filesystem::exists(format_index(pattern, 0))) {
    index = 1;
  }
  for (; std::filesystem::exists(format_index(pattern, index)); ++index) {
    files.push_back(format_index(pattern, index));
  }
  return files;
}

ReplaySource::ReplaySource(const ReplayOptions& options)
    : path_(options.path), frame_rate_hz_(options.frame_rate_hz) {
  if (!(options.frame_rate_hz >= 0.0) || !std::isfinite(options.frame_rate_hz)) {
    throw std::invalid_argument("replay " + path_ + ": frame rate must be >= 0 Hz");
  }
  if (is_image_sequence_pattern(path_)) {
    images_ = image_sequence_files(path_);
    if (images_.empty()) {
      throw std::runtime_error("replay: no image files match '" + path_ + "'");
    }
    if (options.frame_rate_hz <= 0.0) {
      throw std::invalid_argument("replay " + path_ +
                                  ": an image sequence has no timestamps; give its frame rate");
    }
    frame_count_ = images_.size();
  } else {
    if (!std::filesystem::exists(path_)) {
      throw std::runtime_error("replay: cannot open video " + path_ + ": no such file");
    }
    video_ = std::make_unique<cv::VideoCapture>(path_, cv::CAP_FFMPEG);
    if (!video_->isOpened()) {
      throw std::runtime_error("replay: cannot open video " + path_ +
                               ": not a video OpenCV can decode");
    }
    const double declared_hz = video_->get(cv::CAP_PROP_FPS);
    const double declared_frames = video_->get(cv::CAP_PROP_FRAME_COUNT);
    frame_count_ = declared_frames > 0.0 ? static_cast<std::size_t>(declared_frames) : 0;
    container_timestamps_ = options.frame_rate_hz <= 0.0;
    if (container_timestamps_) {
      frame_rate_hz_ = declared_hz > 0.0 && std::isfinite(declared_hz) ? declared_hz : 0.0;
    }
  }
  if (!next_image()) {
    throw std::runtime_error("replay: " + path_ + " has no frames");
  }
  have_decoded_ = true;
  size_ = decoded_.size();
  lens_.emplace(options.lens, size_.width, size_.height, "replay " + path_);
}

ReplaySource::~ReplaySource() = default;

bool ReplaySource::next_image() {
  if (video_) {
    if (!video_->read(decoded_) || decoded_.empty()) {
      return false;
    }
  } else {
    if (next_index_ >= images_.size()) {
      return false;
    }
    const std::string& file = images_[next_index_];
    // imread into a fresh Mat: it allocates per image anyway.
    decoded_ = cv::imread(file, cv::IMREAD_COLOR);
    if (decoded_.empty()) {
      throw std::runtime_error("replay: cannot read image " + file +
                               " (missing, unreadable or not an image)");
    }
  }
  ++next_index_;
  if (decoded_.type() != CV_8UC3) {
    throw std::runtime_error("replay " + path_ + ": frame " + std::to_string(next_index_ - 1) +
                             " is not 8-bit BGR");
  }
  if (!size_.empty() && decoded_.size() != size_) {
    throw std::runtime_error("replay " + path_ + ": frame " + std::to_string(next_index_ - 1) +
                             " is " + std::to_string(decoded_.cols) + "x" +
                             std::to_string(decoded_.rows) + ", the first was " +
                             std::to_string(size_.width) + "x" + std::to_string(size_.height));
  }
  return true;
}

ReadStatus ReplaySource::read(Frame& frame, double /*timeout_s*/) {
  if (!have_decoded_ && !next_image()) {
    return ReadStatus::end_of_stream;
  }
  have_decoded_ = false;
  const std::size_t index = next_index_ - 1;  // every frame decoded is delivered, in order
  double timestamp_s = frame_rate_hz_ > 0.0 ? static_cast<double>(index) / frame_rate_hz_ : 0.0;
  if (container_timestamps_) {
    // The presentation time of the frame just decoded. Containers without one (or a broken
    // one) give 0 or repeat: then the declared rate continues from the last good time.
    const double position_s = video_->get(cv::CAP_PROP_POS_MSEC) * 1e-3;
    if (!previous_timestamp_s_ || position_s > *previous_timestamp_s_) {
      timestamp_s = position_s;
    } else {
      timestamp_s = *previous_timestamp_s_ + (frame_rate_hz_ > 0.0 ? 1.0 / frame_rate_hz_ : 0.0);
    }
  }
  if (previous_timestamp_s_ && !(timestamp_s > *previous_timestamp_s_)) {
    throw std::runtime_error("replay " + path_ + ": frame " + std::to_string(index) +
                             " has no timestamp after the previous frame's; give a frame rate");
  }
  previous_timestamp_s_ = timestamp_s;
  frame.image = lens_->apply(decoded_);
  frame.timestamp_s = timestamp_s;
  frame.sequence = index;
  frame.sim.reset();
  return ReadStatus::ok;
}

}  // namespace flowsteer::camera_io
