#include "flowsteer/servo/obstacle_memory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {
namespace {

using Sight = ObstacleMemory::Point::Sight;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kSpeed_mps = 1.0;
constexpr double kFrame_s = 0.1;
constexpr double kBaseline_s = 0.2;  // the measured flow's interval

// A 320×240 camera of 90° a metre above the floor, pitched down 0.1 rad, whose frames show what
// each test says: one visible region (label 0) standing on the ground at the points given.
class ObstacleMemoryTest : public ::testing::Test {
 protected:
  ObstacleMemoryTest()
      : mount_{1.0, 0.1},
        field_(base::CameraIntrinsics::from_horizontal_fov(320, 240, 90.0 * kDeg)),
        ground_(mount_),
        memory_(mount_) {
    use_camera(320, 240);
  }

  // A camera of 90° with width × height pixels, the floor in every pixel.
  void use_camera(int width, int height) {
    field_ = FlowField(base::CameraIntrinsics::from_horizontal_fov(width, height, 90.0 * kDeg));
    segmentation_.width = field_.width();
    segmentation_.height = field_.height();
    segmentation_.labels.assign(field_.size(), Segmentation::kNoRegion);
    segmentation_.kinds = {RegionKind::visible};
    segmentation_.source_ids = {1};
    floor_.assign(field_.size(), 1);  // the floor everywhere, unless a test covers it
  }

  // One frame in which region 0 stands on the ground at `points_m` (body frame), its fitted τ
  // `ttc_scale` times a static point's at its contacts' mean depth.
  void observe(const std::vector<Eigen::Vector2d>& points_m, double ttc_scale = 1.0) {
    contacts_.clear();
    double nearest_depth_m = std::numeric_limits<double>::infinity();
    double depth_sum_m = 0.0;
    for (const Eigen::Vector2d& p : points_m) {
      const auto seen = ground_.image_of(p);
      ASSERT_TRUE(seen);
      const double pixel = 1.0 / field_.intrinsics().fy_px;
      contacts_.push_back({0, seen->x(), seen->y() - pixel, seen->y(), seen->z(), false});
      nearest_depth_m = std::min(nearest_depth_m, seen->z());
      depth_sum_m += seen->z();
    }
    ObjectFeatures region;
    region.label = 0;
    region.status = MotionStatus::approaching;
    region.fit.static_foe = true;
    const double mean_depth_m = depth_sum_m / static_cast<double>(points_m.size());
    region.ttc_s = ttc_scale * mean_depth_m / (kSpeed_mps * std::cos(mount_.pitch_rad));
    region.min_x_depth_m = nearest_depth_m;  // it stands on the ground at both ends
    region.max_x_depth_m = nearest_depth_m;
    objects_ = {region};
    memory_.observe({field_, segmentation_, floor_, objects_, contacts_}, kSpeed_mps, kFrame_s);
  }
  // The frames over which region 0 is seen standing at `points_m` until the memory confirms it:
  // sightings spanning confirm_span_s.
  void observe_standing(const std::vector<Eigen::Vector2d>& points_m) {
    const auto frames = std::lround(std::ceil(ObstacleMemoryOptions{}.confirm_span_s / kFrame_s));
    for (long frame = 0; frame <= frames; ++frame) {
      observe(points_m);
    }
  }
  // One frame in which nothing stands anywhere: only floor, where the mask shows it.
  void observe_nothing() {
    contacts_.clear();
    memory_.observe({field_, segmentation_, floor_, {}, contacts_}, kSpeed_mps, kFrame_s);
  }

