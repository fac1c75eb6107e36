#include "flowsteer/servo/optical_flow.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A smooth random texture, so that every estimator has something to track everywhere.
cv::Mat textured_image(int width, int height, unsigned seed) {
  cv::Mat noise(height / 4 + 2, width / 4 + 2, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat image;
  cv::resize(noise, image, cv::Size(width + 40, height + 40), 0, 0, cv::INTER_CUBIC);
  return image;
}

// The texture moved by (dx, dy) pixels: a crop of a larger image.
cv::Mat shifted(const cv::Mat& texture, int width, int height, int dx, int dy) {
  return texture(cv::Rect(20 - dx, 20 - dy, width, height)).clone();
}

// The next image of a camera that does not turn.
FlowStatus update(FlowSource& flow, const cv::Mat& image, double timestamp_s, FlowField& field) {
  return flow.update({image, timestamp_s}, {}, field);
}

class EveryEstimator : public ::testing::TestWithParam<FlowMethod> {};

TEST_P(EveryEstimator, ATranslatedTextureGivesItsShiftInNormalisedUnitsPerSecond) {
  const int width = 96;
  const int height = 64;
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(width, height, 90.0 * kDeg);
  const cv::Mat texture = textured_image(width, height, 7);
  OpticalFlowOptions options;
  options.baseline_s = 0.1;
  const std::unique_ptr<FlowSource> flow = make_flow_source(GetParam(), options);
  EXPECT_TRUE(flow->estimated());
  FlowField field(intrinsics);
  EXPECT_EQ(update(*flow, shifted(texture, width, height, 0, 0), 1.0, field),
            FlowStatus::no_previous_frame);
  ASSERT_EQ(update(*flow, shifted(texture, width, height, 2, -1), 1.1, field), FlowStatus::ok);
  EXPECT_NEAR(field.interval_s(), 0.1, 1e-12);
  // 2 px right and 1 px up in 0.1 s.
  const double expected_u = 2.0 / intrinsics.fx_px / 0.1;
  const double expected_v = -1.0 / intrinsics.fy_px / 0.1;
  int near = 0;
  int valid = 0;
  for (int row = 8; row < height - 8; ++row) {
    for (int col = 8; col < width - 8; ++col) {
      const Eigen::Vector2f& u = field.at(col, row);
      if (!u.allFinite())
        continue;
      ++valid;
      near += std::abs(u.x() - expected_u) < 0.15 * expected_u &&
              std::abs(u.y() - expected_v) < 0.3 * std::abs(expected_v);
    }
  }
  EXPECT_GT(valid, (width - 16) * (height - 16) / 2);
  EXPECT_GT(near, valid * 8 / 10) << to_string(GetParam());
}

INSTANTIATE_TEST_SUITE_P(Methods, EveryEstimator,
                         ::testing::ValuesIn(numerical_flow_methods().begin(),
                                             numerical_flow_methods().end()),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(FlowSource, BadFramesGiveAStatusNotACrash) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg);
  FlowField field(intrinsics);
  const std::unique_ptr<FlowSource> source = make_flow_source(FlowMethod::dis_fast);
  FlowSource& flow = *source;
  const cv::Mat texture = textured_image(64, 48, 3);
  EXPECT_EQ(update(flow, cv::Mat(), 0.0, field), FlowStatus::empty_frame);
  EXPECT_EQ(update(flow, cv::Mat(48, 64, CV_8UC1, cv::Scalar(128)), 0.0, field),
            FlowStatus::untextured);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 0, 0), 0.0, field),
            FlowStatus::no_previous_frame);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 1, 0), 0.0, field), FlowStatus::no_time_elapsed);
  // Another size: kept as the start of the next pair, nothing computed.
  EXPECT_EQ(update(flow, textured_image(80, 60, 4), 0.1, field), FlowStatus::size_changed);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 1, 0), 0.2, field), FlowStatus::size_changed);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 2, 0), 0.3, field), FlowStatus::ok);
  // A single-colour frame breaks the chain: the next textured one starts it again.
  EXPECT_EQ(update(flow, cv::Mat(48, 64, CV_8UC3, cv::Scalar(9, 9, 9)), 0.4, field),
            FlowStatus::untextured);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 3, 0), 0.5, field),
            FlowStatus::no_previous_frame);
  // A clock that jumps back: that image starts the history again, the next one has flow.
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 4, 0), 0.55, field), FlowStatus::ok);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 5, 0), 0.05, field), FlowStatus::time_went_back);
  EXPECT_EQ(update(flow, shifted(texture, 64, 48, 6, 0), 0.1, field), FlowStatus::ok);
  EXPECT_THROW(update(flow, cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.0F)), 0.6, field),
               std::invalid_argument);
  OpticalFlowOptions no_baseline;
  no_baseline.max_kept_images = 0;
  EXPECT_THROW(make_flow_source(FlowMethod::dis_fast, no_baseline), std::invalid_argument);
}

