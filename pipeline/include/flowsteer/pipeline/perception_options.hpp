#pragma once

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/dark_regions.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/obstacle_memory.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/servo/steering.hpp"
#include "flowsteer/servo/untextured_fill.hpp"

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
  // Numerical flow only: plain surfaces standing on the ground get the flow of their foot.
  servo::UntexturedFillOptions untextured_fill;
  // Numerical flow's error in pixels over its interval: the ground test allows it on top of its
  // relative tolerance, since the ground left over joins every object standing on it.
  double numerical_flow_noise_px = 0.3;
  // Remember what stood still and recall it where the view no longer shows it
  // (servo::ObstacleMemory): for flow segmentation without the renderer's depth, a camera's.
  bool obstacle_memory = false;
  servo::ObstacleMemoryOptions memory;
};

// Whether the field carries the renderer's depth at every pixel.
inline bool per_pixel_depth(const PerceptionOptions& options) {
  return options.flow == servo::FlowMethod::synthetic && options.use_depth &&
         options.depth == servo::DepthSource::renderer;
}

}  // namespace flowsteer::pipeline
