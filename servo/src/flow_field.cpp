#include "flowsteer/servo/flow_field.hpp"

#include <limits>

#include <Eigen/Geometry>

#include <cmath>

namespace flowsteer::servo {

FlowField::FlowField(const base::CameraIntrinsics& intrinsics, bool with_depth)
    : intrinsics_(intrinsics) {
  intrinsics_.validate();
  x_of_col_.resize(static_cast<std::size_t>(width()));
  y_of_row_.resize(static_cast<std::size_t>(height()));
  for (int col = 0; col < width(); ++col) {
    x_of_col_[static_cast<std::size_t>(col)] = (col - intrinsics_.cx_px) / intrinsics_.fx_px;
  }
  for (int row = 0; row < height(); ++row) {
    y_of_row_[static_cast<std::size_t>(row)] = (row - intrinsics_.cy_px) / intrinsics_.fy_px;
  }
  const auto pixels = static_cast<std::size_t>(width()) * static_cast<std::size_t>(height());
  flow_.assign(pixels, Eigen::Vector2f::Zero());
  if (with_depth) {
    depth_.assign(pixels, std::numeric_limits<float>::infinity());
  }
}

Eigen::Vector3d camera_angular_velocity(double turn_rate_cy, double pitch_rad) {
  // The agent turns about the world's vertical; in a camera pitched down by θ the downward
  // vertical is (0, cos θ, sin θ).
  return turn_rate_cy * Eigen::Vector3d(0.0, std::cos(pitch_rad), std::sin(pitch_rad));
}

Eigen::Vector2d rotational_flow(double x, double y, const Eigen::Vector3d& w) {
  // Rotational part of the point interaction matrix; with w = (0, ω, 0) it is the ω term of
  // CGF Eq. 1.
  return {x * y * w.x() - (1.0 + x * x) * w.y() + y * w.z(),
          (1.0 + y * y) * w.x() - x * y * w.y() - x * w.z()};
}

Eigen::Matrix3d rotation_over(const Eigen::Vector3d& camera_omega, double interval_s) {
  const double angle = camera_omega.norm() * interval_s;
  return angle > 0.0 ? Eigen::AngleAxisd(angle, camera_omega.normalized()).toRotationMatrix()
                     : Eigen::Matrix3d::Identity();
}

void derotate(FlowField& field, const Eigen::Vector3d& camera_omega) {
  auto flow = field.flow();
  for (int row = 0; row < field.height(); ++row) {
    const double y = field.y(row);
    for (int col = 0; col < field.width(); ++col) {
      const Eigen::Vector2d rotation = rotational_flow(field.x(col), y, camera_omega);
      flow[field.index(col, row)] -= rotation.cast<float>();
    }
  }
  field.removed_rotation_ = camera_omega;
}

}  // namespace flowsteer::servo
