#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace flowsteer::camera_io {

struct V4l2OutputOptions {
  std::string device;  // a V4L2 video output node
  int width_px = 0;
  int height_px = 0;
  // Buffers kept queued. The driver shows the oldest, so each buffer more is a frame period
  // more of delay; a driver that keeps showing its last buffer when no other is queued (vivid)
  // needs no more than 2.
  int buffer_count = 2;
};

// A V4L2 video output device (an HDMI transmitter, vivid's output node looped back to its
// capture node) showing BGR images, sent as YUYV (BT.601, limited range, as webcams send it).
// The driver takes a buffer off its queue at its own frame rate and a queue that runs dry shows
// nothing (vivid's loop then shows noise), so a thread of this class keeps buffer_count buffers
// queued, refilling each one the driver gives back with the latest image. Construction opens
// the device, sets the format (the driver must take exactly this size) and starts streaming a
// black image; failures throw std::runtime_error naming the device and the failed ioctl.
class V4l2Output {
 public:
  explicit V4l2Output(const V4l2OutputOptions& options);
  // Stops streaming and closes the device.
  ~V4l2Output();
  V4l2Output(const V4l2Output&) = delete;
  V4l2Output& operator=(const V4l2Output&) = delete;

  // The buffers refilled from now on show `bgr` (CV_8UC3, the configured size). Throws
  // std::runtime_error with the driver's error once streaming has failed.
  void show(const cv::Mat& bgr);
  // Frames the driver has shown since the start (buffers it gave back): the device's clock.
  std::uint64_t frames_shown() const;
  // Waits until the driver has shown `count` frames; false when it has not within timeout_s (a
  // stalled or failed device).
  bool wait_for_frames(std::uint64_t count, double timeout_s) const;
  // What ended the streaming (the driver's error), empty while it goes on.
  std::string error() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// BGR (CV_8UC3, even width) to packed YUYV (CV_8UC2) with BT.601 limited-range coefficients,
// the inverse of OpenCV's COLOR_YUV2BGR_YUYV; each pixel pair shares the mean of its chroma.
void bgr_to_yuyv(const cv::Mat& bgr, cv::Mat& yuyv);

}  // namespace flowsteer::camera_io
