#include "flowsteer/servo/untextured_fill.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kSpeedMps = 0.7;
constexpr double kIntervalS = 0.2;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A robot's camera: 0.45 m up, pitched 8° down, 90° across 96×72.
struct View {
  base::CameraMount mount{0.45, 8.0 * std::numbers::pi / 180.0};
  FlowField field{base::CameraIntrinsics::from_horizontal_fov(96, 72, std::numbers::pi / 2)};
  cv::Mat grey{72, 96, CV_8UC1, cv::Scalar(0)};
  std::vector<std::uint8_t> ground_mask = std::vector<std::uint8_t>(96 * 72, 0);
  std::vector<double> truth_distance_m = std::vector<double>(96 * 72, 0.0);  // 0: not the wall
};

// A plain wall `height_m` tall standing on a textured floor, `ahead_m(x)` metres ahead in column
// x (normalised); the floor has exact flow, the wall and the sky none, as a camera's texture test
// leaves them. Grey: floor 90, wall 170, sky 230.
template <typename AheadOf>
View wall_view(AheadOf ahead_m, double height_m = 2.0) {
  View v;
  const FlatGround ground(v.mount);
  const double cos_pitch = std::cos(v.mount.pitch_rad);
  const double sin_pitch = std::sin(v.mount.pitch_rad);
  v.field.set_interval_s(kIntervalS);
  for (int row = 0; row < v.field.height(); ++row) {
    const double y = v.field.y(row);
    for (int col = 0; col < v.field.width(); ++col) {
      const double x = v.field.x(col);
      const std::size_t i = v.field.index(col, row);
      const double wall_ahead_m = ahead_m(x);
      const auto floor_depth = ground.depth_at(x, y);
      if (floor_depth && ground.distance_ahead_m(y, *floor_depth) < wall_ahead_m) {
        v.field.flow()[i] =
            ground.static_flow_at(x, y, *floor_depth, kSpeedMps, kIntervalS).cast<float>();
        v.grey.at<std::uint8_t>(row, col) = 90;
        continue;
      }
      v.field.flow()[i] = Eigen::Vector2f(kNaN, kNaN);
      // The ray's height above the floor where it reaches the wall.
      const double depth_m = wall_ahead_m / (cos_pitch - y * sin_pitch);
      const double height_at_wall_m = v.mount.height_m - depth_m * (y * cos_pitch + sin_pitch);
      if (height_at_wall_m < height_m) {
        v.grey.at<std::uint8_t>(row, col) = 170;
        v.truth_distance_m[i] = wall_ahead_m;
      } else if (floor_depth) {
        // Over a wall lower than the camera: the floor behind it.
        v.field.flow()[i] =
            ground.static_flow_at(x, y, *floor_depth, kSpeedMps, kIntervalS).cast<float>();
        v.grey.at<std::uint8_t>(row, col) = 90;
      } else {
        v.grey.at<std::uint8_t>(row, col) = 230;
      }
    }
  }
  mark_ground(v.field, v.mount, kSpeedMps, {}, v.ground_mask);
  return v;
}

// The share of the wall's pixels without flow whose filled flow is within 0.5 px + 20% of a
// static point's flow there; no pixel but the wall's is filled.
double share_filled_right(View& v, const UntexturedFillOptions& options = {},
                          std::span<const Eigen::Vector2f> edge_flow = {}) {
  std::vector<bool> measured(v.field.size());
  for (std::size_t i = 0; i < v.field.size(); ++i) {
    measured[i] = v.field.flow()[i].allFinite();
  }
  UntexturedFill fill(options);
  fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask, edge_flow);
  const FlatGround ground(v.mount);
  const double to_px = v.field.intrinsics().fx_px * kIntervalS;
  int wall = 0;
  int right = 0;
  for (int row = 0; row < v.field.height(); ++row) {
    for (int col = 0; col < v.field.width(); ++col) {
      const std::size_t i = v.field.index(col, row);
      if (v.truth_distance_m[i] == 0.0) {
        EXPECT_EQ(fill.filled()[i], 0) << "col " << col << " row " << row;
        continue;
      }
      if (measured[i]) {
        continue;
      }
      ++wall;
      if (fill.filled()[i] == 0) {
        continue;
      }
      const double y = v.field.y(row);
      const double depth_m = *ground.depth_at_distance_ahead(y, v.truth_distance_m[i]);
      const Eigen::Vector2d exact =
          ground.static_flow_at(v.field.x(col), y, depth_m, kSpeedMps, kIntervalS);
      const double error_px = (v.field.flow()[i].cast<double>() - exact).norm() * to_px;
      right += error_px <= 0.5 + 0.2 * exact.norm() * to_px ? 1 : 0;
    }
  }
  return static_cast<double>(right) / wall;
}

