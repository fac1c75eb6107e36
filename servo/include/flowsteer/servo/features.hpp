#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

// What the radial-flow fit found for an object.
enum class MotionStatus : std::uint8_t {
  approaching,  // τ > 0: the FOE and τ are valid
  receding,     // τ < 0: the object moves away; the FOE is valid (a focus of contraction)
  lateral,      // no expansion: the FOE is at infinity, τ is infinite
  no_flow,      // not fitted: a dark region, or too few valid flow vectors
};

const char* to_string(MotionStatus status);

struct FitQuality {
  int samples = 0;               // flow vectors the robust fit used
  int iterations = 0;            // solver iterations, all rounds together
  double residual_rms = 0.0;     // over the inliers, normalised units per second
  double inlier_fraction = 0.0;  // share of samples within the inlier threshold
  // The flow could not be told from a static object's (FeatureOptions::static_foe and
  // static_surface_rss_ratio): the FOE is the static one and τ was fitted about it.
  bool static_foe = false;
};

// Moments of the derotated flow over a region, for velocity alignment (CGF Eq. 11).
struct FlowMoments {
  double mean_u = 0.0;   // (Σ u_j) / N
  double mean_xu = 0.0;  // (Σ x_j u_j) / N
  // Present when every valid pixel has a finite depth.
  std::optional<double> mean_inv_depth;    // (Σ 1/Z_j) / N, 1/m
  std::optional<double> mean_x_inv_depth;  // (Σ x_j/Z_j) / N, 1/m
};

// The visual features of one region (CGF §5).
struct ObjectFeatures {
  int label = Segmentation::kNoRegion;
  std::int32_t source_id = -1;
  RegionKind kind = RegionKind::visible;
  int pixel_count = 0;
  int invalid_flow_count = 0;  // NaN/Inf vectors, ignored

  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // g: centroid, normalised
  double width = 0.0;                                // horizontal extent, normalised
  double min_x = 0.0;  // leftmost and rightmost pixel centres, normalised
  double max_x = 0.0;
  // The region reaches the left / right edge of the image. The object may go on past that edge:
  // on a cut side, centre, width and min_x / max_x describe the visible part only.
  bool cut_left = false;
  bool cut_right = false;
  std::optional<double> depth_m;  // mean depth when the field has depth
  // Depth of the nearest point in the leftmost / rightmost column, when the field has depth: the
  // two ends of a wall along the path are at very different depths.
  std::optional<double> min_x_depth_m;
  std::optional<double> max_x_depth_m;
  // The region's point nearest the camera on the ground, Z √(1 + x²) smallest, at image column
  // nearest_x and depth nearest_depth_m, when the field has depth: a building seen at its corner is
  // nearest there, and the line between its ends passes behind the corner.
  double nearest_x = 0.0;
  std::optional<double> nearest_depth_m;

  MotionStatus status = MotionStatus::no_flow;
  Eigen::Vector2d foe = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double ttc_s = std::numeric_limits<double>::quiet_NaN();      // from the fit
  double ttc_eq5_s = std::numeric_limits<double>::quiet_NaN();  // CGF Eq. 5, for comparison
  FitQuality fit;
  FlowMoments moments;

  bool has_foe() const {
    return status == MotionStatus::approaching || status == MotionStatus::receding;
  }
};

// One flow vector u at normalised point x.
struct FlowSample {
  Eigen::Vector2d point;
  Eigen::Vector2d flow;
  // |u| as the flow source gave it, before derotation took the camera's turn out, scaled as
  // `flow` is: float flow is exact only to that. The fit's rounding floor follows the larger of
  // it and |flow|.
  double delivered_norm = 0.0;
};

struct RadialFitOptions {
  int max_rounds = 2;             // Cauchy rounds, each re-estimating the noise scale (+2 Tukey)
  int max_iterations = 10;        // TinySolver iterations per round
  double inlier_threshold = 3.0;  // in robust standard deviations
  // |1/τ| below this (1/s) means no expansion: the motion is lateral.
  double min_inverse_ttc = 1e-3;
};