// The renderer's flow is copied as it comes (the sky's too, unless a camera is imitated), with
// its depth where the field carries depth, and derotated by the angular velocity at the frame.
TEST(FlowSource, TheRenderersFlowIsCopiedAndDerotated) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(4, 3, 90.0 * kDeg);
  const cv::Mat flow(3, 4, CV_32FC2, cv::Scalar(0.25F, -0.5F));
  cv::Mat depth(3, 4, CV_32FC1, cv::Scalar(2.0F));
  depth.at<float>(0, 1) = std::numeric_limits<float>::infinity();
  const cv::Mat no_image;
  const FlowFrame frame{no_image, 1.0, &flow, &depth};
  const Eigen::Vector3d omega = camera_angular_velocity(0.5, 0.1);
  for (const bool camera_sky : {false, true}) {
    const std::unique_ptr<FlowSource> renderer =
        make_flow_source(FlowMethod::synthetic, {}, {.no_flow_without_depth = camera_sky});
    EXPECT_FALSE(renderer->estimated());
    EXPECT_EQ(renderer->noise_correlation_px(), 1.0);
    FlowField field(intrinsics, true);
    ASSERT_EQ(renderer->update(frame, {omega, {}, {}, {}}, field), FlowStatus::ok);
    EXPECT_EQ(field.removed_rotation(), omega);
    const Eigen::Vector2d derotated =
        Eigen::Vector2d(0.25, -0.5) - rotational_flow(field.x(2), field.y(2), omega);
    EXPECT_NEAR(field.at(2, 2).x(), derotated.x(), 1e-6);
    EXPECT_NEAR(field.at(2, 2).y(), derotated.y(), 1e-6);
    EXPECT_EQ(field.depth()[field.index(2, 2)], 2.0F);
    EXPECT_EQ(field.at(1, 0).allFinite(), !camera_sky);
  }
  FlowField field(intrinsics);
  const std::unique_ptr<FlowSource> renderer = make_flow_source(FlowMethod::synthetic);
  EXPECT_EQ(renderer->update({no_image, 1.0, &no_image, &depth}, {}, field),
            FlowStatus::empty_frame);
  EXPECT_THROW(renderer->update({no_image, 1.0}, {}, field), std::invalid_argument);
}

// Left half: `texture` shifted by (dx, dy); right half: dark above bright, a horizon-like edge at
// row height / 2 + dy.
cv::Mat texture_beside_edge(const cv::Mat& texture, int width, int height, int dx, int dy) {
  cv::Mat image = shifted(texture, width, height, dx, dy);
  image(cv::Rect(width / 2, 0, width / 2, height / 2 + dy)).setTo(60);
  image(cv::Rect(width / 2, height / 2 + dy, width / 2, height / 2 - dy)).setTo(180);
  return image;
}

// Along a straight edge only the motion across it can be seen (the aperture problem): such pixels
// get no flow, though their gradient is strong, while textured pixels beside them keep theirs.
TEST(FlowSource, AStraightEdgeGivesNoFlowWhereTextureDoes) {
  const int width = 96;
  const int height = 64;
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(width, height, 90.0 * kDeg);
  const cv::Mat texture = textured_image(width, height, 5);
  // The texture moves sideways; the edge stays at row 32.
  const auto scene = [&](int dx) { return texture_beside_edge(texture, width, height, dx, 0); };
  const std::unique_ptr<FlowSource> flow = make_flow_source(FlowMethod::dis_medium);
  FlowField field(intrinsics);
  ASSERT_EQ(update(*flow, scene(0), 0.0, field), FlowStatus::no_previous_frame);
  ASSERT_EQ(update(*flow, scene(2), 0.2, field), FlowStatus::ok);
  int edge_valid = 0;
  for (int row = height / 2 - 2; row <= height / 2 + 1; ++row) {
    for (int col = width / 2 + 8; col < width - 8; ++col) {
      edge_valid += field.at(col, row).allFinite();
    }
  }
  int texture_valid = 0;
  for (int row = 8; row < height - 8; ++row) {
    for (int col = 8; col < width / 2 - 8; ++col) {
      texture_valid += field.at(col, row).allFinite();
    }
  }
  EXPECT_EQ(edge_valid, 0);
  EXPECT_GT(texture_valid, (width / 2 - 16) * (height - 16) * 9 / 10);
}

