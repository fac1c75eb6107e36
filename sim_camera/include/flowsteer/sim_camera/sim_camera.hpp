#pragma once

#include <cstddef>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::sim_camera {

// Points `frame` at `view`, rendered from the world as it is now: the image (empty when only the
// geometry channels were drawn) and the simulator's exact channels, stamped with the world's
// time. The frame's sequence number is the caller's.
void point_frame_at(const RenderedView& view, const World& world, camera_io::Frame& frame);

// An agent's head camera in the simulated world, as a FrameSource: each read renders the world
// as it is now and carries the simulator's exact channels (depth, ids, flow) with the image.
class SimCamera final : public camera_io::FrameSource {
 public:
  // The world and the renderer must outlive the camera.
  SimCamera(const World& world, Renderer& renderer, std::size_t agent);

  const base::CameraIntrinsics& intrinsics() const override { return intrinsics_; }
  // Never times out: a render is always there. Timestamps are simulated time.
  camera_io::ReadStatus read(camera_io::Frame& frame, double timeout_s) override;

 private:
  const World& world_;
  Renderer& renderer_;
  std::size_t agent_;
  base::CameraIntrinsics intrinsics_;
  std::uint64_t sequence_ = 0;
  RenderedView view_;
};

}  // namespace flowsteer::sim_camera
