#include "flowsteer/camera_io/libcamera_camera.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <libcamera/libcamera.h>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/clock.hpp"
#include "sequence_gaps.hpp"

namespace flowsteer::camera_io {
namespace {

// One buffer's plane mapped into memory; mmap wants a page-aligned offset, so the mapping may
// start before the plane.
struct PlaneMapping {
  void* base = MAP_FAILED;
  std::size_t mapped_length = 0;
  const std::uint8_t* data = nullptr;
  std::size_t length = 0;
};

// libcamera allows one CameraManager per process and aborts the process (a Fatal log) on a
// second; a ManagerSlot is held for each manager's lifetime, so a second one is an exception.
class ManagerSlot {
 public:
  ManagerSlot() {
    std::lock_guard lock(mutex_);
    if (taken_) {
      throw std::logic_error(
          "libcamera: one camera manager per process, and a LibcameraCamera holds it: close it "
          "before opening another camera or listing cameras");
    }
    taken_ = true;
  }
  ~ManagerSlot() {
    std::lock_guard lock(mutex_);
    taken_ = false;
  }
  ManagerSlot(const ManagerSlot&) = delete;
  ManagerSlot& operator=(const ManagerSlot&) = delete;

 private:
  static inline std::mutex mutex_;
  static inline bool taken_ = false;
};

// The formats read() converts to BGR, in the order tried when none is asked for.
constexpr std::array<libcamera::PixelFormat, 4> kConvertedFormats = {
    libcamera::formats::RGB888, libcamera::formats::BGR888, libcamera::formats::XRGB8888,
    libcamera::formats::YUYV};

std::string format_names(const std::vector<libcamera::PixelFormat>& formats) {
  std::string names;
  for (const libcamera::PixelFormat& format : formats) {
    names += (names.empty() ? "" : ", ") + format.toString();
  }
  return names;
}

}  // namespace

struct LibcameraCamera::Impl {
  std::string name;  // "libcamera camera <id>", for messages
  ManagerSlot slot;  // before the manager: claimed first, released last
  libcamera::CameraManager manager;
  std::shared_ptr<libcamera::Camera> camera;
  bool acquired = false;
  bool started = false;
  std::unique_ptr<libcamera::CameraConfiguration> config;
  libcamera::Stream* stream = nullptr;
  libcamera::PixelFormat format;
  unsigned int stride = 0;
  int width_px = 0;
  int height_px = 0;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<libcamera::Request>> requests;
  std::vector<PlaneMapping> mappings;  // by the buffer's cookie

  // Completed requests, handed from libcamera's thread to read(); capacity reserved up front.
  std::mutex mutex;
  std::condition_variable completed_cv;
  std::vector<libcamera::Request*> completed;

  std::optional<Lens> lens;
  cv::Mat converted;
  std::optional<std::uint32_t> last_sequence;  // libcamera's, of the last frame read
  std::uint64_t dropped = 0;
  std::uint64_t sequence = 0;

  // Opening the camera, phase by phase; each throws std::runtime_error where it fails, and the
  // destructor undoes what the phases before it did.
  void start_manager();
  void select_camera(const std::string& camera_id);
  void acquire_camera();
  void configure(const LibcameraOptions& options);
  void choose_pixel_format(libcamera::StreamConfiguration& stream_config, const std::string& asked);
  void create_requests();
  PlaneMapping map_plane(const libcamera::FrameBuffer::Plane& plane, long page) const;
  void start(double frame_rate_hz);

  void on_complete(libcamera::Request* request) {
    if (request->status() == libcamera::Request::RequestCancelled) {
      return;  // stop() cancels what is queued
    }
    {
      std::lock_guard lock(mutex);
      completed.push_back(request);
    }
    completed_cv.notify_one();
  }

