#include "flowsteer/servo/features.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <ceres/tiny_solver.h>
#include <Eigen/Dense>

#include "flowsteer/servo/ground.hpp"
#include "radial_fit.hpp"

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

// The radial model in a form linear in its parameters. With N = 3, p = (1/τ, −f_x/τ, −f_y/τ)
// and u = p0 x + p1, v = p0 y + p2: well conditioned for any τ, including the lateral case
// 1/τ → 0 where f runs off to infinity. With N = 1 the FOE is given as `foe` and only p0 = 1/τ
// is fitted: u = p0 (x − f). Row k of the design maps p to flow component k.
template <int N>
Eigen::Matrix<double, 2, N> design(const FlowSample& s, const Eigen::Vector2d& foe) {
  Eigen::Matrix<double, 2, N> a = Eigen::Matrix<double, 2, N>::Zero();
  a.col(0) = s.point - foe;
  if constexpr (N == 3) {
    a(0, 1) = 1.0;
    a(1, 2) = 1.0;
  }
  return a;
}

// Each sample's residual carries a weight that the robust rounds set, in the form Ceres'
// TinySolver takes.
template <int N>
struct WeightedRadialResiduals {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = N };

  std::span<const FlowSample> samples;
  std::span<const double> weights;
  Eigen::Vector2d foe;

  int NumResiduals() const { return static_cast<int>(2 * samples.size()); }

  bool operator()(const double* p, double* residuals, double* jacobian) const {
    const Eigen::Map<const Eigen::Matrix<double, N, 1>> params(p);
    const auto rows = static_cast<std::size_t>(NumResiduals());
    for (std::size_t j = 0; j < samples.size(); ++j) {
      const Eigen::Matrix<double, 2, N> a = design<N>(samples[j], foe);
      const double w = weights[j];
      const Eigen::Vector2d r = w * (samples[j].flow - a * params);
      residuals[2 * j] = r.x();
      residuals[2 * j + 1] = r.y();
      if (jacobian != nullptr) {  // column-major, rows × N
        for (int k = 0; k < N; ++k) {
          jacobian[static_cast<std::size_t>(k) * rows + 2 * j] = -w * a(0, k);
          jacobian[static_cast<std::size_t>(k) * rows + 2 * j + 1] = -w * a(1, k);
        }
      }
    }
    return true;
  }
};

// Robust standard deviation of scaled residuals from the median of their norms: for isotropic
// Gaussian noise the norm is Rayleigh distributed with median σ·sqrt(2 ln 2).
double robust_sigma(std::span<const double> norms, std::vector<double>& scratch) {
  scratch.assign(norms.begin(), norms.end());
  auto middle = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), middle, scratch.end());
  return *middle / 1.1774100225154747;
}

enum class Loss { cauchy, tukey };

// IRLS weight ψ(e)/e of a residual of norm e, as the square root that scales the residual.
double robust_weight(Loss loss, double e, double sigma) {
  if (loss == Loss::cauchy) {
    const double c = 2.385 * sigma;  // 95% efficiency on Gaussian noise
    return std::sqrt(1.0 / (1.0 + (e / c) * (e / c)));
  }
  const double c = 4.685 * sigma;  // likewise
  return e < c ? 1.0 - (e / c) * (e / c) : 0.0;
}

template <int N>
using RadialSolver = ceres::TinySolver<WeightedRadialResiduals<N>>;

}  // namespace

struct RadialFitWorkspace::Buffers {
  std::vector<double> scale;
  std::vector<double> norms;
  std::vector<double> weights;
  std::vector<double> sorted;
  RadialSolver<1> solver_about;  // the FOE given: 1/τ alone
  RadialSolver<3> solver;
};

RadialFitWorkspace::RadialFitWorkspace() : buffers_(std::make_unique<Buffers>()) {}
RadialFitWorkspace::~RadialFitWorkspace() = default;
RadialFitWorkspace::RadialFitWorkspace(RadialFitWorkspace&&) noexcept = default;
RadialFitWorkspace& RadialFitWorkspace::operator=(RadialFitWorkspace&&) noexcept = default;

namespace {

template <int N>
using Parameters = Eigen::Matrix<double, N, 1>;
template <int N>
using ParameterMatrix = Eigen::Matrix<double, N, N>;

// The samples a fit explains and the FOE its design is taken about (see `design`).
template <int N>
struct RadialProblem {
  std::span<const FlowSample> samples;
  Eigen::Vector2d foe;

