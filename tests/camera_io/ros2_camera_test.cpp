// Ros2Camera against images published in this process with ros2_dds on loopback: an Image with
// CameraInfo for its lens, a CompressedImage, and what it must refuse by name (an image that does
// not decode, a binned camera).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "../ros2_dds/loopback_dds.hpp"
#include "flowsteer/camera_io/ros2_camera.hpp"
#include "flowsteer/ros2_dds/participant.hpp"
#include "flowsteer/ros2_dds/topics.hpp"

namespace {

using namespace flowsteer;
namespace ros2 = recording::ros2;

constexpr int kDomain = 141;

// Calls publish() every 30 ms on a thread of its own until destroyed: a camera driver.
class Driver {
 public:
  explicit Driver(std::function<void()> publish)
      : thread_([this, publish] {
          while (!stop_) {
            publish();
            std::this_thread::sleep_for(std::chrono::milliseconds(30));
          }
        }) {}
  ~Driver() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

ros2::Image grey_image(std::uint8_t value) {
  ros2::Image image;
  image.header.stamp = ros2::Time::from_ns(0);  // unset: the time it was taken from DDS counts
  image.height = 6;
  image.width = 8;
  image.encoding = "mono8";
  image.step = 8;
  image.data.assign(48, value);
  return image;
}

ros2::CameraInfo camera_info(std::uint32_t binning) {
  ros2::CameraInfo info;
  info.width = 8;
  info.height = 6;
  info.distortion_model = "plumb_bob";
  info.d = {0, 0, 0, 0, 0};
  info.k = {11.5, 0, 4, 0, 12.5, 3, 0, 0, 1};
  info.binning_x = info.binning_y = binning;
  return info;
}

camera_io::Ros2CameraOptions options(const std::string& prefix) {
  camera_io::Ros2CameraOptions o;
  o.domain_id = kDomain;
  o.image_topic = prefix + "/image_raw";
  o.connect_timeout_s = 10.0;
  return o;
}

TEST(Ros2Camera, ImageWithCameraInfoForItsLens) {
  ros2_dds_test::use_loopback_dds();
  const ros2_dds::Participant driver_node(kDomain);
  ros2_dds::Publisher<ros2::Image> images(driver_node, "/a/image_raw", ros2_dds::Qos{});
  ros2_dds::Publisher<ros2::CameraInfo> infos(driver_node, "/a/camera_info", ros2_dds::Qos{});
  std::uint8_t grey = 10;
  const Driver driver([&] {
    images.publish(grey_image(grey));
    infos.publish(camera_info(1));
  });
  camera_io::Ros2CameraOptions o = options("/a");
  o.camera_info_topic = "/a/camera_info";
  camera_io::Ros2Camera camera(o);
  EXPECT_EQ(camera.intrinsics().width_px, 8);
  EXPECT_EQ(camera.intrinsics().fx_px, 11.5);
  EXPECT_EQ(camera.intrinsics().fy_px, 12.5);
  camera_io::Frame frame;
  ASSERT_EQ(camera.read(frame, 5.0), camera_io::ReadStatus::ok);
  EXPECT_EQ(frame.image.type(), CV_8UC3);
  EXPECT_EQ(frame.image.at<cv::Vec3b>(2, 3), cv::Vec3b(10, 10, 10));
  const double first_s = frame.timestamp_s;
  ASSERT_EQ(camera.read(frame, 5.0), camera_io::ReadStatus::ok);
  EXPECT_GT(frame.timestamp_s, first_s);
  EXPECT_EQ(frame.sequence, 1u);
}

TEST(Ros2Camera, CompressedImagesDecodeAndABadOneIsNamed) {
  ros2_dds_test::use_loopback_dds();
  const ros2_dds::Participant driver_node(kDomain);
  ros2_dds::Publisher<ros2::CompressedImage> images(driver_node, "/b/image_raw/compressed",
                                                    ros2_dds::Qos{});
  std::atomic<bool> corrupt{false};
  ros2::CompressedImage png;
  png.format = "png";
  cv::imencode(".png", cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3)), png.data);
  ros2::CompressedImage bad = png;
  bad.data.resize(bad.data.size() / 2);
  const Driver driver([&] { images.publish(corrupt ? bad : png); });
  camera_io::Ros2CameraOptions o = options("/b");
  o.image_topic = "/b/image_raw/compressed";
  o.image_type = camera_io::Ros2ImageType::compressed_image;
  camera_io::Ros2Camera camera(o);
  camera_io::Frame frame;
  ASSERT_EQ(camera.read(frame, 5.0), camera_io::ReadStatus::ok);
  EXPECT_EQ(frame.image.at<cv::Vec3b>(5, 7), cv::Vec3b(1, 2, 3));
  corrupt = true;
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  try {
    for (int i = 0; i < 20; ++i) {
      camera.read(frame, 1.0);
    }
    FAIL() << "a CompressedImage that does not decode was delivered";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("ros2 camera /b/image_raw/compressed (domain 141): a "
                                         "CompressedImage in format 'png' of"),
              std::string::npos)
        << e.what();
  }
}

TEST(Ros2Camera, ABinnedCameraInfoIsRefusedByName) {
  ros2_dds_test::use_loopback_dds();
  const ros2_dds::Participant driver_node(kDomain);
  ros2_dds::Publisher<ros2::Image> images(driver_node, "/c/image_raw", ros2_dds::Qos{});
  ros2_dds::Publisher<ros2::CameraInfo> infos(driver_node, "/c/camera_info", ros2_dds::Qos{});
  const Driver driver([&] {
    images.publish(grey_image(0));
    infos.publish(camera_info(2));
  });
  camera_io::Ros2CameraOptions o = options("/c");
  o.camera_info_topic = "/c/camera_info";
  try {
    camera_io::Ros2Camera camera(o);
    FAIL() << "a binned camera's CameraInfo was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("binning_x 2"), std::string::npos) << e.what();
  }
}

}  // namespace
