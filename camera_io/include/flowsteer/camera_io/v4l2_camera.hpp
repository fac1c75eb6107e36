#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/lens.hpp"
#include "flowsteer/camera_io/v4l2_device.hpp"

struct v4lconvert_data;

namespace flowsteer::camera_io {

// Pixel formats a V4L2 camera may be asked to deliver; every one is converted to BGR.
enum class PixelFormat { yuyv, mjpeg, grey };

// "YUYV", "MJPG", "GREY": the fourcc V4L2 uses, as v4l2-ctl prints it.
std::string_view fourcc_name(PixelFormat format);
// The inverse of fourcc_name, also accepting "MJPEG"; std::nullopt for anything else.
std::optional<PixelFormat> pixel_format_from_name(std::string_view name);

struct V4l2Options {
  std::string device = "/dev/video0";
  // Both zero: keep the size the driver has. Otherwise the driver must give exactly this size.
  int width_px = 640;
  int height_px = 480;
  // 0 keeps the driver's rate. Drivers round to the intervals they support: frame_rate_hz()
  // tells what was set.
  double frame_rate_hz = 30.0;
  PixelFormat format = PixelFormat::yuyv;
  // Buffers the driver fills while the loop works on one: at least 2. More rides out longer
  // stalls of the loop before the driver has to drop frames.
  int buffer_count = 4;
  // The calibration for this size, or the field of view to assume without one.
  LensOptions lens;
};

// A V4L2 video capture device (a USB webcam, a CSI bridge with a V4L2 driver, vivid) streaming
// through mmap buffers. Construction opens the device, checks it can capture and stream,
// negotiates format, size and rate, maps the buffers and starts streaming; every failure
// throws std::runtime_error naming the device and, for a failed ioctl, the ioctl and errno
// text. Not thread-safe.
class V4l2Camera final : public FrameSource {
 public:
  explicit V4l2Camera(const V4l2Options& options);
  // Stops streaming, unmaps the buffers and closes the device; errors are swallowed here, call
  // stop() first to see them.
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  const base::CameraIntrinsics& intrinsics() const override { return lens_->intrinsics(); }
  // Waits up to timeout_s for the next filled buffer, converts it to BGR and undistorts it;
  // frame.image shares the camera's buffer for that, valid until the next read(). Timestamps are
  // the driver's when it stamps buffers with the monotonic clock (driver_timestamps()), else the
  // time of dequeue. A driver stamp that cannot be right (more than kStampWindow_s after the
  // dequeue or before it, or not after the last frame's: a clock that wrapped or jumped) makes
  // the camera use dequeue times from then on, so frame times only ever increase. Buffers
  // the driver flags as corrupt are returned to it, counted as dropped, and the wait goes on.
  // Throws std::runtime_error once stop() has been called.
  ReadStatus read(Frame& frame, double timeout_s) override;

  // STREAMOFF, unmap, release the buffers and close the device. Throws if STREAMOFF or the
  // release fails (the device is closed either way).
  void stop();

  // Frames the driver skipped or returned flagged as corrupt, from the gaps in the sequence
  // numbers of the frames read (a corrupt buffer at the end of the stream is not counted).
  std::uint64_t dropped_frames() const { return dropped_frames_; }
  // The driver's sequence number of the last frame read (gaps are dropped frames).
  std::uint32_t driver_sequence() const { return last_driver_sequence_.value_or(0); }
  // The frame rate the driver set (S_PARM), 0 when it cannot set one.
  double frame_rate_hz() const { return frame_rate_hz_; }
  // Whether the last frame's time is the driver's stamp (see read()).
  bool driver_timestamps() const { return driver_timestamps_; }
  // A filled buffer waits in the queue a few frame periods at most, and a stamp for the end of
  // an exposure may come a little ahead of the handover (vivid's by up to a period).
  static constexpr double kStampWindow_s = 5.0;
  // The driver's name and the card's, from VIDIOC_QUERYCAP.
  const std::string& driver() const { return driver_; }
  const std::string& card() const { return card_; }
  const std::string& device() const { return device_; }

  // The pixel formats the device offers (VIDIOC_ENUM_FMT) as fourcc names, e.g. "YUYV".
  // Throws like the constructor when the device cannot be opened or is not a capture device.
  static std::vector<std::string> list_formats(const std::string& device);

 private:
  // The frame's time by the rule in read(); updates the trust in the driver's stamps.
  double frame_time_s(bool monotonic_stamp, double stamped_s, double dequeued_s);
  struct OpenOnly {};
  // Opens and checks the device without configuring or streaming (for list_formats).
  V4l2Camera(const std::string& device, OpenOnly);

  void open_device();
  void negotiate(const V4l2Options& options);
  void set_frame_rate(double frame_rate_hz);
  void map_buffers(int buffer_count);
  void convert(std::span<const std::uint8_t> data, cv::Mat& bgr);

  std::string device_;
  base::UniqueFd fd_;
  std::string driver_;
  std::string card_;
  std::uint32_t fourcc_ = 0;
  int width_px_ = 0;
  int height_px_ = 0;
  std::uint32_t bytes_per_line_ = 0;
  double frame_rate_hz_ = 0.0;
  std::vector<v4l2::Mapping> buffers_;
  bool streaming_ = false;
  // Only for MJPEG, whose decoding (including the Huffman tables many webcams leave out) is
  // libv4lconvert's.
  std::unique_ptr<v4lconvert_data, void (*)(v4lconvert_data*)> converter_;
  std::optional<Lens> lens_;
  cv::Mat converted_;  // BGR, before undistortion
  bool driver_timestamps_ = false;
  bool driver_stamps_distrusted_ = false;
  double last_timestamp_s_ = -std::numeric_limits<double>::infinity();
  std::optional<std::uint32_t> last_driver_sequence_;  // none before the first frame
  std::uint64_t dropped_frames_ = 0;
  std::uint64_t sequence_ = 0;
};

}  // namespace flowsteer::camera_io
