#include "flowsteer/servo/features.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>
#include <string>

#include <ceres/ceres.h>
#include <Eigen/Dense>

namespace flowsteer::servo {

const char* to_string(MotionStatus status) {
  switch (status) {
    case MotionStatus::approaching:
      return "approaching";
    case MotionStatus::receding:
      return "receding";
    case MotionStatus::lateral:
      return "lateral";
    case MotionStatus::no_flow:
      return "no_flow";
  }
  return "unknown";
}

namespace {

// The radial model in a form linear in its parameters p = (1/τ, −f_x/τ, −f_y/τ):
// u = p0 x + p1, v = p0 y + p2. The fit is well conditioned for any τ, including the lateral
// case 1/τ → 0 where f runs off to infinity. Each residual carries a weight that the robust
// rounds set; it stays constant within a Ceres solve, so the residual stays linear in p.
class RadialResidual final : public ceres::SizedCostFunction<2, 3> {
 public:
  explicit RadialResidual(const FlowSample& sample) : sample_(sample) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* p = parameters[0];
    const Eigen::Vector2d& x = sample_.point;
    residuals[0] = weight_ * (sample_.flow.x() - (p[0] * x.x() + p[1]));
    residuals[1] = weight_ * (sample_.flow.y() - (p[0] * x.y() + p[2]));
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      double* j = jacobians[0];
      j[0] = -weight_ * x.x();
      j[1] = -weight_;
      j[2] = 0.0;
      j[3] = -weight_ * x.y();
      j[4] = 0.0;
      j[5] = -weight_;
    }
    return true;
  }

  Eigen::Vector2d predicted(const Eigen::Vector3d& p) const {
    return p[0] * sample_.point + Eigen::Vector2d(p[1], p[2]);
  }
  double unweighted_norm(const Eigen::Vector3d& p) const {
    return (sample_.flow - predicted(p)).norm();
  }
  double weighted_norm(const Eigen::Vector3d& p) const { return weight_ * unweighted_norm(p); }
  void set_weight(double weight) { weight_ = weight; }

 private:
  FlowSample sample_;
  double weight_ = 1.0;
};

// Robust standard deviation of the weighted 2D residuals from the median of their norms: for
// isotropic Gaussian noise the norm is Rayleigh distributed with median σ·sqrt(2 ln 2).
double robust_sigma(const std::deque<RadialResidual>& residuals, const Eigen::Vector3d& p,
                    std::vector<double>& scratch) {
  scratch.resize(residuals.size());
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    scratch[i] = residuals[i].weighted_norm(p);
  }
  auto middle = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), middle, scratch.end());
  return *middle / 1.1774100225154747;
}

// Flow noise grows with the flow (numerical flow errs in proportion to the displacement), so
// after the first round each residual is divided by the magnitude the model predicts there,
// floored near the FOE where that magnitude vanishes.
void weight_by_predicted_magnitude(std::deque<RadialResidual>& residuals,
                                   const Eigen::Vector3d& p) {
  double mean = 0.0;
  for (const RadialResidual& r : residuals) {
    mean += r.predicted(p).norm();
  }
  mean /= static_cast<double>(residuals.size());
  const double floor = 0.25 * mean + 1e-12;
  for (RadialResidual& r : residuals) {
    r.set_weight(1.0 / (r.predicted(p).norm() + floor));
  }
}

}  // namespace

