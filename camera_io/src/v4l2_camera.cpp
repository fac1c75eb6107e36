#include "flowsteer/camera_io/v4l2_camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <libv4lconvert.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "flowsteer/base/clock.hpp"
#include "sequence_gaps.hpp"
#include "v4l2_io.hpp"

namespace flowsteer::camera_io {

using v4l2::checked_ioctl;
using v4l2::errno_message;
using v4l2::fixed_text;
using v4l2::fourcc_text;
using v4l2::map_buffer;
using v4l2::throw_errno;
using v4l2::try_ioctl;

namespace {

std::uint32_t to_fourcc(PixelFormat format) {
  switch (format) {
    case PixelFormat::yuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::mjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case PixelFormat::grey:
      return V4L2_PIX_FMT_GREY;
  }
  throw std::invalid_argument("unknown pixel format");
}

// The fourcc names of the pixel formats the device offers (VIDIOC_ENUM_FMT). The driver ends the
// list with EINVAL; another error ends it too and is left in `error` (0 when the list is whole).
std::vector<std::string> offered_formats(int fd, int& error) {
  std::vector<std::string> names;
  v4l2_fmtdesc desc{};
  desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  while (try_ioctl(fd, VIDIOC_ENUM_FMT, &desc)) {
    names.push_back(fourcc_text(desc.pixelformat));
    ++desc.index;
  }
  error = errno == EINVAL ? 0 : errno;
  return names;
}

std::string capability_names(std::uint32_t caps) {
  static constexpr std::pair<std::uint32_t, const char*> kNames[] = {
      {V4L2_CAP_VIDEO_CAPTURE, "video capture"},
      {V4L2_CAP_VIDEO_CAPTURE_MPLANE, "multi-planar video capture"},
      {V4L2_CAP_VIDEO_OUTPUT, "video output"},
      {V4L2_CAP_VIDEO_OUTPUT_MPLANE, "multi-planar video output"},
      {V4L2_CAP_VIDEO_M2M, "memory-to-memory"},
      {V4L2_CAP_VIDEO_M2M_MPLANE, "multi-planar memory-to-memory"},
      {V4L2_CAP_VBI_CAPTURE, "VBI capture"},
      {V4L2_CAP_VBI_OUTPUT, "VBI output"},
      {V4L2_CAP_SLICED_VBI_CAPTURE, "sliced VBI capture"},
      {V4L2_CAP_SLICED_VBI_OUTPUT, "sliced VBI output"},
      {V4L2_CAP_RADIO, "radio"},
      {V4L2_CAP_MODULATOR, "modulator"},
      {V4L2_CAP_SDR_CAPTURE, "SDR capture"},
      {V4L2_CAP_SDR_OUTPUT, "SDR output"},
      {V4L2_CAP_META_CAPTURE, "metadata capture"},
      {V4L2_CAP_META_OUTPUT, "metadata output"},
      {V4L2_CAP_TOUCH, "touch"},
  };
  std::string names;
  for (const auto& [bit, name] : kNames) {
    if ((caps & bit) != 0) {
      names += names.empty() ? name : std::string(", ") + name;
    }
  }
  return names.empty() ? "nothing V4L2 streams" : names;
}

}  // namespace

std::string_view fourcc_name(PixelFormat format) {
  switch (format) {
    case PixelFormat::yuyv:
      return "YUYV";
    case PixelFormat::mjpeg:
      return "MJPG";
    case PixelFormat::grey:
      return "GREY";
  }
  return "?";
}

std::optional<PixelFormat> pixel_format_from_name(std::string_view name) {
  if (name == "YUYV") {
    return PixelFormat::yuyv;
  }
  if (name == "MJPG" || name == "MJPEG") {
    return PixelFormat::mjpeg;
  }
  if (name == "GREY") {
    return PixelFormat::grey;
  }
  return std::nullopt;
}

V4l2Camera::V4l2Camera(const V4l2Options& options)
    : device_(options.device), converter_(nullptr, v4lconvert_destroy) {
  if (options.buffer_count < 2) {
    throw std::invalid_argument(device_ + ": buffer_count must be at least 2, got " +
                                std::to_string(options.buffer_count));
  }
  if ((options.width_px == 0) != (options.height_px == 0) || options.width_px < 0 ||
      options.height_px < 0) {
    throw std::invalid_argument(
        device_ + ": width and height must both be positive or both 0, got " +
        std::to_string(options.width_px) + "x" + std::to_string(options.height_px));
  }
  if (!(options.frame_rate_hz >= 0.0) || !std::isfinite(options.frame_rate_hz)) {
    throw std::invalid_argument(device_ + ": frame rate must be >= 0 Hz");
  }
  open_device();
  negotiate(options);
  set_frame_rate(options.frame_rate_hz);
  lens_.emplace(options.lens, width_px_, height_px_, "camera " + device_);
  map_buffers(options.buffer_count);
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  checked_ioctl(fd_.get(), VIDIOC_STREAMON, &type, "VIDIOC_STREAMON", device_);
  streaming_ = true;
}

V4l2Camera::~V4l2Camera() {
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    try_ioctl(fd_.get(), VIDIOC_STREAMOFF, &type);
  }
  // The members unmap the buffers and then close the device, which frees them in the driver.
}

