// Robot launch files (`flowsteer run FILE`), with their camera, drive, perception, controller
// and goal sections: a launch whose every number is within its bound, or a base::ConfigError. The
// camera_info and camera mount files a launch file may name are in the scratch folder the paths
// resolve against, so the fuzzer reaches the size check against the calibration. A drive section
// the reader accepts must also build its base (nothing is opened): a setting the reader lets
// through but a driver refuses is a finding, as the user would get an error that names no line.
#include <cstddef>
#include <cstdint>

#include "bounds_check.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/drive_config.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "fuzz_support.hpp"

namespace {

constexpr const char* kCameraInfo = R"(image_width: 640
image_height: 480
camera_name: fuzz
camera_matrix: {rows: 3, cols: 3, data: [430, 0, 320, 0, 430, 240, 0, 0, 1]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [-0.3, 0.1, 0, 0, 0]}
rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}
projection_matrix: {rows: 3, cols: 4, data: [430, 0, 320, 0, 0, 430, 240, 0, 0, 0, 1, 0]}
)";

constexpr const char* kMount = "height_m: 0.35\npitch_rad: 0.1\nroll_rad: 0.01\n";

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  flowsteer::fuzz::write_scratch_file("camera_info.yaml", kCameraInfo);
  flowsteer::fuzz::write_scratch_file("mount.yaml", kMount);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const flowsteer::config::RobotLaunch launch = flowsteer::config::parse_robot_launch(
        flowsteer::fuzz::as_text(data, size), "fuzz_launch.yaml",
        flowsteer::fuzz::scratch_dir().string());
    flowsteer::fuzz::check_bounds(launch);
    if (launch.drive) {
      flowsteer::config::make_base(*launch.drive);
    }
  } catch (const flowsteer::base::ConfigError&) {
    // The reader's documented refusal; anything else escapes and is a finding.
  }
  return 0;
}
