// The overlay of a percept on its frame (pipeline/overlay.hpp): a small simulated view is
// enlarged before the features are drawn, so that the video is 640 px wide or more and its TTC
// labels legible.
#include "flowsteer/pipeline/overlay.hpp"

#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace flowsteer::pipeline {
namespace {

const cv::Vec3b kCentreColor(0, 140, 255);  // the object's centre and its TTC

struct Percept {
  base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(128, 64, 1.5);
  cv::Mat image = cv::Mat(64, 128, CV_8UC3, cv::Scalar::all(128));
  servo::FlowField flow{k};
  std::vector<servo::ObjectFeatures> objects;
  Percept() {
    servo::ObjectFeatures o;
    o.centre = {0.0, 0.0};
    o.status = servo::MotionStatus::approaching;
    o.foe = {0.3, 0.0};
    o.ttc_s = 2.5;
    objects.push_back(o);
  }
  cv::Mat overlay() const { return draw_overlay(image, flow, objects, k, 0.2); }
};

TEST(Overlay, ASmallViewIsEnlargedToAtLeast640PxByAWholeFactor) {
  const Percept p;
  const cv::Mat overlay = p.overlay();
  EXPECT_EQ(overlay_scale(p.image.size()), 3);
  EXPECT_EQ(overlay.size(), overlay_size(p.image.size()));
  EXPECT_EQ(overlay.size(), cv::Size(768, 192));
  // Nearest neighbour: each source pixel is a 3 × 3 block of its own colour.
  EXPECT_EQ(overlay.at<cv::Vec3b>(190, 0), cv::Vec3b(128, 128, 128));
  // A camera's 640 px image is drawn on as it is.
  EXPECT_EQ(overlay_scale({640, 480}), 1);
  EXPECT_EQ(overlay_size({640, 480}), cv::Size(1280, 480));
  EXPECT_GE(overlay_size({16, 16}).width, 640);
}

TEST(Overlay, TheTtcLabelIsDrawnAtTheEnlargedSize) {
  const Percept p;
  const cv::Mat overlay = p.overlay();
  // The centre marker on the enlarged pixel of the image centre (fx · 0 + cx, at 3 × scale).
  const cv::Point centre(static_cast<int>((p.k.cx_px + 0.5) * 3 - 0.5),
                         static_cast<int>((p.k.cy_px + 0.5) * 3 - 0.5));
  EXPECT_EQ(overlay.at<cv::Vec3b>(centre), kCentreColor);
  // "2.5s" right of and above the marker: at least 14 px tall (a 7 px label before).
  cv::Mat label;
  cv::inRange(overlay(cv::Rect(centre.x + 8, 0, 200, centre.y)), kCentreColor, kCentreColor, label);
  std::vector<cv::Point> ink;
  cv::findNonZero(label, ink);
  ASSERT_FALSE(ink.empty());
  EXPECT_GE(cv::boundingRect(ink).height, 14);
  EXPECT_GE(cv::boundingRect(ink).width, 40);
}

}  // namespace
}  // namespace flowsteer::pipeline
