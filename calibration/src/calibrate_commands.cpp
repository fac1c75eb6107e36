#include "flowsteer/calibration/calibrate_commands.hpp"

#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "flowsteer/calibration/intrinsics.hpp"
#include "flowsteer/calibration/mount.hpp"

namespace flowsteer::calibration {

namespace {

IntrinsicsOptions intrinsics_options(const std::string& model, int min_views) {
  IntrinsicsOptions options;
  options.model = lens_model(model);
  options.min_views = min_views;
  return options;
}

void print_model(const camera_io::CameraModel& m, std::ostream& out) {
  out << std::setprecision(6) << "fx " << m.fx << "  fy " << m.fy << "  cx " << m.cx << "  cy "
      << m.cy << "  " << camera_io::distortion_model_name(m.distortion) << " [";
  for (std::size_t i = 0; i < m.coefficients.size(); ++i) {
    out << (i > 0 ? ", " : "") << m.coefficients[i];
  }
  out << "]\n";
}

void warn_all(const std::vector<std::string>& warnings, std::ostream& log) {
  for (const std::string& w : warnings) {
    log << "warning: " << w << "\n";
  }
}

}  // namespace

camera_io::DistortionModel lens_model(const std::string& name) {
  if (name == "pinhole") {
    return camera_io::DistortionModel::plumb_bob;
  }
  if (name == "rational") {
    return camera_io::DistortionModel::rational_polynomial;
  }
  if (name == "fisheye") {
    return camera_io::DistortionModel::equidistant;
  }
  throw std::invalid_argument("lens model '" + name + "': expected pinhole, rational or fisheye");
}

void run_calibrate_intrinsics(const IntrinsicsCommand& command, std::ostream& out,
                              std::ostream& log) {
  const IntrinsicsOptions options = intrinsics_options(command.model, command.min_views);
  const BoardDetector detector(BoardSpec::parse(command.board));
  warn_all(detector.spec().warnings(), log);
  const auto images = expand_glob(command.images);
  log << "flowsteer calibrate intrinsics: " << images.size() << " images, board "
      << detector.spec().text() << "\n";
  const IntrinsicsResult result = calibrate_from_images(images, detector, options);
  out << result.report.text();
  print_model(result.model, out);
  write_camera_info(command.out, CameraInfo::monocular(command.camera_name, result.model));
  out << "wrote " << command.out.string() << "\n";
}

void run_calibrate_capture(const CaptureCommand& command, camera_io::FrameSource& source,
                           std::ostream& out, std::ostream& log) {
  const IntrinsicsOptions options = intrinsics_options(command.model, command.min_views);
  const BoardDetector detector(BoardSpec::parse(command.board));
  warn_all(detector.spec().warnings(), log);
  const CaptureResult capture = capture_views(source, detector, command.capture, log);
  log << "read " << capture.frames << " frames, the board in " << capture.frames_with_board
      << ", kept " << capture.views.size() << " views"
      << (capture.source_ended ? " (the source ended)" : "") << "\n";
  std::vector<CalibrationView> views;
  for (std::size_t i = 0; i < capture.views.size(); ++i) {
    std::ostringstream name;
    name << "view_" << std::setw(2) << std::setfill('0') << i << ".png";
    views.push_back({name.str(), capture.views[i].board});
  }
  const IntrinsicsResult result =
      calibrate_board_views(views, {}, capture.image_size, detector.spec(),
                            std::to_string(capture.frames) + " frames read", options);
  const std::string report = result.report.text();
  out << report;
  print_model(result.model, out);

  base::OutputDir dir(command.out_dir);
  for (std::size_t i = 0; i < capture.views.size(); ++i) {
    const std::filesystem::path path = dir.staging_path(views[i].name);
    if (!cv::imwrite(path.string(), capture.views[i].image)) {
      throw std::runtime_error("cannot write " + path.string());
    }
  }
  write_camera_info(dir.staging_path("camera_info.yaml"),
                    CameraInfo::monocular(command.camera_name, result.model));
  base::write_text(dir.staging_path("report.txt"), report);
  dir.commit();
  out << "wrote " << capture.views.size() << " views, camera_info.yaml and report.txt into "
      << command.out_dir.string() << "\n";
}

void run_calibrate_mount(const MountCommand& command, std::ostream& out, std::ostream& log) {
  if (!(command.board_thickness_m >= 0.0)) {
    throw std::invalid_argument("--board-thickness must be >= 0");
  }
  const BoardDetector detector(BoardSpec::parse(command.board));
  warn_all(detector.spec().warnings(), log);
  std::vector<std::string> warnings;
  const CameraInfo info = read_camera_info(command.intrinsics, warnings);
  warn_all(warnings, log);
  const cv::Mat image = cv::imread(command.image.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    throw std::runtime_error(command.image.string() + ": cannot be read as an image");
  }
  if (image.cols != info.model.width_px || image.rows != info.model.height_px) {
    throw std::runtime_error(command.image.string() + " is " + std::to_string(image.cols) + "x" +
                             std::to_string(image.rows) + " but " + command.intrinsics.string() +
                             " calibrates a " + std::to_string(info.model.width_px) + "x" +
                             std::to_string(info.model.height_px) + " camera");
  }
  std::string why;
  const auto board = detector.detect(image, why);
  if (!board) {
    throw std::runtime_error(command.image.string() + ": " + why);
  }
  MountMeasurement m = measure_mount(info.model, *board);
  m.mount.mount.height_m += command.board_thickness_m;
  const double deg = 180.0 / std::numbers::pi;
  out << std::fixed << std::setprecision(3) << "camera height " << m.mount.mount.height_m
      << " m, pitch " << std::setprecision(2) << m.mount.mount.pitch_rad * deg
      << " deg (down), roll " << m.mount.roll_rad * deg << " deg; board pose error "
      << std::setprecision(3) << m.rms_px << " px over " << m.corners << " corners\n";
  write_camera_mount(command.out, m.mount);
  out << "wrote " << command.out.string() << "\n";
}

}  // namespace flowsteer::calibration
