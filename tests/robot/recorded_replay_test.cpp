// `flowsteer replay FILE.mcap` on recordings written here, as a robot's camera driver and
// odometry would write them: raw Image messages of each encoding, no odometry or several
// channels, and messages that are not what their channel says.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "flowsteer/recording/mcap_writer.hpp"
#include "flowsteer/recording/recording_error.hpp"
#include "flowsteer/recording/ros2_messages.hpp"
#include "flowsteer/robot/robot_commands.hpp"

namespace flowsteer::robot {
namespace {

namespace fs = std::filesystem;
namespace ros2 = recording::ros2;

constexpr int kWidth = 96;
constexpr int kHeight = 72;

// A textured picture that slides right by `shift_px` a frame: flow for the estimator.
cv::Mat textured(int shift_px) {
  cv::Mat image(kHeight, kWidth, CV_8UC3);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      const double u = c - shift_px;
      const auto v = static_cast<std::uint8_t>(128 + 60 * std::sin(0.4 * u) * std::cos(0.3 * r));
      image.at<cv::Vec3b>(r, c) = {v, static_cast<std::uint8_t>(255 - v), v};
    }
  }
  return image;
}

class RecordedReplay : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("flowsteer_recorded_replay_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  template <typename M>
  std::uint16_t channel(recording::McapWriter& w, const std::string& topic) {
    using T = ros2::MessageType<M>;
    return w.add_channel(topic, "cdr", w.add_schema(T::name(), "ros2msg", T::schema()));
  }
  template <typename M>
  void put(recording::McapWriter& w, std::uint16_t channel, std::uint64_t t_ns, const M& m) {
    ros2::MessageType<M>::encode(m, bytes_);
    w.write(channel, t_ns, bytes_);
  }

  static ros2::Image image_message(const cv::Mat& bgr, const std::string& encoding,
                                   std::uint64_t t_ns, const std::string& frame = "front_camera") {
    ros2::Image m;
    m.header = {ros2::Time::from_ns(t_ns), frame};
    cv::Mat pixels;
    if (encoding == "rgb8") {
      cv::cvtColor(bgr, pixels, cv::COLOR_BGR2RGB);
    } else {
      cv::cvtColor(bgr, pixels, cv::COLOR_BGR2GRAY);
    }
    m.width = static_cast<std::uint32_t>(pixels.cols);
    m.height = static_cast<std::uint32_t>(pixels.rows);
    m.encoding = encoding;
    m.step = static_cast<std::uint32_t>(pixels.cols * pixels.elemSize());
    m.data.assign(pixels.datastart, pixels.dataend);
    return m;
  }

  static ros2::CameraInfo camera_info(std::uint64_t t_ns) {
    ros2::CameraInfo info;
    info.header = {ros2::Time::from_ns(t_ns), "front_camera"};
    info.width = kWidth;
    info.height = kHeight;
    info.d.assign(5, 0.0);
    info.k = {80.0, 0.0, 47.5, 0.0, 80.0, 35.5, 0.0, 0.0, 1.0};
    return info;
  }

  // `frames` rgb8 frames on /front/image_raw at 20 Hz with their CameraInfo; with `second`, a
  // mono8 camera on /rear/image_raw too; with `odometry`, /odom at 100 Hz turning left at
  // 0.3 rad/s.
  fs::path write_recording(int frames, bool second, bool odometry) {
    const fs::path path = dir_ / "robot.mcap";
    recording::McapWriter w(path, {});
    const std::uint16_t front = channel<ros2::Image>(w, "/front/image_raw");
    const std::uint16_t info = channel<ros2::CameraInfo>(w, "/front/camera_info");
    const std::uint16_t rear = second ? channel<ros2::Image>(w, "/rear/image_raw") : 0;
    const std::uint16_t odom = odometry ? channel<ros2::Odometry>(w, "/odom") : 0;
    for (int k = 0; k < frames * 5; ++k) {
      const std::uint64_t t_ns = 1'000'000'000 + static_cast<std::uint64_t>(k) * 10'000'000;
      if (odometry) {
        ros2::Odometry o;
        o.header = {ros2::Time::from_ns(t_ns), "odom"};
        o.child_frame_id = "base_link";
        o.twist.linear.x = 0.4;
        o.twist.angular.z = 0.3;
        put(w, odom, t_ns, o);
      }
      if (k % 5 == 0) {
        const cv::Mat picture = textured(k / 5);
        put(w, front, t_ns, image_message(picture, "rgb8", t_ns));
        put(w, info, t_ns, camera_info(t_ns));
        if (second) {
          put(w, rear, t_ns, image_message(picture, "mono8", t_ns, "rear_camera"));
        }
      }
    }
    w.finish();
    return path;
  }

  ReplaySummary replay(const fs::path& recording, ReplayCommand command = {}) {
    command.video = recording.string();
    command.out_dir = (dir_ / "out").string();
    std::ostringstream log;
    const ReplaySummary summary = run_replay_command(command, log);
    log_ = log.str();
    return summary;
  }

  // The commands.csv column `name`, one value per frame.
  std::vector<double> column(const std::string& name) {
    std::ifstream in(dir_ / "out" / "commands.csv");
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');)
      header.push_back(cell);
    const auto index = std::find(header.begin(), header.end(), name) - header.begin();
    std::vector<double> values;
    while (std::getline(in, line)) {
      std::stringstream row(line);
      std::string cell;
      for (long k = 0; k <= index; ++k)
        std::getline(row, cell, ',');
      values.push_back(std::stod(cell));
    }
    return values;
  }

  fs::path dir_;
  std::vector<std::uint8_t> bytes_;
  std::string log_;  // the last replay's
};