  enum class ColumnMotion { upright, floor };
  // One frame in which region 0, fitted as nothing static (no ends with depths, no FOE), covers
  // the column of the ground point `foot_m` from its foot up to column_height_m, its flow over
  // kBaseline_s that of an upright surface standing there or that of the floor seen there.
  void observe_column(const Eigen::Vector2d& foot_m, ColumnMotion motion,
                      double speed_mps = kSpeed_mps) {
    field_.set_interval_s(kBaseline_s);
    const auto foot = ground_.image_of(foot_m);
    const auto top = ground_.image_of(foot_m, ObstacleMemoryOptions{}.column_height_m);
    ASSERT_TRUE(foot && top);
    const base::CameraIntrinsics& k = field_.intrinsics();
    const auto col = static_cast<int>(std::lround(k.fx_px * foot->x() + k.cx_px));
    const auto foot_row = static_cast<int>(std::lround(k.fy_px * foot->y() + k.cy_px));
    const auto top_row = static_cast<int>(std::lround(k.fy_px * top->y() + k.cy_px));
    const double x = field_.x(col);
    for (int row = std::max(top_row, 0); row <= foot_row; ++row) {
      const double y = field_.y(row);
      const auto depth_m = motion == ColumnMotion::upright
                               ? ground_.depth_at_distance_ahead(y, foot_m.x())
                               : ground_.depth_at(x, y);
      const Eigen::Vector2d flow =
          depth_m ? ground_.static_flow_at(x, y, *depth_m, speed_mps, kBaseline_s)
                  : Eigen::Vector2d::Zero();  // above the horizon the floor is not seen
      field_.at(col, row) = flow.cast<float>();
      segmentation_.labels[field_.index(col, row)] = 0;
      floor_[field_.index(col, row)] = 0;
    }
    const double pixel = 1.0 / k.fy_px;
    contacts_ = {{0, foot->x(), foot->y() - pixel, foot->y(), foot->z(), false}};
    ObjectFeatures region;
    region.label = 0;
    region.status = MotionStatus::lateral;
    objects_ = {region};
    memory_.observe({field_, segmentation_, floor_, objects_, contacts_}, speed_mps, kFrame_s);
  }