  ~Impl() {
    if (started) {
      camera->stop();
    }
    if (camera) {
      camera->requestCompleted.disconnect(this, &Impl::on_complete);
    }
    for (const PlaneMapping& m : mappings) {
      if (m.base != MAP_FAILED) {
        ::munmap(m.base, m.mapped_length);
      }
    }
    requests.clear();
    allocator.reset();
    if (acquired) {
      camera->release();
    }
    camera.reset();
    manager.stop();
  }
};

namespace {

void check_options(const LibcameraOptions& options) {
  if (options.buffer_count < 2 || options.width_px <= 0 || options.height_px <= 0 ||
      !(options.frame_rate_hz >= 0.0)) {
    throw std::invalid_argument(
        "libcamera: need a positive size, a frame rate >= 0 and at least 2 buffers");
  }
  if (!options.pixel_format.empty() &&
      std::find(kConvertedFormats.begin(), kConvertedFormats.end(),
                libcamera::PixelFormat::fromString(options.pixel_format)) ==
          kConvertedFormats.end()) {
    throw std::invalid_argument("libcamera: pixel format '" + options.pixel_format +
                                "' is not one LibcameraCamera converts (" +
                                format_names({kConvertedFormats.begin(), kConvertedFormats.end()}) +
                                ")");
  }
}

}  // namespace

void LibcameraCamera::Impl::start_manager() {
  if (const int error = manager.start(); error != 0) {
    throw std::runtime_error("libcamera: the camera manager did not start: " +
                             std::string(std::strerror(-error)));
  }
}

// The camera with `camera_id`, or the first camera when that is empty.
void LibcameraCamera::Impl::select_camera(const std::string& camera_id) {
  const auto cameras = manager.cameras();
  if (cameras.empty()) {
    throw std::runtime_error(
        "libcamera: no camera found (libcamera lists the cameras its pipeline handlers support; "
        "a plain V4L2 device is better opened with the v4l2 camera type)");
  }
  if (camera_id.empty()) {
    camera = cameras.front();
  } else {
    camera = manager.get(camera_id);
    if (!camera) {
      std::string ids;
      for (const auto& found : cameras) {
        ids += (ids.empty() ? "" : ", ") + found->id();
      }
      throw std::runtime_error("libcamera: no camera with id '" + camera_id + "' (found: " + ids +
                               ")");
    }
  }
  name = "libcamera camera " + camera->id();
}

void LibcameraCamera::Impl::acquire_camera() {
  if (const int error = camera->acquire(); error != 0) {
    throw std::runtime_error(
        name + ": cannot acquire it (in use by another program?): " + std::strerror(-error));
  }
  acquired = true;
}

// One video stream of exactly the size asked for, in a format read() converts.
void LibcameraCamera::Impl::configure(const LibcameraOptions& options) {
  config = camera->generateConfiguration({libcamera::StreamRole::VideoRecording});
  if (!config || config->size() != 1) {
    throw std::runtime_error(name + ": offers no video stream");
  }
  libcamera::StreamConfiguration& stream_config = config->at(0);
  const libcamera::Size asked(static_cast<unsigned int>(options.width_px),
                              static_cast<unsigned int>(options.height_px));
  stream_config.size = asked;
  stream_config.bufferCount = static_cast<unsigned int>(options.buffer_count);
  choose_pixel_format(stream_config, options.pixel_format);
  if (stream_config.size != asked) {
    // validate() replaced the size with the nearest the pipeline can give.
    throw std::runtime_error(name + ": does not offer " + asked.toString() + " in " +
                             stream_config.pixelFormat.toString() + ": the nearest it offers is " +
                             stream_config.size.toString());
  }
  if (const int error = camera->configure(config.get()); error != 0) {
    throw std::runtime_error(name + ": configure failed: " + std::strerror(-error));
  }
  stream = stream_config.stream();
  format = stream_config.pixelFormat;
  stride = stream_config.stride;
  width_px = static_cast<int>(stream_config.size.width);
  height_px = static_cast<int>(stream_config.size.height);
}

// The format asked for, else the first of the formats read() converts, that the camera keeps
// when the configuration is validated (validate() replaces a format the camera lacks with one
// it has, and may adjust the size to it: each try starts from the size asked for).
void LibcameraCamera::Impl::choose_pixel_format(libcamera::StreamConfiguration& stream_config,
                                                const std::string& asked) {
  std::vector<libcamera::PixelFormat> wanted(kConvertedFormats.begin(), kConvertedFormats.end());
  if (!asked.empty()) {
    wanted = {libcamera::PixelFormat::fromString(asked)};  // check_options() checked it
  }
  const libcamera::Size size = stream_config.size;
  for (const libcamera::PixelFormat& wanted_format : wanted) {
    stream_config.pixelFormat = wanted_format;
    stream_config.size = size;
    if (config->validate() != libcamera::CameraConfiguration::Invalid &&
        stream_config.pixelFormat == wanted_format) {
      return;
    }
  }
  throw std::runtime_error(name + ": does not offer pixel format " + format_names(wanted) +
                           " (it offers " + format_names(stream_config.formats().pixelformats()) +
                           ")");
}

// Allocates the stream's buffers, maps each into memory (read() finds a buffer's mapping by its
// cookie) and makes a capture request of each.
void LibcameraCamera::Impl::create_requests() {
  allocator = std::make_unique<libcamera::FrameBufferAllocator>(camera);
  if (allocator->allocate(stream) < 0) {
    throw std::runtime_error(name + ": cannot allocate frame buffers");
  }
  const long page = ::sysconf(_SC_PAGESIZE);
  const auto& buffers = allocator->buffers(stream);
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    libcamera::FrameBuffer* buffer = buffers[i].get();
    buffer->setCookie(i);
    mappings.push_back(map_plane(buffer->planes().front(), page));
    std::unique_ptr<libcamera::Request> request = camera->createRequest(i);
    if (!request || request->addBuffer(stream, buffer) != 0) {
      throw std::runtime_error(name + ": cannot create a capture request");
    }
    requests.push_back(std::move(request));
  }
}

