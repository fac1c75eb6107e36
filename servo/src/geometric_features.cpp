#include "flowsteer/servo/geometric_features.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "contact_time.hpp"

namespace flowsteer::servo {

namespace {

// Points closer than this along the optical axis are cut: their projection is unbounded.
constexpr double kNearPlaneM = 0.05;

// Keeps the part of the convex polygon `in` (points (X, Z) in the camera's horizontal plane)
// where a·X + b·Z + c >= 0 (Sutherland–Hodgman, one plane). Returns whether it cut anything.
bool clip(const std::vector<Eigen::Vector2d>& in, double a, double b, double c,
          std::vector<Eigen::Vector2d>& out) {
  out.clear();
  bool cut = false;
  const std::size_t n = in.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d& p = in[k];
    const Eigen::Vector2d& q = in[(k + 1) % n];
    const double dp = a * p.x() + b * p.y() + c;
    const double dq = a * q.x() + b * q.y() + c;
    if (dp >= 0.0) {
      out.push_back(p);
    } else {
      cut = true;
    }
    if ((dp >= 0.0) != (dq >= 0.0)) {
      out.push_back(p + (q - p) * (dp / (dp - dq)));
    }
  }
  return cut;
}

// The polygon's point nearest the camera (its boundary's: the camera is outside every body).
void set_nearest_point(const std::vector<Eigen::Vector2d>& polygon, ObjectFeatures& f) {
  Eigen::Vector2d nearest = polygon.front();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d p =
        detail::nearest_on_segment(polygon[i], polygon[(i + 1) % polygon.size()]);
    if (p.squaredNorm() < nearest.squaredNorm()) {
      nearest = p;
    }
  }
  f.nearest_x = nearest.x() / nearest.y();
  f.nearest_depth_m = nearest.y();
}

}  // namespace

std::span<const ObjectFeatures> GeometricFeatures::compute(std::span<const GeometricBody> bodies,
                                                           const base::CameraIntrinsics& intrinsics,
                                                           const base::CameraMount& mount,
                                                           double agent_speed_mps) {
  features_.clear();
  const Eigen::Matrix3d body_to_camera = mount.camera_to_body().transpose();
  const double cp = std::cos(mount.pitch_rad);
  // Edges of the view: the outer edges of the first and last pixel columns and rows.
  const double left_x = (-0.5 - intrinsics.cx_px) / intrinsics.fx_px;
  const double right_x = (intrinsics.width_px - 0.5 - intrinsics.cx_px) / intrinsics.fx_px;
  const double top_y = (-0.5 - intrinsics.cy_px) / intrinsics.fy_px;
  const double bottom_y = (intrinsics.height_px - 0.5 - intrinsics.cy_px) / intrinsics.fy_px;
  // The image row of a body point x ahead, z_up above the camera, on the optical axis' plane.
  auto image_y = [&](double x, double z_up) {
    const Eigen::Vector3d p = body_to_camera * Eigen::Vector3d(x, 0.0, z_up);
    return p.y() / p.z();
  };

  for (const GeometricBody& body : bodies) {
    clip_in_.clear();
    for (const Eigen::Vector2d& p : body.footprint_m) {
      // (X, Z) at the camera's height.
      const Eigen::Vector3d in_camera = body_to_camera * Eigen::Vector3d(p.x(), p.y(), 0.0);
      clip_in_.emplace_back(in_camera.x(), in_camera.z());
    }
    if (clip_in_.size() < 3) {
      continue;
    }
    // In front of the camera, then inside the left and the right edge of the view.
    bool cut_left = false;
    bool cut_right = false;
    const std::array<Eigen::Vector3d, 3> planes = {Eigen::Vector3d(0.0, 1.0, -kNearPlaneM),
                                                   Eigen::Vector3d(1.0, -left_x, 0.0),
                                                   Eigen::Vector3d(-1.0, right_x, 0.0)};
    for (std::size_t k = 0; k < planes.size() && clip_in_.size() >= 3; ++k) {
      const bool cut = clip(clip_in_, planes[k].x(), planes[k].y(), planes[k].z(), clip_out_);
      (k == 1 ? cut_left : cut_right) |= k > 0 && cut;
      std::swap(clip_in_, clip_out_);
    }
    if (clip_in_.size() < 3) {
      continue;  // behind the camera or out of the view
    }

    ObjectFeatures f;
    f.label = static_cast<int>(features_.size());
    f.source_id = body.id;
    f.kind = RegionKind::visible;
    f.min_x = std::numeric_limits<double>::infinity();
    f.max_x = -f.min_x;
    double depth = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& p : clip_in_) {
      const double x = p.x() / p.y();
      if (x < f.min_x) {
        f.min_x = x;
        f.min_x_depth_m = p.y();
      }
      if (x > f.max_x) {
        f.max_x = x;
        f.max_x_depth_m = p.y();
      }
      depth = std::min(depth, p.y());
    }
    set_nearest_point(clip_in_, f);
    f.cut_left = cut_left;
    f.cut_right = cut_right;
    f.width = f.max_x - f.min_x;
    f.depth_m = depth;
    const double nearest_x = depth / cp;  // forward distance of the nearest point
    const double centre_x = 0.5 * (f.min_x + f.max_x);
    f.centre = {centre_x, image_y(nearest_x, 0.5 * body.height_m - mount.height_m)};

    const double top = std::max(top_y, image_y(nearest_x, body.height_m - mount.height_m));
    const double bottom = std::min(bottom_y, image_y(nearest_x, -mount.height_m));
    const double columns = f.width * intrinsics.fx_px;
    const double rows = std::max(0.0, bottom - top) * intrinsics.fy_px;
    f.pixel_count = std::max(1, static_cast<int>(std::lround(columns * rows)));

    const Eigen::Vector2d relative = body.velocity_mps - Eigen::Vector2d(agent_speed_mps, 0.0);
    const Eigen::Vector3d v = body_to_camera * Eigen::Vector3d(relative.x(), relative.y(), 0.0);
    const double inverse_ttc = -v.z() / depth;  // 1/τ with τ = −Z / v_z
    // The flow fit's threshold on |1/τ| (RadialFitOptions::min_inverse_ttc) tells lateral motion.
    if (std::abs(inverse_ttc) < RadialFitOptions{}.min_inverse_ttc) {
      f.status = MotionStatus::lateral;
      f.ttc_s = std::numeric_limits<double>::infinity();
    } else {
      f.status = inverse_ttc > 0.0 ? MotionStatus::approaching : MotionStatus::receding;
      f.foe = {v.x() / v.z(), v.y() / v.z()};  // CGF Eq. 3
      f.ttc_s = 1.0 / inverse_ttc;
    }
    f.ttc_eq5_s = f.ttc_s;
    f.fit.static_foe = body.velocity_mps.isZero();        // what the flow fit tells from its flow
    const double u = (v.x() - centre_x * v.z()) / depth;  // CGF Eq. 2 at the centre
    f.moments = {u, centre_x * u, 1.0 / depth, centre_x / depth};
    features_.push_back(f);
  }
  return features_;
}

}  // namespace flowsteer::servo
