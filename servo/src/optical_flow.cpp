#include "flowsteer/servo/optical_flow.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/LU>
#include <opencv2/imgproc.hpp>
#include <opencv2/optflow.hpp>
#include <opencv2/video/tracking.hpp>

namespace flowsteer::servo {

namespace {

// A 5-tap mean, applied along rows and columns: a separable 5×5 mean. cv::blur sums floats in
// double, 4× slower.
const cv::Matx<float, 5, 1> kMeanOf5 = cv::Matx<float, 5, 1>::all(0.2F);

constexpr std::array kNumericalMethods{FlowMethod::dis_ultrafast, FlowMethod::dis_fast,
                                       FlowMethod::dis_medium, FlowMethod::farneback,
                                       FlowMethod::tvl1};

cv::Ptr<cv::DenseOpticalFlow> create_estimator(FlowMethod method) {
  switch (method) {
    case FlowMethod::dis_ultrafast:
      return cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_ULTRAFAST);
    case FlowMethod::dis_fast:
      return cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST);
    case FlowMethod::dis_medium:
      return cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
    case FlowMethod::farneback:
      return cv::FarnebackOpticalFlow::create();
    case FlowMethod::tvl1:
      return cv::optflow::createOptFlow_DualTVL1();
    case FlowMethod::synthetic:
      break;
  }
  throw std::invalid_argument(
      "OpticalFlow: the synthetic flow comes from the renderer, not from images");
}

}  // namespace

double noise_correlation_px(FlowMethod method) {
  if (method == FlowMethod::synthetic) {
    return 1.0;
  }
  const cv::Ptr<cv::DenseOpticalFlow> estimator = create_estimator(method);
  if (const auto dis = estimator.dynamicCast<cv::DISOpticalFlow>()) {
    return std::ldexp(static_cast<double>(dis->getPatchSize()), dis->getFinestScale());
  }
  if (const auto farneback = estimator.dynamicCast<cv::FarnebackOpticalFlow>()) {
    return farneback->getWinSize();
  }
  if (const auto tvl1 = estimator.dynamicCast<cv::optflow::DualTVL1OpticalFlow>()) {
    return std::max(tvl1->getMedianFiltering(), 1);
  }
  return 1.0;
}

std::string_view to_string(FlowMethod method) {
  switch (method) {
    case FlowMethod::synthetic:
      return "synthetic";
    case FlowMethod::dis_ultrafast:
      return "dis_ultrafast";
    case FlowMethod::dis_fast:
      return "dis_fast";
    case FlowMethod::dis_medium:
      return "dis_medium";
    case FlowMethod::farneback:
      return "farneback";
    case FlowMethod::tvl1:
      return "tvl1";
  }
  return "unknown";
}

std::optional<FlowMethod> parse_flow_method(std::string_view name) {
  if (name == to_string(FlowMethod::synthetic))
    return FlowMethod::synthetic;
  for (FlowMethod method : kNumericalMethods) {
    if (name == to_string(method))
      return method;
  }
  return std::nullopt;
}

std::string flow_method_names() {
  std::string names(to_string(FlowMethod::synthetic));
  for (FlowMethod method : kNumericalMethods) {
    names += ", ";
    names += to_string(method);
  }
  return names;
}

std::span<const FlowMethod> numerical_flow_methods() {
  return kNumericalMethods;
}

const char* to_string(FlowStatus status) {
  switch (status) {
    case FlowStatus::ok:
      return "ok";
    case FlowStatus::no_previous_frame:
      return "no previous frame";
    case FlowStatus::size_changed:
      return "image size changed";
    case FlowStatus::empty_frame:
      return "empty frame";
    case FlowStatus::untextured:
      return "single-colour frame";
    case FlowStatus::no_time_elapsed:
      return "timestamp did not increase";
    case FlowStatus::time_went_back:
      return "timestamp went back";
  }
  return "unknown";
}

struct OpticalFlow::Estimator {
  cv::Ptr<cv::DenseOpticalFlow> algorithm;
};

OpticalFlow::OpticalFlow(FlowMethod method, const OpticalFlowOptions& options)
    : method_(method),
      options_(options),
      estimator_(std::make_unique<Estimator>(Estimator{create_estimator(method)})) {
  if (!(options.baseline_s >= 0.0) || options.max_kept_images < 1) {
    throw std::invalid_argument("OpticalFlow: baseline_s must be >= 0 and max_kept_images >= 1");
  }
  kept_.resize(static_cast<std::size_t>(options.max_kept_images));
}

OpticalFlow::~OpticalFlow() = default;
OpticalFlow::OpticalFlow(OpticalFlow&&) noexcept = default;
OpticalFlow& OpticalFlow::operator=(OpticalFlow&&) noexcept = default;

void OpticalFlow::reset() {
  kept_count_ = 0;
}

FlowStatus OpticalFlow::update(const cv::Mat& image, double timestamp_s, FlowField& field) {
  return update(image, timestamp_s, field, RotationBetween{});
}

FlowStatus OpticalFlow::update(const cv::Mat& image, double timestamp_s, FlowField& field,
                               const RotationBetween& rotation) {
  if (image.empty())
    return FlowStatus::empty_frame;
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw std::invalid_argument("OpticalFlow: expected an 8-bit grey or BGR image, got type " +
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
  if (rotation) {
    Eigen::Matrix3d camera_matrix;
    camera_matrix << k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0;
    to_older =
        camera_matrix * rotation(reference->timestamp_s, timestamp_s) * camera_matrix.inverse();
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

  // Backward flow (newer → older image) lands on the newer image's pixels, where this frame's
  // segmentation and depth are; its negation is the motion that brought each pixel there.
  estimator_->algorithm->calc(grey_, *older, flow_px_);

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
  const auto min_gradient_squared =
      static_cast<float>(options_.min_gradient * options_.min_gradient);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  auto flow = field.flow();
  for (int row = 0; row < grey_.rows; ++row) {
    const auto* d = flow_px_.ptr<cv::Vec2f>(row);
    const auto* xx = tensor_xx_.ptr<float>(row);
    const auto* xy = tensor_xy_.ptr<float>(row);
    const auto* yy = tensor_yy_.ptr<float>(row);
    for (int col = 0; col < grey_.cols; ++col) {
      bool seen_before = true;
      if (rotation) {
        const Eigen::Vector3d at = to_older * Eigen::Vector3d(col, row, 1.0);
        seen_before = at.z() > 0.0 && at.x() >= 0.0 && at.x() <= at.z() * (grey_.cols - 1) &&
                      at.y() >= 0.0 && at.y() <= at.z() * (grey_.rows - 1);
      }
      const float half_trace = 0.5F * (xx[col] + yy[col]);
      const float half_difference = 0.5F * (xx[col] - yy[col]);
      const float min_eigenvalue =
          half_trace - std::sqrt(half_difference * half_difference + xy[col] * xy[col]);
      flow[field.index(col, row)] = min_eigenvalue < min_gradient_squared || !seen_before
                                        ? Eigen::Vector2f(kNaN, kNaN)
                                        : Eigen::Vector2f(d[col][0] * to_x, d[col][1] * to_y);
    }
  }
  keep(timestamp_s);
  return FlowStatus::ok;
}

void OpticalFlow::keep(double timestamp_s) {
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

}  // namespace flowsteer::servo