  std::size_t size() const { return samples.size(); }
  Eigen::Vector2d predicted(const Parameters<N>& p, std::size_t j) const {
    return design<N>(samples[j], foe) * p;
  }
  double residual_norm(const Parameters<N>& p, std::size_t j) const {
    return (samples[j].flow - predicted(p, j)).norm();
  }
};

// The linear least-squares p, and the samples' mean flow magnitude as delivered (before
// derotation, FlowSample::delivered_norm) in `flow_scale`. Empty when p is not finite or all
// samples sit at one point, where the model is not identifiable.
template <int N>
std::optional<Parameters<N>> least_squares_start(const RadialProblem<N>& problem,
                                                 double& flow_scale) {
  const auto n = static_cast<double>(problem.size());
  ParameterMatrix<N> normal = ParameterMatrix<N>::Zero();
  Parameters<N> rhs = Parameters<N>::Zero();
  flow_scale = 0.0;
  for (const FlowSample& s : problem.samples) {
    const Eigen::Matrix<double, 2, N> a = design<N>(s, problem.foe);
    normal.noalias() += a.transpose() * a;
    rhs.noalias() += a.transpose() * s.flow;
    flow_scale += std::max(s.flow.norm(), s.delivered_norm);
  }
  flow_scale /= n;
  Parameters<N> p;
  if constexpr (N == 1) {
    p = rhs / normal(0, 0);
  } else {
    p = normal.ldlt().solve(rhs);
  }
  // The spread of the points about their mean (N = 3) or about the FOE (N = 1).
  double spread = normal(0, 0);
  if constexpr (N == 3) {
    spread -= (normal(0, 1) * normal(0, 1) + normal(0, 2) * normal(0, 2)) / n;
  }
  if (!p.allFinite() || spread <= 1e-12 * n) {
    return std::nullopt;
  }
  return p;
}

// Each sample's residual norm times its scale, into buffers.norms.
template <int N>
void scale_residual_norms(const RadialProblem<N>& problem, const Parameters<N>& p,
                          RadialFitWorkspace::Buffers& buffers) {
  for (std::size_t j = 0; j < problem.size(); ++j) {
    buffers.norms[j] = buffers.scale[j] * problem.residual_norm(p, j);
  }
}

// Flow noise grows with the flow (numerical flow errs in proportion to the displacement), so
// after the first round a residual is measured relative to the flow the model predicts there,
// floored near the FOE where that vanishes.
template <int N>
void scale_by_predicted_flow(const RadialProblem<N>& problem, const Parameters<N>& p,
                             std::vector<double>& scale) {
  const auto n = static_cast<double>(problem.size());
  double mean = 0.0;
  for (std::size_t j = 0; j < problem.size(); ++j) {
    mean += problem.predicted(p, j).norm();
  }
  const double floor = 0.25 * mean / n + 1e-12;
  for (std::size_t j = 0; j < problem.size(); ++j) {
    scale[j] = 1.0 / (problem.predicted(p, j).norm() + floor);
  }
}

template <int N>
RadialSolver<N>& solver_for(RadialFitWorkspace::Buffers& buffers) {
  if constexpr (N == 1) {
    return buffers.solver_about;
  } else {
    return buffers.solver;
  }
}

// Iteratively reweighted least squares from p, with σ the robust spread of the norms in
// `buffers`: Cauchy rounds find the bulk of the inliers from any start; Tukey rounds then give
// outliers no weight at all, which Cauchy's long tail still does. Each round is solved by Ceres'
// TinySolver. Leaves the last round's weights, scales and norms in `buffers`; returns their σ.
template <int N>
double reweighted_rounds(const RadialProblem<N>& problem, const RadialFitOptions& options,
                         RadialFitWorkspace::Buffers& buffers, double sigma, Parameters<N>& p,
                         RadialFit& fit) {
  RadialSolver<N>& solver = solver_for<N>(buffers);
  solver.options.max_num_iterations = options.max_iterations;
  const WeightedRadialResiduals<N> residuals{problem.samples, buffers.weights, problem.foe};
  const int rounds = options.max_rounds + 2;
  for (int round = 0; round < rounds; ++round) {
    const Loss loss = round < options.max_rounds ? Loss::cauchy : Loss::tukey;
    for (std::size_t j = 0; j < problem.size(); ++j) {
      buffers.weights[j] = buffers.scale[j] * robust_weight(loss, buffers.norms[j], sigma);
    }
    const Parameters<N> previous = p;
    fit.quality.iterations += solver.Solve(residuals, &p).iterations;
    if (round == 0) {
      scale_by_predicted_flow(problem, p, buffers.scale);
    }
    scale_residual_norms(problem, p, buffers);
    sigma = robust_sigma(buffers.norms, buffers.sorted);
    const bool settled = (p - previous).norm() <= 1e-6 * p.norm();
    if (settled && round >= options.max_rounds) {
      break;
    }
    if (settled && round > 0) {
      round = options.max_rounds - 1;  // on to the Tukey rounds
    }
  }
  return sigma;
}

// The fit's quality over the inliers of the last round, and the covariance of p by the sandwich
// H⁻¹ M H⁻¹ over its weights: H the weighted information, M the spread of each sample's weighted
// score. Unlike the residual variance times H⁻¹ it stays honest where the noise is not alike
// over the region, or the model does not quite hold (a slanted surface without depth). Float
// rounding (`exact`) sets its floor. Returns the covariance.
template <int N>
ParameterMatrix<N> assess_fit(const RadialProblem<N>& problem, const Parameters<N>& p,
                              const RadialFitOptions& options,
                              const RadialFitWorkspace::Buffers& buffers, double sigma,
                              double exact, FitQuality& quality) {
  int inliers = 0;
  double sum_squares = 0.0;
  ParameterMatrix<N> information = ParameterMatrix<N>::Zero();
  ParameterMatrix<N> score_spread = ParameterMatrix<N>::Zero();
  for (std::size_t j = 0; j < problem.size(); ++j) {
    const Eigen::Vector2d r = problem.samples[j].flow - problem.predicted(p, j);
    const double e = r.norm();
    if (buffers.norms[j] <= options.inlier_threshold * std::max(sigma, exact * buffers.scale[j])) {
      ++inliers;
      sum_squares += e * e;
    }
    const Eigen::Matrix<double, 2, N> a = design<N>(problem.samples[j], problem.foe);
    const double w2 = buffers.weights[j] * buffers.weights[j];
    information.noalias() += w2 * a.transpose() * a;
    const Eigen::Matrix2d spread2 = r * r.transpose() + exact * exact * Eigen::Matrix2d::Identity();
    score_spread.noalias() += (w2 * w2) * a.transpose() * spread2 * a;
  }
  quality.samples = static_cast<int>(problem.size());
  quality.inlier_fraction = inliers / static_cast<double>(problem.size());
  quality.residual_rms = inliers > 0 ? std::sqrt(sum_squares / inliers) : 0.0;
  const ParameterMatrix<N> bread = information.inverse();
  return bread * score_spread * bread;
}

// The robust fit shared by both forms of the model (see `design`): a least-squares start, then
// iteratively reweighted rounds. Returns p; the fit's quality and the covariance of p go into
// `fit`. Empty when the samples cannot identify p.
template <int N>
std::optional<Parameters<N>> robust_radial_fit(std::span<const FlowSample> samples,
                                               const Eigen::Vector2d& foe,
                                               const RadialFitOptions& options,
                                               RadialFitWorkspace::Buffers& buffers,
                                               RadialFit& fit) {
  if (samples.size() < 3) {
    return std::nullopt;
  }
  const RadialProblem<N> problem{samples, foe};
  double flow_scale = 0.0;
  const std::optional<Parameters<N>> start = least_squares_start(problem, flow_scale);
  if (!start) {
    return std::nullopt;
  }
  Parameters<N> p = *start;
  // The first round measures residuals unscaled (see scale_by_predicted_flow).
  buffers.scale.assign(samples.size(), 1.0);
  buffers.norms.resize(samples.size());
  buffers.weights.assign(samples.size(), 1.0);
  scale_residual_norms(problem, p, buffers);
  double sigma = robust_sigma(buffers.norms, buffers.sorted);
  // Flow comes in float32: residuals below this are rounding, not noise. A turning camera's flow
  // rounds at its magnitude before derotation (the rotation's grows as 1 + x², 15 times the
  // centre's at a 150° view's edges): below that, a static wall failed the static-FOE test on
  // rounding alone.
  const double exact = 1e-6 * flow_scale + 1e-12;
  if (sigma > exact) {
    sigma = reweighted_rounds(problem, options, buffers, sigma, p, fit);
  }
  const ParameterMatrix<N> covariance =
      assess_fit(problem, p, options, buffers, sigma, exact, fit.quality);
  if constexpr (N == 3) {
    fit.parameters = p;
    fit.parameter_covariance = covariance;
  } else {
    // p1 = −f_x p0 and p2 = −f_y p0 follow p0, and so do their variances.
    const Eigen::Vector3d map(1.0, -foe.x(), -foe.y());
    fit.parameters = map * p[0];
    fit.parameter_covariance = map * covariance(0, 0) * map.transpose();
  }
  return p;
}

// Status, τ and FOE from a fitted 1/τ and FOE.
void set_motion(RadialFit& fit, double inverse_ttc, const Eigen::Vector2d& foe,
                const RadialFitOptions& options) {
  if (std::abs(inverse_ttc) < options.min_inverse_ttc) {
    fit.status = MotionStatus::lateral;
    fit.ttc_s = std::numeric_limits<double>::infinity();
    return;
  }
  fit.status = inverse_ttc > 0.0 ? MotionStatus::approaching : MotionStatus::receding;
  fit.ttc_s = 1.0 / inverse_ttc;
  fit.foe = foe;
}

// How far (in columns) a region's leftmost or rightmost ground contact may lie inside its extent
// and still give that end its depth: a person's silhouette is rounded at the feet.
constexpr double kContactColumns = 2.0;

// Z² + X² of the point at depth Z seen in normalised column x: what "nearest" compares.
double squared_range(double depth_m, double x) {
  return depth_m * depth_m * (1.0 + x * x);
}

// Ends' depths from flow (FeatureExtractor::depths_from_static_flow): the columns of an end, the
// vectors it needs, and how far from the FOE (normalised) its pixels must be on average.
constexpr double kFlowDepthColumns = 3.0;
constexpr int kMinFlowDepthSamples = 4;
constexpr double kMinFlowDepthOffset = 0.1;
constexpr double kMaxFlowDepthHeight_m = 0.5;  // the region's top above the ground

// dx/dy of the world's vertical through (x, y) in the image (normalised units): an upright edge
// is seen along it. Its vanishing point, the nadir, is (0, cot θ) for a camera pitched by θ;
// without pitch upright edges are the image's columns.
double upright_slant(const base::CameraMount& mount, double x, double y) {
  const double nadir_y = std::cos(mount.pitch_rad) / std::sin(mount.pitch_rad);
  return std::isfinite(nadir_y) ? -x / (nadir_y - y) : 0.0;
}

}  // namespace

