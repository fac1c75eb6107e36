// Capture against a SimCamera: views are kept for new coverage or a new pose, duplicates are
// not; `flowsteer calibrate capture`'s work (calibration::run_calibrate_capture) writes its folder
// only when the calibration succeeds. And the boards: specs, the ChArUco path, its warning.
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/aruco/charuco.hpp>

#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/calibration/capture.hpp"
#include "flowsteer/calibration/intrinsics.hpp"
#include "flowsteer/calibration/calibrate_commands.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"
#include "target_scene.hpp"

namespace {

namespace fs = std::filesystem;
using namespace flowsteer::calibration;
namespace sim = flowsteer::sim_camera;

// An agent's head camera in front of the standing board, as a SimCamera. Moving, it takes the
// tests' views around the board in turn, each for three frames in a row (as a camera held still
// for a moment delivers them); still, it stays at the first.
class MovingCamera final : public flowsteer::camera_io::FrameSource {
 public:
  MovingCamera(sim::Renderer& renderer, bool moving)
      : renderer_(renderer), poses_(test::standing_board_views()), moving_(moving) {
    place(poses_.front());
  }

  const flowsteer::base::CameraIntrinsics& intrinsics() const override {
    return camera_->intrinsics();
  }
  flowsteer::camera_io::ReadStatus read(flowsteer::camera_io::Frame& frame,
                                        double timeout_s) override {
    const std::size_t pose = frames_ / kRepeats;
    if (pose >= poses_.size()) {
      return flowsteer::camera_io::ReadStatus::end_of_stream;
    }
    if (moving_ && frames_ % kRepeats == 0) {
      place(poses_[pose]);
    }
    const auto status = camera_->read(frame, timeout_s);
    frame.sequence = frames_++;
    return status;
  }

 private:
  static constexpr std::size_t kRepeats = 3;

  // The agent's pose and head camera are the world's: a new world per pose.
  void place(const test::CameraPose& pose) {
    sim::WorldSpec w = test::standing_board_world(test::test_board());
    sim::AgentSpec& a = w.agents.front();
    a.start_m = pose.eye_m.head<2>();
    a.heading_rad = pose.yaw_rad;
    a.goals = {a.start_m + Eigen::Vector2d(-1.0, 0.0)};
    a.camera.width_px = 640;
    a.camera.height_px = 480;
    a.camera.hfov_rad = 2.0 * std::atan(320.0 / 520.0);
    a.camera.height_m = pose.eye_m.z();
    a.camera.pitch_rad = pose.pitch_rad;
    camera_.reset();
    world_ = std::make_unique<sim::World>(w);
    camera_ = std::make_unique<sim::SimCamera>(*world_, renderer_, 0);
  }

