// The base's measured motion over a numerical flow's span when the camera drops frames: the
// span's rotation and distance from MotionHistory against the exact integrals.
#include "motion_history.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace flowsteer::pipeline {
namespace {

// A camera at 30 Hz that dropped frames 3–4 and 8 (the gaps are 2/30 and 3/30 s), and a base
// whose measured turn rate and speed change at every frame.
struct Drive {
  std::vector<double> frame_s = {0.0,      1.0 / 30, 2.0 / 30, 5.0 / 30,
                                 6.0 / 30, 7.0 / 30, 9.0 / 30, 10.0 / 30};
  // Measured over (frame_s[k-1], frame_s[k]]: held since the frame before.
  double turn_rate(std::size_t k) const { return 0.3 * std::sin(1.7 * static_cast<double>(k)); }
  double speed(std::size_t k) const { return 0.5 + 0.1 * static_cast<double>(k); }
  // ∫ turn rate and ∫ speed over (frame_s[i], frame_s[j]].
  double rotation(std::size_t i, std::size_t j) const {
    double sum = 0.0;
    for (std::size_t k = i + 1; k <= j; ++k) {
      sum += turn_rate(k) * (frame_s[k] - frame_s[k - 1]);
    }
    return sum;
  }
  double distance(std::size_t i, std::size_t j) const {
    double sum = 0.0;
    for (std::size_t k = i + 1; k <= j; ++k) {
      sum += speed(k) * (frame_s[k] - frame_s[k - 1]);
    }
    return sum;
  }
};

TEST(MotionHistory, SpanMeansGiveTheExactRotationAndDistanceAcrossDroppedFrames) {
  const Drive drive;
  MotionHistory history(drive.frame_s.size());
  for (std::size_t k = 0; k < drive.frame_s.size(); ++k) {
    history.remember(drive.frame_s[k], {drive.speed(k), drive.turn_rate(k)});
  }
  for (std::size_t i = 0; i < drive.frame_s.size(); ++i) {
    for (std::size_t j = i + 1; j < drive.frame_s.size(); ++j) {
      SCOPED_TRACE("span from frame " + std::to_string(i) + " to " + std::to_string(j));
      const double span_s = drive.frame_s[j] - drive.frame_s[i];
      const MotionHistory::Motion mean =
          history.mean(drive.frame_s[i], drive.frame_s[j], {99.0, 99.0});
      EXPECT_NEAR(mean.turn_rate_cy * span_s, drive.rotation(i, j), 1e-12);
      EXPECT_NEAR(mean.speed_mps * span_s, drive.distance(i, j), 1e-12);
    }
  }
}

TEST(MotionHistory, ASpanPastTheOldestSampleIsTheMeanOfWhatIsRemembered) {
  const Drive drive;
  MotionHistory history(4);  // keeps frames 4–7 of the 8
  for (std::size_t k = 0; k < drive.frame_s.size(); ++k) {
    history.remember(drive.frame_s[k], {drive.speed(k), drive.turn_rate(k)});
  }
  const double covered_s = drive.frame_s[7] - drive.frame_s[4];
  const MotionHistory::Motion mean = history.mean(drive.frame_s[0], drive.frame_s[7], {});
  EXPECT_NEAR(mean.turn_rate_cy, drive.rotation(4, 7) / covered_s, 1e-12);
  EXPECT_NEAR(mean.speed_mps, drive.distance(4, 7) / covered_s, 1e-12);
}

TEST(MotionHistory, NoSampleOverTheSpanGivesTheFallback) {
  MotionHistory history(4);
  history.remember(1.0, {0.5, 0.2});
  const MotionHistory::Motion mean = history.mean(0.0, 1.0, {0.7, -0.1});
  EXPECT_EQ(mean.speed_mps, 0.7);  // one sample covers no interval
  EXPECT_EQ(mean.turn_rate_cy, -0.1);
}

}  // namespace
}  // namespace flowsteer::pipeline
