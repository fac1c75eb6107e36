// Boots the libcamera test VM (tests/vm/run_libcamera_vm.sh), in which
// tests/vm/libcamera_vm_probe runs LibcameraCamera against the kernel's vimc driver through
// libcamera's vimc pipeline handler, and checks what the probe printed: the camera found by its
// id, the streams configured as asked and the size the pipeline would have adjusted refused,
// frames with rising sequence numbers and monotonic timestamps, vimc's colour bars in both RGB
// orders, closing and opening again, the one camera manager libcamera allows, and the errors
// for a missing camera, a format the camera lacks, one the class does not convert and a size
// too large.

#include <array>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "camera_vm_run.hpp"

namespace {

constexpr const char* kVimcCamera = "platform/vimc.0 Sensor B";

using VmRun = flowsteer::vm_test::CameraVmRun;
using ProbeFrame = flowsteer::vm_test::CameraFrame;

// "ID|FORMAT|SECONDS" of a "<key>-open" line.
struct Opened {
  std::string id;
  std::string format;
  double seconds = -1.0;
};

Opened opened(const std::string& value) {
  Opened o;
  const std::size_t first = value.find('|');
  const std::size_t second = value.find('|', first + 1);
  if (first == std::string::npos || second == std::string::npos) {
    return o;
  }
  o.id = value.substr(0, first);
  o.format = value.substr(first + 1, second - first - 1);
  o.seconds = std::stod(value.substr(second + 1));
  return o;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

class VimcVm : public flowsteer::vm_test::CameraVmTest {};

TEST_F(VimcVm, ListsTheVimcCameraAndOpensItById) {
  ASSERT_EQ(run_.cameras.size(), 1u) << run_.console;
  EXPECT_EQ(run_.cameras[0], kVimcCamera);
  EXPECT_EQ(run_.probe["camera-count"], "1");
  for (const char* key : {"default", "bgr", "rgb"}) {
    EXPECT_EQ(opened(run_.probe[std::string(key) + "-open"]).id, kVimcCamera) << key;
  }
}

// Each stream runs in the pixel format and at the size asked for, and every frame has it.
TEST_F(VimcVm, StreamsAreConfiguredAsAsked) {
  struct Expected {
    const char* key;
    const char* format;
    int width;
    int height;
  };
  // "default" asked for no format: RGB888 comes first of those the camera converts.
  for (const Expected& e :
       {Expected{"default", "RGB888", 636, 480}, Expected{"bgr", "BGR888", 318, 240},
        Expected{"rgb", "RGB888", 636, 480}}) {
    SCOPED_TRACE(e.key);
    const Opened o = opened(run_.probe[std::string(e.key) + "-open"]);
    EXPECT_EQ(o.format, e.format);
    // Opening means configuring the pipeline's five entities and allocating buffers.
    EXPECT_GT(o.seconds, 0.0);
    EXPECT_LT(o.seconds, 5.0);
    ASSERT_FALSE(run_.frames[e.key].empty()) << run_.console;
    for (const ProbeFrame& f : run_.frames[e.key]) {
      EXPECT_EQ(f.width, e.width);
      EXPECT_EQ(f.height, e.height);
    }
  }
}

// 640x480 is not a multiple of 6, so libcamera's vimc pipeline would give 636x480; the camera
// refuses a size it was not asked for and names both.
TEST_F(VimcVm, RefusesASizeThePipelineAdjusts) {
  const std::string& message = run_.probe["error-adjusted-size"];
  EXPECT_TRUE(contains(message, kVimcCamera)) << message;
  EXPECT_TRUE(contains(message, "640x480")) << message;
  EXPECT_TRUE(contains(message, "636x480")) << message;
}

// Frames numbered from 0 with libcamera's sequence numbers rising, stamped on the monotonic
// clock: increasing, just before the probe got each frame, and spaced at least by the 1/60 s
// vimc's streaming thread sleeps between frames.
void check_stream(const VmRun& run, const std::string& key, std::size_t count) {
  SCOPED_TRACE(key);
  const auto it = run.frames.find(key);
  ASSERT_NE(it, run.frames.end()) << run.console;
  const std::vector<ProbeFrame>& frames = it->second;
  ASSERT_EQ(frames.size(), count) << run.console;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ProbeFrame& f = frames[i];
    EXPECT_EQ(f.sequence, i);
    EXPECT_LE(f.timestamp_s, f.read_s);
    // An emulated machine is slow, but a stamp from another clock would be far off.
    EXPECT_LT(f.read_s - f.timestamp_s, 1.0);
    if (i > 0) {
      EXPECT_GT(f.timestamp_s, frames[i - 1].timestamp_s);
      EXPECT_GT(f.driver_sequence, frames[i - 1].driver_sequence);
    }
  }
  const double mean_period_s = (frames.back().timestamp_s - frames.front().timestamp_s) /
                               static_cast<double>(frames.size() - 1);
  // 1/60 s in jiffies of 4 ms (HZ=250): 16 ms.
  EXPECT_GE(mean_period_s, 0.016);
  EXPECT_LT(mean_period_s, 0.5);
  flowsteer::vm_test::expect_drops_counted(run, key);
}

TEST_F(VimcVm, FramesHaveRisingSequenceAndMonotonicTimestamps) {
  check_stream(run_, "default", 20);
}

// The camera closed and opened again (another format and size, then the first again): frames
// come, from a new stream whose sequence numbers start again at 0.
TEST_F(VimcVm, ClosedAndOpenedAgainItStreamsAgain) {
  check_stream(run_, "bgr", 10);
  check_stream(run_, "rgb", 10);
  for (const char* key : {"default", "bgr", "rgb"}) {
    ASSERT_FALSE(run_.frames[key].empty()) << key;
    EXPECT_EQ(run_.frames[key].front().driver_sequence, 0u) << key;
  }
}

// vimc's sensor shows 75% colour bars (white, yellow, cyan, green, magenta, red, blue, black;
// 191 of 255), which the pipeline debayers and triples in size: in BGR, the same whichever RGB
// order the camera streamed.
TEST_F(VimcVm, ImagesShowTheColourBarsInBgr) {
  const std::vector<std::array<double, 3>> expected = {
      {191, 191, 191}, {0, 191, 191}, {191, 191, 0}, {0, 191, 0},
      {191, 0, 191},   {0, 0, 191},   {191, 0, 0},   {0, 0, 0}};
  for (const char* key : {"default", "bgr", "rgb"}) {
    SCOPED_TRACE(key);
    const auto measured = flowsteer::vm_test::colour_bars(run_.probe[std::string(key) + "-bars"]);
    ASSERT_EQ(measured.size(), expected.size()) << run_.console;
    for (std::size_t bar = 0; bar < expected.size(); ++bar) {
      for (int channel = 0; channel < 3; ++channel) {
        EXPECT_NEAR(measured[bar][channel], expected[bar][channel], 12.0)
            << "bar " << bar << " channel " << channel;
      }
    }
    // Not one value: the black bar and the 75% white one.
    int min_value = -1;
    int max_value = -1;
    ASSERT_EQ(std::sscanf(run_.probe[std::string(key) + "-range"].c_str(), "%d %d", &min_value,
                          &max_value),
              2);
    EXPECT_LE(min_value, 5);
    EXPECT_GE(max_value, 185);
  }
}

// libcamera allows one camera manager per process and aborts the process on a second; with a
// camera open, listing cameras is an exception instead.
TEST_F(VimcVm, ASecondCameraManagerIsAClearError) {
  for (const char* key : {"default", "bgr", "rgb"}) {
    const std::string& message = run_.probe[std::string(key) + "-second-manager"];
    EXPECT_TRUE(contains(message, "one camera manager per process")) << key << ": " << message;
  }
}

// The probe ends after every camera has been closed; under the sanitizers a leak or an error
// in closing would make its exit status non-zero.
TEST_F(VimcVm, ProbeExitsCleanly) {
  EXPECT_EQ(run_.exit_status, "0") << run_.console;
}

TEST_F(VimcVm, ErrorsNameWhatWasWrong) {
  const std::string& missing = run_.probe["error-missing-id"];
  EXPECT_TRUE(contains(missing, "'platform/no-such-camera.0 Sensor Z'")) << missing;
  EXPECT_TRUE(contains(missing, std::string("found: ") + kVimcCamera)) << missing;

  // vimc's capture offers BGR888 and RGB888 only.
  const std::string& format = run_.probe["error-format"];
  EXPECT_TRUE(contains(format, kVimcCamera)) << format;
  EXPECT_TRUE(contains(format, "pixel format YUYV")) << format;
  EXPECT_TRUE(contains(format, "it offers BGR888, RGB888")) << format;

  const std::string& name = run_.probe["error-format-name"];
  EXPECT_TRUE(contains(name, "'NV12' is not one LibcameraCamera converts")) << name;

  // The pipeline's largest is 4096x2160, rounded down to multiples of 6.
  const std::string& size = run_.probe["error-size"];
  EXPECT_TRUE(contains(size, "8000x6000")) << size;
  EXPECT_TRUE(contains(size, "4092x2160")) << size;
}

}  // namespace
