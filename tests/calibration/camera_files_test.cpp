// camera_info and camera mount files: round trips, ROS's format, tolerated variants, bad files;
// and the camera model's undistortion.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "flowsteer/camera_io/camera_model.hpp"

namespace {

namespace fs = std::filesystem;
using flowsteer::base::ConfigError;
using flowsteer::calibration::CameraInfo;
using flowsteer::camera_io::CameraModel;
using flowsteer::camera_io::DistortionModel;

const fs::path kData = FLOWSTEER_CALIBRATION_DATA;

// A fresh, empty folder per test.
fs::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() / ("flowsteer_calib_" + std::string(info->name()) +
                                                    "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

CameraModel sample_model(DistortionModel distortion, std::vector<double> coefficients) {
  CameraModel m;
  m.width_px = 640;
  m.height_px = 480;
  m.fx = 512.25;
  m.fy = 509.0 + 1.0 / 3.0;
  m.cx = 321.125;
  m.cy = 236.7;
  m.distortion = distortion;
  m.coefficients = std::move(coefficients);
  return m;
}

void expect_same(const CameraInfo& a, const CameraInfo& b) {
  EXPECT_EQ(a.camera_name, b.camera_name);
  EXPECT_EQ(a.model.width_px, b.model.width_px);
  EXPECT_EQ(a.model.height_px, b.model.height_px);
  EXPECT_EQ(a.model.fx, b.model.fx);
  EXPECT_EQ(a.model.fy, b.model.fy);
  EXPECT_EQ(a.model.cx, b.model.cx);
  EXPECT_EQ(a.model.cy, b.model.cy);
  EXPECT_EQ(a.model.distortion, b.model.distortion);
  EXPECT_EQ(a.model.coefficients, b.model.coefficients);
  EXPECT_EQ(a.rectification, b.rectification);
  EXPECT_EQ(a.projection, b.projection);
}

// `text` contains `part`, shown in full when it does not.
void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "'" << text << "' lacks '" << part << "'";
}

std::string error_of(const fs::path& path) {
  std::vector<std::string> warnings;
  try {
    flowsteer::calibration::read_camera_info(path, warnings);
  } catch (const flowsteer::base::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CameraInfoFile, WrittenThenReadBackIdentically) {
  const fs::path dir = scratch_dir();
  for (const auto& [model, coefficients] :
       {std::pair{DistortionModel::plumb_bob,
                  std::vector<double>{-0.2814, 0.0713, 1.7e-4, -2.3e-4, -0.0071}},
        std::pair{DistortionModel::rational_polynomial,
                  std::vector<double>{0.1, -0.02, 1e-4, 2e-4, 0.003, 0.4, -0.05, 0.01}},
        std::pair{DistortionModel::equidistant,
                  std::vector<double>{0.031, -0.0052, 0.0011, 1e-5}}}) {
    CameraInfo info =
        CameraInfo::monocular("front camera: \"left\"", sample_model(model, coefficients));
    info.rectification[1] = 0.1 / 3.0;  // not the identity, to see it kept
    const fs::path file = dir / "camera.yaml";
    flowsteer::calibration::write_camera_info(file, info);
    std::vector<std::string> warnings;
    const CameraInfo back = flowsteer::calibration::read_camera_info(file, warnings);
    expect_same(info, back);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
  }
  // Nothing but the file itself: the temporary file was renamed, not left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(CameraInfoFile, ReadsWhatRosCameraCalibrationParsersWrites) {
  std::vector<std::string> warnings;
  const CameraInfo info =
      flowsteer::calibration::read_camera_info(kData / "ros_camera_info.yaml", warnings);
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(info.camera_name, "narrow_stereo");
  EXPECT_EQ(info.model.width_px, 640);
  EXPECT_EQ(info.model.height_px, 480);
  EXPECT_DOUBLE_EQ(info.model.fx, 430.21555);
  EXPECT_DOUBLE_EQ(info.model.fy, 430.531693);
  EXPECT_DOUBLE_EQ(info.model.cx, 306.691343);
  EXPECT_DOUBLE_EQ(info.model.cy, 227.2248);
  EXPECT_EQ(info.model.distortion, DistortionModel::plumb_bob);
  ASSERT_EQ(info.model.coefficients.size(), 5U);
  EXPECT_DOUBLE_EQ(info.model.coefficients[0], -0.337586);
  EXPECT_DOUBLE_EQ(info.model.coefficients[3], -3e-05);
  EXPECT_DOUBLE_EQ(info.projection[0], 360.457275);
  EXPECT_DOUBLE_EQ(info.projection[6], 226.082812);
  EXPECT_DOUBLE_EQ(info.rectification[4], 1.0);
}

TEST(CameraInfoFile, ToleratesMissingNameAndModelWithWarnings) {
  std::vector<std::string> warnings;
  const CameraInfo info =
      flowsteer::calibration::read_camera_info(kData / "old_camera_info.yaml", warnings);
  EXPECT_EQ(info.camera_name, "");
  EXPECT_EQ(info.model.distortion, DistortionModel::plumb_bob);
  EXPECT_DOUBLE_EQ(info.model.fx, 538.63);
  ASSERT_EQ(warnings.size(), 2U);
  expect_contains(warnings[0], "camera_name: missing, left empty");
  expect_contains(warnings[1], "distortion_model: missing, taken as plumb_bob");
}

TEST(CameraInfoFile, BadFilesNameTheFileAndField) {
  const std::string truncated = error_of(kData / "truncated_camera_info.yaml");
  expect_contains(truncated, "truncated_camera_info.yaml:");
  const std::string cut = error_of(kData / "cut_after_distortion.yaml");
  expect_contains(cut, "cut_after_distortion.yaml:1:1: rectification_matrix: missing");
  const std::string absent = error_of(kData / "no_such_camera_info.yaml");
  expect_contains(absent, "no_such_camera_info.yaml: cannot open");

  const fs::path dir = scratch_dir();
  auto error_for = [&](const std::string& text) {
    std::ofstream(dir / "bad.yaml") << text;
    return error_of(dir / "bad.yaml");
  };
  const std::string ros = [] {
    std::ifstream in(kData / "ros_camera_info.yaml");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = ros;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  expect_contains(error_for(replaced("cols: 5", "cols: 4")),
                  "bad.yaml:12:9: distortion_coefficients.data: expected a list of 4 numbers");
  expect_contains(error_for(replaced("plumb_bob", "fisheye_v2")),
                  "bad.yaml:8:19: distortion_model: expected plumb_bob");
  expect_contains(error_for(replaced("430.21555000000001", "-430")),
                  "camera_matrix.data[0]: fx must be positive");
  expect_contains(error_for(replaced("image_width: 640", "image_width: wide")),
                  "bad.yaml:1:14: image_width: expected a whole number");
  expect_contains(error_for(replaced("image_width: 640", "image_width: 100000")),
                  "bad.yaml:1:14: image_width: must be from 8 to 4096 px, got 100000");
  expect_contains(error_for(""), "bad.yaml:1:1: expected a camera_info mapping");
  fs::remove_all(dir);
}

// Found by fuzz/camera_info_yaml (tests/fuzz/regressions/camera_info_yaml/complex_key.yaml): a
// key that is a mapping ("? {...}") threw yaml-cpp's bad conversion, which named no field.
TEST(CameraInfoFile, AKeyThatIsNotTextIsAnErrorAtTheKey) {
  std::vector<std::string> warnings;
  try {
    flowsteer::calibration::parse_camera_info("image_width: 640\n? {camera_name: x}\n",
                                              "fuzzed.yaml", warnings);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "fuzzed.yaml:2:3: expected a text key, got a mapping");
  }
}

TEST(CameraInfoFile, AFailedWriteLeavesTheOldFile) {
  const fs::path dir = scratch_dir();
  const fs::path file = dir / "camera.yaml";
  std::ofstream(file) << "old";
  CameraInfo bad = CameraInfo::monocular("x", sample_model(DistortionModel::plumb_bob, {0.1}));
  EXPECT_THROW(flowsteer::calibration::write_camera_info(file, bad), std::invalid_argument);
  EXPECT_THROW(flowsteer::calibration::write_camera_info(
                   dir / "no_dir" / "camera.yaml",
                   CameraInfo::monocular("x", sample_model(DistortionModel::none, {}))),
               std::runtime_error);
  std::ifstream in(file);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(CameraMountFile, WrittenThenReadBackIdentically) {
  const fs::path dir = scratch_dir();
  flowsteer::calibration::MountCalibration m;
  m.mount.height_m = 0.4213;
  m.mount.pitch_rad = 0.3491 / 3.0;
  m.roll_rad = -0.0123;
  flowsteer::calibration::write_camera_mount(dir / "mount.yaml", m);
  const auto back = flowsteer::calibration::read_camera_mount(dir / "mount.yaml");
  EXPECT_EQ(back.mount.height_m, m.mount.height_m);
  EXPECT_EQ(back.mount.pitch_rad, m.mount.pitch_rad);
  EXPECT_EQ(back.roll_rad, m.roll_rad);
  fs::remove_all(dir);
}

// Found by fuzz/camera_mount_yaml (tests/fuzz/regressions/camera_mount_yaml/complex_key.yaml).
TEST(CameraMountFile, AKeyThatIsNotTextIsAnErrorAtTheKey) {
  auto error_for = [](const std::string& text) {
    try {
      flowsteer::calibration::parse_camera_mount(text, "fuzzed.yaml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_for("? hgight_m:h_c rad: 2.0\n"),
            "fuzzed.yaml:1:3: expected a text key, got a mapping");
  EXPECT_EQ(error_for("height_m: 0.5\n? [pitch_rad]\n: 0.2\n"),
            "fuzzed.yaml:2:3: expected a text key, got a sequence");
}

TEST(CameraMountFile, BadFilesNameTheField) {
  const fs::path dir = scratch_dir();
  auto error_for = [&](const std::string& text) {
    std::ofstream(dir / "mount.yaml") << text;
    try {
      flowsteer::calibration::read_camera_mount(dir / "mount.yaml");
    } catch (const flowsteer::base::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_for("height_m: 0.5\npitch_rad: 0.2\n"), "no error");
  expect_contains(error_for("height_m: 0.5\n"), "mount.yaml:1:1: pitch_rad: missing");
  expect_contains(error_for("height_m: -0.5\npitch_rad: 0.2\n"),
                  "mount.yaml:1:11: height_m: must be from 0.01 to 10 m, got -0.5");
  expect_contains(error_for("height_m: 1e9\npitch_rad: 0.2\n"),
                  "mount.yaml:1:11: height_m: must be from 0.01 to 10 m, got 1000000000");
  expect_contains(error_for("height_m: 0.5\npitch_rad: 2\n"),
                  "pitch_rad: must be from -1.553343034 to 1.553343034 rad, got 2");
  expect_contains(error_for("height_m: 0.5\npitch_rad: 0.2\nyaw_rad: 1\n"),
                  "3:1: yaw_rad: unknown key");
  expect_contains(error_for("height_m: [0.5\n"), "mount.yaml:");
  fs::remove_all(dir);
}

TEST(Undistorter, IdentityWithoutDistortion) {
  flowsteer::camera_io::Undistorter undistorter(
      sample_model(DistortionModel::plumb_bob, {0, 0, 0, 0, 0}));
  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));
  EXPECT_EQ(&undistorter.apply(image), &image);
  EXPECT_THROW(undistorter.apply(cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
}

// A dot drawn where the distorted camera sees a point lands, after undistortion, where the
// pinhole camera would see it; the output buffer is reused from call to call.
TEST(Undistorter, MovesDistortedPointsToTheirPinholePositions) {
  for (const auto& model : {sample_model(DistortionModel::plumb_bob, {-0.3, 0.1, 0.0, 0.0, 0.0}),
                            sample_model(DistortionModel::equidistant, {0.05, -0.01, 0.0, 0.0})}) {
    flowsteer::camera_io::Undistorter undistorter(model);
    const cv::Point2d normalised(-0.45, 0.3);
    std::vector<cv::Point3d> object = {{normalised.x, normalised.y, 1.0}};
    std::vector<cv::Point2d> distorted;
    const cv::Vec3d zero(0, 0, 0);
    if (model.distortion == DistortionModel::equidistant) {
      cv::fisheye::projectPoints(object, distorted, zero, zero, model.camera_matrix(),
                                 model.coefficients);
    } else {
      cv::projectPoints(object, zero, zero, model.camera_matrix(), model.coefficients, distorted);
    }
    cv::Mat image(480, 640, CV_8UC1, cv::Scalar(0));
    cv::circle(image, cv::Point(cvRound(distorted[0].x), cvRound(distorted[0].y)), 3,
               cv::Scalar(255), cv::FILLED);
    const cv::Mat& first = undistorter.apply(image);
    const uchar* buffer = first.data;
    const cv::Mat& out = undistorter.apply(image);
    EXPECT_EQ(out.data, buffer);
    const cv::Moments moments = cv::moments(out, false);
    const double col = moments.m10 / moments.m00;
    const double row = moments.m01 / moments.m00;
    EXPECT_NEAR(col, model.cx + model.fx * normalised.x, 1.0);
    EXPECT_NEAR(row, model.cy + model.fy * normalised.y, 1.0);
    EXPECT_GT(std::hypot(distorted[0].x - col, distorted[0].y - row), 5.0);
  }
}

}  // namespace
