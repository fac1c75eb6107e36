#include "flowsteer/robot/camera_source.hpp"

#include "flowsteer/camera_io/v4l2_camera.hpp"

namespace flowsteer::robot {

std::unique_ptr<camera_io::FrameSource> open_camera(const std::string& device) {
  // No calibration given: the lens is an ideal pinhole and the images stay as the camera took
  // them, which is what calibration needs.
  camera_io::V4l2Options options;
  options.device = device;
  return std::make_unique<camera_io::V4l2Camera>(options);
}

}  // namespace flowsteer::robot
