// ReplaySource on recordings the test writes: a video (MJPG in AVI) and image sequences, their
// timestamps and end, and the errors for missing, unreadable and inconsistent input. Lens
// options: a calibration of the wrong size is refused, a distorted one gives its pinhole.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/camera_io/replay_source.hpp"

#ifdef FLOWSTEER_HAVE_LIBCAMERA
#include "flowsteer/camera_io/libcamera_camera.hpp"
#endif

namespace {

namespace fs = std::filesystem;
using flowsteer::camera_io::CameraModel;
using flowsteer::camera_io::DistortionModel;
using flowsteer::camera_io::Frame;
using flowsteer::camera_io::ReadStatus;
using flowsteer::camera_io::ReplayOptions;
using flowsteer::camera_io::ReplaySource;

// Frame i: a grey level of 20·i, so that the order of frames can be read back from the pixels.
cv::Mat numbered_frame(int i, cv::Size size = {64, 48}) {
  return cv::Mat(size, CV_8UC3, cv::Scalar::all(20.0 * i));
}

class Replay : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::path(::testing::TempDir()) /
        ("replay_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write_video(int frames, double fps) {
    const std::string path = (dir_ / "run.avi").string();
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, {64, 48});
    EXPECT_TRUE(writer.isOpened());
    for (int i = 0; i < frames; ++i) {
      writer.write(numbered_frame(i));
    }
    return path;
  }
  void write_images(const char* pattern, int first, int count) {
    for (int i = 0; i < count; ++i) {
      char name[64];
      std::snprintf(name, sizeof name, pattern, first + i);
      ASSERT_TRUE(cv::imwrite((dir_ / name).string(), numbered_frame(i)));
    }
  }

  fs::path dir_;
};

TEST_F(Replay, VideoFramesComeInOrderWithContainerTimestampsThenEnd) {
  ReplayOptions options;
  options.path = write_video(6, 20.0);
  ReplaySource source(options);
  EXPECT_FALSE(source.is_image_sequence());
  EXPECT_DOUBLE_EQ(source.frame_rate_hz(), 20.0);
  EXPECT_EQ(source.intrinsics().width_px, 64);
  EXPECT_EQ(source.intrinsics().height_px, 48);
  Frame frame;
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok) << i;
    EXPECT_EQ(frame.sequence, static_cast<std::uint64_t>(i));
    EXPECT_NEAR(frame.timestamp_s, i / 20.0, 1e-6) << i;
    EXPECT_NEAR(cv::mean(frame.image)[1], 20.0 * i, 3.0) << "MJPG keeps flat grey levels";
    EXPECT_EQ(frame.image.type(), CV_8UC3);
  }
  EXPECT_EQ(source.read(frame, 0.1), ReadStatus::end_of_stream);
  EXPECT_EQ(source.read(frame, 0.1), ReadStatus::end_of_stream);
}

TEST_F(Replay, AGivenRateOverridesTheContainer) {
  ReplayOptions options;
  options.path = write_video(3, 20.0);
  options.frame_rate_hz = 5.0;
  ReplaySource source(options);
  Frame frame;
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, i / 5.0);
  }
}

TEST_F(Replay, PrintfPatternFromOneWithARate) {
  write_images("frame_%03d.png", 1, 4);
  ReplayOptions options;
  options.path = (dir_ / "frame_%03d.png").string();
  options.frame_rate_hz = 10.0;
  ReplaySource source(options);
  EXPECT_TRUE(source.is_image_sequence());
  EXPECT_EQ(source.frame_count(), 4u);
  Frame frame;
  for (int i = 0; i < 4; ++i) {
    ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, i / 10.0);
    EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0)[0], 20 * i);  // PNG is lossless
  }
  EXPECT_EQ(source.read(frame, 0.1), ReadStatus::end_of_stream);
}

TEST_F(Replay, GlobIsSortedByName) {
  write_images("img_%02d.png", 0, 12);  // img_10 sorts after img_09 only with the zero padding
  ReplayOptions options;
  options.path = (dir_ / "img_*.png").string();
  options.frame_rate_hz = 30.0;
  ReplaySource source(options);
  EXPECT_EQ(source.frame_count(), 12u);
  Frame frame;
  for (int i = 0; i < 12; ++i) {
    ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
    EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0)[0], 20 * i) << i;
  }
}

TEST_F(Replay, GlobTakesCharacterRanges) {
  write_images("img_%02d.png", 0, 12);
  ReplayOptions options;
  options.path = (dir_ / "img_0[2-4].png").string();
  options.frame_rate_hz = 30.0;
  ReplaySource source(options);
  EXPECT_EQ(source.frame_count(), 3u);
  Frame frame;
  for (int i = 2; i <= 4; ++i) {
    ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
    EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0)[0], 20 * i) << i;
  }
  EXPECT_EQ(source.read(frame, 0.1), ReadStatus::end_of_stream);
}

