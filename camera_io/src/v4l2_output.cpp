#include "flowsteer/camera_io/v4l2_output.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>

#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "flowsteer/camera_io/v4l2_device.hpp"
#include "v4l2_io.hpp"

namespace flowsteer::camera_io {

using v4l2::checked_ioctl;
using v4l2::map_buffer;
using v4l2::throw_errno;
using v4l2::try_ioctl;

struct V4l2Output::Impl {
  explicit Impl(const V4l2OutputOptions& options) : device(options.device) {
    open_device();
    set_format(options.width_px, options.height_px);
    map_and_queue(options.buffer_count);
    int type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    checked_ioctl(fd.get(), VIDIOC_STREAMON, &type, "VIDIOC_STREAMON", device);
    feeder = std::thread([this] { feed(); });
  }

  ~Impl() {
    stop = true;
    feeder.join();
    int type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    try_ioctl(fd.get(), VIDIOC_STREAMOFF, &type);
  }

  void open_device() {
    fd = base::UniqueFd(::open(device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
    if (fd.get() < 0) {
      throw_errno(device, "open", errno);
    }
    v4l2_capability cap{};
    checked_ioctl(fd.get(), VIDIOC_QUERYCAP, &cap, "VIDIOC_QUERYCAP", device);
    const std::string driver = v4l2::fixed_text(cap.driver);
    const std::uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    if ((caps & V4L2_CAP_VIDEO_OUTPUT) == 0 || (caps & V4L2_CAP_STREAMING) == 0) {
      throw std::runtime_error(device + " (" + driver +
                               ") is not a video output device that streams");
    }
  }

  void set_format(int width_px, int height_px) {
    if (width_px <= 0 || height_px <= 0 || width_px % 2 != 0) {
      throw std::invalid_argument(device + ": the size must be positive with an even width, got " +
                                  std::to_string(width_px) + "x" + std::to_string(height_px));
    }
    v4l2_format format{};
    format.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    format.fmt.pix.width = static_cast<std::uint32_t>(width_px);
    format.fmt.pix.height = static_cast<std::uint32_t>(height_px);
    format.fmt.pix.pixelformat = V4L2_PIX_FMT_YUYV;
    format.fmt.pix.field = V4L2_FIELD_NONE;
    checked_ioctl(fd.get(), VIDIOC_S_FMT, &format, "VIDIOC_S_FMT", device);
    const v4l2_pix_format& got = format.fmt.pix;
    if (got.pixelformat != V4L2_PIX_FMT_YUYV || static_cast<int>(got.width) != width_px ||
        static_cast<int>(got.height) != height_px) {
      throw std::runtime_error(device + ": asked for YUYV " + std::to_string(width_px) + "x" +
                               std::to_string(height_px) + ", the driver set " +
                               v4l2::fourcc_text(got.pixelformat) + " " +
                               std::to_string(got.width) + "x" + std::to_string(got.height));
    }
    width = width_px;
    height = height_px;
    bytes_per_line = got.bytesperline;
    size_image = got.sizeimage;
    latest.create(height, width, CV_8UC2);
    latest.setTo(cv::Scalar(16, 128));  // black
  }

  void map_and_queue(int buffer_count) {
    v4l2_requestbuffers request{};
    request.count = static_cast<std::uint32_t>(buffer_count);
    request.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    request.memory = V4L2_MEMORY_MMAP;
    checked_ioctl(fd.get(), VIDIOC_REQBUFS, &request, "VIDIOC_REQBUFS", device);
    for (std::uint32_t index = 0; index < request.count; ++index) {
      v4l2_buffer buffer{};
      map_buffer(fd.get(), V4L2_BUF_TYPE_VIDEO_OUTPUT, index, device, "mmap of an output buffer",
                 buffer, buffers);
      queue(buffer);
    }
  }

  // Copies the latest image into the buffer and hands it to the driver.
  void queue(v4l2_buffer& buffer) {
    const std::span<std::uint8_t> bytes = buffers[buffer.index].writable();
    {
      const std::lock_guard lock(mutex);
      for (int row = 0; row < height; ++row) {
        std::memcpy(bytes.data() + std::size_t{bytes_per_line} * row, latest.ptr(row),
                    std::size_t{2} * width);
      }
    }
    buffer.bytesused = size_image;
    buffer.field = V4L2_FIELD_NONE;
    checked_ioctl(fd.get(), VIDIOC_QBUF, &buffer, "VIDIOC_QBUF", device);
  }

  // The feeder thread: each buffer the driver has shown goes back with the latest image.
  void feed() {
    try {
      while (!stop) {
        pollfd ready{fd.get(), POLLOUT, 0};
        const int n = ::poll(&ready, 1, 50);
        if (n < 0 && errno != EINTR) {
          throw_errno(device, "poll", errno);
        }
        if (n <= 0) {
          continue;
        }
        if ((ready.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
          throw std::runtime_error(device + ": the driver ended the output stream (poll)");
        }
        v4l2_buffer buffer{};
        buffer.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
        buffer.memory = V4L2_MEMORY_MMAP;
        checked_ioctl(fd.get(), VIDIOC_DQBUF, &buffer, "VIDIOC_DQBUF", device);
        queue(buffer);
        {
          const std::lock_guard lock(mutex);
          ++shown;
        }
        frame_shown.notify_all();
      }
    } catch (const std::exception& e) {
      const std::lock_guard lock(mutex);
      error = e.what();
    }
    frame_shown.notify_all();
  }

  std::string device;
  base::UniqueFd fd;
  int width = 0;
  int height = 0;
  std::uint32_t bytes_per_line = 0;
  std::uint32_t size_image = 0;
  std::vector<v4l2::Mapping> buffers;
  mutable std::mutex mutex;
  mutable std::condition_variable frame_shown;
  cv::Mat latest;           // YUYV; guarded by mutex
  std::string error;        // what ended the feeding; guarded by mutex
  std::uint64_t shown = 0;  // buffers the driver gave back; guarded by mutex
  std::atomic<bool> stop{false};
  std::thread feeder;
};

V4l2Output::V4l2Output(const V4l2OutputOptions& options) : impl_(std::make_unique<Impl>(options)) {}

V4l2Output::~V4l2Output() = default;

void V4l2Output::show(const cv::Mat& bgr) {
  if (bgr.type() != CV_8UC3 || bgr.cols != impl_->width || bgr.rows != impl_->height) {
    throw std::invalid_argument(impl_->device + ": show() needs a " + std::to_string(impl_->width) +
                                "x" + std::to_string(impl_->height) + " BGR image");
  }
  const std::lock_guard lock(impl_->mutex);
  if (!impl_->error.empty()) {
    throw std::runtime_error(impl_->error);
  }
  bgr_to_yuyv(bgr, impl_->latest);
}

std::uint64_t V4l2Output::frames_shown() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->shown;
}

bool V4l2Output::wait_for_frames(std::uint64_t count, double timeout_s) const {
  std::unique_lock lock(impl_->mutex);
  return impl_->frame_shown.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] {
    return impl_->shown >= count || !impl_->error.empty();
  }) && impl_->shown >= count;
}

std::string V4l2Output::error() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->error;
}

