// bgr_to_yuyv, what V4l2Output sends: the inverse of the YUYV conversion V4l2Camera uses
// (OpenCV's COLOR_YUV2BGR_YUYV), so a view looped through a V4L2 output and capture pair comes
// back as it went out, but for chroma shared by each pixel pair.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "flowsteer/camera_io/v4l2_output.hpp"

namespace {

using flowsteer::camera_io::bgr_to_yuyv;

// The largest difference, in levels, of the image after bgr_to_yuyv and OpenCV's way back.
double round_trip_error(const cv::Mat& bgr) {
  cv::Mat yuyv;
  bgr_to_yuyv(bgr, yuyv);
  cv::Mat back;
  cv::cvtColor(yuyv, back, cv::COLOR_YUV2BGR_YUYV);
  cv::Mat diff;
  cv::absdiff(back, bgr, diff);
  double worst = 0.0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  return worst;
}

TEST(BgrToYuyv, GreysComeBackWithinTwoLevels) {
  cv::Mat ramp(4, 256, CV_8UC3);
  for (int x = 0; x < 256; ++x) {
    ramp.col(x).setTo(cv::Scalar::all(x));
  }
  EXPECT_LE(round_trip_error(ramp), 2.0);
}

TEST(BgrToYuyv, ColoursSharedByAPixelPairComeBackWithinThreeLevels) {
  cv::Mat image(32, 64, CV_8UC3);
  cv::RNG rng(7);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; x += 2) {
      const cv::Vec3b colour(rng.uniform(16, 240), rng.uniform(16, 240), rng.uniform(16, 240));
      image.at<cv::Vec3b>(y, x) = image.at<cv::Vec3b>(y, x + 1) = colour;
    }
  }
  EXPECT_LE(round_trip_error(image), 3.0);
}

TEST(BgrToYuyv, LumaIsPerPixelAndChromaPerPair) {
  cv::Mat image(1, 2, CV_8UC3);
  image.at<cv::Vec3b>(0, 0) = {0, 0, 0};
  image.at<cv::Vec3b>(0, 1) = {255, 255, 255};
  cv::Mat yuyv;
  bgr_to_yuyv(image, yuyv);
  const auto* bytes = yuyv.ptr<std::uint8_t>(0);
  EXPECT_EQ(bytes[0], 16);   // Y of black, limited range
  EXPECT_EQ(bytes[2], 235);  // Y of white
  EXPECT_EQ(bytes[1], 128);  // grey pair: no chroma
  EXPECT_EQ(bytes[3], 128);
}

}  // namespace