TEST(FlowSource, AStraightEdgeGivesTheFlowAcrossIt) {
  const int width = 96;
  const int height = 64;
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(width, height, 90.0 * kDeg);
  const cv::Mat texture = textured_image(width, height, 5);
  // The texture and the edge move down together.
  const auto scene = [&](int dy) { return texture_beside_edge(texture, width, height, 0, dy); };
  const std::unique_ptr<FlowSource> flow = make_flow_source(FlowMethod::dis_medium);
  FlowField field(intrinsics);
  ASSERT_EQ(update(*flow, scene(0), 0.0, field), FlowStatus::no_previous_frame);
  ASSERT_EQ(update(*flow, scene(2), 0.2, field), FlowStatus::ok);
  ASSERT_EQ(flow->edge_flow().size(), field.size());
  const double across = 2.0 / (intrinsics.fy_px * 0.2);
  int measured = 0;
  int right = 0;
  for (int row = height / 2; row <= height / 2 + 3; ++row) {
    for (int col = width / 2 + 8; col < width - 8; ++col) {
      const Eigen::Vector2f edge = flow->edge_flow()[field.index(col, row)];
      EXPECT_FALSE(field.at(col, row).allFinite());
      if (edge.allFinite()) {
        ++measured;
        right += std::abs(edge.x()) < 0.1 * across && std::abs(edge.y() - across) < 0.3 * across;
      }
    }
  }
  EXPECT_GT(measured, (width / 2 - 16) * 2);
  EXPECT_GT(right, measured * 9 / 10);
  // Textured pixels have their flow in the field, none across an edge.
  EXPECT_FALSE(flow->edge_flow()[field.index(width / 4, height / 2)].allFinite());
}

// OpenCV's presets and defaults: DIS matches 8 px patches, at half resolution (medium) or a
// quarter (fast, ultrafast); Farneback averages over 13 px, TV-L1's median filter is 5 px wide.
TEST(FlowSource, NoiseCorrelationIsTheEstimatorsWindow) {
  const auto window_px = [](FlowMethod method) {
    return make_flow_source(method)->noise_correlation_px();
  };
  EXPECT_EQ(window_px(FlowMethod::synthetic), 1.0);
  EXPECT_EQ(window_px(FlowMethod::dis_medium), 16.0);
  EXPECT_EQ(window_px(FlowMethod::dis_fast), 32.0);
  EXPECT_EQ(window_px(FlowMethod::dis_ultrafast), 32.0);
  EXPECT_EQ(window_px(FlowMethod::farneback), 13.0);
  EXPECT_EQ(window_px(FlowMethod::tvl1), 5.0);
}

TEST(FlowSource, MethodNamesRoundTrip) {
  for (FlowMethod method : numerical_flow_methods()) {
    EXPECT_EQ(parse_flow_method(to_string(method)), method);
  }
  EXPECT_EQ(parse_flow_method("synthetic"), FlowMethod::synthetic);
  EXPECT_FALSE(parse_flow_method("flownet"));
}

// Where a static point's ray seen at normalised (x, y) in the newer image fell in the older one.
Eigen::Vector3d older_ray(const Eigen::Matrix3d& rotation, double x, double y) {
  return rotation * Eigen::Vector3d(x, y, 1.0);
}

