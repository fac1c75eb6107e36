// Intrinsics, mount and capture against views rendered by sim_camera with known parameters.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/calibration/intrinsics.hpp"
#include "flowsteer/calibration/mount.hpp"
#include "target_scene.hpp"

namespace {

namespace fs = std::filesystem;
using namespace flowsteer::calibration;
using flowsteer::camera_io::CameraModel;
using flowsteer::camera_io::DistortionModel;
namespace sim = flowsteer::sim_camera;

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<CalibrationView> render_standing_views(const CameraModel& camera,
                                                   sim::Renderer& renderer,
                                                   std::vector<RejectedView>& rejected) {
  const BoardDetector detector(test::test_board());
  const sim::World world(test::standing_board_world(detector.spec()));
  test::DistortedCamera distorted(camera, renderer);
  std::vector<CalibrationView> views;
  int index = 0;
  for (const test::CameraPose& pose : test::standing_board_views()) {
    const std::string name = "view " + std::to_string(index++);
    const cv::Mat image = distorted.render(world, pose);
    std::string why;
    if (auto board = detector.detect(image, why)) {
      views.push_back({name, std::move(*board)});
    } else {
      rejected.push_back({name, why});
    }
  }
  return views;
}

void expect_recovered(const CameraModel& truth, const IntrinsicsResult& result) {
  const CameraModel& m = result.model;
  std::cout << result.report.text();
  std::cout << "fx " << m.fx << " (true " << truth.fx << "), fy " << m.fy << " (" << truth.fy
            << "), cx " << m.cx << " (" << truth.cx << "), cy " << m.cy << " (" << truth.cy
            << ")\n";
  EXPECT_NEAR(m.fx, truth.fx, 0.005 * truth.fx);
  EXPECT_NEAR(m.fy, truth.fy, 0.005 * truth.fy);
  EXPECT_NEAR(m.cx, truth.cx, 0.005 * truth.cx);
  EXPECT_NEAR(m.cy, truth.cy, 0.005 * truth.cy);
  EXPECT_LT(result.report.rms_px, 0.3);
}

TEST(RenderedTargets, RecoversPlumbBobIntrinsics) {
  const CameraModel truth = test::true_camera();
  std::vector<RejectedView> rejected;
  const auto views = render_standing_views(truth, test::shared_renderer(), rejected);
  for (const auto& r : rejected) {
    std::cout << "not found: " << r.name << ": " << r.reason << "\n";
  }
  EXPECT_GE(views.size(), 13U);
  const IntrinsicsResult result =
      calibrate_intrinsics(views, rejected, {truth.width_px, truth.height_px}, {});
  expect_recovered(truth, result);
  EXPECT_NEAR(result.model.coefficients[0], truth.coefficients[0], 0.02);
}

TEST(RenderedTargets, RecoversEquidistantIntrinsics) {
  CameraModel truth = test::true_camera();
  truth.distortion = DistortionModel::equidistant;
  truth.coefficients = {-0.05, 0.01, 0.0, 0.0};
  std::vector<RejectedView> rejected;
  const auto views = render_standing_views(truth, test::shared_renderer(), rejected);
  EXPECT_GE(views.size(), 13U);
  IntrinsicsOptions options;
  options.model = DistortionModel::equidistant;
  const IntrinsicsResult result =
      calibrate_intrinsics(views, rejected, {truth.width_px, truth.height_px}, options);
  expect_recovered(truth, result);
  EXPECT_EQ(result.model.distortion, DistortionModel::equidistant);
  // k1…k4 weigh θ³…θ⁹ and trade off against each other, so the fit is judged by the mapping
  // it gives, as a user sees it: each pixel's ray (by the truth) projected back by the
  // recovered model, over the part of the image the boards covered. Beyond it the polynomial
  // is extrapolated (the report's coverage says so); that error is printed, not bounded.
  const auto& k = result.model.coefficients;
  std::cout << "k1..k4 " << k[0] << " " << k[1] << " " << k[2] << " " << k[3]
            << " (true -0.05 0.01 0 0)\n";
  std::vector<std::vector<cv::Point2f>> hulls(views.size());
  for (std::size_t v = 0; v < views.size(); ++v) {
    cv::convexHull(views[v].board.image_points, hulls[v]);
  }
  const auto covered = [&](const cv::Point2d& p) {
    return std::any_of(hulls.begin(), hulls.end(), [&](const std::vector<cv::Point2f>& hull) {
      return cv::pointPolygonTest(hull, cv::Point2f(p), false) >= 0;
    });
  };
  std::vector<cv::Point2d> pixels;
  for (int y = 0; y <= truth.height_px; y += 20) {
    for (int x = 0; x <= truth.width_px; x += 20) {
      pixels.emplace_back(x, y);
    }
  }
  std::vector<cv::Point2d> rays;
  cv::fisheye::undistortPoints(pixels, rays, truth.camera_matrix(), truth.coefficients);
  std::vector<cv::Point3d> points;
  for (const cv::Point2d& r : rays) {
    points.emplace_back(r.x, r.y, 1.0);
  }
  std::vector<cv::Point2d> reprojected;
  const cv::Vec3d zero(0, 0, 0);
  cv::fisheye::projectPoints(points, reprojected, zero, zero, result.model.camera_matrix(),
                             result.model.coefficients);
  double worst_covered_px = 0.0;
  double worst_px = 0.0;
  std::size_t covered_count = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const double error_px = cv::norm(reprojected[i] - pixels[i]);
    worst_px = std::max(worst_px, error_px);
    if (covered(pixels[i])) {
      worst_covered_px = std::max(worst_covered_px, error_px);
      ++covered_count;
    }
  }
  std::cout << "mapping error: at most " << worst_covered_px << " px where the boards were ("
            << covered_count << " of " << pixels.size() << " grid points), " << worst_px
            << " px over the whole image\n";
  EXPECT_GT(covered_count, 2 * pixels.size() / 5);  // not a vacuous check
  EXPECT_LT(worst_covered_px, 1.0);
  EXPECT_NEAR(k[0], truth.coefficients[0], 0.05);  // the leading term, θ³
}

