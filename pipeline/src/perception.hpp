#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/pipeline/perception_options.hpp"
#include "flowsteer/servo/dark_regions.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/obstacle_memory.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/servo/segmentation.hpp"
#include "flowsteer/servo/untextured_fill.hpp"

namespace flowsteer::pipeline {

class MotionHistory;

// One frame through the servo core's perception: flow (the renderer's, or computed from this
// frame and older ones) derotated with the measured turn rate, ground removal, segmentation,
// dark regions and per-object features. Brain's, and private to pipeline.
class Perception {
 public:
  Perception(const base::CameraIntrinsics& intrinsics, const PerceptionOptions& options);
  ~Perception();

  // speed_mps and turn_rate_cy are what the base measured (turn rate positive to the right) over
  // the interval that ends with this frame; numerical flow spans several frames and is computed
  // against the older image turned by the rotation these give over its span (rotation
  // compensation), so it comes out derotated.
  // Anything but FlowStatus::ok leaves no objects: the first frame, a frame of another size, a
  // single-colour frame. Throws std::invalid_argument when the options need simulator channels
  // the frame does not carry.
  servo::FlowStatus process(const camera_io::Frame& frame, double speed_mps, double turn_rate_cy,
                            StageTimes& times);

  // Whether process reads the frame's image (numerical flow, dark regions, grey in the flow
  // segmentation) rather than only the simulator's channels.
  bool reads_image() const;
  const base::CameraIntrinsics& intrinsics() const { return field_.intrinsics(); }
  servo::FlowStatus status() const { return status_; }
  const servo::FlowField& flow() const { return field_; }
  const servo::Segmentation& segmentation() const { return segmentation_; }
  std::span<const servo::ObjectFeatures> objects() const { return objects_; }
  // One entry per pixel: 1 where the flow was not measured but filled (UntexturedFill); empty
  // before the first numerical flow.
  std::span<const std::uint8_t> filled_pixels() const { return untextured_fill_.filled(); }

 private:
  // Carries the memory to this frame, shows it the frame's static obstacles (seen moving at
  // flow_speed_mps over the flow's interval), and returns the extracted objects with the memory's
  // recalled ones after them.
  std::span<const servo::ObjectFeatures> with_remembered(double timestamp_s, double speed_mps,
                                                         double turn_rate_cy,
                                                         double flow_speed_mps);
  bool segments_by_grey() const;

  PerceptionOptions options_;
  servo::FlowField field_;
  std::unique_ptr<servo::FlowSource> flow_source_;
  std::optional<servo::FlowSegmenter> segmenter_;
  std::optional<double> segmented_at_s_;  // the frame the segmenter last saw
  servo::GroundRegionMarker ground_regions_;
  servo::UntexturedFill untextured_fill_;
  servo::DarkRegionFinder dark_finder_;
  servo::FeatureExtractor extractor_;
  servo::Segmentation segmentation_;
  std::vector<std::uint8_t> ground_mask_;
  std::unique_ptr<MotionHistory> motions_;  // what the base measured, frame by frame
  cv::Mat grey_;
  std::optional<servo::ObstacleMemory> memory_;
  std::optional<double> memory_time_s_;                 // of the last frame the memory saw
  std::vector<servo::ObjectFeatures> percept_objects_;  // the features' and the memory's
  std::span<const servo::ObjectFeatures> objects_;
  servo::FlowStatus status_ = servo::FlowStatus::no_previous_frame;
};

}  // namespace flowsteer::pipeline
