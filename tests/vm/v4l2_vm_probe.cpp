// Runs inside the vivid test VM (tests/vm/vivid_init.sh): V4l2Camera against the kernel's vivid
// driver. Prints "PROBE key value" lines for tests/camera_io/v4l2_vm_test.cpp to check; the
// checks themselves are on the host, so that a failure there shows the whole console.

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "camera_probe_support.hpp"
#include "flowsteer/base/clock.hpp"
#include "flowsteer/camera_io/v4l2_camera.hpp"
#include "vivid_control.hpp"

namespace {

using flowsteer::vm_test::expect_error;
using flowsteer::vm_test::print_bars;

using flowsteer::base::monotonic_now_s;
using flowsteer::camera_io::Frame;
using flowsteer::camera_io::PixelFormat;
using flowsteer::camera_io::ReadStatus;
using flowsteer::camera_io::V4l2Camera;
using flowsteer::camera_io::V4l2Options;
using flowsteer::vm_test::set_vivid_control;

std::uint32_t device_caps(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK);
  if (fd < 0) {
    return 0;
  }
  v4l2_capability cap{};
  const bool ok = ::ioctl(fd, VIDIOC_QUERYCAP, &cap) == 0;
  ::close(fd);
  return ok ? cap.device_caps : 0;
}

void capture(const char* key, const V4l2Options& options, int frames, bool bars) {
  V4l2Camera camera(options);
  std::printf("PROBE %s-open %s %s rate=%.3f\n", key, camera.driver().c_str(),
              camera.card().c_str(), camera.frame_rate_hz());
  Frame frame;
  for (int i = 0; i < frames; ++i) {
    const ReadStatus status = camera.read(frame, 2.0);
    const double now_s = monotonic_now_s();
    if (status != ReadStatus::ok) {
      std::printf("PROBE %s-frame timeout\n", key);
      return;
    }
    std::printf("PROBE %s-frame %llu %.6f %.6f %u %dx%d %d\n", key,
                static_cast<unsigned long long>(frame.sequence), frame.timestamp_s, now_s,
                camera.driver_sequence(), frame.image.cols, frame.image.rows,
                camera.driver_timestamps() ? 1 : 0);
  }
  if (bars) {
    // A 16×16 patch of each bar, half-way down.
    print_bars(std::string(key) + "-bars", frame.image, frame.image.rows / 2, 8);
  }
  std::printf("PROBE %s-dropped %llu\n", key,
              static_cast<unsigned long long>(camera.dropped_frames()));
  try {
    camera.stop();
    std::printf("PROBE %s-stop ok\n", key);
  } catch (const std::exception& e) {
    std::printf("PROBE %s-stop %s\n", key, e.what());
  }
}

// At each press of vivid's button the next buffer it fills comes back flagged
// V4L2_BUF_FLAG_ERROR: the camera skips it, counts it as dropped and reads on. Prints the frames
// delivered (three reads before the first press and after each), the frames counted as dropped
// after the first, and the driver's sequence numbers they span.
void capture_through_buffer_errors(const V4l2Options& options, int presses) {
  V4l2Camera camera(options);
  Frame frame;
  int delivered = 0;
  std::uint32_t first_sequence = 0;
  std::uint64_t dropped_before = 0;
  for (int press = 0; press <= presses; ++press) {
    if (press > 0) {
      set_vivid_control(options.device, "Inject V4L2_BUF_FLAG_ERROR", 1);
    }
    for (int i = 0; i < 3; ++i) {
      delivered += camera.read(frame, 2.0) == ReadStatus::ok ? 1 : 0;
      if (delivered == 1) {
        first_sequence = camera.driver_sequence();
        dropped_before = camera.dropped_frames();
      }
    }
  }
  std::printf("PROBE buffer-errors %d %llu %u\n", delivered,
              static_cast<unsigned long long>(camera.dropped_frames() - dropped_before),
              camera.driver_sequence() - first_sequence);
}

}  // namespace