  sim::Renderer& renderer_;
  std::vector<test::CameraPose> poses_;
  bool moving_;
  std::size_t frames_ = 0;
  std::unique_ptr<sim::World> world_;
  std::unique_ptr<sim::SimCamera> camera_;
};

TEST(Capture, KeepsViewsThatAddCoverageOrPoseAndSkipsDuplicates) {
  MovingCamera source(test::shared_renderer(), true);
  const BoardDetector detector(test::test_board());
  CaptureOptions options;
  options.views = 100;  // more than there are: the source's end stops the capture
  std::ostringstream log;
  const CaptureResult result = capture_views(source, detector, options, log);
  std::cout << log.str() << result.frames << " frames, " << result.frames_with_board
            << " with the board, " << result.views.size() << " views kept\n";
  EXPECT_TRUE(result.source_ended);
  EXPECT_EQ(result.frames, 45);
  EXPECT_GE(result.views.size(), 10U);
  // At most one view per pose: the repeats add nothing.
  std::set<std::uint64_t> poses;
  for (const CapturedView& v : result.views) {
    EXPECT_TRUE(poses.insert(v.sequence / 3).second) << "frame " << v.sequence;
  }
}

TEST(Capture, AStillCameraGivesOneViewAndNoCalibration) {
  MovingCamera source(test::shared_renderer(), false);
  const BoardDetector detector(test::test_board());
  CaptureOptions options;
  options.max_frames = 6;
  std::ostringstream log;
  EXPECT_EQ(capture_views(source, detector, options, log).views.size(), 1U);

  MovingCamera again(test::shared_renderer(), false);
  flowsteer::calibration::CaptureCommand command;
  command.board = "chessboard:9x6:0.05";
  command.out_dir =
      fs::temp_directory_path() / ("flowsteer_capture_still_" + std::to_string(::getpid()));
  command.capture.max_frames = 6;
  std::ostringstream out;
  try {
    flowsteer::calibration::run_calibrate_capture(command, again, out, log);
    ADD_FAILURE() << "calibrated from one view";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("too few views to calibrate: 1 usable"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(command.out_dir / "camera_info.yaml"));
  fs::remove_all(command.out_dir);
}

TEST(Capture, CalibratesAndWritesItsFolder) {
  MovingCamera source(test::shared_renderer(), true);
  flowsteer::calibration::CaptureCommand command;
  command.board = "chessboard:9x6:0.05";
  command.out_dir = fs::temp_directory_path() / ("flowsteer_capture_" + std::to_string(::getpid()));
  command.capture.views = 12;
  std::ostringstream out;
  std::ostringstream log;
  flowsteer::calibration::run_calibrate_capture(command, source, out, log);
  std::cout << out.str();
  EXPECT_TRUE(fs::exists(command.out_dir / "view_00.png"));
  EXPECT_TRUE(fs::exists(command.out_dir / "report.txt"));
  std::vector<std::string> warnings;
  const CameraInfo info = read_camera_info(command.out_dir / "camera_info.yaml", warnings);
  // The SimCamera's pinhole: fx = fy = 520, principal point at the centre. Its renders are
  // aliased (no supersampling here), so the tolerance is looser than the intrinsics tests'.
  EXPECT_NEAR(info.model.fx, 520.0, 0.02 * 520.0);
  EXPECT_NEAR(info.model.fy, 520.0, 0.02 * 520.0);
  EXPECT_NEAR(info.model.cx, 319.5, 0.02 * 319.5);
  EXPECT_NEAR(info.model.cy, 239.5, 0.02 * 239.5);
  fs::remove_all(command.out_dir);
}

TEST(BoardSpec, TextReadsBackAsTheSameNumbers) {
  const BoardSpec spec = BoardSpec::parse("charuco:5x7:0.0254001:0.0190001:DICT_4X4_50");
  EXPECT_EQ(spec.text(), "charuco:5x7:0.0254001:0.0190001:DICT_4X4_50");
  const BoardSpec back = BoardSpec::parse(spec.text());
  EXPECT_EQ(back.square_m, spec.square_m);
  EXPECT_EQ(back.marker_m, spec.marker_m);
}

TEST(BoardSpec, ParsesAndExplainsBadSpecs) {
  const BoardSpec c = BoardSpec::parse("charuco:5x7:0.04:0.03:DICT_4X4_50");
  EXPECT_EQ(c.kind, BoardSpec::Kind::charuco);
  EXPECT_EQ(c.corner_count(), 24);
  EXPECT_TRUE(c.warnings().empty());
  EXPECT_EQ(BoardSpec::parse(c.text()).text(), c.text());
  const auto even = BoardSpec::parse("charuco:5x4:0.04:0.03:DICT_4X4_50").warnings();
  ASSERT_EQ(even.size(), 1U);
  EXPECT_NE(even[0].find("even number of rows"), std::string::npos);
  auto error = [](const std::string& text) {
    try {
      BoardSpec::parse(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("chess:9x6:0.05").find("unknown board type 'chess'"), std::string::npos);
  EXPECT_NE(error("chessboard:9by6:0.05").find("size '9by6' is not COLSxROWS"), std::string::npos);
  EXPECT_NE(error("chessboard:9x6:-1").find("SQUARE_M must be positive"), std::string::npos);
  EXPECT_NE(error("chessboard:9x6").find("takes 2 fields"), std::string::npos);
  EXPECT_NE(error("charuco:5x7:0.04:0.05:DICT_4X4_50").find("MARKER_M (0.05) must be smaller"),
            std::string::npos);
  // Equal once made the floats OpenCV's board takes.
  EXPECT_NE(error("charuco:5x7:0.10000000001:0.1:DICT_4X4_50").find("must be smaller"),
            std::string::npos);
  EXPECT_NE(error("charuco:5x7:0.04:0.03:DICT_9X9").find("unknown dictionary 'DICT_9X9'"),
            std::string::npos);
}

// The message of the std::invalid_argument that parsing `text` (and, with `detector`, building
// its detector) throws; "no error" when there is none.
std::string board_error(const std::string& text, bool detector = false) {
  try {
    const BoardSpec spec = BoardSpec::parse(text);
    if (detector) {
      const BoardDetector built(spec);
    }
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

// Found by fuzz/board_spec (tests/fuzz/regressions/board_spec/huge_charuco.txt): a board of
// 599999 columns was accepted and its detector took minutes to build before it was refused.
TEST(BoardSpec, ABoardOfMoreThanAHundredCornersASideIsRefused) {
  EXPECT_NE(board_error("charuco:599999x7:0.04:0.02:DICT_APRILTAG_36h11")
                .find("COLS must be at most 100, got 599999"),
            std::string::npos);
  EXPECT_EQ(BoardSpec::parse("chessboard:100x100:0.01").corner_count(), 10000);
  EXPECT_NE(board_error("chessboard:9x101:0.01").find("ROWS must be at most 100, got 101"),
            std::string::npos);
  // The dictionary's size is checked before the board is made.
  EXPECT_NE(board_error("charuco:100x100:0.04:0.02:DICT_4X4_50", true)
                .find("needs 5000 markers, DICT_4X4_50 has only 50"),
            std::string::npos);
}

// Found by fuzz/board_spec (tests/fuzz/regressions/board_spec/tiny_marker.txt and
// tiny_marker_fuzzed.txt): a marker of 2e-50 m is 0 as OpenCV's float, and its assertion escaped
// as a cv::Exception.
TEST(BoardSpec, LengthsBelowATenthOfAMillimetreOrAboveTenMetresAreRefused) {
  EXPECT_NE(board_error("charuco:9x6:0.04:2e-50:DICT_APRILTAG_16h5")
                .find("MARKER_M must be at least 0.0001 m, got 2e-50"),
            std::string::npos);
  const std::string tiny = "0." + std::string(86, '0') + "2";
  EXPECT_NE(board_error("charuco:9x6:0.04:" + tiny + ":DICT_APRILTAG_16h5")
                .find("MARKER_M must be at least 0.0001 m, got " + tiny),
            std::string::npos);
  EXPECT_NE(board_error("chessboard:9x6:0.00005").find("SQUARE_M must be at least 0.0001 m"),
            std::string::npos);
  EXPECT_EQ(board_error("charuco:9x6:0.0002:0.0001:DICT_4X4_50", true), "no error");
  EXPECT_NE(board_error("chessboard:9x6:1e300").find("SQUARE_M must be at most 10 m, got 1e300"),
            std::string::npos);
}

// A ChArUco board as OpenCV draws it (cv::aruco::CharucoBoard::draw), seen whole and with a
// third of it covered: every visible corner found, at the drawn positions.
TEST(BoardDetector, FindsChArUcoCornersAlsoWhenPartlyHidden) {
  const BoardSpec spec = BoardSpec::parse("charuco:7x5:0.04:0.03:DICT_4X4_50");
  const BoardDetector detector(spec);
  const auto board = cv::aruco::CharucoBoard::create(
      7, 5, 0.04F, 0.03F, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50));
  cv::Mat image;
  board->draw(cv::Size(7 * 60 + 80, 5 * 60 + 80), image, 40);
  std::string why;
  const auto whole = detector.detect(image, why);
  ASSERT_TRUE(whole) << why;
  EXPECT_EQ(static_cast<int>(whole->image_points.size()), spec.corner_count());
  for (std::size_t i = 0; i < whole->image_points.size(); ++i) {
    // 60 px per square, the board 40 px in from the edges of the drawing.
    EXPECT_NEAR(whole->image_points[i].x, 40.0 + 1500.0 * whole->object_points[i].x, 1.0);
    EXPECT_NEAR(whole->image_points[i].y, 40.0 + 1500.0 * whole->object_points[i].y, 1.0);
  }
  image(cv::Rect(0, 0, image.cols / 3, image.rows)).setTo(cv::Scalar(255));
  const auto part = detector.detect(image, why);
  ASSERT_TRUE(part) << why;
  EXPECT_GE(part->image_points.size(), 8U);
  EXPECT_LT(part->image_points.size(), whole->image_points.size());
  EXPECT_FALSE(detector.detect(cv::Mat(300, 400, CV_8UC1, cv::Scalar(128)), why));
  EXPECT_EQ(why, "no DICT_4X4_50 marker found");
}

}  // namespace
