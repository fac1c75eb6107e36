#include "flowsteer/servo/flow_field.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

AnalyticScene scene_with(double turn_rate, double pitch_rad) {
  AnalyticScene scene;
  scene.intrinsics = base::CameraIntrinsics::from_horizontal_fov(96, 64, 80.0 * kDeg);
  scene.mount = {1.2, pitch_rad};
  scene.agent_speed_mps = 1.3;
  scene.agent_turn_rate = turn_rate;
  SceneObject box;
  box.id = 1;
  box.position_m = {6.0, 1.0};
  box.velocity_mps = {-0.5, -0.2};
  SceneObject post;
  post.id = 2;
  post.shape = SceneObject::Shape::cylinder;
  post.radius_m = 0.3;
  post.position_m = {4.0, -1.5};
  scene.objects = {box, post};
  return scene;
}

TEST(Intrinsics, InvalidValuesAreNamed) {
  base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(64, 48, 60.0 * kDeg);
  k.fx_px = 0.0;
  try {
    k.validate();
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx_px"), std::string::npos) << e.what();
  }
  EXPECT_THROW(base::CameraIntrinsics::from_horizontal_fov(64, 48, 190.0 * kDeg),
               std::invalid_argument);
  EXPECT_THROW(base::CameraIntrinsics::from_horizontal_fov(0, 48, 60.0 * kDeg),
               std::invalid_argument);
}

TEST(Derotation, RotationalFlowIsTheOmegaTermOfEq1) {
  const Eigen::Vector2d r = rotational_flow(0.3, -0.2, Eigen::Vector3d(0.0, 0.5, 0.0));
  EXPECT_NEAR(r.x(), -0.5 * (0.3 * 0.3 + 1.0), 1e-12);
  EXPECT_NEAR(r.y(), -0.5 * 0.3 * -0.2, 1e-12);
}

TEST(Derotation, RemovesExactlyTheTurnOfTheAgent) {
  for (const double pitch : {0.0, 12.0 * kDeg}) {
    SceneRender turning = render_scene(scene_with(0.6, pitch));
    const SceneRender straight = render_scene(scene_with(0.0, pitch));
    derotate(turning.flow, camera_angular_velocity(0.6, pitch));
    const auto a = turning.flow.flow();
    const auto b = straight.flow.flow();
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      worst = std::max(worst, static_cast<double>((a[i] - b[i]).norm()));
    }
    EXPECT_LT(worst, 1e-5) << "pitch " << pitch;
  }
}

TEST(Derotation, PositiveTurnMovesTheImageLeft) {
  // Turning right (ω > 0) sweeps the world to the left in the image.
  const SceneRender turning = render_scene(scene_with(0.6, 0.0));
  const SceneRender straight = render_scene(scene_with(0.0, 0.0));
  const std::size_t centre = turning.flow.index(48, 10);
  EXPECT_LT(turning.flow.flow()[centre].x(), straight.flow.flow()[centre].x());
}

class GroundRemoval : public ::testing::TestWithParam<double> {};

TEST_P(GroundRemoval, DepthAndFlowTestsFindTheGround) {
  const double pitch = GetParam();
  AnalyticScene scene = scene_with(0.0, pitch);
  SceneRender render = render_scene(scene);
  for (const bool use_depth : {true, false}) {
    FlowField field = render.flow;
    if (!use_depth) {
      FlowField no_depth(field.intrinsics());
      std::copy(field.flow().begin(), field.flow().end(), no_depth.flow().begin());
      field = no_depth;
    }
    std::vector<std::uint8_t> mask(field.size(), 0);
    const GroundRemovalResult result =
        mark_ground(field, scene.mount, scene.agent_speed_mps, {}, mask);
    EXPECT_EQ(result.test, use_depth ? GroundTest::depth : GroundTest::flow);
    int ground = 0;
    int ground_found = 0;
    int objects = 0;
    int objects_marked = 0;
    for (std::size_t i = 0; i < mask.size(); ++i) {
      if (render.ids[i] == kGroundId) {
        ++ground;
        ground_found += mask[i];
      } else if (render.ids[i] >= 0) {
        ++objects;
        objects_marked += mask[i];
      } else {
        EXPECT_EQ(mask[i], 0) << "sky marked as ground";
      }
    }
    ASSERT_GT(ground, 100);
    EXPECT_EQ(ground_found, ground) << "use_depth " << use_depth;
    // Only the object pixels touching the ground may pass for it.
    EXPECT_LT(objects_marked, objects / 10) << "use_depth " << use_depth;
    EXPECT_EQ(result.ground_pixels, ground_found + objects_marked);
  }
}

