#pragma once

#include <cstddef>
#include <vector>

namespace flowsteer::pipeline {

// What the base measured at each of the newest frames, each value held since the frame before:
// numerical flow spans several frames, and its derotation and ground test need the motion over
// that span. A ring of fixed capacity: remembering allocates nothing.
class MotionHistory {
 public:
  struct Motion {
    double speed_mps;
    double turn_rate_cy;  // positive to the right
  };

  explicit MotionHistory(std::size_t capacity) : samples_(capacity) {}

  void remember(double timestamp_s, const Motion& motion);
  // The time-weighted means over (from_s, to_s]: the distance driven and the rotation between
  // two images divided by the time between them; `fallback` when no sample covers the span.
  Motion mean(double from_s, double to_s, const Motion& fallback) const;

 private:
  struct Sample {
    double timestamp_s;
    Motion motion;
  };
  const Sample& at(std::size_t k) const { return samples_[(begin_ + k) % samples_.size()]; }

  std::vector<Sample> samples_;
  std::size_t begin_ = 0;  // the oldest
  std::size_t count_ = 0;
};

}  // namespace flowsteer::pipeline
