#pragma once

// What the camera VM probes (tests/vm: V4L2 on vivid, libcamera on vimc) share: the colour bars
// of the drivers' test patterns as probe lines, and an expected error as one.

#include <cstdio>
#include <exception>
#include <functional>
#include <string>

#include <opencv2/core.hpp>

namespace flowsteer::vm_test {

// "PROBE KEY b,g,r b,g,r ...": the mean BGR over a patch 2*half pixels wide at the centre of each
// of the eight vertical colour bars of a test pattern, at `row`.
inline void print_bars(const std::string& key, const cv::Mat& bgr, int row, int half) {
  std::printf("PROBE %s", key.c_str());
  for (int bar = 0; bar < 8; ++bar) {
    const int col = (2 * bar + 1) * bgr.cols / 16;
    const cv::Scalar mean = cv::mean(bgr(cv::Rect(col - half, row - half, 2 * half, 2 * half)));
    std::printf(" %.0f,%.0f,%.0f", mean[0], mean[1], mean[2]);
  }
  std::printf("\n");
}

// Runs `open`, expecting it to throw; prints "PROBE KEY <message>" or "PROBE KEY no error".
inline void expect_error(const std::string& key, const std::function<void()>& open) {
  try {
    open();
    std::printf("PROBE %s no error\n", key.c_str());
  } catch (const std::exception& e) {
    std::printf("PROBE %s %s\n", key.c_str(), e.what());
  }
}

}  // namespace flowsteer::vm_test