TEST_F(RecordedReplay, RawImagesWithOdometryGiveTheLastOdometryAtEachImage) {
  const ReplaySummary summary = replay(write_recording(12, false, true));
  EXPECT_EQ(summary.frames, 12u);
  EXPECT_LT(summary.blind_frames, 12u);
  for (const double v : column("speed_mps"))
    EXPECT_EQ(v, 0.4);
  // ROS's yaw rate 0.3 (left) is flowsteer's turn rate −0.3.
  for (const double w : column("turn_rate_measured"))
    EXPECT_EQ(w, -0.3);
  const std::vector<double> t = column("t_s");
  ASSERT_EQ(t.size(), 12u);
  EXPECT_NEAR(t[1] - t[0], 0.05, 1e-12);
}

TEST_F(RecordedReplay, TheMountComesFromTheChainOfStaticTransformsToTheBase) {
  const fs::path path = dir_ / "mounted.mcap";
  {
    recording::McapWriter w(path, {});
    const std::uint16_t front = channel<ros2::Image>(w, "/front/image_raw");
    const std::uint16_t info = channel<ros2::CameraInfo>(w, "/front/camera_info");
    const std::uint16_t tf = channel<ros2::TFMessage>(w, "/tf_static");
    // A driver's usual pair: the camera's body pitched 10° down, 0.3 m up and 0.1 m ahead, and
    // its optical frame (z forward, x right, y down) turned from it.
    const double half = 0.5 * 10.0 * M_PI / 180.0;
    ros2::TransformStamped body;
    body.header.frame_id = "robot/base_link";
    body.child_frame_id = "camera_link";
    body.translation = {0.1, 0.0, 0.3};
    body.rotation = {0.0, std::sin(half), 0.0, std::cos(half)};
    ros2::TransformStamped optical;
    optical.header.frame_id = "camera_link";
    optical.child_frame_id = "front_camera";
    optical.rotation = {-0.5, 0.5, -0.5, 0.5};
    const ros2::TFMessage mounts{{body, optical}};
    put(w, tf, 0, mounts);
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t t_ns = 50'000'000u * static_cast<std::uint64_t>(k);
      put(w, info, t_ns, camera_info(t_ns));
      put(w, front, t_ns, image_message(textured(k), "rgb8", t_ns));
    }
    w.finish();
  }
  replay(path);
  EXPECT_NE(log_.find("camera mount from /tf_static: 0.30 m high, pitched 10.0 deg down"),
            std::string::npos)
      << log_;
}

TEST_F(RecordedReplay, WithoutOdometryTheSpeedIsTheOneGiven) {
  ReplayCommand command;
  command.speed_mps = 0.25;
  replay(write_recording(6, false, false), command);
  for (const double v : column("speed_mps"))
    EXPECT_EQ(v, 0.25);
  for (const double w : column("turn_rate_measured"))
    EXPECT_EQ(w, 0.0);
}

TEST_F(RecordedReplay, TwoCamerasNeedATopicAndAGrayOneIsRead) {
  const fs::path recording = write_recording(6, true, false);
  try {
    replay(recording);
    FAIL() << "two image channels were not refused";
  } catch (const recording::RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "2 image channels (/front/image_raw, /rear/image_raw): choose one with "
                  "--image-topic"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  ReplayCommand command;
  command.image_topic = "/rear/image_raw";
  command.hfov_deg = 60.0;  // the rear camera's frame has no CameraInfo of its own
  EXPECT_EQ(replay(recording, command).frames, 6u);
}

TEST_F(RecordedReplay, ACameraWithoutCameraInfoOrLensIsNamed) {
  const fs::path recording = write_recording(3, true, false);
  ReplayCommand command;
  command.image_topic = "/rear/image_raw";
  try {
    replay(recording, command);
    FAIL();
  } catch (const recording::RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("no CameraInfo for the frame 'rear_camera' of "
                                         "/rear/image_raw: give --camera-info or --hfov-deg"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(RecordedReplay, AnImageShorterThanItsSizeNamesTopicAndIndex) {
  const fs::path path = dir_ / "short.mcap";
  {
    recording::McapWriter w(path, {});
    const std::uint16_t front = channel<ros2::Image>(w, "/front/image_raw");
    const std::uint16_t info = channel<ros2::CameraInfo>(w, "/front/camera_info");
    put(w, info, 0, camera_info(0));
    put(w, front, 0, image_message(textured(0), "rgb8", 0));
    ros2::Image cut = image_message(textured(1), "rgb8", 50'000'000);
    cut.data.resize(cut.data.size() / 2);
    put(w, front, 50'000'000, cut);
    w.finish();
  }
  try {
    replay(path);
    FAIL();
  } catch (const recording::RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("/front/image_raw message 1: 96x72 pixels of rgb8 with "
                                         "step 288 do not fit its 10368 bytes"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
}  // namespace flowsteer::robot
