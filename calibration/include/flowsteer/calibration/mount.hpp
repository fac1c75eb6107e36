#pragma once

#include "flowsteer/calibration/board.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "flowsteer/camera_io/camera_model.hpp"

namespace flowsteer::calibration {

struct MountMeasurement {
  MountCalibration mount;
  double rms_px = 0.0;  // reprojection error of the board's pose
  int corners = 0;
};

// The camera's height, pitch and roll above the floor from one view of a board lying flat on
// it: the board's pose (cv::solvePnP with SOLVEPNP_IPPE, made for planar targets) gives the
// floor plane in the camera frame, and the plane's normal and distance give the rest. The
// height is that of the board's surface; add its thickness for the floor. Throws
// std::invalid_argument when the view cannot be the board on a floor under the camera.
MountMeasurement measure_mount(const camera_io::CameraModel& camera, const BoardView& board);

}  // namespace flowsteer::calibration