RadialFit fit_radial_flow(std::span<const FlowSample> samples, const RadialFitOptions& options,
                          RadialFitWorkspace& workspace) {
  RadialFit fit;
  const auto p =
      robust_radial_fit<3>(samples, Eigen::Vector2d::Zero(), options, workspace.buffers(), fit);
  if (p) {
    const double inverse_ttc = (*p)[0];
    set_motion(fit, inverse_ttc, Eigen::Vector2d(-(*p)[1], -(*p)[2]) / inverse_ttc, options);
  }
  return fit;
}

RadialFit fit_radial_flow(std::span<const FlowSample> samples, const RadialFitOptions& options) {
  RadialFitWorkspace workspace;
  return fit_radial_flow(samples, options, workspace);
}

RadialFit fit_radial_flow_about(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                                const RadialFitOptions& options, RadialFitWorkspace& workspace) {
  RadialFit fit;
  const auto p = robust_radial_fit<1>(samples, foe, options, workspace.buffers(), fit);
  if (p) {
    set_motion(fit, (*p)[0], foe, options);
  }
  return fit;
}

RadialFit fit_radial_flow_about(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                                const RadialFitOptions& options) {
  RadialFitWorkspace workspace;
  return fit_radial_flow_about(samples, foe, options, workspace);
}

double foe_hypothesis_statistic(const RadialFit& fit, const Eigen::Vector2d& foe,
                                double covariance_scale) {
  // The hypothesis is linear in p: C p = 0 with C = [f | I].
  Eigen::Matrix<double, 2, 3> c;
  c << foe.x(), 1.0, 0.0, foe.y(), 0.0, 1.0;
  const Eigen::Vector2d misfit = c * fit.parameters;
  const Eigen::Matrix2d covariance =
      covariance_scale * c * fit.parameter_covariance * c.transpose();
  if (!misfit.allFinite() || !covariance.allFinite()) {
    return std::numeric_limits<double>::infinity();
  }
  const Eigen::LDLT<Eigen::Matrix2d> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
    return misfit.isZero(0.0) ? 0.0 : std::numeric_limits<double>::infinity();
  }
  return misfit.dot(ldlt.solve(misfit));
}

