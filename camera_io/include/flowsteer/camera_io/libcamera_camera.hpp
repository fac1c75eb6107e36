#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/lens.hpp"

namespace flowsteer::camera_io {

struct LibcameraOptions {
  // libcamera's id of the camera (`cam --list` prints them); empty: the first camera.
  std::string camera_id;
  int width_px = 640;
  int height_px = 480;
  // libcamera's name of the pixel format to stream ("RGB888", "BGR888", "XRGB8888", "YUYV": the
  // ones read() converts); empty: the first of them, in that order, that the camera offers.
  std::string pixel_format;
  // 0 keeps the camera's default; otherwise asked for through FrameDurationLimits where the
  // camera has that control.
  double frame_rate_hz = 30.0;
  int buffer_count = 4;
  LensOptions lens;
};

// The header is there with or without libcamera; the class is defined only where
// FLOWSTEER_HAVE_LIBCAMERA is.
//
// A camera through libcamera (Raspberry Pi cameras, UVC webcams and the other pipelines
// libcamera handles), built only when pkg-config finds libcamera. The stream is asked for in
// RGB888 (BGR in memory, OpenCV's order), else BGR888, XRGB8888 or YUYV, and converted to BGR.
// Construction starts the camera; errors throw std::runtime_error naming the camera, and
// what it offers where it lacks the size or pixel format asked for. libcamera allows one
// camera manager per process: a second LibcameraCamera, or list_cameras() while one exists,
// throws std::logic_error (libcamera itself would abort the process).
class LibcameraCamera final : public FrameSource {
 public:
  explicit LibcameraCamera(const LibcameraOptions& options);
  // Stops the camera and releases it.
  ~LibcameraCamera() override;
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  const base::CameraIntrinsics& intrinsics() const override;
  ReadStatus read(Frame& frame, double timeout_s) override;

  // Frames the camera skipped, from gaps in its frame sequence numbers, and failed frames.
  std::uint64_t dropped_frames() const;
  // libcamera's sequence number of the last frame read (gaps are dropped frames).
  std::uint32_t driver_sequence() const;
  const std::string& camera_id() const;
  // The pixel format the camera streams, by libcamera's name ("RGB888").
  std::string pixel_format() const;

  // The ids of the cameras libcamera finds. libcamera allows one camera manager per process:
  // not while a LibcameraCamera exists.
  static std::vector<std::string> list_cameras();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace flowsteer::camera_io