void bgr_to_yuyv(const cv::Mat& bgr, cv::Mat& yuyv) {
  CV_Assert(bgr.type() == CV_8UC3 && bgr.cols % 2 == 0);
  yuyv.create(bgr.rows, bgr.cols, CV_8UC2);
  // ITU-R BT.601 in 8-bit integers (Y 16..235, Cb and Cr 16..240), rounded.
  const auto luma = [](int r, int g, int b) {
    return static_cast<std::uint8_t>(16 + ((66 * r + 129 * g + 25 * b + 128) >> 8));
  };
  for (int row = 0; row < bgr.rows; ++row) {
    const std::uint8_t* in = bgr.ptr<std::uint8_t>(row);
    std::uint8_t* out = yuyv.ptr<std::uint8_t>(row);
    for (int col = 0; col < bgr.cols; col += 2, in += 6, out += 4) {
      const int b = (in[0] + in[3] + 1) / 2;
      const int g = (in[1] + in[4] + 1) / 2;
      const int r = (in[2] + in[5] + 1) / 2;
      out[0] = luma(in[2], in[1], in[0]);
      out[1] = static_cast<std::uint8_t>(128 + ((-38 * r - 74 * g + 112 * b + 128) >> 8));
      out[2] = luma(in[5], in[4], in[3]);
      out[3] = static_cast<std::uint8_t>(128 + ((112 * r - 94 * g - 18 * b + 128) >> 8));
    }
  }
}

}  // namespace flowsteer::camera_io
