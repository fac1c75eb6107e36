#include "flowsteer/launch/camera_source.hpp"

#include <stdexcept>

namespace flowsteer::launch {

std::unique_ptr<camera_io::FrameSource> open_camera(const std::string& device) {
  // camera_io has no V4L2 source yet (issue "camera_io and the robot loop"); it plugs in here.
  throw std::runtime_error("cannot open " + device +
                           ": V4L2 capture not built (camera_io has no V4L2 source yet); "
                           "record images and use flowsteer calibrate intrinsics --images");
}

}  // namespace flowsteer::launch
