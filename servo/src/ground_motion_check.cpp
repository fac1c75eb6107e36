#include "ground_motion_check.hpp"

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {

namespace {

const cv::Matx<float, 5, 1> kMeanOf5 = cv::Matx<float, 5, 1>::all(0.2F);

// The 5×5 mean of (newer − warped)², into `error`; `difference` is scratch.
void patch_error(const cv::Mat& newer, const cv::Mat& warped, cv::Mat& difference, cv::Mat& error) {
  cv::subtract(newer, warped, difference, cv::noArray(), CV_32F);
  cv::multiply(difference, difference, difference);
  cv::sepFilter2D(difference, error, CV_32F, kMeanOf5, kMeanOf5);
}

}  // namespace

Eigen::Vector2d moved_since(const BaseTravel& travel) {
  const double half_turn = 0.5 * travel.turned_rad;
  // The chord of an arc of length s turning by 2a is s sin(a) / a.
  const double chord_m =
      std::abs(half_turn) > 1e-9 ? travel.path_m * std::sin(half_turn) / half_turn : travel.path_m;
  return {chord_m * std::cos(half_turn), -chord_m * std::sin(half_turn)};
}

void GroundMotionCheck::prepare(const cv::Mat& newer, const cv::Mat& older,
                                const cv::Mat& displacement_px,
                                const base::CameraIntrinsics& intrinsics,
                                const base::CameraMount& mount, const BaseTravel& travel) {
  const FlatGround ground(mount);
  const Eigen::Vector2d moved_m = moved_since(travel);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  ground_x_.create(newer.size(), CV_32FC1);
  ground_y_.create(newer.size(), CV_32FC1);
  flow_x_.create(newer.size(), CV_32FC1);
  flow_y_.create(newer.size(), CV_32FC1);
  for (int row = 0; row < newer.rows; ++row) {
    auto* gx = ground_x_.ptr<float>(row);
    auto* gy = ground_y_.ptr<float>(row);
    auto* fx = flow_x_.ptr<float>(row);
    auto* fy = flow_y_.ptr<float>(row);
    const auto* d = displacement_px.ptr<cv::Vec2f>(row);
    const double y = (row - intrinsics.cy_px) / intrinsics.fy_px;
    for (int col = 0; col < newer.cols; ++col) {
      const double x = (col - intrinsics.cx_px) / intrinsics.fx_px;
      const auto before = ground.seen_before_moving(x, y, moved_m);
      gx[col] =
          before ? static_cast<float>(before->x() * intrinsics.fx_px + intrinsics.cx_px) : kNaN;
      gy[col] =
          before ? static_cast<float>(before->y() * intrinsics.fy_px + intrinsics.cy_px) : kNaN;
      fx[col] = static_cast<float>(col) + d[col][0];
      fy[col] = static_cast<float>(row) + d[col][1];
    }
  }
  cv::remap(older, warped_, ground_x_, ground_y_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  patch_error(newer, warped_, difference_, ground_error_);
  cv::remap(older, warped_, flow_x_, flow_y_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  patch_error(newer, warped_, difference_, flow_error_);
}

std::optional<Eigen::Vector2f> GroundMotionCheck::better_displacement_px(
    int col, int row, double ratio, double max_error_grey2) const {
  const float x = ground_x_.ptr<float>(row)[col];
  const float y = ground_y_.ptr<float>(row)[col];
  // A ground point the older image did not see has nothing to match.
  if (!(x >= 0.0F && x <= static_cast<float>(ground_x_.cols - 1) && y >= 0.0F &&
        y <= static_cast<float>(ground_x_.rows - 1))) {
    return std::nullopt;
  }
  const double ground_error = ground_error_.ptr<float>(row)[col];
  const double flow_error = flow_error_.ptr<float>(row)[col];
  if (!(ground_error <= max_error_grey2 && ground_error < ratio * flow_error)) {
    return std::nullopt;
  }
  return Eigen::Vector2f(x - static_cast<float>(col), y - static_cast<float>(row));
}

}  // namespace flowsteer::servo
