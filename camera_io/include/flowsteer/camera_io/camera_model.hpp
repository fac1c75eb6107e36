#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::camera_io {

// Lens distortion models, with the coefficient order of OpenCV and of ROS camera_info.
enum class DistortionModel {
  none,                 // an ideal pinhole: no coefficients
  plumb_bob,            // Brown-Conrady: k1, k2, p1, p2, k3
  rational_polynomial,  // k1, k2, p1, p2, k3, k4, k5, k6
  equidistant,  // fisheye, theta_d = theta (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸): k1..k4
};

// The ROS name ("plumb_bob", "rational_polynomial", "equidistant"; "none" for none).
std::string_view distortion_model_name(DistortionModel model);
std::optional<DistortionModel> distortion_model_from_name(std::string_view name);
// How many coefficients the model takes.
std::size_t distortion_coefficient_count(DistortionModel model);

// A calibrated camera as it delivers images: size, pinhole matrix and lens distortion.
struct CameraModel {
  int width_px = 0;
  int height_px = 0;
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  DistortionModel distortion = DistortionModel::none;
  std::vector<double> coefficients;  // distortion_coefficient_count(distortion) of them

  // The intrinsics of the undistorted image Undistorter makes: same size and matrix.
  base::CameraIntrinsics pinhole() const;
  cv::Matx33d camera_matrix() const;
  // True when the image needs no remapping (no model, or every coefficient zero).
  bool is_pinhole() const;
  // Throws std::invalid_argument naming the first field that is wrong.
  void validate() const;
};

// The model a ROS 2 CameraInfo describes (a recording's, a camera driver's): its size, K, and,
// unless D is all zero, its distortion model with D padded or cut to the model's count. Throws
// std::invalid_argument naming binning or a region of interest (K would not be the image's), a
// distortion model flowsteer does not undistort, or the first field that is wrong
// (CameraModel::validate).
CameraModel camera_model_of(const recording::ros2::CameraInfo& info);

// Turns a camera's distorted images into undistorted pinhole images with the same size and
// camera matrix (CameraModel::pinhole()); wide fisheye views lose what falls outside that frame.
// The maps are computed once (cv::initUndistortRectifyMap, cv::fisheye::initUndistortRectifyMap)
// and every image is resampled with cv::remap into a buffer the undistorter keeps.
class Undistorter {
 public:
  // Throws std::invalid_argument when the model is invalid.
  explicit Undistorter(const CameraModel& model);

  // The undistorted image, valid until the next apply(). Without distortion it is `image`
  // itself (no copy). Allocates only on the first call. Throws std::invalid_argument when the
  // image size is not the model's.
  const cv::Mat& apply(const cv::Mat& image);

  const base::CameraIntrinsics& intrinsics() const { return intrinsics_; }

 private:
  base::CameraIntrinsics intrinsics_;
  cv::Mat map_xy_;  // CV_16SC2 fixed-point maps: cv::remap's fast path
  cv::Mat map_fraction_;
  cv::Mat undistorted_;
};

}  // namespace flowsteer::camera_io