SurfaceResiduals static_surface_residuals(std::span<const FlowSample> samples,
                                          const Eigen::Vector2d& static_foe) {
  SurfaceResiduals out;
  if (samples.size() < 3) {
    return out;
  }
  // Each sample gives one equation per flow component, u_k = J_k · θ, for both models.
  const auto plane_row = [&](const FlowSample& s, int k) {
    return ((s.point[k] - static_foe[k]) * Eigen::Vector3d(s.point.x(), s.point.y(), 1.0)).eval();
  };
  const auto radial_row = [](const FlowSample& s, int k) {
    return Eigen::Vector3d(s.point[k], k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0);
  };
  Eigen::Matrix3d plane_normal = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d radial_normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d plane_rhs = Eigen::Vector3d::Zero();
  Eigen::Vector3d radial_rhs = Eigen::Vector3d::Zero();
  for (const FlowSample& s : samples) {
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d p = plane_row(s, k);
      const Eigen::Vector3d r = radial_row(s, k);
      plane_normal.noalias() += p * p.transpose();
      radial_normal.noalias() += r * r.transpose();
      plane_rhs += p * s.flow[k];
      radial_rhs += r * s.flow[k];
    }
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> plane_lu(plane_normal);
  const Eigen::FullPivLU<Eigen::Matrix3d> radial_lu(radial_normal);
  if (!plane_lu.isInvertible() || !radial_lu.isInvertible()) {
    return out;
  }
  const Eigen::Vector3d plane = plane_lu.solve(plane_rhs);
  const Eigen::Vector3d radial = radial_lu.solve(radial_rhs);
  out.static_plane = 0.0;
  out.radial = 0.0;
  // Summed from the residuals themselves: uᵀu − θᵀb cancels badly when the fit is close.
  for (const FlowSample& s : samples) {
    for (int k = 0; k < 2; ++k) {
      out.static_plane += std::pow(s.flow[k] - plane_row(s, k).dot(plane), 2);
      out.radial += std::pow(s.flow[k] - radial_row(s, k).dot(radial), 2);
    }
  }
  return out;
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
  double min_x_depth = std::numeric_limits<double>::infinity();  // nearest in that column
  double max_x_depth = std::numeric_limits<double>::infinity();
  double nearest_range2 = std::numeric_limits<double>::infinity();  // Z² (1 + x²)
  double nearest_x = 0.0;
  double nearest_depth = 0.0;
  double sum_u = 0.0;
  double sum_xu = 0.0;
  int depth_count = 0;  // over all pixels: the region's depth
  double sum_depth = 0.0;
  int valid_depth_count = 0;  // over pixels with a valid vector: the flow moments
  double sum_inv_depth = 0.0;
  double sum_x_inv_depth = 0.0;
  // Where the region stands on the ground (FeatureOptions::ground_mount): its leftmost and
  // rightmost such columns, and the depth there.
  double contact_min_x = std::numeric_limits<double>::infinity();
  double contact_max_x = -std::numeric_limits<double>::infinity();
  double contact_min_x_depth = std::numeric_limits<double>::infinity();
  double contact_max_x_depth = std::numeric_limits<double>::infinity();
  double contact_min_x_y = 0.0;  // the contacts' image rows, normalised
  double contact_max_x_y = 0.0;
  double min_y = std::numeric_limits<double>::infinity();  // the region's top

  int valid() const { return pixels - invalid; }
  // Every pixel has a depth, so the fit's samples are scaled by it (FeatureOptions::use_depth).
  bool scales_by_depth(bool use_depth) const {
    return use_depth && depth_count == pixels && pixels > 0;
  }
  // What scales a vector at depth Z to the region's mean depth, times Z; empty when the samples
  // are not scaled by depth.
  std::optional<double> inverse_mean_depth(bool use_depth) const {
    if (!scales_by_depth(use_depth)) {
      return std::nullopt;
    }
    return pixels / sum_depth;
  }

  // Adds one of the region's pixels: its position, its depth (NaN without one) and its flow.
  // Returns whether the flow vector is valid.
  bool add(double x, double y, float depth, const Eigen::Vector2f& flow) {
    ++pixels;
    sum_x += x;
    sum_y += y;
    const bool has_depth = std::isfinite(depth) && depth > 0.0F;
    const double column_depth = has_depth ? depth : std::numeric_limits<double>::infinity();
    min_x_depth = x < min_x    ? column_depth
                  : x == min_x ? std::min(min_x_depth, column_depth)
                               : min_x_depth;
    max_x_depth = x > max_x    ? column_depth
                  : x == max_x ? std::min(max_x_depth, column_depth)
                               : max_x_depth;
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    if (has_depth) {
      ++depth_count;
      sum_depth += depth;
      if (const double range2 = squared_range(column_depth, x); range2 < nearest_range2) {
        nearest_range2 = range2;
        nearest_x = x;
        nearest_depth = column_depth;
      }
    }
    if (!flow.allFinite()) {
      ++invalid;
      return false;
    }
    sum_u += flow.x();
    sum_xu += x * flow.x();
    if (has_depth) {  // the depth moments go with the flow moments: over valid vectors
      const double inverse_depth = 1.0 / depth;
      ++valid_depth_count;
      sum_inv_depth += inverse_depth;
      sum_x_inv_depth += x * inverse_depth;
    }
    return true;
  }

  // Adds a point where the region meets the ground, at the ground's depth there. Without a depth
  // per pixel, the nearest point is the nearest such contact.
  void add_contact(double x, double y, double depth) {
    if (x < contact_min_x || (x == contact_min_x && depth < contact_min_x_depth)) {
      contact_min_x = x;
      contact_min_x_depth = depth;
      contact_min_x_y = y;
    }
    if (x > contact_max_x || (x == contact_max_x && depth < contact_max_x_depth)) {
      contact_max_x = x;
      contact_max_x_depth = depth;
      contact_max_x_y = y;
    }
    if (const double range2 = squared_range(depth, x); range2 < nearest_range2) {
      nearest_range2 = range2;
      nearest_x = x;
      nearest_depth = depth;
    }
  }

  // The ends' and nearest point's depths from the ground contacts, for a region that rises above
  // the horizon (taller than the camera's height: the ground never does, and a camera at rest
  // sees no flow to tell a patch of ground by) and whose leftmost and rightmost columns stand on
  // the ground: within two columns, or as far as an upright edge from the contact up to the
  // region's top leans in a pitched camera's image. An end further out stands behind
  // something, or below the image.
  void describe_contacts(const FlowField& field, const base::CameraMount& mount,
                         ObjectFeatures& f) const {
    if (FlatGround(mount).depth_at(0.0, min_y)) {
      return;
    }
    const double columns = kContactColumns / field.intrinsics().fx_px;
    const auto lean = [&](double x, double y) {
      return std::abs(upright_slant(mount, x, y)) * std::max(0.0, y - min_y);
    };
    if (contact_min_x - min_x > columns + lean(contact_min_x, contact_min_x_y) ||
        max_x - contact_max_x > columns + lean(contact_max_x, contact_max_x_y)) {
      return;
    }
    f.min_x_depth_m = contact_min_x_depth;
    f.max_x_depth_m = contact_max_x_depth;
    f.nearest_x = nearest_x;
    f.nearest_depth_m = nearest_depth;
  }

  // The region's size, extent, mean depth and flow moments into f: all but its fit.
  void describe(const FlowField& field, const std::optional<base::CameraMount>& ground_mount,
                ObjectFeatures& f) const {
    f.pixel_count = pixels;
    f.invalid_flow_count = invalid;
    if (pixels == 0) {
      return;
    }
    f.centre = Eigen::Vector2d(sum_x, sum_y) / pixels;
    f.width = max_x - min_x + 1.0 / field.intrinsics().fx_px;
    f.min_x = min_x;
    f.max_x = max_x;
    f.cut_left = min_x <= field.x(0);
    f.cut_right = max_x >= field.x(field.width() - 1);
    if (depth_count > 0) {
      f.depth_m = sum_depth / depth_count;
      f.nearest_x = nearest_x;
      f.nearest_depth_m = nearest_depth;
      if (std::isfinite(min_x_depth) && std::isfinite(max_x_depth)) {
        f.min_x_depth_m = min_x_depth;
        f.max_x_depth_m = max_x_depth;
      }
    } else if (ground_mount && std::isfinite(contact_min_x)) {
      describe_contacts(field, *ground_mount, f);
    }
    if (valid() > 0) {
      f.moments.mean_u = sum_u / valid();
      f.moments.mean_xu = sum_xu / valid();
      if (valid_depth_count == valid()) {
        f.moments.mean_inv_depth = sum_inv_depth / valid();
        f.moments.mean_x_inv_depth = sum_x_inv_depth / valid();
      }
    }
  }
};

