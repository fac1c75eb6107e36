#include "flowsteer/camera_io/camera_model.hpp"

#include <algorithm>
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

CameraModel camera_model_of(const recording::ros2::CameraInfo& info) {
  // K describes the full sensor; a binned or cropped image would need it scaled and shifted.
  const recording::ros2::RegionOfInterest& roi = info.roi;
  const bool whole = roi.x_offset == 0 && roi.y_offset == 0 &&
                     (roi.width == 0 || roi.width == info.width) &&
                     (roi.height == 0 || roi.height == info.height);
  if (info.binning_x > 1 || info.binning_y > 1 || !whole) {
    throw std::invalid_argument("binning_x " + std::to_string(info.binning_x) + ", binning_y " +
                                std::to_string(info.binning_y) + ", roi " +
                                std::to_string(roi.width) + "x" + std::to_string(roi.height) + "+" +
                                std::to_string(roi.x_offset) + "+" + std::to_string(roi.y_offset) +
                                ": flowsteer takes only whole images, not binned");
  }
  CameraModel model;
  model.width_px = static_cast<int>(info.width);
  model.height_px = static_cast<int>(info.height);
  model.fx = info.k[0];
  model.cx = info.k[2];
  model.fy = info.k[4];
  model.cy = info.k[5];
  const bool no_distortion =
      std::all_of(info.d.begin(), info.d.end(), [](double d) { return d == 0.0; });
  const auto distortion = distortion_model_from_name(info.distortion_model);
  if (!no_distortion && !distortion) {
    throw std::invalid_argument("distortion model '" + info.distortion_model +
                                "' (known: plumb_bob, rational_polynomial, equidistant)");
  }
  if (!no_distortion) {
    model.distortion = *distortion;
    model.coefficients = info.d;
    model.coefficients.resize(distortion_coefficient_count(*distortion), 0.0);
  }
  model.validate();
  return model;
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