RadialFit fit_radial_flow(std::span<const FlowSample> samples, const RadialFitOptions& options) {
  RadialFit fit;
  if (samples.size() < 3) {
    return fit;
  }

  // Least-squares start.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double flow_scale = 0.0;
  for (const FlowSample& s : samples) {
    const double x = s.point.x();
    const double y = s.point.y();
    normal(0, 0) += x * x + y * y;
    normal(0, 1) += x;
    normal(0, 2) += y;
    rhs += Eigen::Vector3d(x * s.flow.x() + y * s.flow.y(), s.flow.x(), s.flow.y());
    flow_scale += s.flow.norm();
  }
  const auto n = static_cast<double>(samples.size());
  normal(1, 1) = n;
  normal(2, 2) = n;
  normal(1, 0) = normal(0, 1);
  normal(2, 0) = normal(0, 2);
  flow_scale /= n;
  Eigen::Vector3d p = normal.ldlt().solve(rhs);
  const double spread =
      normal(0, 0) - (normal(0, 1) * normal(0, 1) + normal(0, 2) * normal(0, 2)) / n;
  if (!p.allFinite() || spread <= 1e-12 * n) {
    return fit;  // all samples at one point: the model is not identifiable
  }

  std::deque<RadialResidual> residuals;  // cost functions cannot move
  for (const FlowSample& s : samples) {
    residuals.emplace_back(s);
  }
  std::vector<double> scratch;
  double sigma = robust_sigma(residuals, p, scratch);
  // Flow comes in float32: residuals below this are rounding, not noise.
  const double exact = 1e-6 * flow_scale + 1e-12;
  bool weighted = false;

  if (sigma > exact) {
    ceres::LossFunctionWrapper loss(nullptr, ceres::DO_NOT_TAKE_OWNERSHIP);
    ceres::Problem::Options problem_options;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    for (RadialResidual& r : residuals) {
      problem.AddResidualBlock(&r, &loss, p.data());
    }
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.logging_type = ceres::SILENT;
    solver_options.num_threads = 1;
    auto solve = [&](ceres::LossFunction* next_loss) {
      loss.Reset(next_loss, ceres::TAKE_OWNERSHIP);
      ceres::Solver::Summary summary;
      ceres::Solve(solver_options, &problem, &summary);
      fit.quality.iterations += static_cast<int>(summary.iterations.size());
    };
    // Cauchy rounds (2.385 σ: 95% efficiency on Gaussian noise) find the bulk of the inliers
    // from any start; a last Tukey round (4.685 σ) then gives outliers no weight at all, which
    // Cauchy's long tail still does.
    for (int round = 0; round < options.max_rounds; ++round) {
      solve(new ceres::CauchyLoss(2.385 * sigma));
      const double previous = sigma;
      if (!weighted) {
        weight_by_predicted_magnitude(residuals, p);
        weighted = true;
      }
      sigma = robust_sigma(residuals, p, scratch);
      if (round > 0 && std::abs(previous - sigma) <= 0.01 * previous) {
        break;
      }
    }
    solve(new ceres::TukeyLoss(4.685 * sigma));
    sigma = robust_sigma(residuals, p, scratch);
  }

  const double threshold = options.inlier_threshold * (weighted ? sigma : std::max(sigma, exact));
  int inliers = 0;
  double sum_squares = 0.0;
  for (const RadialResidual& r : residuals) {
    if (r.weighted_norm(p) <= threshold) {
      ++inliers;
      sum_squares += r.unweighted_norm(p) * r.unweighted_norm(p);
    }
  }
  fit.quality.samples = static_cast<int>(samples.size());
  fit.quality.inlier_fraction = inliers / n;
  fit.quality.residual_rms = inliers > 0 ? std::sqrt(sum_squares / inliers) : 0.0;

  const double inverse_ttc = p[0];
  if (std::abs(inverse_ttc) < options.min_inverse_ttc) {
    fit.status = MotionStatus::lateral;
    fit.ttc_s = std::numeric_limits<double>::infinity();
    return fit;
  }
  fit.status = inverse_ttc > 0.0 ? MotionStatus::approaching : MotionStatus::receding;
  fit.ttc_s = 1.0 / inverse_ttc;
  fit.foe = Eigen::Vector2d(-p[1], -p[2]) / inverse_ttc;
  return fit;
}

