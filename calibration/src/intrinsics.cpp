#include "flowsteer/calibration/intrinsics.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/camera_io/glob.hpp"

namespace flowsteer::calibration {

namespace {

using camera_io::DistortionModel;

// The coverage mask is this many times smaller than the image: fine enough for percentages.
constexpr int kCoverageScale = 4;
// Below this share a coverage cell is reported as a weak spot.
constexpr double kWeakCell = 0.25;

struct Solved {
  camera_io::CameraModel model;
  double rms_px = 0.0;
  std::vector<double> view_rms_px;
};

Solved solve(const std::vector<CalibrationView>& views, cv::Size size, DistortionModel model) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const CalibrationView& v : views) {
    object.push_back(v.board.object_points);
    image.push_back(v.board.image_points);
  }
  cv::Matx33d k = cv::Matx33d::eye();
  std::vector<cv::Mat> rvecs;
  std::vector<cv::Mat> tvecs;
  Solved s;
  cv::Mat d;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12);
  if (model == DistortionModel::equidistant) {
    d = cv::Mat::zeros(4, 1, CV_64F);
    cv::fisheye::calibrate(object, image, size, k, d, rvecs, tvecs,
                           cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW,
                           criteria);
  } else {
    const int flags = model == DistortionModel::rational_polynomial ? cv::CALIB_RATIONAL_MODEL : 0;
    cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, flags, criteria);
  }
  s.model.width_px = size.width;
  s.model.height_px = size.height;
  s.model.fx = k(0, 0);
  s.model.fy = k(1, 1);
  s.model.cx = k(0, 2);
  s.model.cy = k(1, 2);
  s.model.distortion = model;
  const std::size_t count = camera_io::distortion_coefficient_count(model);
  const cv::Mat flat = d.reshape(1, static_cast<int>(d.total()));
  for (std::size_t i = 0; i < count; ++i) {
    s.model.coefficients.push_back(flat.at<double>(static_cast<int>(i)));
  }
  // Per-view errors from the reprojections, so that the model reported is the one measured.
  double sum_sq = 0.0;
  std::size_t points = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    std::vector<cv::Point2f> projected;
    if (model == DistortionModel::equidistant) {
      cv::fisheye::projectPoints(object[v], projected, rvecs[v], tvecs[v], k, d);
    } else {
      cv::projectPoints(object[v], rvecs[v], tvecs[v], k, d, projected);
    }
    const double view_sq = cv::norm(projected, image[v], cv::NORM_L2SQR);
    s.view_rms_px.push_back(std::sqrt(view_sq / static_cast<double>(projected.size())));
    sum_sq += view_sq;
    points += projected.size();
  }
  s.rms_px = std::sqrt(sum_sq / static_cast<double>(points));
  return s;
}

std::string format(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

// Each rejected view on a line of its own: "\n  name: reason".
std::string rejected_lines(const std::vector<RejectedView>& rejected) {
  std::string lines;
  for (const RejectedView& r : rejected) {
    lines += "\n  " + r.name + ": " + r.reason;
  }
  return lines;
}

[[noreturn]] void too_few(std::size_t usable, int needed,
                          const std::vector<RejectedView>& rejected) {
  std::string message = "too few views to calibrate: " + std::to_string(usable) +
                        " usable, at least " + std::to_string(needed) + " needed";
  if (!rejected.empty()) {
    message += "; rejected:" + rejected_lines(rejected);
  }
  throw CalibrationError(message);
}

}  // namespace

Coverage image_coverage(const std::vector<CalibrationView>& views, cv::Size image_size) {
  const cv::Size small((image_size.width + kCoverageScale - 1) / kCoverageScale,
                       (image_size.height + kCoverageScale - 1) / kCoverageScale);
  cv::Mat mask = cv::Mat::zeros(small, CV_8UC1);
  for (const CalibrationView& v : views) {
    std::vector<cv::Point2f> hull;
    cv::convexHull(v.board.image_points, hull);
    std::vector<cv::Point> scaled;
    for (const cv::Point2f& p : hull) {
      scaled.emplace_back(cvRound(p.x / kCoverageScale), cvRound(p.y / kCoverageScale));
    }
    cv::fillConvexPoly(mask, scaled, cv::Scalar(255));
  }
  Coverage c;
  c.fraction = cv::countNonZero(mask) / static_cast<double>(mask.total());
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) {
      const cv::Rect cell(col * small.width / 3, r * small.height / 3,
                          (col + 1) * small.width / 3 - col * small.width / 3,
                          (r + 1) * small.height / 3 - r * small.height / 3);
      c.cells[static_cast<std::size_t>(3 * r + col)] =
          cv::countNonZero(mask(cell)) / static_cast<double>(cell.area());
    }
  }
  return c;
}

