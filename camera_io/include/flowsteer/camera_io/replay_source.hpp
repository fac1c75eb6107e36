#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/lens.hpp"

namespace cv {
class VideoCapture;
}

namespace flowsteer::camera_io {

struct ReplayOptions {
  // A video file (anything OpenCV's FFmpeg backend decodes), or an image sequence: a glob
  // ("run/*.png", "run/view_0[0-2].png"; sorted by name) or a printf pattern
  // ("run/frame_%05d.png", numbered from 0 or 1 up to the first missing number).
  std::string path;
  // 0: timestamps from the video container (the frame's presentation time); a rate is needed
  // for an image sequence, which has none. > 0: frame n is at n / rate, for both.
  double frame_rate_hz = 0.0;
  LensOptions lens;
};

// Whether ReplayOptions::path names an image sequence (a glob or a printf pattern), not a video.
bool is_image_sequence_pattern(const std::string& path);
// The image files of a sequence pattern, in frame order; empty when none matches. Throws
// std::runtime_error naming the pattern when a printf pattern is not one integer conversion.
std::vector<std::string> image_sequence_files(const std::string& pattern);

// Frames of a recording, one per read(), as fast as they are asked for: the timestamps, not
// the wall clock, carry the recording's timing. read() ends with ReadStatus::end_of_stream and
// never times out. Errors throw std::runtime_error naming the file.
class ReplaySource final : public FrameSource {
 public:
  // Opens the recording and reads its first frame to learn the image size. Throws when the
  // file does not exist, cannot be decoded, or the pattern matches nothing.
  explicit ReplaySource(const ReplayOptions& options);
  ~ReplaySource() override;
  ReplaySource(const ReplaySource&) = delete;
  ReplaySource& operator=(const ReplaySource&) = delete;

  const base::CameraIntrinsics& intrinsics() const override { return lens_->intrinsics(); }
  ReadStatus read(Frame& frame, double timeout_s) override;

  // The frame rate the timestamps follow when they are not the container's: the option, or
  // the rate the video declares.
  double frame_rate_hz() const { return frame_rate_hz_; }
  // Frames in an image sequence; for a video, what the container declares (may be 0).
  std::size_t frame_count() const { return frame_count_; }
  bool is_image_sequence() const { return video_ == nullptr; }

 private:
  // Decodes the next frame into decoded_; false at the end.
  bool next_image();

  std::string path_;
  std::unique_ptr<cv::VideoCapture> video_;
  std::vector<std::string> images_;
  std::size_t next_index_ = 0;  // of the next frame to decode; also its sequence number
  std::size_t frame_count_ = 0;
  double frame_rate_hz_ = 0.0;
  bool container_timestamps_ = false;
  std::optional<double> previous_timestamp_s_;
  cv::Mat decoded_;
  bool have_decoded_ = false;  // the first frame, read by the constructor and not yet delivered
  std::optional<Lens> lens_;
  cv::Size size_;
};

}  // namespace flowsteer::camera_io