double ttc_from_foe(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                    double sign_from) {
  double sum = 0.0;
  int count = 0;
  for (const FlowSample& s : samples) {
    const double speed = s.flow.norm();
    if (speed > 1e-9) {
      sum += (s.point - foe).norm() / speed;
      ++count;
    }
  }
  if (count == 0 || !foe.allFinite()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return std::copysign(sum / count, sign_from);
}

struct FeatureExtractor::Accumulator {
  int pixels = 0;
  int invalid = 0;
  double sum_x = 0.0;
  double sum_y = 0.0;
  double min_x = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
  double sum_u = 0.0;
  double sum_xu = 0.0;
  int depth_count = 0;
  double sum_depth = 0.0;
  double sum_inv_depth = 0.0;
  double sum_x_inv_depth = 0.0;

  int valid() const { return pixels - invalid; }
};

FeatureExtractor::FeatureExtractor(const FeatureOptions& options) : options_(options) {
  if (options_.min_pixels < 3) {
    throw std::invalid_argument("FeatureOptions::min_pixels must be at least 3, got " +
                                std::to_string(options_.min_pixels));
  }
  if (options_.max_fit_samples < options_.min_pixels) {
    throw std::invalid_argument("FeatureOptions::max_fit_samples (" +
                                std::to_string(options_.max_fit_samples) +
                                ") must be at least min_pixels (" +
                                std::to_string(options_.min_pixels) + ")");
  }
}

FeatureExtractor::~FeatureExtractor() = default;
FeatureExtractor::FeatureExtractor(FeatureExtractor&&) noexcept = default;
FeatureExtractor& FeatureExtractor::operator=(FeatureExtractor&&) noexcept = default;

std::span<const ObjectFeatures> FeatureExtractor::extract(const FlowField& field,
                                                          const Segmentation& segmentation) {
  if (segmentation.width != field.width() || segmentation.height != field.height() ||
      segmentation.labels.size() != field.size()) {
    throw std::invalid_argument(
        "FeatureExtractor::extract: segmentation is " + std::to_string(segmentation.width) + "x" +
        std::to_string(segmentation.height) + " but the flow field is " +
        std::to_string(field.width()) + "x" + std::to_string(field.height()));
  }
  const auto regions = static_cast<std::size_t>(segmentation.region_count());
  accumulators_.assign(regions, Accumulator{});
  const auto flow = field.flow();
  const auto depth = field.depth();
  const auto& labels = segmentation.labels;

  for (int row = 0; row < field.height(); ++row) {
    const double y = field.y(row);
    for (int col = 0; col < field.width(); ++col) {
      const std::size_t i = field.index(col, row);
      const std::int32_t label = labels[i];
      if (label < 0) {
        continue;
      }
      Accumulator& a = accumulators_[static_cast<std::size_t>(label)];
      const double x = field.x(col);
      ++a.pixels;
      a.sum_x += x;
      a.sum_y += y;
      a.min_x = std::min(a.min_x, x);
      a.max_x = std::max(a.max_x, x);
      if (!depth.empty() && std::isfinite(depth[i]) && depth[i] > 0.0F) {
        ++a.depth_count;
        a.sum_depth += depth[i];
        a.sum_inv_depth += 1.0 / depth[i];
        a.sum_x_inv_depth += x / depth[i];
      }
      if (!flow[i].allFinite()) {
        ++a.invalid;
        continue;
      }
      a.sum_u += flow[i].x();
      a.sum_xu += x * flow[i].x();
    }
  }

  // Every region with enough valid vectors gets up to max_fit_samples of them, taken at an even
  // stride in raster order.
  sample_offsets_.assign(regions + 1, 0);
  sample_strides_.assign(regions, 0);
  sample_counters_.assign(regions, 0);
  for (std::size_t r = 0; r < regions; ++r) {
    const Accumulator& a = accumulators_[r];
    int take = 0;
    if (segmentation.kinds[r] == RegionKind::visible && a.valid() >= options_.min_pixels) {
      sample_strides_[r] = (a.valid() + options_.max_fit_samples - 1) / options_.max_fit_samples;
      take = (a.valid() + sample_strides_[r] - 1) / sample_strides_[r];
    }
    sample_offsets_[r + 1] = sample_offsets_[r] + take;
  }
  samples_.resize(static_cast<std::size_t>(sample_offsets_[regions]));
  for (int row = 0; row < field.height(); ++row) {
    const double y = field.y(row);
    for (int col = 0; col < field.width(); ++col) {
      const std::size_t i = field.index(col, row);
      const std::int32_t label = labels[i];
      if (label < 0) {
        continue;
      }
      const auto r = static_cast<std::size_t>(label);
      if (sample_strides_[r] == 0 || !flow[i].allFinite()) {
        continue;
      }
      const int k = sample_counters_[r]++;
      if (k % sample_strides_[r] == 0) {
        const auto slot = static_cast<std::size_t>(sample_offsets_[r] + k / sample_strides_[r]);
        samples_[slot] = {{field.x(col), y}, flow[i].cast<double>()};
      }
    }
  }

  features_.resize(regions);
  const double pixel_width = 1.0 / field.intrinsics().fx_px;
  for (std::size_t r = 0; r < regions; ++r) {
    const Accumulator& a = accumulators_[r];
    ObjectFeatures& f = features_[r];
    f = ObjectFeatures{};
    f.label = static_cast<int>(r);
    f.source_id = segmentation.source_ids[r];
    f.kind = segmentation.kinds[r];
    f.pixel_count = a.pixels;
    f.invalid_flow_count = a.invalid;
    if (a.pixels == 0) {
      continue;
    }
    f.centre = Eigen::Vector2d(a.sum_x, a.sum_y) / a.pixels;
    f.width = a.max_x - a.min_x + pixel_width;
    if (a.depth_count > 0) {
      f.depth_m = a.sum_depth / a.depth_count;
    }
    if (a.valid() > 0) {
      f.moments.mean_u = a.sum_u / a.valid();
      f.moments.mean_xu = a.sum_xu / a.valid();
      if (a.depth_count == a.pixels) {
        f.moments.mean_inv_depth = a.sum_inv_depth / a.pixels;
        f.moments.mean_x_inv_depth = a.sum_x_inv_depth / a.pixels;
      }
    }
    const std::span<const FlowSample> region_samples(
        samples_.data() + sample_offsets_[r],
        static_cast<std::size_t>(sample_offsets_[r + 1] - sample_offsets_[r]));
    if (region_samples.empty()) {
      continue;
    }
    const RadialFit fit = fit_radial_flow(region_samples, options_.fit);
    f.status = fit.status;
    f.foe = fit.foe;
    f.ttc_s = fit.ttc_s;
    f.fit = fit.quality;
    if (fit.status == MotionStatus::approaching || fit.status == MotionStatus::receding) {
      f.ttc_eq5_s = ttc_from_foe(region_samples, fit.foe, fit.ttc_s);
    }
  }
  return features_;
}

}  // namespace flowsteer::servo
