// Intrinsics, mount and capture against views rendered by sim_camera with known parameters.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>

#include <gtest/gtest.h>

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