struct RadialFit {
  MotionStatus status = MotionStatus::no_flow;
  Eigen::Vector2d foe = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double ttc_s = std::numeric_limits<double>::quiet_NaN();
  FitQuality quality;
  // The fitted parameters p = (1/τ, −f_x/τ, −f_y/τ) of u = p0 x + (p1, p2), which stay finite
  // when the motion is lateral, and their covariance: the sandwich over the last robust round's
  // weights, each sample counted as an independent measurement.
  Eigen::Vector3d parameters = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Matrix3d parameter_covariance =
      Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// Fits the radial model u_j = (x_j − f)/τ (CGF Eq. 2–3) to the samples: a robust M-estimate
// (Cauchy, then Tukey) by iteratively reweighted least squares with Ceres' TinySolver, the noise
// scale re-estimated each round and relative to the flow's magnitude, so that noisy numerical
// flow and outliers do not pull the FOE. Needs at least 3 samples; fewer give status no_flow.
RadialFit fit_radial_flow(std::span<const FlowSample> samples,
                          const RadialFitOptions& options = {});

struct FeatureOptions {
  // Smaller regions are reported with status no_flow. Four pixels give the fit eight equations
  // for its three parameters. A higher floor hides objects that are small only because the
  // image is coarse: at 48² with a 150° view a car 14 m away near the edge of the view is two
  // rows by a few columns; with 12 it dropped in and out of the percept, and each time it came
  // back it gave a full-size command.
  int min_pixels = 4;
  int max_fit_samples = 256;  // pixels of a region the robust fit uses, evenly spread
  // Where the field has depth (a simulator), fit the flow scaled to the region's mean depth, so
  // that slanted and curved surfaces give the FOE and the TTC at that depth exactly.
  bool use_depth = true;
  RadialFitOptions fit;
  // The FOE of every static object's derotated flow (base::CameraMount::forward_foe). When set, a
  // region whose fitted FOE is consistent with it (Wald statistic below static_foe_chi2) gets
  // it, and its τ is fitted about it. Flow noise scatters a static object's FOE, and without
  // depth a slanted surface pulls it towards its near end; the avoidance term's acceleration
  // gradient (CGF Eq. 10, (τ/Z) f) then takes the same sign for every obstacle beside the path,
  // and the agent speeds up. Only a region whose flow shows that it moves keeps its own FOE.
  std::optional<Eigen::Vector2d> static_foe;
  double static_foe_chi2 = 9.21;  // 99% of a static object's FOEs pass
  // Side in pixels of the window over which the flow's errors are correlated: 1 for exact flow,
  // about an estimator's patch at its finest scale otherwise. Samples closer than this are not
  // independent, which widens the fit's covariance for the test above.
  double flow_noise_correlation_px = 1.0;
  // Without depth (numerical flow), a region is also static when a static plane explains its
  // flow nearly as well as the radial model with a free FOE: residual sums of squares (of
  // static_surface_residuals) plane <= this × radial; 0 turns it off. The radial model is a
  // surface facing the camera; a wall along the path, whose near end expands faster, fits it only
  // with the FOE moved towards that end, a misfit no noise model of the Wald test covers. The
  // margin above 1 leans towards the static reading, which most of what a moving camera sees is;
  // it was chosen by sweeps of `room` and `crossing` with DIS flow over camera resolutions.
  double static_surface_rss_ratio = 1.5;
  // Where the field has no depth (a camera), the mount of a camera above a flat ground: each
  // region that rises above the horizon gets, for its ends and nearest point, the depth of the
  // ground where it stands on it (its lowest pixels, with ground below them),
  // Z = h / (y cos θ + sin θ); in the bottom row, the ground's depth at the image's lower edge,
  // which bounds the hidden foot's from above. An end whose column shows no contact (standing
  // behind another region) leaves both ends without depth; the mean depth (depth_m) stays empty.
  std::optional<base::CameraMount> ground_mount;
};

// A point where a visible region stands on the ground (FeatureOptions::ground_mount): the
// region's pixel (x, y), and the ground's depth at (x, ground_y), the row below it.
struct GroundContact {
  int label = Segmentation::kNoRegion;
  double x = 0.0;  // normalised
  double y = 0.0;
  double ground_y = 0.0;
  double depth_m = 0.0;
  // In the bottom row: the foot is below the image, and depth_m only bounds its depth from above.
  bool below_image = false;
};

// Extracts per-region features from a derotated flow field. Keeps its scratch buffers between
// calls so that a steady stream of frames does not allocate per pixel; one extractor per
// thread.
class RadialFitWorkspace;

class FeatureExtractor {
 public:
  explicit FeatureExtractor(const FeatureOptions& options = {});
  ~FeatureExtractor();
  FeatureExtractor(FeatureExtractor&&) noexcept;
  FeatureExtractor& operator=(FeatureExtractor&&) noexcept;

  // Features of every region of `segmentation`, in label order. Throws std::invalid_argument
  // when the segmentation does not match the field's size. With a camera's depths (a
  // ground_mount, no depth per pixel) and the camera's forward speed over the flow's interval
  // (the speed along the optical axis, m/s), a region that stands still (the static FOE) but
  // shows no ground contact under an end gets its ends' depths from its flow there: a static
  // point at x closes in at that speed, so its flow is u = (x − f) T_z / Z (CGF Eq. 2,
  // τ = Z / T_z) and Z = T_z |x − f|² / ((x − f)·u), over the end's columns (McCarthy, Barnes and
  // Srinivasan, ICRA 2007): a face of a box split from the rest, a box whose foot a nearer object
  // hides. Only what is upright (not a patch of floor), lower than the camera and no higher than
  // a knee: someone walking straight at the camera has the same flow at twice that depth
  // (docs/NAVIGATION.md, "Depth").
  std::span<const ObjectFeatures> extract(const FlowField& derotated,
                                          const Segmentation& segmentation,
                                          double forward_speed_mps = 0.0);
  // The ground contacts the last extract found (without depth and with a ground_mount only).
  std::span<const GroundContact> contacts() const { return contacts_; }

 private:
  struct Accumulator;
  void depths_from_static_flow(const FlowField& field, std::span<const std::uint32_t> pixels,
                               double forward_speed_mps, ObjectFeatures& f) const;
  FeatureOptions options_;
  std::vector<Accumulator> accumulators_;
  std::vector<std::vector<std::uint32_t>> region_pixels_;  // valid pixels of each region
  std::vector<FlowSample> samples_;
  std::vector<int> sample_offsets_;
  std::vector<ObjectFeatures> features_;
  std::vector<GroundContact> contacts_;
  std::unique_ptr<RadialFitWorkspace> fit_workspace_;
};

}  // namespace flowsteer::servo
