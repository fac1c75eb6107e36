#include "flowsteer/calibration/capture.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace flowsteer::calibration {

namespace {

constexpr int kGridCols = 8;
constexpr int kGridRows = 6;

// The outer corners of the detected board, in the board's own order: for a chessboard the
// four extreme corners; for a partly seen ChArUco board those of the points seen.
std::array<cv::Point2f, 4> outline(const BoardView& view) {
  // Extremes along the board's axes: min and max of x + y and x - y of the object points.
  std::size_t a = 0, b = 0, c = 0, d = 0;
  for (std::size_t i = 0; i < view.object_points.size(); ++i) {
    const cv::Point3f& p = view.object_points[i];
    const auto& o = view.object_points;
    if (p.x + p.y < o[a].x + o[a].y)
      a = i;  // first corner
    if (p.x - p.y > o[b].x - o[b].y)
      b = i;  // end of the first row
    if (p.x + p.y > o[c].x + o[c].y)
      c = i;  // last corner
    if (p.y - p.x > o[d].y - o[d].x)
      d = i;  // start of the last row
  }
  return {view.image_points[a], view.image_points[b], view.image_points[c], view.image_points[d]};
}

std::vector<bool> cells_of(const BoardView& view, cv::Size size) {
  std::vector<bool> cells(kGridCols * kGridRows, false);
  std::vector<cv::Point2f> hull;
  cv::convexHull(view.image_points, hull);
  for (int r = 0; r < kGridRows; ++r) {
    for (int c = 0; c < kGridCols; ++c) {
      const cv::Point2f centre(static_cast<float>((c + 0.5) * size.width / kGridCols),
                               static_cast<float>((r + 0.5) * size.height / kGridRows));
      cells[static_cast<std::size_t>(r * kGridCols + c)] =
          cv::pointPolygonTest(hull, centre, false) >= 0;
    }
  }
  return cells;
}

}  // namespace

BoardPose pose_of(const BoardView& view, cv::Size image_size) {
  const auto [p0, p1, p2, p3] = outline(view);
  const cv::Point2f centre = 0.25F * (p0 + p1 + p2 + p3);
  const double area = 0.5 * std::abs((p2 - p0).cross(p3 - p1));
  auto len = [](cv::Point2f a, cv::Point2f b) { return std::hypot(a.x - b.x, a.y - b.y); };
  const double top = len(p0, p1);
  const double right = len(p1, p2);
  const double bottom = len(p2, p3);
  const double left = len(p3, p0);
  // Tilt weighs double: a board turned by 30 degrees changes its side ratio by only ~0.1, yet
  // tilted views are what separates the focal length from the board's distance.
  return {centre.x / image_size.width, centre.y / image_size.height,
          std::sqrt(area / image_size.area()), 2.0 * (right - left) / (right + left),
          2.0 * (bottom - top) / (bottom + top)};
}

CaptureResult capture_views(camera_io::FrameSource& source, const BoardDetector& detector,
                            const CaptureOptions& options, std::ostream& log) {
  CaptureResult result;
  std::vector<bool> covered(kGridCols * kGridRows, false);
  std::vector<BoardPose> poses;
  camera_io::Frame frame;
  double silent_s = 0.0;
  cv::Size& size = result.image_size;
  while (static_cast<int>(result.views.size()) < options.views &&
         result.frames < options.max_frames) {
    const camera_io::ReadStatus status = source.read(frame, options.read_timeout_s);
    if (status == camera_io::ReadStatus::end_of_stream) {
      result.source_ended = true;
      break;
    }
    if (status == camera_io::ReadStatus::timeout) {
      silent_s += options.read_timeout_s;
      if (silent_s >= options.stall_s) {
        throw std::runtime_error("the camera delivered no frame for " +
                                 std::to_string(static_cast<int>(silent_s)) + " s");
      }
      continue;
    }
    silent_s = 0.0;
    ++result.frames;
    if (size.empty()) {
      size = frame.image.size();
    } else if (frame.image.size() != size) {
      throw std::runtime_error("the camera changed its image size during the capture");
    }
    std::string why;
    const std::optional<BoardView> board = detector.detect(frame.image, why);
    if (!board) {
      continue;
    }
    ++result.frames_with_board;
    const std::vector<bool> cells = cells_of(*board, size);
    int new_cells = 0;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      new_cells += cells[i] && !covered[i] ? 1 : 0;
    }
    const BoardPose pose = pose_of(*board, size);
    double nearest = std::numeric_limits<double>::infinity();
    for (const BoardPose& kept : poses) {
      double sum = 0.0;
      for (std::size_t i = 0; i < pose.size(); ++i) {
        sum += std::abs(pose[i] - kept[i]);
      }
      nearest = std::min(nearest, sum);
    }
    if (new_cells < options.min_new_cells && nearest < options.min_pose_distance) {
      continue;
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      covered[i] = covered[i] || cells[i];
    }
    poses.push_back(pose);
    result.views.push_back({frame.image.clone(), *board, frame.sequence});
    const auto covered_cells = std::count(covered.begin(), covered.end(), true);
    log << "view " << result.views.size() << "/" << options.views << " (frame " << frame.sequence
        << "): " << new_cells << " new cells, image covered " << std::fixed << std::setprecision(0)
        << 100.0 * static_cast<double>(covered_cells) / static_cast<double>(covered.size())
        << "%\n";
  }
  return result;
}

}  // namespace flowsteer::calibration
