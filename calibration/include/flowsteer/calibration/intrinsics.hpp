#pragma once

#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/calibration/board.hpp"
#include "flowsteer/camera_io/camera_model.hpp"

namespace flowsteer::calibration {

// A calibration that cannot be made (too few usable views): the message says why, view by view.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One image in which the board was found.
struct CalibrationView {
  std::string name;  // the file, or the frame of a capture
  BoardView board;
};

struct RejectedView {
  std::string name;
  std::string reason;
};

// Which part of the image the views' boards cover: the whole and a 3 x 3 grid of cells
// (row-major from the top left). Distortion is strongest at the edges, so corners that no
// board reached are calibrated by extrapolation.
struct Coverage {
  double fraction = 0.0;
  std::array<double, 9> cells{};
};

struct CalibrationReport {
  double rms_px = 0.0;  // over every corner of every used view
  std::vector<std::pair<std::string, double>> view_rms_px;
  std::vector<RejectedView> rejected;
  Coverage coverage;
  std::vector<std::string> warnings;

  // For a terminal: the numbers, then what to do about weak spots.
  std::string text() const;
};

struct IntrinsicsOptions {
  camera_io::DistortionModel model = camera_io::DistortionModel::plumb_bob;
  int min_views = 8;
  // A view whose error is above max(this, outlier_factor × median) is dropped and the camera
  // calibrated again without it: a misdetected corner or motion blur, not the lens.
  double outlier_floor_px = 1.0;
  double outlier_factor = 3.0;
};

struct IntrinsicsResult {
  camera_io::CameraModel model;
  CalibrationReport report;
};

// Calibrates from the views (cv::calibrateCamera for plumb_bob and rational_polynomial,
// cv::fisheye::calibrate for equidistant). `rejected` are views already turned away (no board
// found...), carried into the report. Throws CalibrationError when fewer than
// options.min_views views are usable, listing every rejected view and why.
IntrinsicsResult calibrate_intrinsics(const std::vector<CalibrationView>& views,
                                      std::vector<RejectedView> rejected, cv::Size image_size,
                                      const IntrinsicsOptions& options);

// calibrate_intrinsics on the views in which `board` was found, the report carrying the board's
// warnings. `searched` says where it was looked for ("12 images", "300 frames read"): when no
// view has it, throws CalibrationError "the board (...) was found in none of the <searched>",
// listing the rejected views.
IntrinsicsResult calibrate_board_views(const std::vector<CalibrationView>& views,
                                       std::vector<RejectedView> rejected, cv::Size image_size,
                                       const BoardSpec& board, const std::string& searched,
                                       const IntrinsicsOptions& options);

// The image files a shell-style pattern names, sorted (camera_io::expand_glob). Throws
// CalibrationError when none does.
std::vector<std::filesystem::path> expand_glob(const std::string& pattern);

// Reads each image, finds the board and calibrates. Unreadable images, images of another size
// than the first and images without the board are rejected with the reason.
IntrinsicsResult calibrate_from_images(const std::vector<std::filesystem::path>& images,
                                       const BoardDetector& detector,
                                       const IntrinsicsOptions& options);

// The part of the image the boards cover (the convex hull of each view's corners).
Coverage image_coverage(const std::vector<CalibrationView>& views, cv::Size image_size);

}  // namespace flowsteer::calibration
