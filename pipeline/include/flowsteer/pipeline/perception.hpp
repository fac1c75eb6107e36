#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/servo/dark_regions.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/servo/servo.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::pipeline {

// Time of each stage of one agent step, in milliseconds.
struct StageTimes {
  double render = 0.0;
  double flow = 0.0;
  double segment = 0.0;
  double features = 0.0;
  double control = 0.0;
  double total = 0.0;

  StageTimes& operator+=(const StageTimes& other);
};

// How an agent sees: where its flow comes from, how it finds objects, whether it looks for dark
// regions. The same choices serve a simulated agent and a robot; the synthetic flow and semantic
// segmentation need a simulator's frames.
struct PerceptionOptions {
  servo::FlowMethod flow = servo::FlowMethod::synthetic;
  servo::SegmentationMethod segmentation = servo::SegmentationMethod::semantic;
  bool dark_regions = false;  // MIG 2019's dark-region awareness
  // With synthetic flow, give the feature fit the renderer's depth (numerical flow has none).
  bool use_depth = true;
  // With synthetic flow, whose depths the features get: the renderer's at every pixel, or the
  // ground's only, a camera's (servo::DepthSource).
  servo::DepthSource depth = servo::DepthSource::renderer;
  base::CameraMount mount;
  servo::OpticalFlowOptions optical_flow;
  servo::FlowSegmentationOptions flow_segmentation;
  servo::DarkRegionOptions dark;
  servo::GroundRemovalOptions ground;
  // Numerical flow's error in pixels over its interval: the ground test allows it on top of its
  // relative tolerance, since the ground left over joins every object standing on it.
  double numerical_flow_noise_px = 0.3;
};

class MotionHistory;

// One frame through the servo core's perception: flow (from the simulator or computed from this
// frame and the previous one), derotation with the measured turn rate, ground removal,
// segmentation, dark regions and per-object features.
class Perception {
 public:
  Perception(const base::CameraIntrinsics& intrinsics, const PerceptionOptions& options);
  ~Perception();
  Perception(Perception&&) noexcept;
  Perception& operator=(Perception&&) noexcept;

  // speed_mps and turn_rate_cy are what the base measured (turn rate positive to the right) over
  // the interval that ends with this frame; numerical flow spans several frames and is computed
  // against the older image turned by the rotation these give over its span (rotation
  // compensation), so it comes out derotated.
  // Anything but FlowStatus::ok leaves no objects: the first frame, a frame of another size, a
  // single-colour frame. Throws std::invalid_argument when the options need simulator channels
  // the frame does not carry.
  servo::FlowStatus process(const camera_io::Frame& frame, double speed_mps, double turn_rate_cy,
                            StageTimes& times);

  const PerceptionOptions& options() const { return options_; }
  // Whether process reads the frame's image (numerical flow, dark regions) rather than only the
  // simulator's channels.
  bool reads_image() const;
  const base::CameraIntrinsics& intrinsics() const { return field_.intrinsics(); }
  servo::FlowStatus status() const { return status_; }
  const servo::FlowField& flow() const { return field_; }
  const servo::Segmentation& segmentation() const { return segmentation_; }
  std::span<const servo::ObjectFeatures> objects() const { return objects_; }
  // 1 where the last frame's ground test found ground (flow segmentation only).
  std::span<const std::uint8_t> ground_mask() const { return ground_mask_; }

 private:
  PerceptionOptions options_;
  servo::FlowField field_;
  std::optional<servo::OpticalFlow> optical_flow_;
  std::optional<servo::FlowSegmenter> segmenter_;
  servo::GroundRegionMarker ground_regions_;
  servo::DarkRegionFinder dark_finder_;
  servo::FeatureExtractor extractor_;
  servo::Segmentation segmentation_;
  std::vector<std::uint8_t> ground_mask_;
  std::unique_ptr<MotionHistory> motions_;  // what the base measured, frame by frame
  cv::Mat grey_;
  std::span<const servo::ObjectFeatures> objects_;
  servo::FlowStatus status_ = servo::FlowStatus::no_previous_frame;
};

}  // namespace flowsteer::pipeline