TEST(UntexturedFill, APlainWallHeadOnGetsItsFootsFlow) {
  View v = wall_view([](double) { return 1.2; });
  EXPECT_GT(share_filled_right(v), 0.95);
}

TEST(UntexturedFill, AnObliqueWallGetsEachColumnsFoot) {
  // From 0.8 m ahead at the left edge to 3 m at the right.
  View v = wall_view([](double x) { return 1.9 + 1.1 * x; });
  EXPECT_GT(share_filled_right(v), 0.9);
}

TEST(UntexturedFill, ACorridorsWallsEachGetTheirFoot) {
  // Two walls 0.8 m either side, seen receding: each column's foot is as far ahead as the ray
  // meets its wall.
  View v = wall_view([](double x) { return 0.8 / std::max(std::abs(x), 0.05); });
  EXPECT_GT(share_filled_right(v), 0.8);
}

// How many columns show the wall down to the image's bottom row: its foot is hidden there.
int columns_with_hidden_foot(const View& v) {
  int hidden = 0;
  for (int col = 0; col < v.field.width(); ++col) {
    hidden += v.truth_distance_m[v.field.index(col, v.field.height() - 1)] > 0.0 ? 1 : 0;
  }
  return hidden;
}

TEST(UntexturedFill, WallsBesideTheRobotStandOnTheLineOfTheFeetInView) {
  // A corridor 0.6 m wide: near the image's sides each wall goes down past the bottom row, and
  // only its far part shows its foot.
  View v = wall_view([](double x) { return 0.3 / std::max(std::abs(x), 0.05); });
  ASSERT_GT(columns_with_hidden_foot(v), 20);
  EXPECT_GT(share_filled_right(v), 0.9);
}

// What an estimator measures across the image's horizontal grey-level edges (FlowSource::
// edge_flow): the vertical component of a static point's flow as far ahead as `ahead_m`.
std::vector<Eigen::Vector2f> flow_across_edges(const View& v, double ahead_m) {
  std::vector<Eigen::Vector2f> across(v.field.size(), Eigen::Vector2f(kNaN, kNaN));
  const FlatGround ground(v.mount);
  for (int row = 1; row + 1 < v.field.height(); ++row) {
    const double y = v.field.y(row);
    const auto depth_m = ground.depth_at_distance_ahead(y, ahead_m);
    for (int col = 0; col < v.field.width(); ++col) {
      if (!depth_m ||
          v.grey.at<std::uint8_t>(row - 1, col) == v.grey.at<std::uint8_t>(row + 1, col)) {
        continue;
      }
      const Eigen::Vector2d flow =
          ground.static_flow_at(v.field.x(col), y, *depth_m, kSpeedMps, kIntervalS);
      across[v.field.index(col, row)] = Eigen::Vector2f(0.0F, static_cast<float>(flow.y()));
    }
  }
  return across;
}

TEST(UntexturedFill, AWallWhoseFootIsNowhereInViewStandsWhereItsTopEdgeMoves) {
  // 0.35 m ahead, nearer than the bottom row's floor (0.45 m): no column shows its foot, and no
  // neighbour gives a line. Its top, 0.6 m up, moves across the sky's edge as a point 0.35 m
  // ahead does.
  View v = wall_view([](double) { return 0.35; }, 0.6);
  ASSERT_EQ(columns_with_hidden_foot(v), v.field.width());
  View without_edge_flow = v;
  EXPECT_EQ(share_filled_right(without_edge_flow), 0.0);
  const std::vector<Eigen::Vector2f> across = flow_across_edges(v, 0.35);
  EXPECT_GT(share_filled_right(v, {}, across), 0.9);
}

