#pragma once

// What the camera VM tests (V4L2 on vivid, libcamera on vimc) read from their probes' console:
// the probe lines by key, the cameras listed, each stream's frames and the probe's exit status
// (camera_probe_support.hpp prints them).

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "vm_test_support.hpp"

namespace flowsteer::vm_test {

// "PROBE <stream>-frame SEQUENCE TIMESTAMP_S READ_S DRIVER_SEQUENCE WxH [DRIVER_TIMESTAMPS]".
struct CameraFrame {
  unsigned long long sequence = 0;
  double timestamp_s = 0.0;
  double read_s = 0.0;  // the probe's monotonic clock just after read() returned
  unsigned driver_sequence = 0;
  int width = 0;
  int height = 0;
  int driver_timestamps = -1;  // 1: the driver's clock is monotonic; -1: not printed
};

struct CameraVmRun {
  std::string console;
  std::map<std::string, std::string> probe;                // last line per key
  std::vector<std::string> cameras;                        // "PROBE camera ID", in order
  std::map<std::string, std::vector<CameraFrame>> frames;  // stream → its frames
  std::string exit_status;                                 // the init's "VM: probe exit status"
};

inline CameraVmRun parse_camera_console(const std::string& console) {
  CameraVmRun run;
  run.console = console;
  const std::string exit_line = "VM: probe exit status ";
  for_each_line(console, [&](const std::string& line) {
    if (line.starts_with(exit_line)) {
      run.exit_status = line.substr(exit_line.size());
    }
    const auto probe = probe_line(line);
    if (!probe) {
      return;
    }
    const auto& [key, value] = *probe;
    if (key == "camera") {
      run.cameras.push_back(value);
    } else if (key.ends_with("-frame")) {
      CameraFrame f;
      if (std::sscanf(value.c_str(), "%llu %lf %lf %u %dx%d %d", &f.sequence, &f.timestamp_s,
                      &f.read_s, &f.driver_sequence, &f.width, &f.height,
                      &f.driver_timestamps) >= 6) {
        run.frames[key.substr(0, key.size() - 6)].push_back(f);
      }
    }
    run.probe[key] = value;
  });
  return run;
}

// The probe's "<stream>-dropped" count is the frames the driver's sequence numbers skip between
// the stream's first frame and its last.
inline void expect_drops_counted(const CameraVmRun& run, const std::string& stream) {
  const std::vector<CameraFrame>& frames = run.frames.at(stream);
  unsigned long long gaps = 0;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    gaps += frames[i].driver_sequence - frames[i - 1].driver_sequence - 1;
  }
  unsigned long long dropped = 0;
  ASSERT_EQ(std::sscanf(run.probe.at(stream + "-dropped").c_str(), "%llu", &dropped), 1);
  EXPECT_EQ(dropped, gaps);
}

// A camera VM test suite: every test needs the probe to have finished ("PROBE done").
class CameraVmTest : public VmTest<CameraVmRun, parse_camera_console> {
 protected:
  void SetUp() override {
    VmTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) {
      return;
    }
    ASSERT_EQ(run_.probe["done"], "") << run_.console;
  }
};

}  // namespace flowsteer::vm_test