// The board flat on the floor, seen from a known height and pitch: both recovered within 1 cm
// and 0.5 degrees, roll within 0.5 degrees of level.
TEST(RenderedTargets, RecoversTheMountFromABoardOnTheFloor) {
  const CameraModel camera = test::true_camera();
  const BoardDetector detector(test::test_board());
  test::DistortedCamera distorted(camera, test::shared_renderer());
  constexpr double kBoardTop = 0.002;
  struct Case {
    double height_m, pitch_deg, yaw_deg, board_x_m;
  };
  for (const Case& c :
       {Case{0.45, 30.0, 0.0, 0.6}, Case{1.1, 50.0, 8.0, 0.75}, Case{0.3, 20.0, -5.0, 0.55}}) {
    const sim::World world(test::floor_board_world(detector.spec(), {c.board_x_m, 0.0}, kBoardTop));
    const cv::Mat image =
        distorted.render(world, {{0.0, 0.0, c.height_m}, c.yaw_deg * kDeg, c.pitch_deg * kDeg});
    std::string why;
    const auto board = detector.detect(image, why);
    ASSERT_TRUE(board) << why << " (height " << c.height_m << ")";
    const MountMeasurement m = measure_mount(camera, *board);
    std::cout << "height " << m.mount.mount.height_m << " m (true " << c.height_m - kBoardTop
              << "), pitch " << m.mount.mount.pitch_rad / kDeg << " deg (true " << c.pitch_deg
              << "), roll " << m.mount.roll_rad / kDeg << " deg, " << m.rms_px << " px\n";
    EXPECT_NEAR(m.mount.mount.height_m, c.height_m - kBoardTop, 0.01);
    EXPECT_NEAR(m.mount.mount.pitch_rad, c.pitch_deg * kDeg, 0.5 * kDeg);
    EXPECT_NEAR(m.mount.roll_rad, 0.0, 0.5 * kDeg);
  }
}

}  // namespace
