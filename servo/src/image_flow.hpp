#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/optflow.hpp>
#include <opencv2/video/tracking.hpp>

#include "flowsteer/servo/optical_flow.hpp"
#include "ground_motion_check.hpp"

namespace flowsteer::servo {

// Flow estimated from two images of the frame's camera, by an algorithm of OpenCV's: what the
// estimators share (the images kept for the baseline, the rotation compensation, the texture
// test, the units). Each algorithm is a class below that only runs its estimator.
class ImageFlowEstimator : public FlowSource {
 public:
  // On ok the field's interval is the baseline the flow spans. The older image is turned to the
  // newer one's orientation by motion.between before the estimator runs (MIG's rotation
  // compensation), so the estimator sees only the translational flow and the field comes out
  // derotated: a turning agent otherwise hands the estimator displacements of 20 px and more at
  // the edge of a wide view, which DIS falls short of by a quarter, and derotating afterwards
  // leaves that shortfall in every vector as spurious motion. Given the base's travel and the
  // camera's mount, a pixel whose patch the flat ground's motion matches better than the
  // estimator's flow takes the ground's (GroundMotionCheck). Pixels whose ray the older image
  // did not see get NaN. On any status but ok the image (when it has texture) is kept as the
  // start of the next pair.
  FlowStatus update(const FlowFrame& frame, const CameraMotion& motion, FlowField& field) final;
  void reset() final;
  bool estimated() const final { return true; }
  double image_noise_grey() const final { return noise_grey_; }
  std::span<const Eigen::Vector2f> edge_flow() const final { return edge_flow_; }

 protected:
  // Throws std::invalid_argument when baseline_s or a ground_match option is negative or
  // max_kept_images below 1.
  explicit ImageFlowEstimator(const OpticalFlowOptions& options);

  // Pixel displacements (CV_32FC2) from `from` to `to`, at the pixels of `from`. displacement_px
  // holds the previous pair's, or nothing after reset(): DIS starts from it (a warm start, which
  // its coarsest scales then correct), the others ignore it.
  virtual void calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) = 0;

 private:
  void keep(double timestamp_s);

  OpticalFlowOptions options_;
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
  cv::Mat noise_response_;
  GroundMotionCheck ground_check_;
  double noise_grey_ = 0.0;
  std::vector<Eigen::Vector2f> edge_flow_;
};

// Dense inverse search (Kroeger et al. 2016) at one of OpenCV's presets
// (cv::DISOpticalFlow::PRESET_ULTRAFAST, PRESET_FAST, PRESET_MEDIUM).
class DisFlow final : public ImageFlowEstimator {
 public:
  DisFlow(int preset, const OpticalFlowOptions& options);
  double noise_correlation_px() const override;

 private:
  void calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) override;

  cv::Ptr<cv::DISOpticalFlow> algorithm_;
};

// Farneback's polynomial expansion, at OpenCV's defaults.
class FarnebackFlow final : public ImageFlowEstimator {
 public:
  explicit FarnebackFlow(const OpticalFlowOptions& options);
  double noise_correlation_px() const override;

 private:
  void calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) override;

  cv::Ptr<cv::FarnebackOpticalFlow> algorithm_;
};

// Dual TV-L1 (Zach et al. 2007), at OpenCV's defaults.
class TvL1Flow final : public ImageFlowEstimator {
 public:
  explicit TvL1Flow(const OpticalFlowOptions& options);
  double noise_correlation_px() const override;

 private:
  void calc(const cv::Mat& from, const cv::Mat& to, cv::Mat& displacement_px) override;

  cv::Ptr<cv::optflow::DualTVL1OpticalFlow> algorithm_;
};

}  // namespace flowsteer::servo
