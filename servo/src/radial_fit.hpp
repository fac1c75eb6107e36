#pragma once

// Internal to servo: the robust radial fit's workspace and the tests FeatureExtractor runs on a
// region's fit. Unit tests include it from servo/src.

#include <limits>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "flowsteer/servo/features.hpp"

namespace flowsteer::servo {

// The buffers and solvers of the robust radial fit, kept from fit to fit (FeatureExtractor keeps
// one): with them a fit allocates only when Ceres' solver meets another sample count than the
// last fit's, where it resizes its own matrices. One per thread.
class RadialFitWorkspace {
 public:
  RadialFitWorkspace();
  ~RadialFitWorkspace();
  RadialFitWorkspace(RadialFitWorkspace&&) noexcept;
  RadialFitWorkspace& operator=(RadialFitWorkspace&&) noexcept;

  struct Buffers;  // defined where the fit is
  Buffers& buffers() { return *buffers_; }

 private:
  std::unique_ptr<Buffers> buffers_;
};

// fit_radial_flow (features.hpp) with the workspace given.
RadialFit fit_radial_flow(std::span<const FlowSample> samples, const RadialFitOptions& options,
                          RadialFitWorkspace& workspace);

// The same robust fit with the FOE given: only 1/τ is fitted, u_j = (x_j − foe)/τ.
RadialFit fit_radial_flow_about(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                                const RadialFitOptions& options, RadialFitWorkspace& workspace);
RadialFit fit_radial_flow_about(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                                const RadialFitOptions& options = {});

// Wald statistic of the hypothesis that the flow fitted in `fit` expands about `foe`: χ² with 2
// degrees of freedom, 0 for a perfect match. `covariance_scale` widens the fit's covariance where
// its samples are not independent (an estimator's errors are correlated over its window). +∞
// when the fit has no covariance.
double foe_hypothesis_statistic(const RadialFit& fit, const Eigen::Vector2d& foe,
                                double covariance_scale = 1.0);

// Two readings of the same flow, each fitted by linear least squares with three parameters:
// a static plane while the camera translates towards `static_foe` (u_j = (x_j − f)(a x_j + b y_j
// + c): a static point's flow points away from the FOE, scaled by the inverse depth, which is
// linear in the image point on a plane), and the radial model of CGF Eq. 2–3 with a free FOE
// (u_j = (x_j − f')/τ, fronto-parallel: one depth). The residual sums of squares over both
// components of every sample; NaN when either system is singular (fewer than three samples, or
// samples on a line through the FOE).
struct SurfaceResiduals {
  double static_plane = std::numeric_limits<double>::quiet_NaN();
  double radial = std::numeric_limits<double>::quiet_NaN();
};
SurfaceResiduals static_surface_residuals(std::span<const FlowSample> samples,
                                          const Eigen::Vector2d& static_foe);

// CGF Eq. 5: τ = mean_j ‖x_j − f‖ / ‖u_j‖, over samples with a non-negligible flow, signed
// like `sign_from`. NaN when no sample qualifies.
double ttc_from_foe(std::span<const FlowSample> samples, const Eigen::Vector2d& foe,
                    double sign_from);

}  // namespace flowsteer::servo
