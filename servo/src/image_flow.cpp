#include "image_flow.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/LU>
#include <opencv2/imgproc.hpp>

namespace flowsteer::servo {

namespace {

// A 5-tap mean, applied along rows and columns: a separable 5×5 mean. cv::blur sums floats in
// double, 4× slower.
const cv::Matx<float, 5, 1> kMeanOf5 = cv::Matx<float, 5, 1>::all(0.2F);

// Immerkær, "Fast noise variance estimation" (1996): the image convolved with
// N = [1 −2 1; −2 4 −2; 1 −2 1], the difference of two Laplacians, keeps little of smooth shading
// and all of the noise (Σ N² = 36). Its median magnitude, 0.6745 · 6 σ for Gaussian noise, is
// robust to the texture and edges of up to half the pixels. `response` is scratch.
double measure_noise_grey(const cv::Mat& grey, cv::Mat& response) {
  static const cv::Matx33f kLaplacianDifference(1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::filter2D(grey, response, CV_16S, kLaplacianDifference);
  std::array<int, 1024> histogram{};
  for (int row = 1; row < response.rows - 1; ++row) {
    const auto* r = response.ptr<std::int16_t>(row);
    for (int col = 1; col < response.cols - 1; ++col) {
      ++histogram[static_cast<std::size_t>(std::min(std::abs(r[col]), 1023))];
    }
  }
  const int half = (response.rows - 2) * (response.cols - 2) / 2;
  int seen = 0;
  for (std::size_t magnitude = 0; magnitude < histogram.size(); ++magnitude) {
    seen += histogram[magnitude];
    if (seen > half) {
      return static_cast<double>(magnitude) / (0.6745 * 6.0);
    }
  }
  return 1023.0 / (0.6745 * 6.0);
}

}  // namespace

ImageFlowEstimator::ImageFlowEstimator(const OpticalFlowOptions& options) : options_(options) {
  if (!(options.baseline_s >= 0.0) || options.max_kept_images < 1 ||
      !(options.ground_match_ratio >= 0.0) || !(options.ground_match_px >= 0.0) ||
      !(options.ground_match_noise_margin >= 0.0)) {
    throw std::invalid_argument(
        "optical flow: baseline_s and the ground_match options must be >= 0 and "
        "max_kept_images >= 1");
  }
  kept_.resize(static_cast<std::size_t>(options.max_kept_images));
}

void ImageFlowEstimator::reset() {
  kept_count_ = 0;
  // DIS starts from the flow its output holds (calc's displacement_px): a pair after a reset
  // starts from nothing, not from the flow of images it no longer has.
  flow_px_.release();
}

FlowStatus ImageFlowEstimator::update(const FlowFrame& frame, const CameraMotion& motion,
                                      FlowField& field) {
  const cv::Mat& image = frame.image;
  const double timestamp_s = frame.timestamp_s;
  if (image.empty())
    return FlowStatus::empty_frame;
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw std::invalid_argument("optical flow: expected an 8-bit grey or BGR image, got type " +
                                cv::typeToString(image.type()));
  }
  if (image.channels() == 3) {
    cv::cvtColor(image, grey_, cv::COLOR_BGR2GRAY);
  } else {
    image.copyTo(grey_);
  }

  double min_grey = 0.0;
  double max_grey = 0.0;
  cv::minMaxLoc(grey_, &min_grey, &max_grey);
  if (max_grey - min_grey < options_.min_contrast) {
    // Nothing to track in it, and nothing to track from it later either.
    reset();
    return FlowStatus::untextured;
  }

  const KeptImage* newest =
      kept_count_ > 0 ? &kept_[(kept_begin_ + kept_count_ - 1) % kept_.size()] : nullptr;
  FlowStatus status = FlowStatus::ok;
  if (newest == nullptr) {
    status = FlowStatus::no_previous_frame;
  } else if (newest->grey.size() != grey_.size() || grey_.cols != field.width() ||
             grey_.rows != field.height()) {
    status = FlowStatus::size_changed;
    reset();
  } else if (timestamp_s < newest->timestamp_s) {
    // Waiting for the clock to pass the old images' times would leave the robot blind for as
    // long as it jumped back.
    status = FlowStatus::time_went_back;
    reset();
  } else if (!(timestamp_s > newest->timestamp_s)) {
    return FlowStatus::no_time_elapsed;
  }
  if (status != FlowStatus::ok) {
    keep(timestamp_s);
    return status;
  }

