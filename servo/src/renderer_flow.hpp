#pragma once

#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::servo {

// The renderer's exact, instantaneous flow (FlowMethod::synthetic), with its depth where the
// field carries depth, derotated by the camera's angular velocity at the frame.
class RendererFlow final : public FlowSource {
 public:
  explicit RendererFlow(const RendererFlowOptions& options) : options_(options) {}

  // Throws std::invalid_argument when the frame carries no renderer's flow and depth.
  FlowStatus update(const FlowFrame& frame, const CameraMotion& motion, FlowField& field) override;
  // Each frame's flow stands alone: there is nothing to forget.
  void reset() override {}
  bool estimated() const override { return false; }
  double noise_correlation_px() const override { return 1.0; }

 private:
  RendererFlowOptions options_;
};

}  // namespace flowsteer::servo
