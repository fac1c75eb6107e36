#include "flowsteer/camera_io/lens.hpp"

#include <numbers>
#include <stdexcept>

namespace flowsteer::camera_io {

Lens::Lens(const LensOptions& options, int width_px, int height_px, const std::string& source) {
  if (options.model) {
    const CameraModel& model = *options.model;
    if (model.width_px != width_px || model.height_px != height_px) {
      throw std::invalid_argument(
          source + ": the calibration is for " + std::to_string(model.width_px) + "x" +
          std::to_string(model.height_px) + " images, the source delivers " +
          std::to_string(width_px) + "x" + std::to_string(height_px));
    }
    try {
      undistorter_.emplace(model);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(source + ": " + e.what());
    }
    intrinsics_ = undistorter_->intrinsics();
    return;
  }
  if (!(options.horizontal_fov_rad > 0.0 && options.horizontal_fov_rad < std::numbers::pi)) {
    throw std::invalid_argument(source + ": horizontal field of view must be in (0, pi) rad, got " +
                                std::to_string(options.horizontal_fov_rad));
  }
  intrinsics_ =
      base::CameraIntrinsics::from_horizontal_fov(width_px, height_px, options.horizontal_fov_rad);
}

const cv::Mat& Lens::apply(const cv::Mat& image) {
  return undistorter_ ? undistorter_->apply(image) : image;
}

}  // namespace flowsteer::camera_io
