// Renders the calibration targets the command tests run `flowsteer calibrate` on, and checks
// what the command wrote against the truth the targets were rendered with.
//   calibration_views render DIR                 DIR/board/view_NN.png and left.png (no board,
//                                                another size), DIR/floor/floor.png and
//                                                true_camera.yaml, DIR/blank/blank_N.png; an
//                                                empty DIR/out for the commands' outputs
//   calibration_views check-intrinsics CAMERA_INFO REPORT
//   calibration_views check-mount MOUNT_FILE
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <regex>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "target_scene.hpp"

namespace {

namespace fs = std::filesystem;
using namespace flowsteer::calibration;

constexpr double kDeg = std::numbers::pi / 180.0;
// The floor view: camera 45 cm above the floor pitched 30 degrees down, board 2 mm thick.
constexpr double kHeight = 0.45;
constexpr double kPitchDeg = 30.0;
constexpr double kBoardTop = 0.002;

void write_png(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) {
    throw std::runtime_error("cannot write " + path.string());
  }
}

int render(const fs::path& dir) {
  fs::remove_all(dir);
  for (const char* sub : {"board", "floor", "blank", "out"}) {
    fs::create_directories(dir / sub);
  }
  const auto renderer = flowsteer::sim_camera::Renderer::create();
  const flowsteer::camera_io::CameraModel camera = test::true_camera();
  test::DistortedCamera distorted(camera, *renderer);
  const BoardSpec board = test::test_board();
  const flowsteer::sim_camera::World standing(test::standing_board_world(board));
  int index = 0;
  for (const test::CameraPose& pose : test::standing_board_views()) {
    char name[32];
    std::snprintf(name, sizeof name, "view_%02d.png", index++);
    write_png(dir / "board" / name, distorted.render(standing, pose));
  }
  // As in OpenCV's sample folder, where left.jpg (612x459, no board) sorts before the views: the
  // camera's size is the views' with the board, not the first image's.
  write_png(dir / "board" / "left.png", cv::Mat(459, 612, CV_8UC1, cv::Scalar(128)));
  // Looking away from the board: no board in these.
  for (int k = 0; k < 3; ++k) {
    write_png(dir / "blank" / ("blank_" + std::to_string(k) + ".png"),
              distorted.render(standing, {{2.0, 0.0, 1.2}, std::numbers::pi + 0.3 * k, 0.2}));
  }
  const flowsteer::sim_camera::World floor(test::floor_board_world(board, {0.6, 0.0}, kBoardTop));
  write_png(dir / "floor" / "floor.png",
            distorted.render(floor, {{0.0, 0.0, kHeight}, 0.0, kPitchDeg * kDeg}));
  write_camera_info(dir / "floor" / "true_camera.yaml", CameraInfo::monocular("truth", camera));
  return 0;
}

bool within(const char* what, double value, double truth, double tolerance) {
  const bool ok = std::abs(value - truth) <= tolerance;
  std::cout << what << " " << value << " (true " << truth << ", tolerance " << tolerance << ") "
            << (ok ? "ok" : "WRONG") << "\n";
  return ok;
}

int check_intrinsics(const fs::path& file, const fs::path& report) {
  std::vector<std::string> warnings;
  const CameraInfo info = read_camera_info(file, warnings);
  const auto truth = test::true_camera();
  bool ok = within("fx", info.model.fx, truth.fx, 0.005 * truth.fx);
  ok = within("fy", info.model.fy, truth.fy, 0.005 * truth.fy) && ok;
  ok = within("cx", info.model.cx, truth.cx, 0.005 * truth.cx) && ok;
  ok = within("cy", info.model.cy, truth.cy, 0.005 * truth.cy) && ok;
  std::ifstream in(report);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  std::smatch match;
  if (!std::regex_search(text, match, std::regex("RMS reprojection error: ([0-9.]+) px"))) {
    std::cout << report.string() << " has no RMS line\n";
    return 1;
  }
  ok = within("RMS px", std::stod(match[1]), 0.0, 0.3) && ok;
  if (text.find("left.png: ") == std::string::npos) {
    std::cout << report.string() << " does not report left.png as rejected\n";
    ok = false;
  }
  return ok ? 0 : 1;
}

int check_mount(const fs::path& file) {
  const MountCalibration m = read_camera_mount(file);
  bool ok = within("height_m", m.mount.height_m, kHeight, 0.01);
  ok = within("pitch_deg", m.mount.pitch_rad / kDeg, kPitchDeg, 0.5) && ok;
  ok = within("roll_deg", m.roll_rad / kDeg, 0.0, 0.5) && ok;
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 2 && args[0] == "render") {
      return render(args[1]);
    }
    if (args.size() == 3 && args[0] == "check-intrinsics") {
      return check_intrinsics(args[1], args[2]);
    }
    if (args.size() == 2 && args[0] == "check-mount") {
      return check_mount(args[1]);
    }
  } catch (const std::exception& e) {
    std::cerr << "calibration_views: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "usage: calibration_views render DIR | check-intrinsics CAMERA_INFO REPORT | "
               "check-mount MOUNT_FILE\n";
  return 2;
}
