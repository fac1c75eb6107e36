#pragma once

#include <time.h>

#include <cstdint>
#include <optional>

namespace flowsteer::base {

// The project's one clock (docs/CONVENTIONS.md: time in seconds, monotonic clock): CLOCK_MONOTONIC
// in seconds. V4L2 and libcamera stamp frames with this clock, and std::chrono::steady_clock reads
// it on Linux, so every time in the stack is comparable with every other.
inline double monotonic_now_s() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// A stamp of the realtime clock (a kernel's receive stamp, a ROS 2 message's header) on the
// monotonic clock, by its age now. std::nullopt when the stamp lies in the future or is older
// than max_age_s: a clock that stepped, or a stamp that was never set; the caller then takes
// the time of reception.
inline std::optional<double> monotonic_of_realtime_s(std::int64_t stamp_sec,
                                                     std::int64_t stamp_nsec, double max_age_s) {
  const double now_s = monotonic_now_s();
  timespec realtime{};
  ::clock_gettime(CLOCK_REALTIME, &realtime);
  const double age_s = static_cast<double>(realtime.tv_sec - stamp_sec) +
                       1e-9 * static_cast<double>(realtime.tv_nsec - stamp_nsec);
  if (!(age_s >= 0.0 && age_s <= max_age_s)) {
    return std::nullopt;
  }
  return now_s - age_s;
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
