#pragma once

#include <Eigen/Core>

namespace flowsteer::base {

// Pinhole intrinsics of an undistorted image: they map a pixel (col, row) to normalised
// image coordinates x = X/Z, y = Y/Z of the camera frame (z forward, x right, y down).
// Pixel centres sit at integer coordinates, as in OpenCV.
struct CameraIntrinsics {
  int width_px = 0;
  int height_px = 0;
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;

  // Square pixels, principal point at the image centre.
  static CameraIntrinsics from_horizontal_fov(int width_px, int height_px, double hfov_rad);

  // Throws std::invalid_argument naming the first field that is out of range.
  void validate() const;

  Eigen::Vector2d normalise(double col_px, double row_px) const {
    return {(col_px - cx_px) / fx_px, (row_px - cy_px) / fy_px};
  }
};

// Where the camera sits on the agent: height of the optical centre above a flat ground and
// pitch of the optical axis below the horizon (positive looks down). The optical axis is in
// the agent's direction of motion otherwise.
struct CameraMount {
  double height_m = 1.0;
  double pitch_rad = 0.0;

  void validate() const;

  // The rotation from the camera frame (x right, y down, z forward) to the body frame (x
  // forward, y left, z up): its columns are the camera's axes in the body frame. Its transpose
  // takes a body vector into the camera frame.
  Eigen::Matrix3d camera_to_body() const;

  // Where the image shows the direction the base drives in, normalised: the FOE of the derotated
  // flow of every static point while the base moves forward.
  Eigen::Vector2d forward_foe() const;
};

}  // namespace flowsteer::base
