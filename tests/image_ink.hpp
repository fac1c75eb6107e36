#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace flowsteer::test {

// Runs of consecutive rows of a BGR `image` that hold ink (dark pixels): the labelled ticks of an
// axis drawn down its side, say.
inline int ink_row_runs(const cv::Mat& image) {
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  int runs = 0;
  bool in_run = false;
  for (int row = 0; row < grey.rows; ++row) {
    const bool ink = cv::countNonZero(grey.row(row) < 128) > 0;
    runs += ink && !in_run ? 1 : 0;
    in_run = ink;
  }
  return runs;
}

}  // namespace flowsteer::test
