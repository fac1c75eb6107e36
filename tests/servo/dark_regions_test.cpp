// DarkRegionFinder (MIG 2019 §5): which dark pixels become dark regions, and what the feature
// extractor makes of them.
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/dark_regions.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::servo {
namespace {

constexpr int kSide = 40;
constexpr std::uint8_t kLit = 200;
constexpr std::uint8_t kDark = 20;

// A segmentation of kSide² pixels with one visible region (id 7) over the whole lower half.
Segmentation with_visible_lower_half() {
  Segmentation s;
  s.width = kSide;
  s.height = kSide;
  s.labels.assign(kSide * kSide, Segmentation::kNoRegion);
  for (int row = kSide / 2; row < kSide; ++row) {
    for (int col = 0; col < kSide; ++col) {
      s.labels[static_cast<std::size_t>(row * kSide + col)] = 0;
    }
  }
  s.kinds = {RegionKind::visible};
  s.source_ids = {7};
  return s;
}

cv::Mat lit_image() {
  return cv::Mat(kSide, kSide, CV_8UC1, cv::Scalar(kLit));
}

TEST(DarkRegionFinder, DarkBlockInTheLowerHalfBecomesADarkRegion) {
  cv::Mat grey = lit_image();
  const cv::Rect block(24, 26, 10, 8);  // columns 24–33, rows 26–33
  grey(block).setTo(kDark);
  Segmentation s = with_visible_lower_half();
  DarkRegionFinder finder;
  ASSERT_EQ(finder.add_dark_regions(grey, s), 1);
  ASSERT_EQ(s.region_count(), 2);
  EXPECT_EQ(s.kinds[1], RegionKind::dark);
  EXPECT_EQ(s.source_ids[1], -1);
  // Every pixel of the block left the visible region; none outside it did.
  int dark_pixels = 0;
  for (int row = 0; row < kSide; ++row) {
    for (int col = 0; col < kSide; ++col) {
      const std::int32_t label = s.labels[static_cast<std::size_t>(row * kSide + col)];
      if (block.contains(cv::Point(col, row))) {
        EXPECT_EQ(label, 1) << col << "," << row;
        ++dark_pixels;
      } else if (row >= kSide / 2) {
        EXPECT_EQ(label, 0) << col << "," << row;
      }
    }
  }
  EXPECT_EQ(dark_pixels, block.area());

  // The extractor gives the dark region its place and width (and no flow fit).
  const base::CameraIntrinsics k =
      base::CameraIntrinsics::from_horizontal_fov(kSide, kSide, 1.5707963);
  FlowField field(k);
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  ASSERT_EQ(objects.size(), 2U);
  EXPECT_EQ(objects[1].kind, RegionKind::dark);
  EXPECT_EQ(objects[1].pixel_count, block.area());
  const double centre_x = 0.5 * (field.x(24) + field.x(33));
  EXPECT_NEAR(objects[1].centre.x(), centre_x, 1e-6);
  EXPECT_GT(objects[1].centre.x(), 0.0);  // right of the image centre
  // Width from edge to edge of the ten columns.
  EXPECT_NEAR(objects[1].width, 10.0 * (field.x(1) - field.x(0)), 1e-6);
}

TEST(DarkRegionFinder, UpperHalfAndSmallRegionsAreDropped) {
  cv::Mat grey = lit_image();
  grey(cv::Rect(2, 2, 12, 10)).setTo(kDark);  // sky-high: rows 2–11
  grey(cv::Rect(30, 30, 2, 2)).setTo(kDark);  // 4 px in the lower half
  Segmentation s = with_visible_lower_half();
  DarkRegionOptions options;
  options.min_area_fraction = 5.0 / (kSide * kSide);  // 4 px is too small
  DarkRegionFinder finder(options);
  EXPECT_EQ(finder.add_dark_regions(grey, s), 0);
  EXPECT_EQ(s.region_count(), 1);
  for (const std::int32_t label : s.labels) {
    EXPECT_NE(label, 1);
  }
}

// At night the sky is as dark as the ground: a dark column from the top of the image to the
// bottom (a night sky joined to a dark street) still yields the part of it below the middle.
TEST(DarkRegionFinder, DarkReachingIntoTheUpperHalfKeepsItsLowerPart) {
  cv::Mat grey = lit_image();
  grey(cv::Rect(0, 0, kSide, kSide / 2)).setTo(kDark);  // night sky
  grey(cv::Rect(0, 0, 10, kSide)).setTo(kDark);         // dark street on the left, joined to it
  Segmentation s = with_visible_lower_half();
  DarkRegionFinder finder;
  ASSERT_EQ(finder.add_dark_regions(grey, s), 1);
  for (int row = 0; row < kSide; ++row) {
    for (int col = 0; col < kSide; ++col) {
      const std::int32_t label = s.labels[static_cast<std::size_t>(row * kSide + col)];
      const bool dark_below = row >= kSide / 2 && col < 10;
      EXPECT_EQ(label == 1, dark_below) << col << "," << row;
    }
  }
}

// MIG §5: a dark pixel's flow is not trusted wherever it is. Above the middle row it leaves its
// object without becoming part of a dark region.
TEST(DarkRegionFinder, DarkPixelsInTheUpperHalfLeaveTheirObject) {
  cv::Mat grey = lit_image();
  const cv::Rect patch(5, 4, 10, 8);  // rows 4–11
  grey(patch).setTo(kDark);
  Segmentation s = with_visible_lower_half();
  for (int row = 0; row < kSide / 2; ++row) {  // the object reaches into the upper half
    for (int col = 0; col < kSide; ++col) {
      s.labels[static_cast<std::size_t>(row * kSide + col)] = 0;
    }
  }
  DarkRegionFinder finder;
  EXPECT_EQ(finder.add_dark_regions(grey, s), 0);
  EXPECT_EQ(s.region_count(), 1);
  for (int row = 0; row < kSide; ++row) {
    for (int col = 0; col < kSide; ++col) {
      const std::int32_t label = s.labels[static_cast<std::size_t>(row * kSide + col)];
      EXPECT_EQ(label, patch.contains(cv::Point(col, row)) ? Segmentation::kNoRegion : 0)
          << col << "," << row;
    }
  }
}

// Dark ground across the whole width (at night, beyond the light) is split at the middle column
// into the dark on the left and the dark on the right of the heading.
TEST(DarkRegionFinder, DarkAcrossTheWholeWidthIsSplitAtTheHeading) {
  cv::Mat grey = lit_image();
  grey(cv::Rect(0, 24, kSide, 6)).setTo(kDark);  // rows 24–29, every column
  Segmentation s = with_visible_lower_half();
  DarkRegionFinder finder;
  ASSERT_EQ(finder.add_dark_regions(grey, s), 2);
  for (int row = 24; row < 30; ++row) {
    for (int col = 0; col < kSide; ++col) {
      EXPECT_EQ(s.labels[static_cast<std::size_t>(row * kSide + col)], col < kSide / 2 ? 1 : 2)
          << col << "," << row;
    }
  }
  const base::CameraIntrinsics k =
      base::CameraIntrinsics::from_horizontal_fov(kSide, kSide, 1.5707963);
  FlowField field(k);
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  ASSERT_EQ(objects.size(), 3U);
  EXPECT_TRUE(objects[1].cut_left && !objects[1].cut_right);
  EXPECT_TRUE(objects[2].cut_right && !objects[2].cut_left);
  EXPECT_NEAR(objects[1].centre.x(), -objects[2].centre.x(), 1e-9);
  EXPECT_LT(objects[1].centre.x(), -0.3);
}

// The turn the dark term asks for (ω = −δ ∂L_dark/∂ω, positive to the right) from what the
// finder makes of `grey`.
double dark_turn(const cv::Mat& grey) {
  Segmentation s = with_visible_lower_half();
  DarkRegionFinder finder;
  finder.add_dark_regions(grey, s);
  const base::CameraIntrinsics k =
      base::CameraIntrinsics::from_horizontal_fov(kSide, kSide, 1.5707963);
  FlowField field(k);
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  const auto term = dark_term();
  return -term->evaluate(Percept{objects, {}, {}, {}}, AgentState{1.0}).per_turn;
}

// Even dark on both sides of the heading asks for no turn. Unsplit, the band's centroid sits at
// the cusp of exp(−|g|/σ): one dark pixel more on either side turned the agent at ±1/σ. With
// more of the dark on the right, the agent turns left, away from it.
TEST(DarkRegionFinder, EvenDarkAcrossTheViewAsksForNoTurn) {
  cv::Mat even = lit_image();
  even(cv::Rect(0, 24, kSide, 6)).setTo(kDark);
  EXPECT_NEAR(dark_turn(even), 0.0, 1e-9);
  cv::Mat one_more = even.clone();
  one_more.at<std::uint8_t>(30, kSide / 2 + 3) = kDark;  // below the band, right of the middle
  EXPECT_NEAR(dark_turn(one_more), 0.0, 0.05);
  cv::Mat right_heavy = even.clone();
  right_heavy(cv::Rect(kSide / 2, 30, 8, 6)).setTo(kDark);  // a dark patch just right of ahead
  EXPECT_LT(dark_turn(right_heavy), -0.1);
}

TEST(DarkRegionFinder, BadInputThrows) {
  Segmentation s = with_visible_lower_half();
  DarkRegionFinder finder;
  EXPECT_THROW(finder.add_dark_regions(cv::Mat(kSide, kSide + 1, CV_8UC1, cv::Scalar(0)), s),
               std::invalid_argument);
  EXPECT_THROW(finder.add_dark_regions(cv::Mat(kSide, kSide, CV_8UC3, cv::Scalar(0, 0, 0)), s),
               std::invalid_argument);
  EXPECT_THROW(finder.add_dark_regions(cv::Mat(), s), std::invalid_argument);
  DarkRegionOptions threshold;
  threshold.luminance_threshold = 0.0;
  EXPECT_THROW(DarkRegionFinder{threshold}, std::invalid_argument);
  DarkRegionOptions area;
  area.min_area_fraction = 1.0;
  EXPECT_THROW(DarkRegionFinder{area}, std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::servo
