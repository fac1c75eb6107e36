// Boots the V4L2 test VM (tests/vm/run_vivid_vm.sh), in which tests/vm/v4l2_vm_probe runs
// V4l2Camera against the kernel's vivid driver, and checks what the probe printed: formats,
// frames and their sequence and timestamps, vivid's colour bars, a clean stop, dropped frames,
// buffers flagged as errors, a driver clock that cannot be monotonic, a timeout, a stream the
// driver gives up on and the errors for bad devices and formats.

#include <array>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "camera_vm_run.hpp"

namespace {

using VmRun = flowsteer::vm_test::CameraVmRun;
using ProbeFrame = flowsteer::vm_test::CameraFrame;

class VividVm : public flowsteer::vm_test::CameraVmTest {};

TEST_F(VividVm, OffersYuyvAndGrey) {
  const std::string formats = " " + run_.probe["formats"] + " ";
  EXPECT_NE(formats.find(" YUYV "), std::string::npos) << formats;
  EXPECT_NE(formats.find(" GREY "), std::string::npos) << formats;
}

// Frames come one sequence number apart, with driver timestamps on the monotonic clock that
// increase, lie just before the probe got the frame, and are spaced by the rate.
void check_stream(const VmRun& run, const std::string& key, std::size_t count, int width,
                  int height, double rate_hz) {
  SCOPED_TRACE(key);
  const auto it = run.frames.find(key);
  ASSERT_NE(it, run.frames.end()) << run.console;
  const std::vector<ProbeFrame>& frames = it->second;
  ASSERT_EQ(frames.size(), count) << run.console;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ProbeFrame& f = frames[i];
    EXPECT_EQ(f.sequence, i);
    EXPECT_EQ(f.width, width);
    EXPECT_EQ(f.height, height);
    EXPECT_EQ(f.driver_timestamps, 1) << "vivid stamps buffers with the monotonic clock";
    // vivid stamps "end of frame" as the tick's time plus 0.9 of a period, which can be a
    // little after it hands the buffer over; a stamp from another clock would be far off.
    EXPECT_LE(f.timestamp_s, f.read_s + 1.0 / rate_hz);
    // Stamped at most a few frame periods before the probe saw it (an emulated machine is
    // slow, so not one period).
    EXPECT_LT(f.read_s - f.timestamp_s, 1.0);
    if (i > 0) {
      EXPECT_GT(f.timestamp_s, frames[i - 1].timestamp_s);
      EXPECT_GT(f.driver_sequence, frames[i - 1].driver_sequence);
    }
  }
  // vivid stamps from its own frame clock: the mean spacing is the period, give or take the
  // frames it had to drop on a slow machine (seen in the driver's sequence numbers).
  const double span_s = frames.back().timestamp_s - frames.front().timestamp_s;
  const double periods = frames.back().driver_sequence - frames.front().driver_sequence;
  EXPECT_NEAR(span_s / periods, 1.0 / rate_hz, 0.1 / rate_hz);
  // An emulated machine converts slower than vivid fills buffers, so frames are dropped; each
  // gap in the driver's sequence numbers is counted.
  flowsteer::vm_test::expect_drops_counted(run, key);
}

TEST_F(VividVm, YuyvStreamHasIncreasingSequenceAndMonotonicTimestamps) {
  // 30 Hz was asked; vivid's webcam input runs 640x480 at 25 Hz at most and rounds down.
  EXPECT_NE(run_.probe["yuyv-open"].find("rate=25.000"), std::string::npos)
      << run_.probe["yuyv-open"];
  check_stream(run_, "yuyv", 20, 640, 480, 25.0);
}

TEST_F(VividVm, YuyvImageShowsTheSeventyFivePercentColourBars) {
  // vivid's default test pattern: white, yellow, cyan, green, magenta, red, blue, black at 75%
  // (191 of 255), in BGR; YUYV's chroma subsampling and limited range cost a few levels.
  const std::vector<std::array<double, 3>> expected = {
      {191, 191, 191}, {0, 191, 191}, {191, 191, 0}, {0, 191, 0},
      {191, 0, 191},   {0, 0, 191},   {191, 0, 0},   {0, 0, 0}};
  const auto got = flowsteer::vm_test::colour_bars(run_.probe["yuyv-bars"]);
  ASSERT_EQ(got.size(), expected.size()) << run_.probe["yuyv-bars"];
  for (std::size_t bar = 0; bar < expected.size(); ++bar) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(got[bar][c], expected[bar][c], 8.0) << "bar " << bar << " channel " << c;
    }
  }
}

TEST_F(VividVm, StopReleasesTheBuffersSoAnotherFormatCanStream) {
  EXPECT_EQ(run_.probe["yuyv-stop"], "ok");
  check_stream(run_, "grey", 5, 640, 480, 25.0);
  EXPECT_EQ(run_.probe["grey-stop"], "ok");
}