TEST(RotationOver, MatchesTheRateForSmallAnglesAndTheExactRotationForLargeOnes) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(48, 32, 120.0 * kDeg);
  const FlowField grid(intrinsics);
  const Eigen::Vector3d omega = camera_angular_velocity(0.05, 0.1);
  // A tiny rotation: the displacement over the interval is the rate times the interval.
  const double small_s = 1e-4;
  const Eigen::Matrix3d small = rotation_over(omega, small_s);
  for (int row = 0; row < grid.height(); ++row) {
    for (int col = 0; col < grid.width(); ++col) {
      const double x = grid.x(col);
      const double y = grid.y(row);
      const Eigen::Vector3d before = older_ray(small, x, y);
      const Eigen::Vector2d per_second =
          Eigen::Vector2d(x - before.x() / before.z(), y - before.y() / before.z()) / small_s;
      const Eigen::Vector2d rate = rotational_flow(x, y, omega);
      EXPECT_NEAR(per_second.x(), rate.x(), 1e-4);
      EXPECT_NEAR(per_second.y(), rate.y(), 1e-4);
    }
  }
  // A large yaw: a point at x in the newer image was at tan(atan(x) + θ) in the older one when
  // the camera turned right by θ (ω_cy > 0), so its displacement is x − tan(atan(x) + θ).
  const double turn_rate = 1.5;
  const double interval_s = 0.4;
  const Eigen::Matrix3d large = rotation_over(camera_angular_velocity(turn_rate, 0.0), interval_s);
  for (int col = 0; col < grid.width(); ++col) {
    const double x = grid.x(col);
    const Eigen::Vector3d ray = older_ray(large, x, 0.0);
    const double before = std::atan(x) + turn_rate * interval_s;
    if (before >= 0.5 * std::numbers::pi) {
      EXPECT_LE(ray.z(), 0.0) << col;  // behind the older image: no flow there
      continue;
    }
    const double displacement = x - std::tan(before);
    EXPECT_NEAR((x - ray.x() / ray.z()) / interval_s, displacement / interval_s,
                1e-4 * (1.0 + std::abs(displacement / interval_s)))
        << col;
  }
}

// Fills the field with a left and a right half moving differently; returns a ground mask of the
// rows from ground_from_row down.
std::vector<std::uint8_t> two_halves_over_ground(FlowField& field, int ground_from_row) {
  std::vector<std::uint8_t> ground(field.size(), 0);
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      field.at(col, row) =
          col < field.width() / 2 ? Eigen::Vector2f(0.5F, 0.0F) : Eigen::Vector2f(-0.5F, 0.1F);
      if (row >= ground_from_row)
        ground[field.index(col, row)] = 1;
    }
  }
  return ground;
}

// Two halves moving differently, the bottom rows excluded as ground.
TEST(FlowSegmenter, SplitsByMotionDropsExcludedPixelsAndKeepsIdsFromFrameToFrame) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg));
  const std::vector<std::uint8_t> ground = two_halves_over_ground(field, 40);
  field.at(5, 5) = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  for (SegmentationMethod method :
       {SegmentationMethod::flow_graph, SegmentationMethod::flow_graph_fast}) {
    FlowSegmenter segmenter(method);
    Segmentation out;
    segmenter.segment(field, ground, {}, out);
    ASSERT_EQ(out.region_count(), 2) << to_string(method);
    const std::int32_t left = out.labels[field.index(10, 10)];
    const std::int32_t right = out.labels[field.index(50, 10)];
    EXPECT_NE(left, right);
    EXPECT_EQ(out.labels[field.index(10, 45)], Segmentation::kNoRegion);
    EXPECT_EQ(out.labels[field.index(5, 5)], Segmentation::kNoRegion);
    EXPECT_GE(out.source_ids[static_cast<std::size_t>(left)], FlowSegmenter::kFirstTrackId);
    const std::int32_t left_id = out.source_ids[static_cast<std::size_t>(left)];
    const std::int32_t right_id = out.source_ids[static_cast<std::size_t>(right)];
    // The same motion a frame later: the regions keep their ids.
    segmenter.segment(field, ground, {}, out);
    EXPECT_EQ(out.source_ids[static_cast<std::size_t>(out.labels[field.index(10, 10)])], left_id);
    EXPECT_EQ(out.source_ids[static_cast<std::size_t>(out.labels[field.index(50, 10)])], right_id);
  }
  EXPECT_THROW(FlowSegmenter{SegmentationMethod::semantic}, std::invalid_argument);
  FlowSegmenter segmenter(SegmentationMethod::flow_graph);
  Segmentation out;
  EXPECT_THROW(segmenter.segment(field, std::vector<std::uint8_t>(3, 0), {}, out),
               std::invalid_argument);
}

