#pragma once

// What the VM probes (tests/vm) share: their main, the clock they stamp events with, and the
// programs they start with their output in a log.

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

namespace flowsteer::vm_test {

// CLOCK_REALTIME in seconds: candump stamps frames with it, so the probes' events and the bus
// can be put on one time line.
inline double realtime_s() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Starts argv[0] (a path) with its stdout and stderr in `log_path`.
inline pid_t start_logged(const std::string& log_path, std::vector<const char*> argv) {
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(log, STDOUT_FILENO);
    ::dup2(log, STDERR_FILENO);
    ::execv(argv[0], const_cast<char* const*>(argv.data()));
    ::_exit(127);
  }
  return pid;
}

// Whether a line of the file holds `text`.
inline bool log_has(const std::string& log_path, const std::string& text) {
  std::ifstream in(log_path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find(text) != std::string::npos) {
      return true;
    }
  }
  return false;
}

// stdout line-buffered, as the console interleaves it with the kernel's messages, and an
// escaping exception printed as "PROBE failed WHAT" with status 1.
template <typename Run>
int probe_main(Run run) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  try {
    return run();
  } catch (const std::exception& e) {
    std::printf("PROBE failed %s\n", e.what());
    return 1;
  }
}

}  // namespace flowsteer::vm_test
