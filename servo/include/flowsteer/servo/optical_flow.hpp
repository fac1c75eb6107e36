#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::servo {

// Where an agent's flow comes from: the renderer's exact flow (synthetic), or computed from two
// consecutive images by one of OpenCV's dense estimators.
enum class FlowMethod { synthetic, dis_ultrafast, dis_fast, dis_medium, farneback, tvl1 };

std::string_view to_string(FlowMethod method);
// Empty when `name` is none of the names to_string gives.
std::optional<FlowMethod> parse_flow_method(std::string_view name);
// "synthetic, dis_ultrafast, ...": every name parse_flow_method accepts, for messages.
std::string flow_method_names();
// Every method that computes flow from images, in the order tables list them.
std::span<const FlowMethod> numerical_flow_methods();

// What became of one frame given to FlowSource::update.
enum class FlowStatus {
  ok,
  no_previous_frame,  // the first image, or the first after reset(): nothing to compare with
  size_changed,       // the image's size differs from the previous one's or the field's
  empty_frame,        // an empty image
  untextured,         // a single-colour image: no motion can be seen in it
  no_time_elapsed,    // the timestamp is the previous image's
  time_went_back,     // the timestamp is before the previous image's (a camera or a recording
                      // whose clock jumped back): the image starts the history again
};

const char* to_string(FlowStatus status);

// The estimators' options (every method but synthetic).
struct OpticalFlowOptions {
  // Pixels whose neighbourhood has less image gradient than this in its least textured
  // direction (RMS over a 5×5 window, grey levels per pixel) get no flow: estimators fill such
  // areas by smoothing, which invents motion there (sky, blank walls, along straight edges).
  double min_gradient = 0.5;
  // ...or than this many times the image's noise (grey levels, measured on each image): noise
  // alone has an RMS gradient of 0.43 σ along any direction, which this keeps out.
  double min_gradient_per_noise = 1.0;
  // An image whose grey levels span less than this is single-coloured.
  double min_contrast = 2.0;
  // The flow compares each image with the newest kept image at least this much older (or the
  // oldest kept while fewer are at hand): a walker moves 5 cm between frames at 20 Hz, which
  // moves most of the image by a fraction of a pixel, below the estimators' error. A longer
  // baseline gives displacements they resolve; too long, and near objects move further than
  // they follow (at 0.4 s DIS fell 25% short on a box 1.2 m ahead, which then passed for
  // ground). `flowsteer eval flow` measures the choice.
  double baseline_s = 0.2;
  int max_kept_images = 8;
  // Over that baseline the near ground moves tens of pixels, and DIS falls short on it (at 128²,
  // ground regions in the view's lowest eighth had a third of the ground's motion). Where the
  // camera's travel and mount are given (CameraMotion), each textured pixel below the horizon whose
  // 5×5 patch the flat ground's motion matches (mean squared grey difference against the older
  // image warped each way) below ground_match_ratio of what the estimator's own flow matches, and
  // as well as a motion within ground_match_px of the true one would (ground_match_px² times the
  // patch's mean squared gradient, plus ground_match_noise_margin σ², σ the image noise
  // measured), takes the ground's flow. An upright object near its foot moves as the floor
  // there; the bound keeps that band to where the two differ by less than ground_match_px, about
  // a centimetre at a robot's camera. A ratio of 0 never tests the ground.
  double ground_match_ratio = 0.7;
  double ground_match_px = 1.0;
  double ground_match_noise_margin = 4.0;
};

// The renderer's flow as it comes, or as a camera would see it.
struct RendererFlowOptions {
  // No flow where the renderer's depth is not finite (the sky): a camera's sky has no texture to
  // show motion by.
  bool no_flow_without_depth = false;
};

// One frame as a flow source reads it.
struct FlowFrame {
  const cv::Mat& image;  // 8-bit grey or BGR; the renderer's flow does not read it
  double timestamp_s = 0.0;
  // The renderer's flow (CV_32FC2, in the field's units) and depth (CV_32FC1, metres): null
  // unless a simulator rendered the frame.
  const cv::Mat* renderer_flow = nullptr;
  const cv::Mat* renderer_depth_m = nullptr;
};

// How far the base drove and turned between two times, as its odometry measured it.
struct BaseTravel {
  double path_m = 0.0;      // along its path, forward positive
  double turned_rad = 0.0;  // left positive
};

// The camera's motion as the base measured it. Every source takes the rotation out of its flow;
// an estimator told the travel and the camera's mount also tests its flow against the flat
// ground's motion (OpticalFlowOptions::ground_match_ratio).
struct CameraMotion {
  // At the frame's time, in the camera frame (camera_angular_velocity): instantaneous flow is
  // derotated by it.
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  // Between two times (from_s older): R with a static point's direction p in the newer image at
  // R p in the older one (rotation_over). Empty: the camera did not turn.
  std::function<Eigen::Matrix3d(double from_s, double to_s)> between;
  // Between two times (from_s older). Empty, or without ground_mount: no ground is tested.
  std::function<BaseTravel(double from_s, double to_s)> travelled;
  // The camera's height and pitch over a flat ground.
  std::optional<base::CameraMount> ground_mount;
};

// Dense optical flow, one class per algorithm behind one interface, as OpenCV's
// cv::DenseOpticalFlow: the renderer's exact flow and each of OpenCV's estimators. Every source
// gives flow in the servo core's units, normalised image coordinates per second at the pixels of
// the newer image (the convention of CGF Eq. 1), derotated, so that the rest of the pipeline
// cannot tell them apart but by their errors.
class FlowSource {
 public:
  virtual ~FlowSource() = default;

  // Takes the next frame, taken at frame.timestamp_s (monotonic). On ok, every vector of `field`
  // is set: flow with the rotation taken out, or NaN where the flow is not known. On any other
  // status `field` is left untouched. Throws std::invalid_argument when the frame lacks what the
  // source reads, or an estimator's image is not 8-bit with 1 or 3 channels.
  virtual FlowStatus update(const FlowFrame& frame, const CameraMotion& motion,
                            FlowField& field) = 0;

  // Forgets the previous frames: an estimator's next update returns no_previous_frame.
  virtual void reset() = 0;

  // Whether the flow is estimated from the frame's image, with an estimator's error, rather than
  // read from the renderer.
  virtual bool estimated() const = 0;

  // Side in pixels of the window over which the flow's errors are correlated: the patch (DIS, at
  // its finest scale), the averaging window (Farneback) or the median filter (TV-L1); 1 for the
  // renderer's flow. Flow vectors closer than this are not independent measurements.
  virtual double noise_correlation_px() const = 0;

  // The standard deviation of the last image's noise in grey levels, as measured on it; 0 for the
  // renderer's flow, which reads no image.
  virtual double image_noise_grey() const { return 0.0; }

  // After an ok update, one entry per pixel: where the texture test left no flow but the image has
  // an edge (its gradient passes the test across the edge, not along it), the flow's component
  // across the edge, the one the aperture problem leaves measurable (normal flow, as a vector
  // along the gradient); NaN elsewhere. Empty for sources that read no image.
  virtual std::span<const Eigen::Vector2f> edge_flow() const { return {}; }
};

// The source of `method`: the renderer's flow (synthetic) with `renderer`, else OpenCV's
// estimator with `estimator`. Throws std::invalid_argument when an estimator's baseline_s is
// negative or max_kept_images below 1.
std::unique_ptr<FlowSource> make_flow_source(FlowMethod method,
                                             const OpticalFlowOptions& estimator = {},
                                             const RendererFlowOptions& renderer = {});

}  // namespace flowsteer::servo
