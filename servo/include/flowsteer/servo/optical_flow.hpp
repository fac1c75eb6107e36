#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

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

// Side in pixels of the window over which a method's errors are correlated: the patch (DIS, at
// its finest scale), the averaging window (Farneback) or the median filter (TV-L1); 1 for the
// synthetic flow. Flow vectors closer than this are not independent measurements.
double noise_correlation_px(FlowMethod method);

// What became of one image given to OpticalFlow::update.
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

struct OpticalFlowOptions {
  // Pixels whose neighbourhood has less image gradient than this in its least textured
  // direction (RMS over a 5×5 window, grey levels per pixel) get no flow: estimators fill such
  // areas by smoothing, which invents motion there (sky, blank walls, along straight edges).
  double min_gradient = 0.5;
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
};

// Dense optical flow between consecutive images, in the servo core's units: normalised image
// coordinates per second at the pixels of the newer image (the convention of CGF Eq. 1), so the
// rest of the pipeline cannot tell it from the renderer's flow. The flow is not derotated.
class OpticalFlow {
 public:
  // Throws std::invalid_argument for FlowMethod::synthetic, which has no images to compute from.
  explicit OpticalFlow(FlowMethod method, const OpticalFlowOptions& options = {});
  ~OpticalFlow();
  OpticalFlow(OpticalFlow&&) noexcept;
  OpticalFlow& operator=(OpticalFlow&&) noexcept;

  FlowMethod method() const { return method_; }

  // Takes the next image (8-bit grey or BGR) taken at timestamp_s (monotonic). On ok, every
  // vector of `field` is set: flow, or NaN where the image has too little texture to show it.
  // On any other status `field` is left untouched and the image (when it has texture) is kept as
  // the start of the next pair. Throws std::invalid_argument when the image is not 8-bit with 1
  // or 3 channels.
  FlowStatus update(const cv::Mat& image, double timestamp_s, FlowField& field);

  // The camera's rotation between two times (from_s older): R with a static point's direction p
  // in the newer image at R p in the older one (rotation_over in flow_field.hpp).
  using RotationBetween = std::function<Eigen::Matrix3d(double from_s, double to_s)>;

  // As above, with the rotation the base measured compensated before the estimator runs (MIG's
  // rotation compensation): the older image is warped to the newer image's orientation, so the
  // estimator sees only the translational flow and the field comes out derotated. A turning
  // agent otherwise hands the estimator displacements of 20 px and more at the edge of a wide
  // view, which DIS falls short of by a quarter; the derotation then leaves that shortfall in
  // every vector as spurious motion. Pixels whose ray the older image did not see get NaN.
  FlowStatus update(const cv::Mat& image, double timestamp_s, FlowField& field,
                    const RotationBetween& rotation);

  // Forgets the previous images: the next update returns no_previous_frame.
  void reset();

 private:
  struct Estimator;
  void keep(double timestamp_s);

  FlowMethod method_;
  OpticalFlowOptions options_;
  std::unique_ptr<Estimator> estimator_;
  struct KeptImage {
    cv::Mat grey;
    double timestamp_s = 0.0;
  };
  // A ring of the newest images, oldest first from kept_begin_.
  std::vector<KeptImage> kept_;
  std::size_t kept_begin_ = 0;
  std::size_t kept_count_ = 0;
  cv::Mat grey_;
  cv::Mat flow_px_;
  cv::Mat gradient_x_;
  cv::Mat gradient_y_;
  cv::Mat gradient_product_;
  cv::Mat tensor_xx_;
  cv::Mat tensor_xy_;
  cv::Mat tensor_yy_;
  cv::Mat warped_;
};

}  // namespace flowsteer::servo