TEST_F(VividVm, GreyImageIsTheBarsLuminance) {
  const auto got = flowsteer::vm_test::colour_bars(run_.probe["grey-bars"]);
  ASSERT_EQ(got.size(), 8u) << run_.probe["grey-bars"];
  for (std::size_t bar = 0; bar < got.size(); ++bar) {
    EXPECT_EQ(got[bar][0], got[bar][1]) << "bar " << bar;
    EXPECT_EQ(got[bar][1], got[bar][2]) << "bar " << bar;
    if (bar > 0) {
      // The bars are ordered by decreasing luma, white (75%) to black.
      EXPECT_LT(got[bar][0], got[bar - 1][0]) << "bar " << bar;
    }
  }
  EXPECT_NEAR(got.front()[0], 191.0, 8.0);
  EXPECT_NEAR(got.back()[0], 0.0, 8.0);
}

TEST_F(VividVm, SequenceGapsAreCountedAsDroppedFrames) {
  EXPECT_NE(run_.probe["control"].find("set"), std::string::npos) << run_.probe["control"];
  EXPECT_NE(run_.probe["drop-open"].find("rate=30.000"), std::string::npos)
      << run_.probe["drop-open"];
  check_stream(run_, "drop", 15, 320, 180, 30.0);
  // With half the buffers dropped, 15 frames in a row without a gap has odds of 2^-14.
  unsigned long long dropped = 0;
  ASSERT_EQ(std::sscanf(run_.probe["drop-dropped"].c_str(), "%llu", &dropped), 1);
  EXPECT_GT(dropped, 0u);
}

TEST_F(VividVm, ACameraThatDeliversNothingTimesOut) {
  double waited_s = 0.0;
  char status[16] = {};
  ASSERT_EQ(std::sscanf(run_.probe["timeout"].c_str(), "%15s %lf", status, &waited_s), 2)
      << run_.probe["timeout"];
  EXPECT_STREQ(status, "timeout");
  EXPECT_GE(waited_s, 0.5);
  EXPECT_LT(waited_s, 1.0);
}

// Three buffers flagged V4L2_BUF_FLAG_ERROR in the stream: none ends it, and every sequence
// number after the first frame is either a frame delivered or one counted as dropped (the
// emulated machine also drops some while it converts, so the count is at least three).
TEST_F(VividVm, BuffersFlaggedErrorAreSkippedAndCountedAsDropped) {
  int delivered = 0;
  unsigned long long dropped = 0;
  unsigned spanned = 0;
  ASSERT_EQ(std::sscanf(run_.probe["buffer-errors"].c_str(), "%d %llu %u", &delivered, &dropped,
                        &spanned),
            3)
      << run_.probe["buffer-errors"];
  EXPECT_EQ(delivered, 12);
  EXPECT_GE(dropped, 3u);
  EXPECT_EQ(dropped + static_cast<unsigned long long>(delivered - 1), spanned);
}

// Stamps 292 years ahead of the monotonic clock: the camera falls back to the time of dequeue,
// so frame times still increase and lie on the stack's clock.
TEST_F(VividVm, ADriverClockThatCannotBeMonotonicFallsBackToTheDequeueTime) {
  ASSERT_NE(run_.console.find("PROBE control Wrap Timestamp=1 set"), std::string::npos);
  const std::vector<ProbeFrame>& frames = run_.frames["wrapped"];
  ASSERT_EQ(frames.size(), 5u) << run_.console;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(frames[i].driver_timestamps, 0);
    EXPECT_LE(frames[i].timestamp_s, frames[i].read_s);
    EXPECT_GT(frames[i].timestamp_s, frames[i].read_s - 0.5);
    if (i > 0) {
      EXPECT_GT(frames[i].timestamp_s, frames[i - 1].timestamp_s);
    }
  }
}

TEST_F(VividVm, AStreamTheDriverGivesUpOnIsAClearError) {
  const std::string& message = run_.probe["fatal-stream-error"];
  EXPECT_NE(message.find("VIDIOC_DQBUF on /dev/video"), std::string::npos) << message;
  EXPECT_NE(message.find("Input/output error"), std::string::npos) << message;
}

TEST_F(VividVm, MissingDeviceIsAClearError) {
  EXPECT_EQ(run_.probe["missing-device"],
            "cannot open camera /dev/video63: No such file or directory");
}

TEST_F(VividVm, ADeviceThatIsNotV4l2IsAClearError) {
  EXPECT_EQ(run_.probe["not-v4l2"],
            "/dev/null is not a V4L2 device (VIDIOC_QUERYCAP failed: Inappropriate ioctl for "
            "device)");
}

TEST_F(VividVm, AnOutputNodeIsNotACaptureDevice) {
  const std::string& message = run_.probe["output-node"];
  EXPECT_NE(message.find("(vivid, "), std::string::npos) << message;
  EXPECT_NE(message.find("is not a video capture device: it offers video output"),
            std::string::npos)
      << message;
}

TEST_F(VividVm, UnsupportedFormatNamesWhatTheDeviceOffers) {
  const std::string& message = run_.probe["mjpeg"];
  EXPECT_NE(message.find("does not offer pixel format MJPG (it offers YUYV, "), std::string::npos)
      << message;
  EXPECT_NE(message.find("GREY"), std::string::npos) << message;
}

TEST_F(VividVm, UnsupportedSizeNamesWhatTheDriverChose) {
  const std::string& message = run_.probe["odd-size"];
  EXPECT_NE(message.find("does not offer 1000x700 in YUYV: the driver chose "), std::string::npos)
      << message;
}

}  // namespace
