#include "flowsteer/camera_io/camera_model.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace flowsteer::camera_io {

namespace {

constexpr std::array<std::pair<DistortionModel, std::string_view>, 4> kNames = {{
    {DistortionModel::none, "none"},
    {DistortionModel::plumb_bob, "plumb_bob"},
    {DistortionModel::rational_polynomial, "rational_polynomial"},
    {DistortionModel::equidistant, "equidistant"},
}};

}  // namespace

std::string_view distortion_model_name(DistortionModel model) {
  for (const auto& [m, name] : kNames) {
    if (m == model) {
      return name;
    }
  }
  throw std::invalid_argument("unknown distortion model " +
                              std::to_string(static_cast<int>(model)));
}

std::optional<DistortionModel> distortion_model_from_name(std::string_view name) {
  for (const auto& [m, n] : kNames) {
    if (n == name) {
      return m;
    }
  }
  return std::nullopt;
}

std::size_t distortion_coefficient_count(DistortionModel model) {
  switch (model) {
    case DistortionModel::none:
      return 0;
    case DistortionModel::plumb_bob:
      return 5;
    case DistortionModel::rational_polynomial:
      return 8;
    case DistortionModel::equidistant:
      return 4;
  }
  throw std::invalid_argument("unknown distortion model " +
                              std::to_string(static_cast<int>(model)));
}

base::CameraIntrinsics CameraModel::pinhole() const {
  base::CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = fx;
  k.fy_px = fy;
  k.cx_px = cx;
  k.cy_px = cy;
  return k;
}

cv::Matx33d CameraModel::camera_matrix() const {
  return {fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0};
}

bool CameraModel::is_pinhole() const {
  for (const double c : coefficients) {
    if (c != 0.0) {
      return false;
    }
  }
  return true;
}

void CameraModel::validate() const {
  pinhole().validate();
  const std::size_t expected = distortion_coefficient_count(distortion);
  if (coefficients.size() != expected) {
    throw std::invalid_argument("camera model: distortion model " +
                                std::string(distortion_model_name(distortion)) + " takes " +
                                std::to_string(expected) + " coefficients, got " +
                                std::to_string(coefficients.size()));
  }
  for (std::size_t i = 0; i < coefficients.size(); ++i) {
    if (!std::isfinite(coefficients[i])) {
      throw std::invalid_argument("camera model: distortion coefficient " + std::to_string(i) +
                                  " is not finite");
    }
  }
}

Undistorter::Undistorter(const CameraModel& model) : intrinsics_(model.pinhole()) {
  model.validate();
  if (model.is_pinhole()) {
    return;
  }
  const cv::Size size(model.width_px, model.height_px);
  const cv::Matx33d k = model.camera_matrix();
  if (model.distortion == DistortionModel::equidistant) {
    cv::fisheye::initUndistortRectifyMap(k, model.coefficients, cv::Matx33d::eye(), k, size,
                                         CV_16SC2, map_xy_, map_fraction_);
  } else {
    cv::initUndistortRectifyMap(k, model.coefficients, cv::noArray(), k, size, CV_16SC2, map_xy_,
                                map_fraction_);
  }
}

const cv::Mat& Undistorter::apply(const cv::Mat& image) {
  if (image.cols != intrinsics_.width_px || image.rows != intrinsics_.height_px) {
    throw std::invalid_argument("undistorter: image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the camera model is " +
                                std::to_string(intrinsics_.width_px) + "x" +
                                std::to_string(intrinsics_.height_px));
  }
  if (map_xy_.empty()) {
    return image;
  }
  cv::remap(image, undistorted_, map_xy_, map_fraction_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return undistorted_;
}

}  // namespace flowsteer::camera_io
