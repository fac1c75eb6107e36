// Runs inside the libcamera test VM (tests/vm/vimc_init.sh): LibcameraCamera against the
// kernel's vimc driver through libcamera's vimc pipeline handler. Prints "PROBE key value" lines
// for tests/camera_io/libcamera_vm_test.cpp to check; the checks themselves are on the host, so
// that a failure there shows the whole console.

#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "camera_probe_support.hpp"
#include "flowsteer/base/clock.hpp"
#include "flowsteer/camera_io/libcamera_camera.hpp"
#include "probe_support.hpp"

namespace {

using flowsteer::vm_test::expect_error;
using flowsteer::vm_test::print_bars;

using flowsteer::base::monotonic_now_s;
using flowsteer::camera_io::Frame;
using flowsteer::camera_io::LibcameraCamera;
using flowsteer::camera_io::LibcameraOptions;
using flowsteer::camera_io::ReadStatus;

// Opens the camera, reads `frames` frames and prints each with the probe's monotonic clock
// just after read() returned, then the last image's colour bars and value range. The camera
// is closed (stopped and released) on return.
void capture(const std::string& key, const LibcameraOptions& options, int frames) {
  const double open_start_s = monotonic_now_s();
  LibcameraCamera camera(options);
  std::printf("PROBE %s-open %s|%s|%.3f\n", key.c_str(), camera.camera_id().c_str(),
              camera.pixel_format().c_str(), monotonic_now_s() - open_start_s);
  // libcamera allows one camera manager per process: a clear error while this camera has it.
  expect_error((key + "-second-manager").c_str(), [] { LibcameraCamera::list_cameras(); });
  Frame frame;
  for (int i = 0; i < frames; ++i) {
    const ReadStatus status = camera.read(frame, 5.0);
    const double now_s = monotonic_now_s();
    if (status != ReadStatus::ok) {
      std::printf("PROBE %s-frame timeout\n", key.c_str());
      return;
    }
    std::printf("PROBE %s-frame %llu %.6f %.6f %u %dx%d\n", key.c_str(),
                static_cast<unsigned long long>(frame.sequence), frame.timestamp_s, now_s,
                camera.driver_sequence(), frame.image.cols, frame.image.rows);
  }
  // Seven eighths down: the upper part carries the text of vimc's "Show Information" control.
  print_bars(key + "-bars", frame.image, frame.image.rows * 7 / 8, frame.image.cols / 64);
  double min_value = 0.0;
  double max_value = 0.0;
  cv::minMaxLoc(frame.image.reshape(1), &min_value, &max_value);
  std::printf("PROBE %s-range %.0f %.0f\n", key.c_str(), min_value, max_value);
  std::printf("PROBE %s-dropped %llu\n", key.c_str(),
              static_cast<unsigned long long>(camera.dropped_frames()));
}

}  // namespace

int main() {
  return flowsteer::vm_test::probe_main([] {
    const std::vector<std::string> ids = LibcameraCamera::list_cameras();
    std::printf("PROBE camera-count %zu\n", ids.size());
    for (const std::string& id : ids) {
      std::printf("PROBE camera %s\n", id.c_str());
    }
    if (ids.empty()) {
      std::printf("PROBE done no camera\n");
      return 1;
    }

    LibcameraOptions options;
    options.camera_id = ids.front();
    // libcamera's vimc pipeline gives sizes in multiples of 6 (its scaler triples the
    // sensor's size, which is even): 640x480 is adjusted, which the camera refuses.
    options.width_px = 640;
    options.height_px = 480;
    expect_error("error-adjusted-size", [&] { LibcameraCamera camera(options); });
    options.width_px = 636;
    capture("default", options, 20);

    // Closed and opened again, in the other RGB order and another size: the first camera
    // released everything, and the colours come out the same.
    options.width_px = 318;
    options.height_px = 240;
    options.pixel_format = "BGR888";
    capture("bgr", options, 10);

    // And once more as the first time, the format named.
    options.width_px = 636;
    options.height_px = 480;
    options.pixel_format = "RGB888";
    capture("rgb", options, 10);

    expect_error("error-missing-id", [&] {
      LibcameraOptions missing = options;
      missing.camera_id = "platform/no-such-camera.0 Sensor Z";
      LibcameraCamera camera(missing);
    });
    expect_error("error-format", [&] {
      LibcameraOptions yuyv = options;
      yuyv.pixel_format = "YUYV";
      LibcameraCamera camera(yuyv);
    });
    expect_error("error-format-name", [&] {
      LibcameraOptions nv12 = options;
      nv12.pixel_format = "NV12";
      LibcameraCamera camera(nv12);
    });
    expect_error("error-size", [&] {
      LibcameraOptions huge = options;
      huge.width_px = 8000;
      huge.height_px = 6000;
      LibcameraCamera camera(huge);
    });
    std::printf("PROBE done\n");
    return 0;
  });
}