IntrinsicsResult calibrate_intrinsics(const std::vector<CalibrationView>& views,
                                      std::vector<RejectedView> rejected, cv::Size image_size,
                                      const IntrinsicsOptions& options) {
  if (static_cast<int>(views.size()) < options.min_views) {
    too_few(views.size(), options.min_views, rejected);
  }
  Solved s = solve(views, image_size, options.model);
  std::vector<double> sorted = s.view_rms_px;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
  const double limit = std::max(options.outlier_floor_px, options.outlier_factor * median);
  std::vector<CalibrationView> kept;
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (s.view_rms_px[v] > limit) {
      rejected.push_back({views[v].name, "reprojection error " + format(s.view_rms_px[v], 2) +
                                             " px, above " + format(limit, 2) +
                                             " px (a misdetected board or motion blur?)"});
    } else {
      kept.push_back(views[v]);
    }
  }
  if (kept.size() != views.size()) {
    if (static_cast<int>(kept.size()) < options.min_views) {
      too_few(kept.size(), options.min_views, rejected);
    }
    s = solve(kept, image_size, options.model);
  }

  IntrinsicsResult result;
  result.model = s.model;
  CalibrationReport& report = result.report;
  report.rms_px = s.rms_px;
  for (std::size_t v = 0; v < kept.size(); ++v) {
    report.view_rms_px.emplace_back(kept[v].name, s.view_rms_px[v]);
  }
  report.rejected = std::move(rejected);
  report.coverage = image_coverage(kept, image_size);
  return result;
}

std::string CalibrationReport::text() const {
  static const char* const kCellNames[9] = {"top left",    "top",    "top right",
                                            "left",        "centre", "right",
                                            "bottom left", "bottom", "bottom right"};
  std::ostringstream out;
  out << "RMS reprojection error: " << format(rms_px, 3) << " px over " << view_rms_px.size()
      << " views\n";
  out << "per view:\n";
  for (const auto& [name, rms] : view_rms_px) {
    out << "  " << format(rms, 3) << " px  " << name << "\n";
  }
  if (!rejected.empty()) {
    out << "rejected views: " << rejected.size() << rejected_lines(rejected) << "\n";
  }
  out << "coverage: boards cover " << format(100.0 * coverage.fraction, 0) << "% of the image\n";
  for (int r = 0; r < 3; ++r) {
    out << " ";
    for (int c = 0; c < 3; ++c) {
      out << std::setw(6) << format(100.0 * coverage.cells[static_cast<std::size_t>(3 * r + c)], 0)
          << "%";
    }
    out << "\n";
  }
  std::string weak;
  for (std::size_t i = 0; i < coverage.cells.size(); ++i) {
    if (coverage.cells[i] < kWeakCell) {
      weak += (weak.empty() ? "" : ", ") + std::string(kCellNames[i]);
    }
  }
  if (!weak.empty()) {
    out << "weak coverage (" << weak
        << "): add views with the board there, where distortion is strongest\n";
  }
  for (const std::string& w : warnings) {
    out << "warning: " << w << "\n";
  }
  return out.str();
}

IntrinsicsResult calibrate_board_views(const std::vector<CalibrationView>& views,
                                       std::vector<RejectedView> rejected, cv::Size image_size,
                                       const BoardSpec& board, const std::string& searched,
                                       const IntrinsicsOptions& options) {
  if (views.empty()) {
    throw CalibrationError("the board (" + board.text() + ") was found in none of the " + searched +
                           rejected_lines(rejected));
  }
  IntrinsicsResult result = calibrate_intrinsics(views, std::move(rejected), image_size, options);
  result.report.warnings = board.warnings();
  return result;
}

std::vector<std::filesystem::path> expand_glob(const std::string& pattern) {
  std::vector<std::filesystem::path> paths = camera_io::expand_glob(pattern);
  if (paths.empty()) {
    throw CalibrationError("no file matches '" + pattern + "'");
  }
  return paths;
}

namespace {

std::string size_text(cv::Size size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

// The size most views with the board share (the first such view's on a tie): one odd image in
// a folder, such as a sample without the board that sorts first, does not set the camera's size.
cv::Size most_common_size(const std::vector<cv::Size>& sizes) {
  cv::Size best;
  long best_count = 0;
  for (const cv::Size& size : sizes) {
    const long count = std::count(sizes.begin(), sizes.end(), size);
    if (count > best_count) {
      best = size;
      best_count = count;
    }
  }
  return best;
}

}  // namespace

IntrinsicsResult calibrate_from_images(const std::vector<std::filesystem::path>& images,
                                       const BoardDetector& detector,
                                       const IntrinsicsOptions& options) {
  std::vector<CalibrationView> found;
  std::vector<cv::Size> sizes;  // of the views in `found`
  std::vector<RejectedView> rejected;
  for (const std::filesystem::path& path : images) {
    const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    if (image.empty()) {
      rejected.push_back({path.string(), "cannot be read as an image"});
      continue;
    }
    std::string why;
    if (auto board = detector.detect(image, why)) {
      found.push_back({path.string(), std::move(*board)});
      sizes.push_back(image.size());
    } else {
      rejected.push_back({path.string(), why});
    }
  }
  const cv::Size size = most_common_size(sizes);
  std::vector<CalibrationView> views;
  for (std::size_t i = 0; i < found.size(); ++i) {
    if (sizes[i] == size) {
      views.push_back(std::move(found[i]));
    } else {
      rejected.push_back({found[i].name, "is " + size_text(sizes[i]) + ", most views with the " +
                                             "board are " + size_text(size)});
    }
  }
  return calibrate_board_views(views, std::move(rejected), size, detector.spec(),
                               std::to_string(images.size()) + " images", options);
}

}  // namespace flowsteer::calibration
