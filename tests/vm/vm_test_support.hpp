#pragma once

// The host side of a VM test (tests/vm): boots the VM once per test suite with the runner the
// test was built with and reads what the probe printed on the console, "PROBE key value" lines.
// The test's CMake target defines FLOWSTEER_VM_SCRIPT (run_*_vm.sh), FLOWSTEER_VM_KERNEL_CACHE,
// FLOWSTEER_VM_WORK_DIR, FLOWSTEER_VM_PROBE and FLOWSTEER_VM_ALSO (a second program for the
// script, or empty; flowsteer_add_vm_test in tests/CMakeLists.txt).

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace flowsteer::vm_test {

// Runs a shell command and returns its stdout; `status` is its exit status, -1 when it did not
// exit normally.
inline std::string run_command(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    status = -1;
    return "popen failed";
  }
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) {
    out += buf;
  }
  const int raw = ::pclose(pipe);
  status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return out;
}

// Whether a run's log says the camera `device` went away while streaming. The kernel fails the
// next buffer ioctl with ENODEV: VIDIOC_DQBUF when the run was waiting for a frame, VIDIOC_QBUF
// when it had just dequeued the last one; which comes first depends on timing alone.
inline bool says_camera_gone(const std::string& log, const std::string& device) {
  return std::regex_search(log,
                           std::regex("VIDIOC_D?QBUF on " + device + " failed: No such device"));
}

// Calls on_line(line) for each line of the console, without the '\r' the serial port adds.
template <typename OnLine>
void for_each_line(const std::string& console, OnLine on_line) {
  std::istringstream in(console);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    on_line(line);
  }
}

// "b,g,r b,g,r ..." (a probe's colour bars, camera_probe_support.hpp) as numbers.
inline std::vector<std::array<double, 3>> colour_bars(const std::string& text) {
  std::vector<std::array<double, 3>> out;
  std::istringstream in(text);
  std::string item;
  while (in >> item) {
    std::array<double, 3> bgr{};
    if (std::sscanf(item.c_str(), "%lf,%lf,%lf", &bgr[0], &bgr[1], &bgr[2]) == 3) {
      out.push_back(bgr);
    }
  }
  return out;
}

struct ProbeLine {
  std::string key;
  std::string value;  // the rest after the key and one space; empty when there is none
};

// "PROBE key value", anywhere in the line (the kernel's messages may come first); nullopt for a
// line without "PROBE ".
inline std::optional<ProbeLine> probe_line(const std::string& line) {
  const std::size_t at = line.find("PROBE ");
  if (at == std::string::npos) {
    return std::nullopt;
  }
  const std::string rest = line.substr(at + 6);
  const std::size_t space = rest.find(' ');
  return ProbeLine{rest.substr(0, space), space == std::string::npos ? "" : rest.substr(space + 1)};
}

// A test suite on one boot of the VM: SetUpTestSuite boots it and gives the console to Parse,
// whose ProbeRun holds the console (`console`) and the probe's lines by key (`probe`); the probe
// prints "PROBE done" last. Each test is skipped where qemu cannot run at all (the runner exits
// 77), except under CI=true: scripts/setup installs qemu there, so a skip would hide a broken
// VM test. It fails at once when the boot failed or the probe did not finish.
template <typename ProbeRun, ProbeRun (*Parse)(const std::string& console)>
class VmTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string also = FLOWSTEER_VM_ALSO;
    script_output_ = run_command(std::string("bash '") + FLOWSTEER_VM_SCRIPT + "' '" +
                                     FLOWSTEER_VM_KERNEL_CACHE + "' '" + FLOWSTEER_VM_WORK_DIR +
                                     "' '" + FLOWSTEER_VM_PROBE + "'" +
                                     (also.empty() ? "" : " '" + also + "'") + " 2>&1",
                                 status_);
    std::ifstream log(std::string(FLOWSTEER_VM_WORK_DIR) + "/console.log");
    std::stringstream console;
    console << log.rdbuf();
    run_ = Parse(console.str());
  }

  void SetUp() override {
    if (status_ == 77) {
      const char* ci = std::getenv("CI");
      ASSERT_FALSE(ci != nullptr && std::string(ci) == "true")
          << "qemu cannot run, and CI=true does not allow a skip: " << script_output_;
      GTEST_SKIP() << "qemu cannot run: " << script_output_;
    }
    ASSERT_EQ(status_, 0) << script_output_ << "\n--- console ---\n" << run_.console;
    ASSERT_TRUE(run_.probe.count("done")) << run_.console;
  }

  static inline int status_ = 0;
  static inline std::string script_output_;
  static inline ProbeRun run_;
};

}  // namespace flowsteer::vm_test