FeatureExtractor::FeatureExtractor(const FeatureOptions& options)
    : options_(options), fit_workspace_(std::make_unique<RadialFitWorkspace>()) {
  if (options_.min_pixels < 3) {
    throw std::invalid_argument("FeatureOptions::min_pixels must be at least 3, got " +
                                std::to_string(options_.min_pixels));
  }
  if (options_.max_fit_samples < options_.min_pixels) {
    throw std::invalid_argument(
        "FeatureOptions::max_fit_samples (" + std::to_string(options_.max_fit_samples) +
        ") must be at least min_pixels (" + std::to_string(options_.min_pixels) + ")");
  }
  if (!(options_.flow_noise_correlation_px >= 1.0)) {
    throw std::invalid_argument(
        "FeatureOptions::flow_noise_correlation_px must be at least 1, got " +
        std::to_string(options_.flow_noise_correlation_px));
  }
  if (!(options_.static_surface_rss_ratio >= 0.0)) {
    throw std::invalid_argument(
        "FeatureOptions::static_surface_rss_ratio must be 0 (off) or positive, got " +
        std::to_string(options_.static_surface_rss_ratio));
  }
  if (!(options_.static_foe_chi2 > 0.0)) {
    throw std::invalid_argument("FeatureOptions::static_foe_chi2 must be positive, got " +
                                std::to_string(options_.static_foe_chi2));
  }
}

FeatureExtractor::~FeatureExtractor() = default;
FeatureExtractor::FeatureExtractor(FeatureExtractor&&) noexcept = default;
FeatureExtractor& FeatureExtractor::operator=(FeatureExtractor&&) noexcept = default;