TEST(UntexturedFill, AnEdgeFartherThanTheBottomRowsFloorPlacesNothing) {
  // No flow and no edge from the bottom row up to a wall's top, as on a floor without texture
  // that meets a wall of its colour; the edge moves as a point 1.2 m ahead would, well over what
  // the estimators resolve, but farther than the bottom row sees (0.45 m): the wall's foot would
  // be in view, and the floor between cannot be told from a surface.
  View v = wall_view([](double) { return 1.2; }, 0.6);
  std::fill(v.field.flow().begin(), v.field.flow().end(), Eigen::Vector2f(kNaN, kNaN));
  std::fill(v.ground_mask.begin(), v.ground_mask.end(), 0);
  for (int row = 0; row < v.field.height(); ++row) {
    for (int col = 0; col < v.field.width(); ++col) {
      auto& grey = v.grey.at<std::uint8_t>(row, col);
      grey = grey == 230 ? 230 : 170;
    }
  }
  const std::vector<Eigen::Vector2f> across = flow_across_edges(v, 1.2);
  UntexturedFill fill;
  EXPECT_EQ(fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask, across), 0);
}

TEST(UntexturedFill, AFootsBandOfFlowIsPartOfTheFloor) {
  // Estimators spread an edge's flow a few pixels into the plain areas either side of it: 4 rows
  // of floor below a head-on wall's foot and 4 of the wall above it get flow the floor does not
  // have.
  View v = wall_view([](double) { return 1.2; });
  for (int col = 0; col < v.field.width(); ++col) {
    int foot = v.field.height() - 1;
    while (foot > 0 && v.truth_distance_m[v.field.index(col, foot)] == 0.0) {
      --foot;
    }
    for (int row = foot + 4; row > foot - 4; --row) {
      v.field.at(col, row) = Eigen::Vector2f(0.0F, 0.5F);
    }
  }
  std::fill(v.ground_mask.begin(), v.ground_mask.end(), 0);
  mark_ground(v.field, v.mount, kSpeedMps, {}, v.ground_mask);
  View without_spread = v;
  EXPECT_LT(share_filled_right(without_spread), 0.05);
  UntexturedFillOptions spread;
  spread.flow_spread_px = 6.0;
  EXPECT_GT(share_filled_right(v, spread), 0.85);
}

TEST(UntexturedFill, AWallWithSomeTextureIsFilledAroundIt) {
  // Every third row of the wall has the flow a camera measures on it.
  View v = wall_view([](double) { return 1.5; });
  const FlatGround ground(v.mount);
  for (int row = 0; row < v.field.height(); row += 3) {
    const double y = v.field.y(row);
    for (int col = 0; col < v.field.width(); ++col) {
      const double ahead_m = v.truth_distance_m[v.field.index(col, row)];
      if (ahead_m > 0.0) {
        v.field.at(col, row) =
            ground
                .static_flow_at(v.field.x(col), y, *ground.depth_at_distance_ahead(y, ahead_m),
                                kSpeedMps, kIntervalS)
                .cast<float>();
      }
    }
  }
  EXPECT_GT(share_filled_right(v), 0.95);
}

TEST(UntexturedFill, ABoxLowerThanTheCameraGetsItsFootsFlow) {
  // A box 0.25 m tall 0.6 m ahead, the floor behind it. Its top edge moves as the box does: the
  // estimator gives the two rows of floor just over it the box's flow. (Farther, the top edge
  // nears the FOE, where flow cannot tell the box from the floor behind it.)
  View v = wall_view([](double) { return 0.6; }, 0.25);
  const FlatGround ground(v.mount);
  for (int col = 0; col < v.field.width(); ++col) {
    int top = 0;
    while (top < v.field.height() && v.truth_distance_m[v.field.index(col, top)] == 0.0) {
      ++top;
    }
    for (int row = std::max(top - 2, 0); row < top; ++row) {
      const double y = v.field.y(row);
      v.field.at(col, row) =
          ground
              .static_flow_at(v.field.x(col), y, *ground.depth_at_distance_ahead(y, 0.6), kSpeedMps,
                              kIntervalS)
              .cast<float>();
    }
  }
  EXPECT_GT(share_filled_right(v), 0.9);
}

// A box 0.25 m tall and 0.8 m wide 1.2 m ahead, its top near the FOE: only its outer columns'
// top edges move measurably unlike the floor behind them.
View narrow_box_view() {
  return wall_view([](double x) { return std::abs(x) < 0.35 ? 1.2 : 1e6; }, 0.25);
}

// The box's static flow at (col, row).
Eigen::Vector2f box_flow(const View& v, int col, int row) {
  const FlatGround ground(v.mount);
  const double y = v.field.y(row);
  return ground
      .static_flow_at(v.field.x(col), y, *ground.depth_at_distance_ahead(y, 1.2), kSpeedMps,
                      kIntervalS)
      .cast<float>();
}