  base::CameraMount mount_;
  FlowField field_;
  FlatGround ground_;
  ObstacleMemory memory_;
  Segmentation segmentation_;
  std::vector<std::uint8_t> floor_;
  std::vector<ObjectFeatures> objects_;
  std::vector<GroundContact> contacts_;
};

TEST_F(ObstacleMemoryTest, CarriesPointsExactlyAlongStraightAndArcMotion) {
  // Straight on: 1 m at 0.5 m/s in twenty steps.
  observe({{3.0, 0.5}});
  for (int step = 0; step < 20; ++step) {
    memory_.carry(0.5, 0.0, 0.1);
  }
  ASSERT_EQ(memory_.points().size(), 1u);
  EXPECT_NEAR(memory_.points()[0].position_m.x(), 2.0, 1e-9);
  EXPECT_NEAR(memory_.points()[0].position_m.y(), 0.5, 1e-9);

  // A quarter circle of radius 2 m to the left (turn rate negative, CONVENTIONS.md) in ten steps:
  // the agent ends at (2, 2) of the old frame facing +y. (2, 3) is then 1 m ahead, (1, 3.5)
  // 1.5 m ahead and 1 m to the left.
  memory_ = ObstacleMemory(mount_);
  observe({{2.0, 3.0}});
  observe({{1.0, 3.5}});
  ASSERT_EQ(memory_.points().size(), 2u);
  const double radius_m = 2.0;
  const double turn_rate = -kSpeed_mps / radius_m;
  const double duration_s = 0.5 * std::numbers::pi * radius_m / kSpeed_mps;
  for (int step = 0; step < 10; ++step) {
    memory_.carry(kSpeed_mps, turn_rate, duration_s / 10.0);
  }
  ASSERT_EQ(memory_.points().size(), 2u);
  EXPECT_NEAR(memory_.points()[0].position_m.x(), 1.0, 1e-9);
  EXPECT_NEAR(memory_.points()[0].position_m.y(), 0.0, 1e-9);
  EXPECT_NEAR(memory_.points()[1].position_m.x(), 1.5, 1e-9);
  EXPECT_NEAR(memory_.points()[1].position_m.y(), 1.0, 1e-9);
}

TEST_F(ObstacleMemoryTest, DropsPointsOutOfRangeOrBehind) {
  observe({{3.5, 0.0}});
  observe({{1.0, 1.0}});
  ASSERT_EQ(memory_.points().size(), 2u);
  memory_.carry(-1.0, 0.0, 1.0);  // the first is now 4.5 m away
  ASSERT_EQ(memory_.points().size(), 1u);
  memory_.carry(1.0, 0.0, 2.6);  // the second 0.6 m behind
  EXPECT_TRUE(memory_.points().empty());
}

TEST_F(ObstacleMemoryTest, KeepsAPointSeenStandingNotOneSeenInPassing) {
  floor_.assign(field_.size(), 0);  // nothing says it has gone: it only lacks more looks
  observe({{2.0, 0.0}});
  for (int frame = 0; frame < 6; ++frame) {
    observe_nothing();
  }
  EXPECT_TRUE(memory_.points().empty());

  // Two sightings a frame apart span less than confirm_span_s.
  observe({{2.0, 0.0}});
  observe({{2.02, 0.01}});
  ASSERT_EQ(memory_.points().size(), 1u);
  EXPECT_FALSE(memory_.confirmed(memory_.points()[0]));
  for (int frame = 0; frame < 6; ++frame) {
    observe_nothing();
  }
  EXPECT_TRUE(memory_.points().empty());

  observe_standing({{2.0, 0.0}});
  ASSERT_EQ(memory_.points().size(), 1u);
  EXPECT_TRUE(memory_.confirmed(memory_.points()[0]));
  for (int frame = 0; frame < 25; ++frame) {
    observe_nothing();
  }
  EXPECT_EQ(memory_.points().size(), 1u);
  for (int frame = 0; frame < 10; ++frame) {
    observe_nothing();  // not seen for longer than forget_s
  }
  EXPECT_TRUE(memory_.points().empty());
}

TEST_F(ObstacleMemoryTest, DoesNotConfirmWhatWalksPastLookingStatic) {
  // Someone crossing 1.5 m ahead whose flow looks static (a plain coat the untextured fill gave a
  // static point's flow): at 1 m/s, then at 0.6 m/s, each frame's contact a step further on.
  // Faster than spacing_m / confirm_span_s (0.4 m/s), no point is confirmed.
  for (const double speed_mps : {1.0, 0.6}) {
    memory_ = ObstacleMemory(mount_);
    for (int frame = 0; frame < 20; ++frame) {
      observe({{1.5, 1.0 - speed_mps * kFrame_s * frame}});
      for (const ObstacleMemory::Point& p : memory_.points()) {
        EXPECT_FALSE(memory_.confirmed(p)) << speed_mps << " m/s, frame " << frame;
      }
    }
    // Out of view now, what it left behind is not recalled.
    memory_.carry(kSpeed_mps, 0.0, 1.0);
    observe_nothing();
    EXPECT_TRUE(memory_.recall(kSpeed_mps).empty()) << speed_mps << " m/s";
  }
}

TEST_F(ObstacleMemoryTest, DoesNotRememberWhatClosesInFasterThanAStaticObject) {
  for (int frame = 0; frame < 3; ++frame) {
    observe({{2.0, 0.0}}, 0.4);  // someone walking towards the agent faster than it walks
  }
  EXPECT_TRUE(memory_.points().empty());
}

TEST_F(ObstacleMemoryTest, RemembersAContactOnlyNearWhereItsRegionsTimeToContactPutsIt) {
  // A region that took in the floor below a wall has its contact nearer than its τ says: at
  // 1 / 1.4 of it, beyond ttc_tolerance (25 %); at 1 / 1.2 of it, within.
  observe({{2.0, 0.0}}, 1.4);
  EXPECT_TRUE(memory_.points().empty());
  observe({{2.0, 0.0}}, 1.2);
  EXPECT_EQ(memory_.points().size(), 1u);
}

TEST_F(ObstacleMemoryTest, RemembersOnlyContactsWhoseRowPlacesThemWithinItsSpacing) {
  // At 64×48 a row spans 0.07 m of floor 1.5 m ahead and 0.125 m 2 m ahead: more than spacing_m
  // (0.1 m), so a foot found a row off would misplace the point by more than its spacing.
  use_camera(64, 48);
  observe({{2.0, 0.0}});
  EXPECT_TRUE(memory_.points().empty());
  observe({{1.5, 0.0}});
  EXPECT_EQ(memory_.points().size(), 1u);
  // At 320×240 a row spans 0.025 m of floor 2 m ahead.
  use_camera(320, 240);
  observe({{2.0, 0.0}});
  EXPECT_EQ(memory_.points().size(), 2u);
}

TEST_F(ObstacleMemoryTest, RemembersAContactWhoseColumnMovesAsAnUprightSurfaceStandingThere) {
  // A wall along the course: its region's one τ and its ends say nothing of this contact, 1.5 m
  // ahead and 0.8 m to the left, but its column moves as a surface standing there.
  observe_column({1.5, 0.8}, ColumnMotion::upright);
  ASSERT_EQ(memory_.points().size(), 1u);
  EXPECT_NEAR((memory_.points()[0].position_m - Eigen::Vector2d(1.5, 0.8)).norm(), 0.0, 0.05);
}

TEST_F(ObstacleMemoryTest, DoesNotRememberAContactWhoseColumnMovesAsTheFloor) {
  observe_column({1.5, 0.8}, ColumnMotion::floor);
  EXPECT_TRUE(memory_.points().empty());
}

TEST_F(ObstacleMemoryTest, JudgesNoColumnWhereUprightAndFloorMoveAlikeWithinTheFlowsError) {
  // At 0.5 m/s a surface standing 3 m straight ahead and the floor seen above its foot move apart
  // by less than half a pixel and a quarter of the flow in every row: the column cannot tell them
  // apart. At 1.5 m it can.
  observe_column({3.0, 0.0}, ColumnMotion::upright, 0.5);
  EXPECT_TRUE(memory_.points().empty());
  observe_column({1.5, 0.0}, ColumnMotion::upright, 0.5);
  EXPECT_EQ(memory_.points().size(), 1u);
}

TEST_F(ObstacleMemoryTest, DropsARemovedObstacleWithinItsFadeTime) {
  observe_standing({{2.0, 0.0}});
  const auto fade_frames = std::lround(ObstacleMemoryOptions{}.fade_s / kFrame_s);
  long frames = 0;
  for (; !memory_.points().empty() && frames < 100; ++frames) {
    observe_nothing();  // the floor shows where it stood
    if (!memory_.points().empty()) {
      EXPECT_EQ(memory_.points()[0].sight, Sight::contradicted);
    }
  }
  EXPECT_GE(frames, fade_frames - 1);
  EXPECT_LE(frames, fade_frames + 1);
}

TEST_F(ObstacleMemoryTest, KeepsAnObstacleHiddenBehindANearerOne) {
  observe_standing({{2.0, 0.0}});
  // Something nearer covers the column above its foot.
  const auto foot = ground_.image_of({2.0, 0.0});
  const base::CameraIntrinsics& k = field_.intrinsics();
  const auto col = static_cast<int>(std::lround(k.fx_px * foot->x() + k.cx_px));
  for (int row = 0; row < field_.height(); ++row) {
    segmentation_.labels[field_.index(col, row)] = 0;
  }
  for (int frame = 0; frame < 25; ++frame) {
    observe_nothing();
  }
  ASSERT_EQ(memory_.points().size(), 1u);
  EXPECT_EQ(memory_.points()[0].sight, Sight::covered);
  EXPECT_TRUE(memory_.recall(kSpeed_mps).empty());  // the percept has it
}

TEST_F(ObstacleMemoryTest, RecallsAWallBesideTheAgentAsOneStaticObject) {
  std::vector<Eigen::Vector2d> wall;
  for (int k = 0; k < 4; ++k) {
    wall.push_back({1.2 + 0.12 * k, 0.8});
  }
  observe_standing(wall);
  EXPECT_TRUE(memory_.recall(kSpeed_mps).empty());  // in view: the percept has it
  // One metre on, the wall's foot has left the 90° view on the left.
  memory_.carry(kSpeed_mps, 0.0, 1.0);
  for (int frame = 0; frame < 25; ++frame) {
    observe_nothing();  // floor everywhere in view: nothing says the wall has gone
  }
  ASSERT_EQ(memory_.points().size(), wall.size());
  const auto objects = memory_.recall(kSpeed_mps);
  ASSERT_EQ(objects.size(), 1u);
  const ObjectFeatures& o = objects[0];
  EXPECT_EQ(o.kind, RegionKind::visible);
  EXPECT_GE(o.source_id, ObstacleMemory::kFirstId);
  EXPECT_EQ(o.status, MotionStatus::approaching);
  EXPECT_TRUE(o.fit.static_foe);
  EXPECT_NEAR(o.foe.x(), mount_.forward_foe().x(), 1e-12);
  EXPECT_NEAR(o.foe.y(), mount_.forward_foe().y(), 1e-12);
  // Its nearest point 0.2 m ahead closes in at the agent's speed.
  EXPECT_NEAR(o.ttc_s, 0.2 / kSpeed_mps, 1e-6);
  // Left of the heading, from 0.2 m to 0.56 m ahead: x = −left / forward.
  EXPECT_NEAR(o.min_x, -0.8 / 0.2, 1e-6);
  EXPECT_NEAR(*o.min_x_depth_m, 0.2, 1e-6);
  EXPECT_NEAR(o.max_x, -0.8 / 0.56, 1e-6);
  EXPECT_NEAR(*o.max_x_depth_m, 0.56, 1e-6);
  EXPECT_NEAR(*o.nearest_depth_m, 0.2, 1e-6);
  EXPECT_GT(o.width, 0.0);
  // The same object next frame, by its id.
  const std::int32_t id = o.source_id;
  EXPECT_EQ(memory_.recall(kSpeed_mps)[0].source_id, id);
}

}  // namespace
}  // namespace flowsteer::servo