std::string error_of(const ReplayOptions& options) {
  try {
    ReplaySource source(options);
    Frame frame;
    while (source.read(frame, 0.1) == ReadStatus::ok) {
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST_F(Replay, MissingVideoIsAClearError) {
  ReplayOptions options;
  options.path = (dir_ / "nothing.mp4").string();
  EXPECT_EQ(error_of(options), "replay: cannot open video " + options.path + ": no such file");
}

TEST_F(Replay, AFileThatIsNoVideoIsAClearError) {
  ReplayOptions options;
  options.path = (dir_ / "notes.avi").string();
  std::ofstream(options.path) << "not a video\n";
  EXPECT_EQ(error_of(options),
            "replay: cannot open video " + options.path + ": not a video OpenCV can decode");
}

TEST_F(Replay, APatternThatMatchesNothingIsAClearError) {
  ReplayOptions options;
  options.path = (dir_ / "*.png").string();
  options.frame_rate_hz = 10.0;
  EXPECT_EQ(error_of(options), "replay: no image files match '" + options.path + "'");
}

TEST_F(Replay, AnImageSequenceNeedsARate) {
  write_images("f%d.png", 0, 2);
  ReplayOptions options;
  options.path = (dir_ / "f%d.png").string();
  EXPECT_NE(error_of(options).find("an image sequence has no timestamps; give its frame rate"),
            std::string::npos);
}

TEST_F(Replay, AnUnreadableImageIsNamed) {
  write_images("f%d.png", 0, 2);
  std::ofstream(dir_ / "f2.png") << "truncated";
  ReplayOptions options;
  options.path = (dir_ / "f%d.png").string();
  options.frame_rate_hz = 10.0;
  EXPECT_EQ(error_of(options), "replay: cannot read image " + (dir_ / "f2.png").string() +
                                   " (missing, unreadable or not an image)");
}

TEST_F(Replay, ImagesOfAnotherSizeAreAnError) {
  write_images("f%d.png", 0, 2);
  ASSERT_TRUE(cv::imwrite((dir_ / "f2.png").string(), numbered_frame(2, {32, 24})));
  ReplayOptions options;
  options.path = (dir_ / "f%d.png").string();
  options.frame_rate_hz = 10.0;
  EXPECT_NE(error_of(options).find("frame 2 is 32x24, the first was 64x48"), std::string::npos);
}

TEST_F(Replay, PrintfPatternNeedsOneIntegerConversion) {
  ReplayOptions options;
  options.path = (dir_ / "f%s.png").string();
  options.frame_rate_hz = 10.0;
  EXPECT_NE(error_of(options).find("must number frames with one %d"), std::string::npos);
}

// Found by fuzz/replay_pattern (tests/fuzz/regressions/replay_pattern/): a NUL in a printf
// pattern cut it before its %d, so every index named the same existing folder and the search
// for the sequence's end never ended; a field width of 2000000000 formatted 2 GB names.
TEST_F(Replay, APatternWithANulCharacterIsRefused) {
  fs::create_directories(dir_ / "100%");
  const std::string pattern = (dir_ / "100%%").string() + std::string("\0\0/%d.png", 8);
  try {
    flowsteer::camera_io::image_sequence_files(pattern);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("contains a NUL character"), std::string::npos)
        << e.what();
  }
}

TEST_F(Replay, AFieldWidthOverThirtyTwoIsRefused) {
  write_images("frame_%05d.png", 0, 2);
  EXPECT_EQ(flowsteer::camera_io::image_sequence_files((dir_ / "frame_%0005d.png").string()).size(),
            2u);
  try {
    flowsteer::camera_io::image_sequence_files((dir_ / "frame_%2000000000d.png").string());
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("field width 2000000000 is more than 32"),
              std::string::npos)
        << e.what();
  }
}

CameraModel distorted_model(int width, int height) {
  CameraModel model;
  model.width_px = width;
  model.height_px = height;
  model.fx = model.fy = 50.0;
  model.cx = width / 2.0;
  model.cy = height / 2.0;
  model.distortion = DistortionModel::plumb_bob;
  model.coefficients = {0.3, 0.1, 0.0, 0.0, 0.0};
  return model;
}

TEST_F(Replay, ACalibrationOfAnotherSizeIsRefused) {
  ReplayOptions options;
  options.path = write_video(2, 10.0);
  options.lens.model = distorted_model(640, 480);
  EXPECT_NE(
      error_of(options).find("the calibration is for 640x480 images, the source delivers 64x48"),
      std::string::npos);
}

TEST_F(Replay, ACalibratedSourceDeliversUndistortedPinholeImages) {
  ReplayOptions options;
  options.path = write_video(2, 10.0);
  options.lens.model = distorted_model(64, 48);
  ReplaySource source(options);
  EXPECT_DOUBLE_EQ(source.intrinsics().fx_px, 50.0);
  EXPECT_DOUBLE_EQ(source.intrinsics().cx_px, 32.0);
  Frame frame;
  ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
  ASSERT_EQ(source.read(frame, 0.1), ReadStatus::ok);
  // Pincushion distortion undone: the corners of the undistorted image come from beyond the
  // recorded image's corners and are black; the centre keeps the grey of frame 1.
  EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_NEAR(frame.image.at<cv::Vec3b>(24, 32)[0], 20, 3);
}

#ifdef FLOWSTEER_HAVE_LIBCAMERA
// These machines have no camera libcamera can drive; the constructor must say so.
TEST(Libcamera, NoCameraIsAClearError) {
  if (!flowsteer::camera_io::LibcameraCamera::list_cameras().empty()) {
    GTEST_SKIP() << "this machine has a camera libcamera can open";
  }
  try {
    flowsteer::camera_io::LibcameraCamera camera({});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("libcamera: no camera found"), std::string::npos)
        << e.what();
  }
}
#endif

}  // namespace
