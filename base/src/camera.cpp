#include "flowsteer/base/camera.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace flowsteer::base {

namespace {

// The message is built only on failure: validate() runs on every rendered frame.
template <typename Message>
void require(bool ok, const Message& message) {
  if (!ok) {
    throw std::invalid_argument(message());
  }
}

}  // namespace

CameraIntrinsics CameraIntrinsics::from_horizontal_fov(int width_px, int height_px,
                                                       double hfov_rad) {
  require(std::isfinite(hfov_rad) && hfov_rad > 0.0 && hfov_rad < std::numbers::pi, [&] {
    return "horizontal field of view must be in (0, 180) degrees, got " +
           std::to_string(hfov_rad * 180.0 / std::numbers::pi);
  });
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = 0.5 * width_px / std::tan(0.5 * hfov_rad);
  k.fy_px = k.fx_px;
  k.cx_px = 0.5 * (width_px - 1);
  k.cy_px = 0.5 * (height_px - 1);
  k.validate();
  return k;
}

void CameraIntrinsics::validate() const {
  require(width_px > 0, [&] {
    return "camera intrinsics: width_px must be positive, got " + std::to_string(width_px);
  });
  require(height_px > 0, [&] {
    return "camera intrinsics: height_px must be positive, got " + std::to_string(height_px);
  });
  require(std::isfinite(fx_px) && fx_px > 0.0, [&] {
    return "camera intrinsics: fx_px must be positive, got " + std::to_string(fx_px);
  });
  require(std::isfinite(fy_px) && fy_px > 0.0, [&] {
    return "camera intrinsics: fy_px must be positive, got " + std::to_string(fy_px);
  });
  require(std::isfinite(cx_px), [&] { return "camera intrinsics: cx_px is not finite"; });
  require(std::isfinite(cy_px), [&] { return "camera intrinsics: cy_px is not finite"; });
}

void CameraMount::validate() const {
  require(std::isfinite(height_m) && height_m > 0.0, [&] {
    return "camera mount: height_m must be positive, got " + std::to_string(height_m);
  });
  require(std::isfinite(pitch_rad) && std::abs(pitch_rad) < 0.5 * std::numbers::pi, [&] {
    return "camera mount: pitch_rad must be within (-90, 90) degrees, got " +
           std::to_string(pitch_rad);
  });
}

Eigen::Matrix3d CameraMount::camera_to_body() const {
  const double c = std::cos(pitch_rad);
  const double s = std::sin(pitch_rad);
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  r.col(1) = Eigen::Vector3d(-s, 0.0, -c);
  r.col(2) = Eigen::Vector3d(c, 0.0, -s);
  return r;
}

Eigen::Vector2d CameraMount::forward_foe() const {
  const Eigen::Vector3d forward = camera_to_body().transpose() * Eigen::Vector3d::UnitX();
  return forward.head<2>() / forward.z();
}

}  // namespace flowsteer::base