// The top row of the box in column col; the field's height where it has none.
int box_top(const View& v, int col) {
  int top = 0;
  while (top < v.field.height() && v.truth_distance_m[v.field.index(col, top)] == 0.0) {
    ++top;
  }
  return top;
}

TEST(UntexturedFill, ABoxIsFilledWholeWhereItsTopNearsTheFoe) {
  View v = narrow_box_view();
  for (int col = 0; col < v.field.width(); ++col) {
    const int top = box_top(v, col);
    for (int row = std::max(top - 2, 0); row < std::min(top, v.field.height()); ++row) {
      v.field.at(col, row) = box_flow(v, col, row);
    }
  }
  EXPECT_GT(share_filled_right(v), 0.9);
}

TEST(UntexturedFill, ABoxsSidesMoveAsItDoes) {
  // No flow about the box's top (the texture test drops its straight edge); across its side
  // edges, the horizontal flow the box has.
  View v = narrow_box_view();
  std::vector<Eigen::Vector2f> edge_flow(v.field.size(), Eigen::Vector2f(kNaN, kNaN));
  for (int col = 0; col < v.field.width(); ++col) {
    const int top = box_top(v, col);
    for (int row = std::max(top - 4, 0); row < std::min(top, v.field.height()); ++row) {
      v.field.at(col, row) = Eigen::Vector2f(kNaN, kNaN);
    }
    const bool side = top < v.field.height() &&
                      (box_top(v, std::max(col - 1, 0)) == v.field.height() ||
                       box_top(v, std::min(col + 1, v.field.width() - 1)) == v.field.height());
    for (int row = top; side && row < v.field.height(); ++row) {
      if (v.truth_distance_m[v.field.index(col, row)] > 0.0) {
        edge_flow[v.field.index(col, row)] = Eigen::Vector2f(box_flow(v, col, row).x(), 0.0F);
      }
    }
  }
  std::fill(v.ground_mask.begin(), v.ground_mask.end(), 0);
  mark_ground(v.field, v.mount, kSpeedMps, {}, v.ground_mask);
  View without_sides = v;
  UntexturedFill fill;
  EXPECT_EQ(fill.fill(without_sides.field, without_sides.grey, 0.0, without_sides.mount, kSpeedMps,
                      without_sides.ground_mask),
            0);
  EXPECT_GT(fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask, edge_flow),
            0.9 * std::count_if(v.truth_distance_m.begin(), v.truth_distance_m.end(),
                                [](double d) { return d > 0.0; }));
}

TEST(UntexturedFill, AMarkOnATexturedFloorIsNotAWall) {
  // A dark band across the floor 1.5–1.6 m ahead, the floor beyond it textured to the horizon.
  View v = wall_view([](double) { return 1e6; });
  const FlatGround ground(v.mount);
  for (int row = 0; row < v.field.height(); ++row) {
    const auto depth_m = ground.depth_at(0.0, v.field.y(row));
    if (depth_m) {
      const double ahead_m = ground.distance_ahead_m(v.field.y(row), *depth_m);
      if (ahead_m > 1.5 && ahead_m < 1.6) {
        v.grey.row(row).setTo(30);
      }
    }
  }
  UntexturedFill fill;
  EXPECT_EQ(fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask), 0);
}

TEST(UntexturedFill, TheFloorAndTheSkyAloneGetNothing) {
  View v = wall_view([](double) { return 1e6; });
  UntexturedFill fill;
  EXPECT_EQ(fill.fill(v.field, v.grey, 0.0, v.mount, kSpeedMps, v.ground_mask), 0);
}

TEST(UntexturedFill, NoiseRaisesTheEdgeThreshold) {
  // A wall whose foot steps by 80 grey levels is not found when the image's noise is such that
  // a step of that size is within what noise makes.
  View v = wall_view([](double) { return 1.2; });
  UntexturedFill fill;
  EXPECT_GT(fill.fill(v.field, v.grey, 1.0, v.mount, kSpeedMps, v.ground_mask), 0);
  View noisy = wall_view([](double) { return 1.2; });
  EXPECT_EQ(fill.fill(noisy.field, noisy.grey, 25.0, noisy.mount, kSpeedMps, noisy.ground_mask), 0);
}

}  // namespace
}  // namespace flowsteer::servo