INSTANTIATE_TEST_SUITE_P(Pitch, GroundRemoval, ::testing::Values(0.0, 8.0 * kDeg),
                         [](const ::testing::TestParamInfo<double>& info) {
                           return "pitched_" + std::to_string(std::lround(info.param / kDeg)) +
                                  "deg";
                         });

// The region-level test on exact flow without depth: the ground as one region is ground, the
// moving box and the static post standing on it are not, whatever was marked before. The same
// marker serves frames with other region counts.
TEST(GroundRegions, OnlyTheRegionOfTheGroundIsMarked) {
  const AnalyticScene scene = scene_with(0.0, 0.0);
  const SceneRender render = render_scene(scene);
  FlowField field(render.flow.intrinsics());
  std::copy(render.flow.flow().begin(), render.flow.flow().end(), field.flow().begin());
  // Regions 0, 1, 2: the ground, the box, the post.
  Segmentation segmentation;
  segmentation.width = field.width();
  segmentation.height = field.height();
  segmentation.labels.assign(field.size(), Segmentation::kNoRegion);
  for (std::size_t i = 0; i < field.size(); ++i) {
    if (render.ids[i] == kGroundId) {
      segmentation.labels[i] = 0;
    } else if (render.ids[i] >= 0) {
      segmentation.labels[i] = render.ids[i];
    }
  }
  segmentation.kinds.assign(3, RegionKind::visible);
  segmentation.source_ids = {kGroundId, 1, 2};
  GroundRegionMarker marker;
  EXPECT_EQ(marker.mark(field, scene.mount, scene.agent_speed_mps, {}, segmentation), 1);
  EXPECT_EQ(segmentation.kinds[0], RegionKind::ground);
  EXPECT_EQ(segmentation.kinds[1], RegionKind::visible);
  EXPECT_EQ(segmentation.kinds[2], RegionKind::visible);

  // The ground alone, in another frame: the counts start afresh.
  std::replace_if(
      segmentation.labels.begin(), segmentation.labels.end(), [](auto l) { return l > 0; },
      Segmentation::kNoRegion);
  segmentation.kinds.assign(1, RegionKind::visible);
  segmentation.source_ids = {kGroundId};
  EXPECT_EQ(marker.mark(field, scene.mount, scene.agent_speed_mps, {}, segmentation), 1);
  EXPECT_EQ(segmentation.kinds[0], RegionKind::ground);
  // Standing still, the ground has no flow to tell it by.
  segmentation.kinds.assign(1, RegionKind::visible);
  EXPECT_EQ(marker.mark(field, scene.mount, 0.0, {}, segmentation), 0);
  segmentation.labels.resize(3);
  EXPECT_THROW(marker.mark(field, scene.mount, 1.0, {}, segmentation), std::invalid_argument);
}

TEST(GroundRemovalInput, ZeroSpeedFlowTestIsSkipped) {
  FlowField field(base::CameraIntrinsics::from_horizontal_fov(16, 12, 60.0 * kDeg));
  std::vector<std::uint8_t> mask(field.size(), 0);
  const auto result = mark_ground(field, {1.0, 0.0}, 0.0, {}, mask);
  EXPECT_EQ(result.test, GroundTest::skipped_no_motion);
  EXPECT_EQ(result.ground_pixels, 0);
  std::vector<std::uint8_t> short_mask(3, 0);
  EXPECT_THROW(mark_ground(field, {1.0, 0.0}, 1.0, {}, short_mask), std::invalid_argument);
  EXPECT_THROW(mark_ground(field, {-1.0, 0.0}, 1.0, {}, mask), std::invalid_argument);
}

TEST(AnalyticScene, CameraInsideAnObjectIsRejected) {
  AnalyticScene scene = scene_with(0.0, 0.0);
  scene.objects[0].position_m = {0.0, 0.0};
  try {
    render_scene(scene);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("inside"), std::string::npos) << e.what();
  }
}

TEST(AnalyticScene, DepthOfAFrontFaceIsItsDistance) {
  AnalyticScene scene = scene_with(0.0, 0.0);
  scene.objects.resize(1);
  scene.objects[0].position_m = {5.0, 0.0};
  scene.objects[0].velocity_mps = {0.0, 0.0};
  const SceneRender render = render_scene(scene);
  const std::size_t centre = render.flow.index(48, 30);
  EXPECT_EQ(render.ids[centre], 1);
  // Front face at x = 5 − length/2.
  EXPECT_NEAR(render.flow.depth()[centre], 4.5, 1e-5);
}

}  // namespace
}  // namespace flowsteer::servo