// Two walls at either side of the view, standing still, under the sky: the sky (no depth) shows
// the walls' own flow after derotation, none, and joined them into one region across the view.
TEST(FlowSegmenter, PixelsThatSeeNothingAreInNoRegion) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg), true);
  std::vector<std::uint8_t> ground(field.size(), 0);
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      const std::size_t i = field.index(col, row);
      field.at(col, row) = Eigen::Vector2f::Zero();
      const bool wall = col < 16 || col >= 48;
      field.depth()[i] = row < 20 ? (col % 2 == 0 ? std::numeric_limits<float>::infinity()
                                                  : std::numeric_limits<float>::quiet_NaN())
                                  : (wall ? 3.0F : 2.0F);
      ground[i] = row >= 20 && !wall ? 1 : 0;
    }
  }
  for (SegmentationMethod method :
       {SegmentationMethod::flow_graph, SegmentationMethod::flow_graph_fast}) {
    FlowSegmenter segmenter(method);
    Segmentation out;
    segmenter.segment(field, ground, {}, out);
    ASSERT_EQ(out.region_count(), 2) << to_string(method);
    EXPECT_NE(out.labels[field.index(5, 30)], out.labels[field.index(60, 30)]);
    EXPECT_EQ(out.labels[field.index(5, 10)], Segmentation::kNoRegion);
    EXPECT_EQ(out.labels[field.index(32, 10)], Segmentation::kNoRegion);
    EXPECT_EQ(out.labels[field.index(33, 10)], Segmentation::kNoRegion);
  }
}

// A field wider than fast_max_side_px: flow_graph_fast segments it on a reduced grid and brings
// the labels back to every pixel.
TEST(FlowSegmenter, FastGraphLabelsEveryPixelOfAReducedField) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(256, 192, 90.0 * kDeg));
  const std::vector<std::uint8_t> ground = two_halves_over_ground(field, 160);
  FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast);
  Segmentation out;
  segmenter.segment(field, ground, {}, out);
  ASSERT_EQ(out.region_count(), 2);
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      const std::int32_t label = out.labels[field.index(col, row)];
      if (row >= 160) {
        EXPECT_EQ(label, Segmentation::kNoRegion) << col << ", " << row;
      } else {
        EXPECT_EQ(label, col < 128 ? out.labels[0] : out.labels[255]) << col << ", " << row;
      }
    }
  }
  EXPECT_NE(out.labels[0], out.labels[255]);
}

// Islands of flow too small to be regions, scattered over pixels without flow (what a striped
// agent or the far ground leaves after the texture test), beside one object. The merge of small
// segments joins each island to the pixels without flow around it; together the islands must not
// come out as one region spanning the image.
TEST(FlowSegmenter, ScatteredIslandsOfFlowAreNoRegion) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      const bool object = col >= 40 && row >= 10 && row < 34;
      const bool island = col < 36 && col % 6 < 2 && row % 6 < 2;  // 2 x 2 pixels each
      field.at(col, row) = object   ? Eigen::Vector2f(-0.5F, 0.1F)
                           : island ? Eigen::Vector2f(0.3F, 0.0F)
                                    : Eigen::Vector2f(nan, nan);
    }
  }
  for (SegmentationMethod method :
       {SegmentationMethod::flow_graph, SegmentationMethod::flow_graph_fast}) {
    FlowSegmenter segmenter(method);
    Segmentation out;
    segmenter.segment(field, {}, {}, out);
    ASSERT_EQ(out.region_count(), 1) << to_string(method);
    for (int row = 0; row < field.height(); ++row) {
      for (int col = 0; col < 36; ++col) {
        EXPECT_EQ(out.labels[field.index(col, row)], Segmentation::kNoRegion)
            << to_string(method) << " " << col << ", " << row;
      }
    }
    EXPECT_EQ(out.labels[field.index(50, 20)], 0);
  }
}

// One square of flow over pixels without any, its columns [left, left + side) and rows [top,
// top + side), moving at `flow` (normalised units per second).
void square_of_flow(FlowField& field, int left, int top, int side, const Eigen::Vector2f& flow) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      const bool inside = col >= left && col < left + side && row >= top && row < top + side;
      field.at(col, row) = inside ? flow : Eigen::Vector2f(nan, nan);
    }
  }
}

// The id of the region at pixel (col, row).
std::int32_t track_at(const FlowField& field, const Segmentation& out, int col, int row) {
  const std::int32_t region = out.labels[field.index(col, row)];
  return region == Segmentation::kNoRegion ? -1 : out.source_ids[static_cast<std::size_t>(region)];
}

