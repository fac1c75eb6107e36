#pragma once

#include <filesystem>
#include <ostream>
#include <string>

#include "flowsteer/calibration/capture.hpp"
#include "flowsteer/camera_io/camera_model.hpp"
#include "flowsteer/camera_io/frame_source.hpp"

namespace flowsteer::calibration {

// The lens model a user names: pinhole (plumb_bob), rational (rational_polynomial) or fisheye
// (equidistant). Throws std::invalid_argument otherwise.
camera_io::DistortionModel lens_model(const std::string& name);

// flowsteer calibrate intrinsics: the images of a glob, the board, a camera_info file.
struct IntrinsicsCommand {
  std::string images;  // a shell pattern, e.g. "shots/*.png"
  std::string board;   // see BoardSpec
  std::string model = "pinhole";
  std::filesystem::path out = "camera_info.yaml";
  std::string camera_name = "camera";
  int min_views = 8;
};
// Prints the report on `out`, warnings on `log`; writes the file only when the calibration
// succeeds. Throws CalibrationError, std::invalid_argument or std::runtime_error
// with the reason.
void run_calibrate_intrinsics(const IntrinsicsCommand& command, std::ostream& out,
                              std::ostream& log);

// flowsteer calibrate capture: views from a camera, then the calibration, into a folder.
struct CaptureCommand {
  std::string board;
  std::string model = "pinhole";
  std::filesystem::path out_dir = "calibration";
  std::string camera_name = "camera";
  int min_views = 8;
  CaptureOptions capture;
};
// Writes view_NN.png, camera_info.yaml and report.txt into out_dir all at once, after the
// calibration succeeded; nothing when it fails.
void run_calibrate_capture(const CaptureCommand& command, camera_io::FrameSource& source,
                           std::ostream& out, std::ostream& log);

// flowsteer calibrate mount: a camera_info file, one image of the board on the floor, the
// camera mount file.
struct MountCommand {
  std::filesystem::path intrinsics;
  std::filesystem::path image;
  std::string board;
  std::filesystem::path out = "camera_mount.yaml";
  double board_thickness_m = 0.0;  // added to the height: the board's surface is not the floor
};
void run_calibrate_mount(const MountCommand& command, std::ostream& out, std::ostream& log);

}  // namespace flowsteer::calibration
