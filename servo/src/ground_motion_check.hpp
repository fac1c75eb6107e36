#pragma once

#include <optional>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::servo {

// Tests, pixel by pixel, whether the flat ground's motion over an estimator's baseline explains
// the newer image better than the estimator's own displacements (OpticalFlowOptions::
// ground_match_ratio): the older image is warped each way and each pixel's 5×5 mean of squared
// grey differences with the newer image compared. Keeps its images from pair to pair, so that a
// stream of frames does not allocate.
class GroundMotionCheck {
 public:
  // For one pair: `older` as the estimator compared it with `newer` (turned to the newer image's
  // orientation), its displacements (CV_32FC2, newer pixel → older), the base's travel over the
  // pair.
  void prepare(const cv::Mat& newer, const cv::Mat& older, const cv::Mat& displacement_px,
               const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount,
               const BaseTravel& travel);

  // The ground's displacement at (col, row) where its patch error is at most max_error_grey2
  // (squared grey levels) and below `ratio` times the estimator's; else empty, and always at or
  // above the horizon.
  std::optional<Eigen::Vector2f> better_displacement_px(int col, int row, double ratio,
                                                        double max_error_grey2) const;

 private:
  cv::Mat ground_x_;  // where each newer pixel's ground point lies in `older`; NaN where none
  cv::Mat ground_y_;
  cv::Mat flow_x_;  // where the estimator puts it
  cv::Mat flow_y_;
  cv::Mat warped_;
  cv::Mat difference_;
  cv::Mat ground_error_;
  cv::Mat flow_error_;
};

// Where the base stood before, in its body frame of now (x forward, y left), after driving
// travel.path_m along an arc while turning by travel.turned_rad: minus the arc's chord, which
// points half the turn to the right of the heading of now.
Eigen::Vector2d moved_since(const BaseTravel& travel);

}  // namespace flowsteer::servo