// A square that moves further than its own width between frames, as a person crossing close by
// does at 320 px: it has no pixel where it was, and keeps its id only by being followed back
// along its flow.
TEST(FlowSegmenter, AFastRegionKeepsItsIdFollowedAlongItsFlow) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg);
  constexpr double kSinceS = 0.05;
  constexpr int kStepPx = 12;
  const Eigen::Vector2f flow(static_cast<float>(kStepPx / (intrinsics.fx_px * kSinceS)), 0.0F);
  for (const bool followed : {true, false}) {
    FlowField field(intrinsics);
    FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast);
    Segmentation out;
    square_of_flow(field, 10, 20, 10, flow);
    segmenter.segment(field, {}, {}, out);
    ASSERT_EQ(out.region_count(), 1);
    const std::int32_t first = track_at(field, out, 15, 25);
    square_of_flow(field, 10 + kStepPx, 20, 10, flow);
    segmenter.segment(field, {}, {}, out,
                      followed ? ViewMotion{{0.0, 0.0, 0.0}, kSinceS} : ViewMotion{});
    ASSERT_EQ(out.region_count(), 1);
    EXPECT_EQ(track_at(field, out, 15 + kStepPx, 25) == first, followed);
  }
}

// A far wall (no derotated flow) while the camera turns: the image slides by 20 px at the wall,
// twice its width, and the wall keeps its id when the segmenter knows the turn.
TEST(FlowSegmenter, AStandingRegionKeepsItsIdWhileTheCameraTurns) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg);
  constexpr double kSinceS = 0.05;
  FlowField field(intrinsics);
  // A yaw rate (about the camera's y axis) that slides column 35 by +20 px in kSinceS.
  const double x = field.x(35);
  const Eigen::Vector3d yaw(0.0, -20.0 / (intrinsics.fx_px * kSinceS * (1.0 + x * x)), 0.0);
  for (const bool told : {true, false}) {
    FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast);
    Segmentation out;
    square_of_flow(field, 10, 19, 10, Eigen::Vector2f::Zero());
    segmenter.segment(field, {}, {}, out);
    const std::int32_t first = track_at(field, out, 15, 24);
    square_of_flow(field, 30, 19, 10, Eigen::Vector2f::Zero());
    segmenter.segment(field, {}, {}, out, told ? ViewMotion{yaw, kSinceS} : ViewMotion{});
    ASSERT_EQ(out.region_count(), 1);
    EXPECT_EQ(track_at(field, out, 35, 24) == first, told);
  }
}

// A region that grows to three times its size (an untextured part of it gets flow) keeps its id:
// all of what it was is in it, though that is a third of it. What splits off a region keeps the
// id only in its larger part.
TEST(FlowSegmenter, ARegionThatGrowsOrSplitsKeepsItsId) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg));
  FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast);
  Segmentation out;
  const Eigen::Vector2f flow(0.2F, 0.0F);
  square_of_flow(field, 20, 10, 10, flow);
  segmenter.segment(field, {}, {}, out);
  const std::int32_t first = track_at(field, out, 25, 15);
  square_of_flow(field, 15, 5, 18, flow);
  segmenter.segment(field, {}, {}, out);
  ASSERT_EQ(out.region_count(), 1);
  EXPECT_EQ(track_at(field, out, 16, 6), first);
  // Its left third now moves otherwise: two regions, the larger keeps the id.
  for (int row = 5; row < 23; ++row) {
    for (int col = 15; col < 21; ++col) {
      field.at(col, row) = Eigen::Vector2f(-0.4F, 0.0F);
    }
  }
  segmenter.segment(field, {}, {}, out);
  ASSERT_EQ(out.region_count(), 2);
  EXPECT_EQ(track_at(field, out, 30, 10), first);
  EXPECT_NE(track_at(field, out, 16, 10), first);
  EXPECT_GE(track_at(field, out, 16, 10), FlowSegmenter::kFirstTrackId);
}