namespace {

constexpr double kMinTtc_s = 1e-3;

void check_sizes_match(const FlowField& field, const Segmentation& segmentation) {
  if (segmentation.width != field.width() || segmentation.height != field.height() ||
      segmentation.labels.size() != field.size()) {
    throw std::invalid_argument(
        "FeatureExtractor::extract: segmentation is " + std::to_string(segmentation.width) + "x" +
        std::to_string(segmentation.height) + " but the flow field is " +
        std::to_string(field.width()) + "x" + std::to_string(field.height()));
  }
}

// Calls visit(i, col, row, label) for every pixel in a region, in raster order. Most pixels
// belong to no region: blocks of them are skipped with one AND over their labels (kNoRegion is
// all bits set), which the compiler vectorises.
template <typename Visit>
void for_each_region_pixel(const FlowField& field, const Segmentation& segmentation,
                           Visit&& visit) {
  static_assert(Segmentation::kNoRegion == -1);
  constexpr int kBlock = 16;
  for (int row = 0; row < field.height(); ++row) {
    const std::int32_t* row_labels = segmentation.labels.data() + field.index(0, row);
    for (int col = 0; col < field.width(); ++col) {
      if (col % kBlock == 0) {
        const int end = std::min(col + kBlock, field.width());
        std::int32_t all = Segmentation::kNoRegion;
        for (int k = col; k < end; ++k) {
          all &= row_labels[k];
        }
        if (all == Segmentation::kNoRegion) {
          col = end - 1;
          continue;
        }
      }
      const std::int32_t label = row_labels[col];
      if (label >= 0) {
        visit(field.index(col, row), col, row, label);
      }
    }
  }
}

// Rows below a candidate contact that must show no pixel of its region, along the world's
// vertical: enough to follow an upright edge that a pitched camera sees slanted.
constexpr int kContactRows = 3;

// Whether the pixel at (col, row) of `label` stands on the ground: the pixels below it along the
// world's vertical (towards the nadir's vanishing point (0, cot θ) of a camera pitched down by θ,
// straight down without pitch) are ground, no region or a ground region. An upright edge that a
// pitched camera sees slanted has its own pixels there. The pixel must not be in the bottom row.
bool stands_on_ground(const FlowField& field, const Segmentation& segmentation,
                      const base::CameraMount& mount, int col, int row, std::int32_t label) {
  const double dx_per_row = upright_slant(mount, field.x(col), field.y(row)) *
                            field.intrinsics().fx_px / field.intrinsics().fy_px;
  for (int k = 1; k <= kContactRows && row + k < field.height(); ++k) {
    const double traced_col = col + k * dx_per_row;
    for (const double c : {std::floor(traced_col), std::ceil(traced_col)}) {
      if (c < 0.0 || c >= field.width()) {
        continue;
      }
      const std::int32_t below = segmentation.labels[field.index(static_cast<int>(c), row + k)];
      if (below == label ||
          (k == 1 && below >= 0 &&
           segmentation.kinds[static_cast<std::size_t>(below)] != RegionKind::ground)) {
        return false;
      }
    }
  }
  return true;
}

// The points where each visible region stands on the ground (stands_on_ground), at the ground's
// depth one row below the pixel: the foot lies above the next row's centre, which the region
// does not cover, so the depth is never further than the foot's. A region in the bottom row
// stands below the image, nearer than the ground at the image's lower edge: that depth bounds
// its foot's from above (a neighbour a step away, whose feet a level camera does not see).
//
// A region whose lowest pixel lies at or above the horizon, over a pixel with flow, has no contact
// there. That pixel's flow passed the ground's flow test (mark_ground) or lies in a ground region,
// and the test, which runs below the horizon only, takes an upright's rows with the ground up to
// where its flow leaves the test's floor: near the horizon a static point's flow is A/Z, and an
// upright further than |A| / floor passes all the way up (about 5.5 m at x = 0.5 for the
// suite's camera at 128² and 1 m/s, 37 m for the robot's at 320×240). Its foot is anywhere from
// there on; the floor just below the horizon, tens of metres away, is not where it stands.
void find_ground_contacts(const FlowField& field, const Segmentation& segmentation,
                          const base::CameraMount& mount, std::vector<GroundContact>& contacts) {
  contacts.clear();
  const FlatGround ground(mount);
  const auto flow = field.flow();
  // A row's ground depth does not depend on the column.
  const double below_image_y = field.y(field.height() - 1) + 0.5 / field.intrinsics().fy_px;
  const std::optional<double> below_image_m = ground.depth_at(0.0, below_image_y);
  for_each_region_pixel(
      field, segmentation, [&](std::size_t, int col, int row, std::int32_t label) {
        if (segmentation.kinds[static_cast<std::size_t>(label)] != RegionKind::visible) {
          return;
        }
        if (row + 1 == field.height()) {
          if (below_image_m) {
            contacts.push_back(
                {label, field.x(col), field.y(row), below_image_y, *below_image_m, true});
          }
          return;
        }
        const std::size_t below = field.index(col, row + 1);
        if (segmentation.labels[below] == label ||
            (flow[below].allFinite() && !ground.depth_at(field.x(col), field.y(row)))) {
          return;
        }
        const auto depth = ground.depth_at(field.x(col), field.y(row + 1));
        if (depth && stands_on_ground(field, segmentation, mount, col, row, label)) {
          contacts.push_back({label, field.x(col), field.y(row), field.y(row + 1), *depth, false});
        }
      });
}

// Of `valid` vectors, a fit takes `take`, one every `stride`: at most max_samples, evenly spread.
struct SampleStride {
  int take = 0;
  int stride = 1;
};

SampleStride sample_stride(int valid, int max_samples) {
  const int stride = (valid + max_samples - 1) / max_samples;
  return {(valid + stride - 1) / stride, stride};
}

// Fills `out` with every stride-th of a region's valid pixels as fit samples. With a depth for
// every pixel, each vector is scaled to the region's mean depth: across a slanted or curved
// surface τ_j = −Z_j / v_z varies, and u_j Z_j / Z̄ = (x_j − f) / τ̄ holds exactly where the
// shared-τ model of CGF §5 holds only for a surface facing the camera.
void take_samples(const FlowField& field, std::span<const std::uint32_t> pixels, int stride,
                  std::optional<double> inverse_mean_depth, std::span<FlowSample> out) {
  const auto flow = field.flow();
  const auto depth = field.depth();
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::uint32_t i = pixels[k * static_cast<std::size_t>(stride)];
    const auto col = static_cast<int>(i % static_cast<std::uint32_t>(field.width()));
    const auto row = static_cast<int>(i / static_cast<std::uint32_t>(field.width()));
    const double scale = inverse_mean_depth ? depth[i] * *inverse_mean_depth : 1.0;
    const Eigen::Vector2d point(field.x(col), field.y(row));
    const Eigen::Vector2d u = flow[i].cast<double>();
    const Eigen::Vector2d delivered =
        u + rotational_flow(point.x(), point.y(), field.removed_rotation());
    out[k] = {point, scale * u, scale * delivered.norm()};
  }
}