  // The reference: the newest kept image at least baseline_s old, else the oldest.
  const KeptImage* reference = &kept_[kept_begin_];
  for (std::size_t k = kept_count_; k-- > 0;) {
    const KeptImage& candidate = kept_[(kept_begin_ + k) % kept_.size()];
    if (timestamp_s - candidate.timestamp_s >= options_.baseline_s - 1e-9) {
      reference = &candidate;
      break;
    }
  }

  const double dt_s = timestamp_s - reference->timestamp_s;
  const base::CameraIntrinsics& k = field.intrinsics();
  // Pixel homography of the rotation: newer pixel → where its ray fell in the older image.
  Eigen::Matrix3d to_older = Eigen::Matrix3d::Identity();
  const cv::Mat* older = &reference->grey;
  const bool turned = static_cast<bool>(motion.between);
  if (turned) {
    Eigen::Matrix3d camera_matrix;
    camera_matrix << k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0;
    to_older = camera_matrix * motion.between(reference->timestamp_s, timestamp_s) *
               camera_matrix.inverse();
    cv::Matx33d homography;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        homography(r, c) = to_older(r, c);
      }
    }
    cv::warpPerspective(reference->grey, warped_, homography, grey_.size(),
                        cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
    older = &warped_;
  }

  noise_grey_ = measure_noise_grey(grey_, noise_response_);
  // Backward flow (newer → older image) lands on the newer image's pixels, where this frame's
  // segmentation and depth are; its negation is the motion that brought each pixel there.
  calc(grey_, *older, flow_px_);
  const bool check_ground =
      options_.ground_match_ratio > 0.0 && motion.travelled && motion.ground_mount.has_value();
  if (check_ground) {
    ground_check_.prepare(grey_, *older, flow_px_, field.intrinsics(), *motion.ground_mount,
                          motion.travelled(reference->timestamp_s, timestamp_s));
  }
  const double ground_noise_grey2 = options_.ground_match_noise_margin * noise_grey_ * noise_grey_;
  const double ground_match_px2 = options_.ground_match_px * options_.ground_match_px;

