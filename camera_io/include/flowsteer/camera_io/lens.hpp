#pragma once

#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/camera_io/camera_model.hpp"

namespace flowsteer::camera_io {

// What a source knows about its lens, to deliver the undistorted pinhole images FrameSource
// promises.
struct LensOptions {
  // A calibration (calibration::read_camera_info): images are undistorted with it, and its
  // size must be the size the source delivers.
  std::optional<CameraModel> model;
  // Without a calibration: an ideal pinhole with this horizontal field of view, principal
  // point at the centre, no undistortion. 60° suits a common USB webcam.
  double horizontal_fov_rad = 1.0471975511965976;
};

// The lens of one source, set up once the source knows its image size.
class Lens {
 public:
  // Throws std::invalid_argument naming `source` when the calibration's size is not the
  // source's image size, the model is invalid or the field of view is not in (0, π).
  Lens(const LensOptions& options, int width_px, int height_px, const std::string& source);

  const base::CameraIntrinsics& intrinsics() const { return intrinsics_; }
  // The undistorted image, valid until the next apply(); `image` itself when the lens is an
  // ideal pinhole. Allocates only on the first call.
  const cv::Mat& apply(const cv::Mat& image);

 private:
  std::optional<Undistorter> undistorter_;
  base::CameraIntrinsics intrinsics_;
};

}  // namespace flowsteer::camera_io