void V4l2Camera::open_device() {
  // Non-blocking: read() waits in poll() with its own timeout, never in VIDIOC_DQBUF.
  const int fd = ::open(device_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    throw std::runtime_error("cannot open camera " + device_ + ": " + std::strerror(error));
  }
  fd_ = base::UniqueFd(fd);
  v4l2_capability cap{};
  if (!try_ioctl(fd, VIDIOC_QUERYCAP, &cap)) {
    const int error = errno;
    if (error == ENOTTY || error == EINVAL) {
      throw std::runtime_error(
          device_ + " is not a V4L2 device (VIDIOC_QUERYCAP failed: " + std::strerror(error) + ")");
    }
    throw_errno(device_, "VIDIOC_QUERYCAP", error);
  }
  driver_ = fixed_text(cap.driver);
  card_ = fixed_text(cap.card);
  // capabilities covers every node of the physical device; device_caps is this node's.
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
    throw std::runtime_error(
        device_ + " (" + driver_ + ", " + card_ + ") is not a video capture device: it offers " +
        capability_names(caps) +
        ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) != 0 ? " (the multi-planar API is not supported)"
                                                     : ""));
  }
  if ((caps & V4L2_CAP_STREAMING) == 0) {
    throw std::runtime_error(device_ + " (" + driver_ + ", " + card_ +
                             ") cannot stream through buffers (no V4L2_CAP_STREAMING)");
  }
}

std::vector<std::string> V4l2Camera::list_formats(const std::string& device) {
  // A camera that streams nothing: open and check as the constructor does, then enumerate.
  V4l2Camera probe(device, OpenOnly{});
  int error = 0;
  std::vector<std::string> names = offered_formats(probe.fd_.get(), error);
  if (error != 0) {
    throw_errno(device, "VIDIOC_ENUM_FMT", error);
  }
  return names;
}

V4l2Camera::V4l2Camera(const std::string& device, OpenOnly)
    : device_(device), converter_(nullptr, v4lconvert_destroy) {
  open_device();
}

void V4l2Camera::negotiate(const V4l2Options& options) {
  const std::uint32_t wanted = to_fourcc(options.format);
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  checked_ioctl(fd_.get(), VIDIOC_G_FMT, &format, "VIDIOC_G_FMT", device_);
  format.fmt.pix.pixelformat = wanted;
  if (options.width_px > 0) {
    format.fmt.pix.width = static_cast<std::uint32_t>(options.width_px);
    format.fmt.pix.height = static_cast<std::uint32_t>(options.height_px);
  }
  format.fmt.pix.field = V4L2_FIELD_NONE;
  format.fmt.pix.bytesperline = 0;  // the driver's choice
  checked_ioctl(fd_.get(), VIDIOC_S_FMT, &format, "VIDIOC_S_FMT", device_);
  // S_FMT does not fail on a format or size the driver lacks: it answers with the nearest it
  // has, which is checked here.
  const v4l2_pix_format& got = format.fmt.pix;
  if (got.pixelformat != wanted) {
    // What the driver listed before any error: the message is about the format asked for.
    int ignored = 0;
    std::string offered;
    for (const std::string& name : offered_formats(fd_.get(), ignored)) {
      offered += (offered.empty() ? "" : ", ") + name;
    }
    throw std::runtime_error(device_ + " (" + card_ + ") does not offer pixel format " +
                             std::string(fourcc_name(options.format)) + " (it offers " + offered +
                             ")");
  }
  if (options.width_px > 0 && (static_cast<int>(got.width) != options.width_px ||
                               static_cast<int>(got.height) != options.height_px)) {
    throw std::runtime_error(
        device_ + " (" + card_ + ") does not offer " + std::to_string(options.width_px) + "x" +
        std::to_string(options.height_px) + " in " + std::string(fourcc_name(options.format)) +
        ": the driver chose " + std::to_string(got.width) + "x" + std::to_string(got.height));
  }
  if (got.field != V4L2_FIELD_NONE) {
    throw std::runtime_error(device_ + " (" + card_ +
                             ") delivers interlaced fields; only progressive frames are supported");
  }
  fourcc_ = got.pixelformat;
  width_px_ = static_cast<int>(got.width);
  height_px_ = static_cast<int>(got.height);
  bytes_per_line_ = got.bytesperline;
  const std::uint32_t bytes_per_pixel = options.format == PixelFormat::yuyv ? 2u : 1u;
  if (options.format != PixelFormat::mjpeg && bytes_per_line_ < got.width * bytes_per_pixel) {
    bytes_per_line_ = got.width * bytes_per_pixel;
  }
  if (options.format == PixelFormat::mjpeg) {
    converter_.reset(v4lconvert_create(fd_.get()));
    if (!converter_) {
      throw std::runtime_error(device_ + ": libv4lconvert could not set up MJPEG decoding");
    }
  }
}

