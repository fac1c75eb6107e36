#pragma once

#include <time.h>

namespace flowsteer::base {

// The project's one clock (docs/CONVENTIONS.md: time in seconds, monotonic clock): CLOCK_MONOTONIC
// in seconds. V4L2 and libcamera stamp frames with this clock, and std::chrono::steady_clock reads
// it on Linux, so every time in the stack is comparable with every other.
inline double monotonic_now_s() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// Times the stages of a step: elapsed_ms() since construction or the last restart().
class Stopwatch {
 public:
  Stopwatch() : start_s_(monotonic_now_s()) {}
  void restart() { start_s_ = monotonic_now_s(); }
  double elapsed_ms() const { return 1e3 * (monotonic_now_s() - start_s_); }

 private:
  double start_s_;
};

}  // namespace flowsteer::base
