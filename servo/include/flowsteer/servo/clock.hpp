#pragma once

#include <time.h>

namespace flowsteer::servo {

// The project's one clock (DESIGN.md: time in seconds, monotonic clock): CLOCK_MONOTONIC in
// seconds. V4L2 and libcamera stamp frames with this clock, and std::chrono::steady_clock reads
// it on Linux, so every time in the stack is comparable with every other.
inline double monotonic_now_s() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace flowsteer::servo