void V4l2Camera::set_frame_rate(double frame_rate_hz) {
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  checked_ioctl(fd_.get(), VIDIOC_G_PARM, &parm, "VIDIOC_G_PARM", device_);
  const bool settable = (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0;
  if (frame_rate_hz > 0.0 && settable) {
    // A frame period as a fraction with a denominator of 1000 is exact for the usual rates
    // (30, 25, 15, 7.5 Hz) and close enough for others; the driver rounds to what it has.
    std::uint32_t numerator = 1000;
    auto denominator = static_cast<std::uint32_t>(std::lround(frame_rate_hz * 1000.0));
    const std::uint32_t divisor = std::gcd(numerator, denominator);
    parm.parm.capture.timeperframe = {numerator / divisor, denominator / divisor};
    checked_ioctl(fd_.get(), VIDIOC_S_PARM, &parm, "VIDIOC_S_PARM", device_);
  }
  const v4l2_fract period = parm.parm.capture.timeperframe;
  frame_rate_hz_ = settable && period.numerator > 0
                       ? static_cast<double>(period.denominator) / period.numerator
                       : 0.0;
}

void V4l2Camera::map_buffers(int buffer_count) {
  v4l2_requestbuffers request{};
  request.count = static_cast<std::uint32_t>(buffer_count);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  checked_ioctl(fd_.get(), VIDIOC_REQBUFS, &request, "VIDIOC_REQBUFS", device_);
  if (request.count < 2) {
    throw std::runtime_error(device_ + ": the driver granted " + std::to_string(request.count) +
                             " buffers, at least 2 are needed to stream");
  }
  buffers_.reserve(request.count);
  for (std::uint32_t index = 0; index < request.count; ++index) {
    v4l2_buffer buffer{};
    map_buffer(fd_.get(), V4L2_BUF_TYPE_VIDEO_CAPTURE, index, device_, "mmap of a capture buffer",
               buffer, buffers_);
    checked_ioctl(fd_.get(), VIDIOC_QBUF, &buffer, "VIDIOC_QBUF", device_);
  }
}

void V4l2Camera::convert(std::span<const std::uint8_t> data, cv::Mat& bgr) {
  bgr.create(height_px_, width_px_, CV_8UC3);
  auto* bytes = const_cast<std::uint8_t*>(data.data());  // cv::Mat wants a mutable pointer
  switch (fourcc_) {
    case V4L2_PIX_FMT_YUYV: {
      if (data.size() < std::size_t{bytes_per_line_} * height_px_) {
        throw std::runtime_error(device_ + ": short YUYV frame (" + std::to_string(data.size()) +
                                 " bytes)");
      }
      const cv::Mat yuyv(height_px_, width_px_, CV_8UC2, bytes, bytes_per_line_);
      cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
      return;
    }
    case V4L2_PIX_FMT_GREY: {
      if (data.size() < std::size_t{bytes_per_line_} * height_px_) {
        throw std::runtime_error(device_ + ": short GREY frame (" + std::to_string(data.size()) +
                                 " bytes)");
      }
      const cv::Mat grey(height_px_, width_px_, CV_8UC1, bytes, bytes_per_line_);
      cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
      return;
    }
    case V4L2_PIX_FMT_MJPEG: {
      v4l2_format src{};
      src.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      src.fmt.pix.pixelformat = V4L2_PIX_FMT_MJPEG;
      src.fmt.pix.width = static_cast<std::uint32_t>(width_px_);
      src.fmt.pix.height = static_cast<std::uint32_t>(height_px_);
      src.fmt.pix.field = V4L2_FIELD_NONE;
      v4l2_format dst = src;
      dst.fmt.pix.pixelformat = V4L2_PIX_FMT_BGR24;
      dst.fmt.pix.bytesperline = static_cast<std::uint32_t>(bgr.step[0]);
      dst.fmt.pix.sizeimage = static_cast<std::uint32_t>(bgr.step[0] * bgr.rows);
      const int written =
          v4lconvert_convert(converter_.get(), &src, &dst, bytes, static_cast<int>(data.size()),
                             bgr.data, dst.fmt.pix.sizeimage);
      if (written < 0) {
        throw std::runtime_error(device_ + ": cannot decode an MJPEG frame: " +
                                 v4lconvert_get_error_message(converter_.get()));
      }
      return;
    }
    default:
      throw std::logic_error(device_ + ": no conversion for " + fourcc_text(fourcc_));
  }
}

ReadStatus V4l2Camera::read(Frame& frame, double timeout_s) {
  if (!streaming_) {
    throw std::runtime_error(device_ + ": read() after stop()");
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const auto left =
        std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    pollfd pfd{fd_.get(), POLLIN, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(std::max<std::int64_t>(0, left.count())));
    if (ready < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw_errno(device_, "poll", errno);
    }
    if (ready == 0) {
      return ReadStatus::timeout;
    }
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (!try_ioctl(fd_.get(), VIDIOC_DQBUF, &buffer)) {
      if (errno == EAGAIN) {  // woken without a filled buffer
        continue;
      }
      // POLLERR with ENODEV or EIO: the camera was unplugged or the driver gave up.
      throw_errno(device_, "VIDIOC_DQBUF", errno);
    }
    const double dequeued_s = base::monotonic_now_s();
    if (buffer.index >= buffers_.size()) {
      throw std::runtime_error(device_ + ": VIDIOC_DQBUF returned buffer " +
                               std::to_string(buffer.index) + " of " +
                               std::to_string(buffers_.size()));
    }
    const bool corrupt = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0;
    // A corrupt buffer counts as dropped by the gap it leaves before the next frame, not by
    // itself: after a stall a driver may fill two buffers within one frame period under one
    // sequence number (vivid does), and the frame after a corrupt one was then counted twice.
    if (!corrupt) {
      dropped_frames_ += skipped_frames(last_driver_sequence_, buffer.sequence);
    }
    // Read before VIDIOC_QBUF, which writes the buffer's new state into the same struct.
    const bool monotonic =
        (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    const double stamped_s = static_cast<double>(buffer.timestamp.tv_sec) +
                             1e-6 * static_cast<double>(buffer.timestamp.tv_usec);
    if (!corrupt) {
      try {
        convert(buffers_[buffer.index].bytes(buffer.bytesused), converted_);
      } catch (...) {
        try_ioctl(fd_.get(), VIDIOC_QBUF, &buffer);
        throw;
      }
    }
    // The frame is converted into the camera's own image, so the buffer goes back at once.
    checked_ioctl(fd_.get(), VIDIOC_QBUF, &buffer, "VIDIOC_QBUF", device_);
    if (corrupt) {
      continue;
    }
    frame.timestamp_s = frame_time_s(monotonic, stamped_s, dequeued_s);
    frame.image = lens_->apply(converted_);
    frame.sequence = sequence_++;
    frame.sim.reset();
    return ReadStatus::ok;
  }
}

double V4l2Camera::frame_time_s(bool monotonic_stamp, double stamped_s, double dequeued_s) {
  const bool plausible =
      std::abs(stamped_s - dequeued_s) < kStampWindow_s && stamped_s > last_timestamp_s_;
  driver_stamps_distrusted_ = driver_stamps_distrusted_ || (monotonic_stamp && !plausible);
  driver_timestamps_ = monotonic_stamp && !driver_stamps_distrusted_;
  // A stamp may have run a little ahead of this dequeue: the times must still increase.
  last_timestamp_s_ =
      driver_timestamps_ ? stamped_s : std::max(dequeued_s, last_timestamp_s_ + 1e-6);
  return last_timestamp_s_;
}

void V4l2Camera::stop() {
  if (fd_.get() < 0) {
    return;
  }
  std::string failure;
  if (streaming_) {
    streaming_ = false;
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (!try_ioctl(fd_.get(), VIDIOC_STREAMOFF, &type)) {
      failure = errno_message(device_, "VIDIOC_STREAMOFF", errno);
    }
  }
  buffers_.clear();
  v4l2_requestbuffers release{};
  release.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  release.memory = V4L2_MEMORY_MMAP;
  if (!try_ioctl(fd_.get(), VIDIOC_REQBUFS, &release) && failure.empty()) {
    failure = errno_message(device_, "VIDIOC_REQBUFS(0)", errno);
  }
  converter_.reset();
  fd_ = base::UniqueFd();
  if (!failure.empty()) {
    throw std::runtime_error(failure);
  }
}

}  // namespace flowsteer::camera_io