PlaneMapping LibcameraCamera::Impl::map_plane(const libcamera::FrameBuffer::Plane& plane,
                                              long page) const {
  PlaneMapping m;
  const std::size_t aligned = plane.offset - plane.offset % static_cast<std::size_t>(page);
  m.mapped_length = plane.offset - aligned + plane.length;
  m.base = ::mmap(nullptr, m.mapped_length, PROT_READ, MAP_SHARED, plane.fd.get(),
                  static_cast<off_t>(aligned));
  if (m.base == MAP_FAILED) {
    throw std::runtime_error(name + ": mmap of a frame buffer failed: " + std::strerror(errno));
  }
  m.data = static_cast<const std::uint8_t*>(m.base) + (plane.offset - aligned);
  m.length = plane.length;
  return m;
}

// Starts streaming, at frame_rate_hz where that is not 0 and the camera has FrameDurationLimits,
// with every request queued.
void LibcameraCamera::Impl::start(double frame_rate_hz) {
  completed.reserve(requests.size());
  camera->requestCompleted.connect(this, &Impl::on_complete);

  libcamera::ControlList controls(camera->controls());
  if (frame_rate_hz > 0.0 &&
      camera->controls().count(&libcamera::controls::FrameDurationLimits) != 0) {
    const auto period_us = static_cast<std::int64_t>(std::lround(1e6 / frame_rate_hz));
    const std::array<std::int64_t, 2> limits = {period_us, period_us};
    controls.set(libcamera::controls::FrameDurationLimits,
                 libcamera::Span<const std::int64_t, 2>(limits));
  }
  if (const int error = camera->start(&controls); error != 0) {
    throw std::runtime_error(name + ": start failed: " + std::strerror(-error));
  }
  started = true;
  for (const auto& request : requests) {
    if (const int error = camera->queueRequest(request.get()); error != 0) {
      throw std::runtime_error(name + ": queueing a request failed: " + std::strerror(-error));
    }
  }
}

LibcameraCamera::LibcameraCamera(const LibcameraOptions& options)
    : impl_(std::make_unique<Impl>()) {
  check_options(options);
  Impl& c = *impl_;
  c.start_manager();
  c.select_camera(options.camera_id);
  c.acquire_camera();
  c.configure(options);
  c.lens.emplace(options.lens, c.width_px, c.height_px, c.name);
  c.create_requests();
  c.start(options.frame_rate_hz);
}

