#include "flowsteer/calibration/mount.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <opencv2/calib3d.hpp>

namespace flowsteer::calibration {

MountMeasurement measure_mount(const camera_io::CameraModel& camera, const BoardView& board) {
  camera.validate();
  if (board.image_points.size() < 4) {
    throw std::invalid_argument("a board pose needs at least 4 corners, got " +
                                std::to_string(board.image_points.size()));
  }
  // A fisheye's points are undistorted first (cv::fisheye::undistortPoints to pixels of the
  // same camera matrix); the others go to solvePnP with their distortion.
  const cv::Matx33d k = camera.camera_matrix();
  std::vector<cv::Point2f> points = board.image_points;
  std::vector<double> distortion = camera.coefficients;
  if (camera.distortion == camera_io::DistortionModel::equidistant) {
    cv::fisheye::undistortPoints(board.image_points, points, k, camera.coefficients,
                                 cv::Matx33d::eye(), k);
    distortion.clear();
  }
  cv::Vec3d rvec;
  cv::Vec3d tvec;
  if (!cv::solvePnP(board.object_points, points, k, distortion, rvec, tvec, false,
                    cv::SOLVEPNP_IPPE)) {
    throw std::invalid_argument("no pose of the board fits its corners");
  }
  std::vector<cv::Point2f> projected;
  cv::projectPoints(board.object_points, rvec, tvec, k, distortion, projected);
  const double sum_sq = cv::norm(projected, points, cv::NORM_L2SQR);

  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  // The board's normal in the camera frame, turned to point up: towards the camera, which is
  // above the floor. -tvec runs from the board's origin to the camera.
  cv::Vec3d up(r(0, 2), r(1, 2), r(2, 2));
  const double height_m = -up.dot(tvec);
  if (height_m < 0.0) {
    up = -up;
  }
  // A camera pitched down by p and rolled by r about its optical axis sees the floor's up
  // direction as (-sin r cos p, -cos r cos p, -sin p) in its frame (x right, y down, z forward).
  MountMeasurement m;
  m.mount.mount.height_m = std::abs(height_m);
  m.mount.mount.pitch_rad = std::asin(std::clamp(-up[2], -1.0, 1.0));
  m.mount.roll_rad = std::atan2(-up[0], -up[1]);
  m.rms_px = std::sqrt(sum_sq / static_cast<double>(projected.size()));
  m.corners = static_cast<int>(projected.size());
  if (std::abs(m.mount.mount.pitch_rad) >= 0.5 * std::numbers::pi - 1e-6 ||
      std::abs(m.mount.roll_rad) >= 0.5 * std::numbers::pi) {
    throw std::invalid_argument(
        "the board is not below the camera as a floor would be (pitch or roll of 90 degrees or "
        "more): lay it flat on the floor in front of the camera");
  }
  return m;
}

}  // namespace flowsteer::calibration