// Whether a static plane explains the samples' flow about as well as the radial model does
// (FeatureOptions::static_surface_rss_ratio). Not for samples scaled by depth: those have the
// static FOE's radial flow exactly on any surface, which the hypothesis test sees.
bool looks_like_static_surface(std::span<const FlowSample> samples, bool scaled_by_depth,
                               const FeatureOptions& options) {
  if (!(options.static_surface_rss_ratio > 0.0) || scaled_by_depth) {
    return false;
  }
  const SurfaceResiduals residuals = static_surface_residuals(samples, *options.static_foe);
  return residuals.static_plane <= options.static_surface_rss_ratio * residuals.radial;
}

// A region's radial fit. With a static FOE given, the fit is redone about it when the free fit
// agrees with it (its covariance widened for the valid vectors' correlated errors) or the
// flow looks like a static surface.
RadialFit fit_region(std::span<const FlowSample> samples, int valid, bool scaled_by_depth,
                     const FeatureOptions& options, RadialFitWorkspace& workspace) {
  RadialFit fit = fit_radial_flow(samples, options.fit, workspace);
  if (!options.static_foe) {
    return fit;
  }
  const double area_px = options.flow_noise_correlation_px * options.flow_noise_correlation_px;
  const double independent =
      std::min<double>(static_cast<double>(samples.size()), static_cast<double>(valid) / area_px);
  const double covariance_scale = static_cast<double>(samples.size()) / std::max(independent, 1.0);
  if (foe_hypothesis_statistic(fit, *options.static_foe, covariance_scale) <=
          options.static_foe_chi2 ||
      looks_like_static_surface(samples, scaled_by_depth, options)) {
    fit = fit_radial_flow_about(samples, *options.static_foe, options.fit, workspace);
    fit.quality.static_foe = true;
  }
  return fit;
}

// The fit's motion into f, for flow measured over `interval_s`.
void set_motion_features(ObjectFeatures& f, const RadialFit& fit,
                         std::span<const FlowSample> samples, double interval_s) {
  f.status = fit.status;
  f.foe = fit.foe;
  // Displacement flow over an interval Δ fits τ + Δ (flow_field.hpp); the FOE is unchanged.
  f.ttc_s = fit.ttc_s - interval_s;
  if (fit.status == MotionStatus::approaching) {
    // A τ within the interval means contact is imminent; it stays positive, as approaching.
    f.ttc_s = std::max(f.ttc_s, kMinTtc_s);
  }
  f.fit = fit.quality;
  if (fit.status == MotionStatus::approaching || fit.status == MotionStatus::receding) {
    f.ttc_eq5_s = ttc_from_foe(samples, fit.foe, fit.ttc_s) - interval_s;
    if (fit.status == MotionStatus::approaching)
      f.ttc_eq5_s = std::max(f.ttc_eq5_s, kMinTtc_s);
  }
}

}  // namespace

std::span<const ObjectFeatures> FeatureExtractor::extract(const FlowField& field,
                                                          const Segmentation& segmentation,
                                                          double forward_speed_mps) {
  check_sizes_match(field, segmentation);
  const auto regions = static_cast<std::size_t>(segmentation.region_count());
  accumulators_.assign(regions, Accumulator{});
  if (region_pixels_.size() < regions) {
    region_pixels_.resize(regions);
  }
  for (std::size_t r = 0; r < regions; ++r) {
    region_pixels_[r].clear();
  }
  const auto flow = field.flow();
  const auto depth = field.depth();
  for_each_region_pixel(
      field, segmentation, [&](std::size_t i, int col, int row, std::int32_t label) {
        const float z = depth.empty() ? std::numeric_limits<float>::quiet_NaN() : depth[i];
        const auto r = static_cast<std::size_t>(label);
        if (accumulators_[r].add(field.x(col), field.y(row), z, flow[i])) {
          region_pixels_[r].push_back(static_cast<std::uint32_t>(i));
        }
      });
  if (depth.empty() && options_.ground_mount) {
    find_ground_contacts(field, segmentation, *options_.ground_mount, contacts_);
    for (const GroundContact& c : contacts_) {
      accumulators_[static_cast<std::size_t>(c.label)].add_contact(c.x, c.y, c.depth_m);
    }
  } else {
    contacts_.clear();
  }

  // Every region with enough valid vectors gets up to max_fit_samples of them, taken at an even
  // stride from its pixels in raster order.
  sample_offsets_.assign(regions + 1, 0);
  for (std::size_t r = 0; r < regions; ++r) {
    const int valid = static_cast<int>(region_pixels_[r].size());
    SampleStride s;
    if (segmentation.kinds[r] == RegionKind::visible && valid >= options_.min_pixels) {
      s = sample_stride(valid, options_.max_fit_samples);
    }
    sample_offsets_[r + 1] = sample_offsets_[r] + s.take;
    samples_.resize(static_cast<std::size_t>(sample_offsets_[r + 1]));
    take_samples(field, region_pixels_[r], s.stride,
                 accumulators_[r].inverse_mean_depth(options_.use_depth),
                 std::span(samples_).subspan(static_cast<std::size_t>(sample_offsets_[r]),
                                             static_cast<std::size_t>(s.take)));
  }

  features_.resize(regions);
  for (std::size_t r = 0; r < regions; ++r) {
    const Accumulator& a = accumulators_[r];
    ObjectFeatures& f = features_[r];
    f = ObjectFeatures{};
    f.label = static_cast<int>(r);
    f.source_id = segmentation.source_ids[r];
    f.kind = segmentation.kinds[r];
    a.describe(field, options_.ground_mount, f);
    const std::span<const FlowSample> region_samples(
        samples_.data() + sample_offsets_[r],
        static_cast<std::size_t>(sample_offsets_[r + 1] - sample_offsets_[r]));
    if (region_samples.empty()) {
      continue;  // not fitted: too few valid vectors, or not a visible region
    }
    const RadialFit fit =
        fit_region(region_samples, a.valid(), a.scales_by_depth(options_.use_depth), options_,
                   *fit_workspace_);
    set_motion_features(f, fit, region_samples, field.interval_s());
    if (depth.empty() && options_.ground_mount && !f.min_x_depth_m && f.fit.static_foe) {
      depths_from_static_flow(field, region_pixels_[r], forward_speed_mps, f);
    }
  }
  return features_;
}

