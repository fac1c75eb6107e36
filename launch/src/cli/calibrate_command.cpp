#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flowsteer/calibration/calibrate_commands.hpp"
#include "flowsteer/robot/camera_source.hpp"

namespace flowsteer::cli {

namespace {

const char* const kBoardHelp =
    "calibration target: chessboard:COLSxROWS:SQUARE_M (inner corners) or "
    "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT (squares, e.g. DICT_4X4_50)";
const char* const kModelHelp = "lens model: pinhole (plumb_bob), rational or fisheye";

Subcommand add_intrinsics(CLI::App& calibrate) {
  auto command = std::make_shared<calibration::IntrinsicsCommand>();
  CLI::App* intrinsics = calibrate.add_subcommand(
      "intrinsics", "Calibrate from images of a board; write a ROS camera_info YAML");
  intrinsics->add_option("--images", command->images, "images, a quoted glob")->required();
  intrinsics->add_option("--board", command->board, kBoardHelp)->required();
  intrinsics->add_option("--model", command->model, kModelHelp)->capture_default_str();
  intrinsics->add_option("--out", command->out, "camera_info file to write")->capture_default_str();
  intrinsics->add_option("--camera-name", command->camera_name, "camera_name field")
      ->capture_default_str();
  intrinsics->add_option("--min-views", command->min_views, "fewest usable views")
      ->check(CLI::Range(3, 1000))
      ->capture_default_str();
  return {intrinsics, [command] {
            calibration::run_calibrate_intrinsics(*command, std::cout, std::cerr);
            return 0;
          }};
}

struct CaptureCommand {
  calibration::CaptureCommand capture;
  std::string device;
};

Subcommand add_capture(CLI::App& calibrate) {
  auto command = std::make_shared<CaptureCommand>();
  calibration::CaptureCommand& c = command->capture;
  CLI::App* capture = calibrate.add_subcommand(
      "capture",
      "Grab views of a board from a camera, keep the ones that add coverage or a new pose, "
      "calibrate and write the views, camera_info.yaml and report.txt into a folder");
  capture->add_option("--device", command->device, "camera device, e.g. /dev/video0")->required();
  capture->add_option("--board", c.board, kBoardHelp)->required();
  capture->add_option("--out", c.out_dir, "folder for the outputs")->capture_default_str();
  capture->add_option("--model", c.model, kModelHelp)->capture_default_str();
  capture->add_option("--views", c.capture.views, "views to collect")
      ->check(CLI::Range(3, 200))
      ->capture_default_str();
  capture->add_option("--max-frames", c.capture.max_frames, "give up after this many frames")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  capture->add_option("--camera-name", c.camera_name, "camera_name field")->capture_default_str();
  return {capture, [command] {
            calibration::CaptureCommand c = command->capture;
            c.min_views = std::min(c.min_views, c.capture.views);
            const auto source = robot::open_camera(command->device);
            calibration::run_calibrate_capture(c, *source, std::cout, std::cerr);
            return 0;
          }};
}

Subcommand add_mount(CLI::App& calibrate) {
  auto command = std::make_shared<calibration::MountCommand>();
  CLI::App* mount = calibrate.add_subcommand(
      "mount",
      "Camera height, pitch and roll from one image of a board lying flat on the floor; write "
      "the camera mount file");
  mount->add_option("--intrinsics", command->intrinsics, "the camera's camera_info YAML")
      ->required();
  mount->add_option("--image", command->image, "image of the board on the floor")->required();
  mount->add_option("--board", command->board, kBoardHelp)->required();
  mount->add_option("--out", command->out, "camera mount file to write")->capture_default_str();
  mount
      ->add_option("--board-thickness", command->board_thickness_m,
                   "metres from the floor to the board's printed surface")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  return {mount, [command] {
            calibration::run_calibrate_mount(*command, std::cout, std::cerr);
            return 0;
          }};
}

}  // namespace

std::vector<Subcommand> add_calibrate(CLI::App& app) {
  CLI::App* calibrate =
      app.add_subcommand("calibrate", "Measure a camera's intrinsics and its mount on the robot");
  calibrate->require_subcommand(1);
  return {add_intrinsics(*calibrate), add_capture(*calibrate), add_mount(*calibrate)};
}

}  // namespace flowsteer::cli