LibcameraCamera::~LibcameraCamera() = default;

const base::CameraIntrinsics& LibcameraCamera::intrinsics() const {
  return impl_->lens->intrinsics();
}

std::uint64_t LibcameraCamera::dropped_frames() const {
  return impl_->dropped;
}

std::uint32_t LibcameraCamera::driver_sequence() const {
  return impl_->last_sequence.value_or(0);
}

std::string LibcameraCamera::pixel_format() const {
  return impl_->format.toString();
}

const std::string& LibcameraCamera::camera_id() const {
  return impl_->camera->id();
}

std::vector<std::string> LibcameraCamera::list_cameras() {
  const ManagerSlot slot;
  libcamera::CameraManager manager;
  if (const int error = manager.start(); error != 0) {
    throw std::runtime_error("libcamera: the camera manager did not start: " +
                             std::string(std::strerror(-error)));
  }
  std::vector<std::string> ids;
  for (const auto& camera : manager.cameras()) {
    ids.push_back(camera->id());
  }
  manager.stop();
  return ids;
}

ReadStatus LibcameraCamera::read(Frame& frame, double timeout_s) {
  Impl& c = *impl_;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(0.0, timeout_s));
  for (;;) {
    libcamera::Request* request = nullptr;
    {
      std::unique_lock lock(c.mutex);
      if (!c.completed_cv.wait_until(lock, deadline, [&] { return !c.completed.empty(); })) {
        return ReadStatus::timeout;
      }
      request = c.completed.front();
      c.completed.erase(c.completed.begin());
    }
    const libcamera::FrameBuffer* buffer = request->findBuffer(c.stream);
    const libcamera::FrameMetadata& metadata = buffer->metadata();
    c.dropped += skipped_frames(c.last_sequence, metadata.sequence);
    const bool good = request->status() == libcamera::Request::RequestComplete &&
                      metadata.status == libcamera::FrameMetadata::FrameSuccess;
    if (good) {
      const PlaneMapping& m = c.mappings.at(buffer->cookie());
      auto* data = const_cast<std::uint8_t*>(m.data);  // cv::Mat wants a mutable pointer
      if (c.format == libcamera::formats::RGB888) {
        cv::Mat(c.height_px, c.width_px, CV_8UC3, data, c.stride).copyTo(c.converted);
      } else if (c.format == libcamera::formats::BGR888) {
        // libcamera's BGR888 is R, G, B in memory.
        cv::cvtColor(cv::Mat(c.height_px, c.width_px, CV_8UC3, data, c.stride), c.converted,
                     cv::COLOR_RGB2BGR);
      } else if (c.format == libcamera::formats::XRGB8888) {
        cv::cvtColor(cv::Mat(c.height_px, c.width_px, CV_8UC4, data, c.stride), c.converted,
                     cv::COLOR_BGRA2BGR);
      } else {
        cv::cvtColor(cv::Mat(c.height_px, c.width_px, CV_8UC2, data, c.stride), c.converted,
                     cv::COLOR_YUV2BGR_YUYV);
      }
    } else {
      ++c.dropped;
    }
    const std::uint64_t timestamp_ns = metadata.timestamp;
    request->reuse(libcamera::Request::ReuseBuffers);
    if (const int error = c.camera->queueRequest(request); error != 0) {
      throw std::runtime_error(c.name + ": queueing a request failed: " + std::strerror(-error));
    }
    if (!good) {
      continue;
    }
    // libcamera stamps frames with the sensor's (monotonic) start-of-exposure time.
    frame.timestamp_s =
        timestamp_ns != 0 ? 1e-9 * static_cast<double>(timestamp_ns) : base::monotonic_now_s();
    frame.image = c.lens->apply(c.converted);
    frame.sequence = c.sequence++;
    frame.sim.reset();
    return ReadStatus::ok;
  }
}

}  // namespace flowsteer::camera_io