namespace {

// Σ |x − f|², Σ (x − f)·u and Σ y over some of a region's vectors: a static surface's depth
// there, T_z Σ|x − f|² / Σ(x − f)·u (FeatureExtractor::extract).
struct FlowDepthSums {
  double square = 0.0;
  double along = 0.0;
  double sum_y = 0.0;
  int count = 0;

  void add(const Eigen::Vector2d& offset, const Eigen::Vector2d& flow, double y) {
    square += offset.squaredNorm();
    along += offset.dot(flow);
    sum_y += y;
    ++count;
  }
  FlowDepthSums& operator+=(const FlowDepthSums& other) {
    square += other.square;
    along += other.along;
    sum_y += other.sum_y;
    count += other.count;
    return *this;
  }
  // Empty where the vectors do not expand. Displacement flow over Δ is the instantaneous flow of
  // τ + Δ (flow_field.hpp).
  std::optional<double> depth_m(double interval_s, double forward_speed_mps) const {
    const double ttc_s = along > 0.0 ? square / along - interval_s : 0.0;
    return ttc_s > 0.0 ? std::optional(ttc_s * forward_speed_mps) : std::nullopt;
  }
};

// Whether an end's upper and lower halves stand at one depth, as an upright surface does, rather
// than at the floor's ratio of depths between their rows (a patch of floor the ground test
// missed): nearer 1 than that ratio, in proportion. Not where a half has no depth.
bool upright(const FlowDepthSums& upper, const FlowDepthSums& lower, const FlatGround& ground,
             double interval_s, double forward_speed_mps) {
  const auto upper_m = upper.depth_m(interval_s, forward_speed_mps);
  const auto lower_m = lower.depth_m(interval_s, forward_speed_mps);
  if (upper.count < kMinFlowDepthSamples / 2 || lower.count < kMinFlowDepthSamples / 2 ||
      !upper_m || !lower_m) {
    return false;
  }
  const auto floor_upper_m = ground.depth_at(0.0, upper.sum_y / upper.count);
  const auto floor_lower_m = ground.depth_at(0.0, lower.sum_y / lower.count);
  if (!floor_upper_m || !floor_lower_m) {
    return true;  // the upper half is above the horizon: no floor there
  }
  return *upper_m / *lower_m < std::sqrt(*floor_upper_m / *floor_lower_m);
}

}  // namespace

// FeatureExtractor::extract's ends' depths from flow, for a region without them: one lower than
// the camera and than kMaxFlowDepthHeight_m, each of whose ends is upright. Each end's columns
// within kFlowDepthColumns of it; an end too near the FOE (its flow there, the expansion, is too
// small to measure) or whose flow does not expand leaves both ends without.
void FeatureExtractor::depths_from_static_flow(const FlowField& field,
                                               std::span<const std::uint32_t> pixels,
                                               double forward_speed_mps, ObjectFeatures& f) const {
  if (!(forward_speed_mps > 0.0) || f.status != MotionStatus::approaching) {
    return;
  }
  const auto width = static_cast<std::uint32_t>(field.width());
  double top_y = std::numeric_limits<double>::infinity();
  double bottom_y = -top_y;
  for (const std::uint32_t i : pixels) {
    top_y = std::min(top_y, field.y(static_cast<int>(i / width)));
    bottom_y = std::max(bottom_y, field.y(static_cast<int>(i / width)));
  }
  const FlatGround ground(*options_.ground_mount);
  // Lower than the camera: not someone walking at it.
  if (!ground.depth_at(0.0, top_y)) {
    return;
  }
  const double band = kFlowDepthColumns / field.intrinsics().fx_px;
  const double middle_y = 0.5 * (top_y + bottom_y);
  std::array<std::array<FlowDepthSums, 2>, 2> sums{};  // [end][upper, lower half]
  for (const std::uint32_t i : pixels) {
    const Eigen::Vector2d x(field.x(static_cast<int>(i % width)),
                            field.y(static_cast<int>(i / width)));
    const int end = x.x() <= f.min_x + band ? 0 : x.x() >= f.max_x - band ? 1 : -1;
    if (end >= 0) {
      sums[end][x.y() > middle_y ? 1 : 0].add(x - f.foe, field.flow()[i].cast<double>(), x.y());
    }
  }
  std::array<double, 2> depth_m{};
  for (int end = 0; end < 2; ++end) {
    FlowDepthSums whole = sums[end][0];
    whole += sums[end][1];
    const auto measured_m = whole.depth_m(field.interval_s(), forward_speed_mps);
    if (whole.count < kMinFlowDepthSamples || !measured_m ||
        whole.square / whole.count < kMinFlowDepthOffset * kMinFlowDepthOffset ||
        !upright(sums[end][0], sums[end][1], ground, field.interval_s(), forward_speed_mps)) {
      return;
    }
    depth_m[end] = *measured_m;
  }
  // No higher than a knee: a box or a kerb is, someone walking at the camera seen whole is not.
  const base::CameraMount& mount = *options_.ground_mount;
  const double top_height_m =
      mount.height_m - 0.5 * (depth_m[0] + depth_m[1]) *
                           (top_y * std::cos(mount.pitch_rad) + std::sin(mount.pitch_rad));
  if (!(top_height_m < kMaxFlowDepthHeight_m)) {
    return;
  }
  f.min_x_depth_m = depth_m[0];
  f.max_x_depth_m = depth_m[1];
  const bool left_nearer = squared_range(depth_m[0], f.min_x) < squared_range(depth_m[1], f.max_x);
  f.nearest_x = left_nearer ? f.min_x : f.max_x;
  f.nearest_depth_m = left_nearer ? depth_m[0] : depth_m[1];
}

}  // namespace flowsteer::servo
