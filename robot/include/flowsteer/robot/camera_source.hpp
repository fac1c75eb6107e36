#pragma once

#include <memory>
#include <string>

#include "flowsteer/camera_io/frame_source.hpp"

namespace flowsteer::robot {

// The camera behind a device path such as /dev/video0, delivering its raw (distorted) images,
// for the commands that read a real camera. The one place that picks the capture backend.
// Throws std::runtime_error naming the device when it cannot be opened.
std::unique_ptr<camera_io::FrameSource> open_camera(const std::string& device);

}  // namespace flowsteer::robot
