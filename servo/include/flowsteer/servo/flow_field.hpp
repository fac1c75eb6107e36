#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"

namespace flowsteer::servo {

// A dense flow field: one image-plane velocity per pixel, in normalised image coordinates per
// second (CGF Eq. 1), row-major, with an optional depth image in metres (NaN or +inf where
// nothing was hit). Pixel (col, row) sits at normalised point (x(col), y(row)).
class FlowField {
 public:
  explicit FlowField(const base::CameraIntrinsics& intrinsics, bool with_depth = false);

  const base::CameraIntrinsics& intrinsics() const { return intrinsics_; }
  int width() const { return intrinsics_.width_px; }
  int height() const { return intrinsics_.height_px; }
  std::size_t size() const { return flow_.size(); }

  double x(int col) const { return x_of_col_[static_cast<std::size_t>(col)]; }
  double y(int row) const { return y_of_row_[static_cast<std::size_t>(row)]; }

  std::span<Eigen::Vector2f> flow() { return flow_; }
  std::span<const Eigen::Vector2f> flow() const { return flow_; }
  Eigen::Vector2f& at(int col, int row) { return flow_[index(col, row)]; }
  const Eigen::Vector2f& at(int col, int row) const { return flow_[index(col, row)]; }

  bool has_depth() const { return !depth_.empty(); }
  // Empty when the field carries no depth.
  std::span<float> depth() { return depth_; }
  std::span<const float> depth() const { return depth_; }

  // 0 for instantaneous flow (the renderer's). Flow computed from two images Δ apart is their
  // displacement over Δ: for a surface at constant velocity it is (x − f) / (τ + Δ) at the newer
  // image, the instantaneous flow's FOE with τ late by Δ, which FeatureExtractor takes back.
  double interval_s() const { return interval_s_; }
  void set_interval_s(double interval_s) { interval_s_ = interval_s; }

  // The camera rotation the last derotate() took out of this flow, zero until one has. The
  // vectors are float, exact only to their magnitude before it came off
  // (FlowSample::delivered_norm). The renderer's flow source derotates each of its frames.
  const Eigen::Vector3d& removed_rotation() const { return removed_rotation_; }

  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width()) +
           static_cast<std::size_t>(col);
  }

 private:
  base::CameraIntrinsics intrinsics_;
  std::vector<double> x_of_col_;
  std::vector<double> y_of_row_;
  std::vector<Eigen::Vector2f> flow_;
  std::vector<float> depth_;
  double interval_s_ = 0.0;
  Eigen::Vector3d removed_rotation_ = Eigen::Vector3d::Zero();

  friend void derotate(FlowField& field, const Eigen::Vector3d& camera_omega);
};

// Angular velocity of the camera, in the camera frame, for an agent turning at turn_rate_cy
// (rad/s, positive turns right, docs/CONVENTIONS.md) with its camera pitched down by pitch_rad.
Eigen::Vector3d camera_angular_velocity(double turn_rate_cy, double pitch_rad);

// Flow that a rotation of the camera alone gives at normalised point (x, y).
Eigen::Vector2d rotational_flow(double x, double y, const Eigen::Vector3d& camera_omega);

// The rotation R = exp([ω]× Δ) of a camera turning at camera_omega for interval_s: a static
// point's direction p in the newer image was R p in the older one.
Eigen::Matrix3d rotation_over(const Eigen::Vector3d& camera_omega, double interval_s);

// Removes the rotational part of every vector (CGF Eq. 1 -> Eq. 2) of instantaneous flow.
// Non-finite vectors stay non-finite so that later stages can count them. Displacement flow has
// its rotation compensated before it is estimated (CameraMotion::between).
void derotate(FlowField& field, const Eigen::Vector3d& camera_omega);

}  // namespace flowsteer::servo