  // Local texture: √λ_min of the structure tensor over a 5×5 window, the RMS gradient along the
  // image's least textured direction (a 3×3 Sobel is 8× the gradient). On a straight edge (the
  // horizon, an outline) only the flow across the edge is seen, the aperture problem: the
  // estimators fill in the flow along it by smoothing, as they do on blank areas.
  cv::Sobel(grey_, gradient_x_, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(grey_, gradient_y_, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::multiply(gradient_x_, gradient_x_, gradient_product_);
  cv::sepFilter2D(gradient_product_, tensor_xx_, CV_32F, kMeanOf5, kMeanOf5);
  cv::multiply(gradient_x_, gradient_y_, gradient_product_);
  cv::sepFilter2D(gradient_product_, tensor_xy_, CV_32F, kMeanOf5, kMeanOf5);
  cv::multiply(gradient_y_, gradient_y_, gradient_product_);
  cv::sepFilter2D(gradient_product_, tensor_yy_, CV_32F, kMeanOf5, kMeanOf5);

  field.set_interval_s(dt_s);
  const auto to_x = static_cast<float>(-1.0 / (field.intrinsics().fx_px * dt_s));
  const auto to_y = static_cast<float>(-1.0 / (field.intrinsics().fy_px * dt_s));
  const double min_gradient =
      std::max(options_.min_gradient, options_.min_gradient_per_noise * noise_grey_);
  const auto min_gradient_squared = static_cast<float>(min_gradient * min_gradient);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  auto flow = field.flow();
  edge_flow_.resize(field.size());
  for (int row = 0; row < grey_.rows; ++row) {
    const auto* d = flow_px_.ptr<cv::Vec2f>(row);
    const auto* xx = tensor_xx_.ptr<float>(row);
    const auto* xy = tensor_xy_.ptr<float>(row);
    const auto* yy = tensor_yy_.ptr<float>(row);
    for (int col = 0; col < grey_.cols; ++col) {
      bool seen_before = true;
      if (turned) {
        const Eigen::Vector3d at = to_older * Eigen::Vector3d(col, row, 1.0);
        seen_before = at.z() > 0.0 && at.x() >= 0.0 && at.x() <= at.z() * (grey_.cols - 1) &&
                      at.y() >= 0.0 && at.y() <= at.z() * (grey_.rows - 1);
      }
      const float half_trace = 0.5F * (xx[col] + yy[col]);
      const float half_difference = 0.5F * (xx[col] - yy[col]);
      const float radius = std::sqrt(half_difference * half_difference + xy[col] * xy[col]);
      const std::size_t i = field.index(col, row);
      const Eigen::Vector2f measured(d[col][0] * to_x, d[col][1] * to_y);
      const bool textured = half_trace - radius >= min_gradient_squared && seen_before;
      flow[i] = textured ? measured : Eigen::Vector2f(kNaN, kNaN);
      if (textured && check_ground) {
        // A misalignment e changes the patch by eᵀ T e, at most |e|² trace(T) with T the
        // structure tensor. Along an edge the patches cannot tell the two motions apart: the flow
        // across edges stays the estimator's.
        const double max_error_grey2 =
            ground_noise_grey2 + ground_match_px2 * 2.0 * static_cast<double>(half_trace);
        if (const auto ground = ground_check_.better_displacement_px(
                col, row, options_.ground_match_ratio, max_error_grey2)) {
          flow[i] = Eigen::Vector2f(ground->x() * to_x, ground->y() * to_y);
        }
      }
      edge_flow_[i] = Eigen::Vector2f(kNaN, kNaN);
      if (!textured && seen_before && half_trace + radius >= min_gradient_squared) {
        // The gradient's direction, the structure tensor's eigenvector of the larger eigenvalue.
        const Eigen::Vector2f across = half_difference >= 0.0F
                                           ? Eigen::Vector2f(half_difference + radius, xy[col])
                                           : Eigen::Vector2f(xy[col], radius - half_difference);
        const Eigen::Vector2f normal = across.normalized();
        edge_flow_[i] = normal * normal.dot(measured);
      }
    }
  }
  keep(timestamp_s);
  return FlowStatus::ok;
}

void ImageFlowEstimator::keep(double timestamp_s) {
  if (kept_count_ == kept_.size()) {
    kept_begin_ = (kept_begin_ + 1) % kept_.size();
    --kept_count_;
  }
  KeptImage& slot = kept_[(kept_begin_ + kept_count_) % kept_.size()];
  // Swapping hands the slot's old buffer to grey_ for the next image: no allocation.
  cv::swap(slot.grey, grey_);
  slot.timestamp_s = timestamp_s;
  ++kept_count_;
}

DisFlow::DisFlow(int preset, const OpticalFlowOptions& options)
    : ImageFlowEstimator(options), algorithm_(cv::DISOpticalFlow::create(preset)) {}

double DisFlow::noise_correlation_px() const {
  return std::ldexp(static_cast<double>(algorithm_->getPatchSize()), algorithm_->getFinestScale());
}

void DisFlow::calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) {
  algorithm_->calc(from, to, displacement_px);
}

FarnebackFlow::FarnebackFlow(const OpticalFlowOptions& options)
    : ImageFlowEstimator(options), algorithm_(cv::FarnebackOpticalFlow::create()) {}

double FarnebackFlow::noise_correlation_px() const {
  return algorithm_->getWinSize();
}

void FarnebackFlow::calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) {
  algorithm_->calc(from, to, displacement_px);
}

TvL1Flow::TvL1Flow(const OpticalFlowOptions& options)
    : ImageFlowEstimator(options), algorithm_(cv::optflow::createOptFlow_DualTVL1()) {}

double TvL1Flow::noise_correlation_px() const {
  return std::max(algorithm_->getMedianFiltering(), 1);
}

void TvL1Flow::calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) {
  algorithm_->calc(from, to, displacement_px);
}

}  // namespace flowsteer::servo