// With confirm_new_regions, a region is acted on from the second frame of its track: a square
// seen twice becomes visible, one that appears for one frame (the flow's error on the floor) stays
// unconfirmed.
TEST(FlowSegmenter, NewRegionsWaitForTheirSecondFrame) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg));
  FlowSegmentationOptions options;
  options.confirm_new_regions = true;
  FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast, options);
  Segmentation out;
  const auto kind_at = [&](int col, int row) {
    return out.kinds[static_cast<std::size_t>(out.labels[field.index(col, row)])];
  };
  square_of_flow(field, 10, 10, 10, Eigen::Vector2f(0.2F, 0.0F));
  segmenter.segment(field, {}, {}, out);
  ASSERT_EQ(out.region_count(), 1);
  EXPECT_EQ(kind_at(15, 15), RegionKind::unconfirmed);
  // The square again, and a second one for the first time.
  for (int row = 30; row < 40; ++row) {
    for (int col = 40; col < 50; ++col) {
      field.at(col, row) = Eigen::Vector2f(-0.3F, 0.0F);
    }
  }
  segmenter.segment(field, {}, {}, out);
  ASSERT_EQ(out.region_count(), 2);
  EXPECT_EQ(kind_at(15, 15), RegionKind::visible);
  EXPECT_EQ(kind_at(45, 35), RegionKind::unconfirmed);
  EXPECT_STREQ(to_string(RegionKind::unconfirmed), "unconfirmed");
}

// A person far off moves across the view as the wall behind does, but is darker: with the grey
// level in the edge weights the two are two regions, with flow alone one.
TEST(FlowSegmenter, GreyLevelsSeparateWhatMovesAlike) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(64, 48, 90.0 * kDeg));
  cv::Mat grey(field.height(), field.width(), CV_8UC1, cv::Scalar(180));
  grey(cv::Rect(24, 8, 12, 30)).setTo(60);
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      field.at(col, row) = Eigen::Vector2f(0.3F, 0.0F);
    }
  }
  for (SegmentationMethod method :
       {SegmentationMethod::flow_graph, SegmentationMethod::flow_graph_fast}) {
    FlowSegmentationOptions options;
    options.grey_weight = 0.02;
    Segmentation alone;
    Segmentation with_grey;
    FlowSegmenter(method).segment(field, {}, grey, alone);
    FlowSegmenter(method, options).segment(field, {}, grey, with_grey);
    EXPECT_EQ(alone.region_count(), 1) << to_string(method);
    ASSERT_EQ(with_grey.region_count(), 2) << to_string(method);
    EXPECT_NE(with_grey.labels[field.index(30, 20)], with_grey.labels[field.index(5, 20)]);
  }
  FlowSegmenter segmenter(SegmentationMethod::flow_graph_fast);
  Segmentation out;
  EXPECT_THROW(segmenter.segment(field, {}, cv::Mat(10, 10, CV_8UC1), out), std::invalid_argument);
}

// Noisy flow over four differently moving quarters, segmented by OpenCV (flow_graph, into
// `opencv`) and by our own graph (flow_graph_fast, into `own`). With `gaps`, one pixel in 40 has
// no flow and the bottom rows are excluded: many edges between pixels with and without flow then
// weigh the same, and their order decides which segment a small one joins.
void segment_four_quarters(std::uint64_t seed, bool gaps, Segmentation& opencv, Segmentation& own) {
  const auto intrinsics = base::CameraIntrinsics::from_horizontal_fov(80, 60, 90.0 * kDeg);
  const Eigen::Vector2f motions[] = {{0.0F, 0.0F}, {3.0F, 0.0F}, {-2.0F, 1.0F}, {0.5F, -3.0F}};
  FlowField field(intrinsics);
  std::vector<std::uint8_t> excluded(field.size(), 0);
  cv::RNG rng(seed);
  for (int row = 0; row < field.height(); ++row) {
    for (int col = 0; col < field.width(); ++col) {
      const Eigen::Vector2f noise(rng.uniform(-0.6F, 0.6F), rng.uniform(-0.6F, 0.6F));
      field.at(col, row) = motions[(col >= 40 ? 1 : 0) + (row >= 30 ? 2 : 0)] + noise;
      if (gaps && rng.uniform(0, 40) == 0)
        field.at(col, row) = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
      if (gaps && row >= 54)
        excluded[field.index(col, row)] = 1;
    }
  }
  FlowSegmenter(SegmentationMethod::flow_graph).segment(field, excluded, {}, opencv);
  FlowSegmenter(SegmentationMethod::flow_graph_fast).segment(field, excluded, {}, own);
}