int main() {
  std::string capture_node;
  std::string output_node;
  for (int i = 0; i < 16; ++i) {
    const std::string path = "/dev/video" + std::to_string(i);
    const std::uint32_t caps = device_caps(path);
    if (caps == 0) {
      continue;
    }
    std::printf("PROBE node %s 0x%08x\n", path.c_str(), caps);
    if ((caps & V4L2_CAP_VIDEO_CAPTURE) != 0 && capture_node.empty()) {
      capture_node = path;
    } else if ((caps & V4L2_CAP_VIDEO_OUTPUT) != 0 && output_node.empty()) {
      output_node = path;
    }
  }
  if (capture_node.empty()) {
    std::printf("PROBE done no capture node\n");
    return 1;
  }

  try {
    std::printf("PROBE formats");
    for (const std::string& name : V4l2Camera::list_formats(capture_node)) {
      std::printf(" %s", name.c_str());
    }
    std::printf("\n");

    V4l2Options options;
    options.device = capture_node;
    options.width_px = 640;
    options.height_px = 480;
    options.frame_rate_hz = 30.0;
    options.format = PixelFormat::yuyv;
    capture("yuyv", options, 20, true);

    // Straight after stop(): a new format is accepted only when the buffers were released.
    options.format = PixelFormat::grey;
    capture("grey", options, 5, true);

    // vivid skips filling a buffer now and then but still counts its sequence number, as a
    // camera does that finds no free buffer.
    options.format = PixelFormat::yuyv;
    options.width_px = 320;
    options.height_px = 180;
    set_vivid_control(capture_node, "Percentage of Dropped Buffers", 50);
    capture("drop", options, 15, false);

    // A camera that stops delivering: every buffer dropped.
    set_vivid_control(capture_node, "Percentage of Dropped Buffers", 100);
    {
      V4l2Camera camera(options);
      Frame frame;
      const auto start = std::chrono::steady_clock::now();
      const ReadStatus status = camera.read(frame, 0.5);
      const double waited_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("PROBE timeout %s %.3f\n", status == ReadStatus::timeout ? "timeout" : "frame",
                  waited_s);
    }
    set_vivid_control(capture_node, "Percentage of Dropped Buffers", 0);

    capture_through_buffer_errors(options, 3);

    // A driver clock that cannot be the monotonic one: with vivid's "Wrap Timestamp" set before
    // streaming starts, buffers are stamped 16 s before the 64-bit nanosecond clock wraps.
    set_vivid_control(capture_node, "Wrap Timestamp", 1);
    capture("wrapped", options, 5, false);
    set_vivid_control(capture_node, "Wrap Timestamp", 0);

    // A stream the driver gives up on (vb2_queue_error): the read fails, naming the call.
    expect_error("fatal-stream-error", [&] {
      V4l2Camera camera(options);
      Frame frame;
      camera.read(frame, 2.0);
      set_vivid_control(capture_node, "Inject Fatal Streaming Error", 1);
      for (int i = 0; i < 10; ++i) {
        camera.read(frame, 2.0);
      }
    });

    expect_error("missing-device", [] {
      V4l2Options missing;
      missing.device = "/dev/video63";
      V4l2Camera camera(missing);
    });
    expect_error("not-v4l2", [] {
      V4l2Options null_device;
      null_device.device = "/dev/null";
      V4l2Camera camera(null_device);
    });
    expect_error("output-node", [&] {
      V4l2Options output = options;
      output.device = output_node;
      V4l2Camera camera(output);
    });
    expect_error("mjpeg", [&] {
      V4l2Options mjpeg = options;
      mjpeg.format = PixelFormat::mjpeg;
      V4l2Camera camera(mjpeg);
    });
    expect_error("odd-size", [&] {
      V4l2Options odd = options;
      odd.width_px = 1000;
      odd.height_px = 700;
      V4l2Camera camera(odd);
    });
  } catch (const std::exception& e) {
    std::printf("PROBE failed %s\n", e.what());
    return 1;
  }
  std::printf("PROBE done\n");
  return 0;
}
