#pragma once

#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"

namespace flowsteer::camera_io {

// What only a simulator can give with a frame: exact per-pixel channels for the same instant.
struct SimChannels {
  cv::Mat depth_m;     // CV_32F, depth along the optical axis; +inf where nothing was hit
  cv::Mat object_ids;  // CV_32S, the renderer's object ids; negative for ground and sky
                       // (servo/segmentation.hpp)
  cv::Mat flow;        // CV_32FC2, image-plane velocity in normalised units per second (Eq. 1)
};

// One image from a camera, with when it was taken.
struct Frame {
  cv::Mat image;               // CV_8UC3, BGR
  double timestamp_s = 0.0;    // monotonic clock
  std::uint64_t sequence = 0;  // increases by one per frame the source delivered
  std::optional<SimChannels> sim;
};

enum class ReadStatus { ok, timeout, end_of_stream };

// A source of frames: a camera, a recording or the simulator. Errors that are not a timeout or
// the end of a recording throw std::runtime_error naming the device or file.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Intrinsics of the images this source delivers (undistorted pinhole).
  virtual const base::CameraIntrinsics& intrinsics() const = 0;
  // Waits up to timeout_s for the next frame. The frame's images may share memory with the
  // source's buffers (as mapped capture buffers do) and stay valid until the next read():
  // clone() what must outlive it, such as the previous image for numerical flow.
  virtual ReadStatus read(Frame& frame, double timeout_s) = 0;
};

}  // namespace flowsteer::camera_io