// flow_graph_fast runs its own Felzenszwalb–Huttenlocher segmentation, flow_graph OpenCV's. On a
// field no wider than fast_max_side_px neither reduces the flow, and where no two edges weigh the
// same they must agree to the pixel, numbers and ids included: the merge test and the merge of
// small segments are OpenCV's.
TEST(FlowSegmenter, FastGraphSegmentsAsOpenCvGraphSegmentationDoes) {
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    Segmentation expected;
    Segmentation out;
    segment_four_quarters(seed, false, expected, out);
    EXPECT_GE(expected.region_count(), 4) << seed;
    EXPECT_EQ(out.labels, expected.labels) << seed;
    EXPECT_EQ(out.source_ids, expected.source_ids) << seed;
  }
}

// Edges of equal weight: flow_graph_fast takes them by pixel, OpenCV in whatever order its
// std::sort leaves them. The regions are the same sets of pixels; where pixels without flow form
// segments of their own differently, the regions may be numbered in another order.
TEST(FlowSegmenter, FastGraphFindsOpenCvsRegionsWhereEdgesWeighTheSame) {
  bool renumbered = false;
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    Segmentation expected;
    Segmentation out;
    segment_four_quarters(seed, true, expected, out);
    ASSERT_GE(expected.region_count(), 4) << seed;
    ASSERT_EQ(out.region_count(), expected.region_count()) << seed;
    // One to one: each of our regions is exactly one of OpenCV's.
    std::vector<int> theirs(static_cast<std::size_t>(out.region_count()), -2);
    std::vector<int> ours(static_cast<std::size_t>(expected.region_count()), -2);
    for (std::size_t i = 0; i < out.labels.size(); ++i) {
      const int a = out.labels[i];
      const int b = expected.labels[i];
      ASSERT_EQ(a == Segmentation::kNoRegion, b == Segmentation::kNoRegion) << seed << " " << i;
      if (a == Segmentation::kNoRegion)
        continue;
      int& mapped = theirs[static_cast<std::size_t>(a)];
      int& back = ours[static_cast<std::size_t>(b)];
      ASSERT_TRUE(mapped == -2 || mapped == b) << seed << " pixel " << i;
      ASSERT_TRUE(back == -2 || back == a) << seed << " pixel " << i;
      mapped = b;
      back = a;
    }
    renumbered = renumbered || out.labels != expected.labels;
  }
  // The field has equal edges that do matter: otherwise this test would not test the order.
  EXPECT_TRUE(renumbered);
}

}  // namespace
}  // namespace flowsteer::servo

namespace flowsteer::servo {
namespace {

// A plain grey image with Gaussian noise of sigma_grey, seeded.
cv::Mat noisy_plain(double sigma_grey, unsigned seed) {
  cv::Mat noise(96, 128, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma_grey);
  cv::Mat image;
  noise.convertTo(image, CV_8U, 1.0, 128.0);
  return image;
}

TEST(FlowSource, AnEstimatorMeasuresItsImagesNoise) {
  const std::unique_ptr<FlowSource> flow = make_flow_source(FlowMethod::dis_medium);
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(128, 96, 90.0 * kDeg));
  for (const double sigma_grey : {1.0, 2.0, 4.0}) {
    flow->reset();
    flow->update({noisy_plain(sigma_grey, 1), 0.0}, {}, field);
    ASSERT_EQ(flow->update({noisy_plain(sigma_grey, 2), 0.1}, {}, field), FlowStatus::ok);
    // The estimate is quantised to 1 / (0.6745 · 6) ≈ 0.25 grey levels.
    EXPECT_NEAR(flow->image_noise_grey(), sigma_grey, 0.15 * sigma_grey + 0.25) << sigma_grey;
  }
  // Noise as strong as the texture test's floor leaves none of a plain image with flow.
  std::size_t with_flow = 0;
  for (const Eigen::Vector2f& v : field.flow()) {
    with_flow += v.allFinite() ? 1 : 0;
  }
  EXPECT_LT(with_flow, field.size() / 20);
}

TEST(FlowSource, ARenderedTextureHasNoNoise) {
  const std::unique_ptr<FlowSource> flow = make_flow_source(FlowMethod::dis_medium);
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(128, 96, 90.0 * kDeg));
  const cv::Mat texture = textured_image(128, 96, 3);
  flow->update({shifted(texture, 128, 96, 0, 0), 0.0}, {}, field);
  ASSERT_EQ(flow->update({shifted(texture, 128, 96, 1, 0), 0.1}, {}, field), FlowStatus::ok);
  EXPECT_LT(flow->image_noise_grey(), 0.5);
}

}  // namespace
}  // namespace flowsteer::servo
