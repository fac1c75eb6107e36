#include "flowsteer/servo/features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/segmentation.hpp"
#include "radial_fit.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A thin panel facing the agent: one depth, so the radial model holds exactly.
SceneObject panel(std::int32_t id, double x, double y, double width, Eigen::Vector2d velocity) {
  SceneObject o;
  o.id = id;
  o.position_m = {x, y};
  o.length_m = 0.002;
  o.width_m = width;
  o.height_m = 1.8;
  o.velocity_mps = velocity;
  return o;
}

AnalyticScene base_scene(double pitch_rad = 0.0) {
  AnalyticScene scene;
  scene.intrinsics = base::CameraIntrinsics::from_horizontal_fov(256, 192, 90.0 * kDeg);
  scene.mount = {1.0, pitch_rad};
  scene.agent_speed_mps = 1.0;
  scene.agent_turn_rate = 0.3;
  return scene;
}

struct Case {
  const char* name;
  double pitch_rad;
  SceneObject object;
};

std::vector<Case> approaching_cases() {
  return {
      {"static, ahead right", 0.0, panel(3, 6.0, -0.8, 1.0, {0.0, 0.0})},
      {"crossing from the left", 0.0, panel(4, 8.0, 1.5, 1.2, {0.0, -0.4})},
      {"oncoming agent", 0.0, panel(5, 7.0, 0.5, 0.6, {-1.0, 0.0})},
      {"static, camera pitched 10 deg", 10.0 * kDeg, panel(6, 5.0, 0.6, 1.0, {0.0, 0.0})},
  };
}

struct Extracted {
  ObjectFeatures features;
  ObjectTruth truth;
};

// Renders, optionally corrupts, derotates and extracts the features of the case's object.
template <typename Corrupt>
Extracted extract(const Case& c, Corrupt corrupt, const FeatureOptions& options = {}) {
  AnalyticScene scene = base_scene(c.pitch_rad);
  scene.objects = {c.object};
  SceneRender render = render_scene(scene);
  derotate(render.flow, camera_angular_velocity(scene.agent_turn_rate, c.pitch_rad));
  corrupt(render);
  Segmentation segmentation;
  segment_by_ids(render.ids, render.flow.width(), render.flow.height(), {}, segmentation);
  FeatureExtractor extractor(options);
  const auto objects = extractor.extract(render.flow, segmentation);
  for (const ObjectFeatures& f : objects) {
    if (f.source_id == c.object.id) {
      ObjectTruth truth = object_truth(scene, c.object);
      // The panel's face is at its centre's depth; τ there is the truth.
      return {f, truth};
    }
  }
  ADD_FAILURE() << c.name << ": object not found";
  return {};
}

Extracted extract(const Case& c) {
  return extract(c, [](SceneRender&) {});
}

TEST(RadialFit, ExactFlowGivesFoeAndTtc) {
  for (const Case& c : approaching_cases()) {
    const Extracted e = extract(c);
    ASSERT_EQ(e.features.status, MotionStatus::approaching) << c.name;
    EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.005) << c.name;
    EXPECT_NEAR(e.features.ttc_s, e.truth.ttc_s, 0.01 * e.truth.ttc_s) << c.name;
    EXPECT_NEAR(e.features.ttc_eq5_s, e.truth.ttc_s, 0.01 * e.truth.ttc_s) << c.name;
    EXPECT_GT(e.features.fit.inlier_fraction, 0.99) << c.name;
    EXPECT_GT(e.features.pixel_count, 100) << c.name;
    ASSERT_TRUE(e.features.depth_m.has_value());
    EXPECT_NEAR(*e.features.depth_m, e.truth.centre_depth_m, 0.01 * e.truth.centre_depth_m);
  }
}

// Gaussian noise of 10% of each vector's magnitude, and 20% of the vectors replaced by random
// ones of up to twice the region's mean magnitude.
void corrupt_region(SceneRender& render, std::int32_t id, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto flow = render.flow.flow();
  double mean_magnitude = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < flow.size(); ++i) {
    if (render.ids[i] == id) {
      mean_magnitude += flow[i].norm();
      ++count;
    }
  }
  mean_magnitude /= count;
  for (std::size_t i = 0; i < flow.size(); ++i) {
    if (render.ids[i] != id) {
      continue;
    }
    if (unit(rng) < 0.2) {
      const double angle = 2.0 * std::numbers::pi * unit(rng);
      const double magnitude = 2.0 * mean_magnitude * unit(rng);
      flow[i] = Eigen::Vector2f(static_cast<float>(magnitude * std::cos(angle)),
                                static_cast<float>(magnitude * std::sin(angle)));
    } else {
      const double sigma = 0.1 * flow[i].norm();
      flow[i] += Eigen::Vector2f(static_cast<float>(sigma * gauss(rng)),
                                 static_cast<float>(sigma * gauss(rng)));
    }
  }
}

TEST(RadialFit, NoisyFlowWithOutliersStaysWithinBounds) {
  for (const Case& c : approaching_cases()) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const Extracted e = extract(c, [&](SceneRender& r) { corrupt_region(r, c.object.id, seed); });
      ASSERT_EQ(e.features.status, MotionStatus::approaching) << c.name << " seed " << seed;
      EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.02) << c.name << " seed " << seed;
      EXPECT_NEAR(e.features.ttc_s, e.truth.ttc_s, 0.05 * e.truth.ttc_s)
          << c.name << " seed " << seed;
      EXPECT_GT(e.features.fit.inlier_fraction, 0.6) << c.name << " seed " << seed;
      EXPECT_LT(e.features.fit.inlier_fraction, 0.95) << c.name << " seed " << seed;
    }
  }
}

TEST(RadialFit, RecedingObjectIsReportedWithNegativeTtc) {
  // Faster than the agent, ahead: it pulls away.
  const Case c{"receding", 0.0, panel(2, 6.0, 0.3, 1.0, {2.5, 0.0})};
  const Extracted e = extract(c);
  EXPECT_EQ(e.features.status, MotionStatus::receding);
  EXPECT_LT(e.features.ttc_s, 0.0);
  EXPECT_NEAR(e.features.ttc_s, e.truth.ttc_s, 0.01 * std::abs(e.truth.ttc_s));
  EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.005);
}

TEST(RadialFit, ObjectKeepingItsDistanceIsLateral) {
  // Same forward speed as the agent, drifting sideways: no expansion, FOE at infinity.
  const Case c{"lateral", 0.0, panel(2, 6.0, 0.3, 1.0, {1.0, 0.5})};
  const Extracted e = extract(c);
  EXPECT_EQ(e.features.status, MotionStatus::lateral);
  EXPECT_TRUE(std::isinf(e.features.ttc_s));
  EXPECT_FALSE(e.features.has_foe());
}

TEST(RadialFit, TooFewSamplesGiveNoFlow) {
  const std::vector<FlowSample> two = {{{0.1, 0.1}, {0.1, 0.1}}, {{0.2, 0.1}, {0.2, 0.1}}};
  EXPECT_EQ(fit_radial_flow(two).status, MotionStatus::no_flow);
  const std::vector<FlowSample> same_point(5, FlowSample{{0.1, 0.1}, {0.1, 0.1}});
  EXPECT_EQ(fit_radial_flow(same_point).status, MotionStatus::no_flow);
  EXPECT_EQ(fit_radial_flow({}).status, MotionStatus::no_flow);
}

// Exact radial flow about `foe` with 1/τ = 0.5 over a patch of points.
std::vector<FlowSample> radial_samples(const Eigen::Vector2d& foe) {
  std::vector<FlowSample> samples;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      const Eigen::Vector2d x(0.2 + 0.02 * i, -0.1 + 0.03 * j);
      samples.push_back({x, 0.5 * (x - foe)});
    }
  }
  return samples;
}

TEST(RadialFit, FoeHypothesisHoldsOnlyForTheFlowsOwnFoe) {
  const Eigen::Vector2d foe(0.05, -0.02);
  std::vector<FlowSample> samples = radial_samples(foe);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (FlowSample& s : samples) {
    s.flow += Eigen::Vector2d(noise(rng), noise(rng));
  }
  const RadialFit fit = fit_radial_flow(samples);
  ASSERT_EQ(fit.status, MotionStatus::approaching);
  EXPECT_LT(foe_hypothesis_statistic(fit, foe), 9.21);
  EXPECT_GT(foe_hypothesis_statistic(fit, foe + Eigen::Vector2d(0.05, 0.0)), 100.0);
  // Correlated samples widen the covariance: the same offset no longer stands out.
  EXPECT_LT(foe_hypothesis_statistic(fit, foe + Eigen::Vector2d(0.05, 0.0), 1e4), 9.21);

  // Flow of an object keeping its distance has no FOE in the image at all.
  std::vector<FlowSample> lateral = samples;
  for (FlowSample& s : lateral) {
    s.flow = Eigen::Vector2d(0.3, 0.0);
  }
  EXPECT_GT(foe_hypothesis_statistic(fit_radial_flow(lateral), Eigen::Vector2d::Zero()), 100.0);
}

TEST(RadialFit, FitAboutAGivenFoeFindsTtc) {
  const Eigen::Vector2d foe(0.05, -0.02);
  const RadialFit fit = fit_radial_flow_about(radial_samples(foe), foe);
  ASSERT_EQ(fit.status, MotionStatus::approaching);
  EXPECT_NEAR(fit.ttc_s, 2.0, 1e-9);
  EXPECT_EQ(fit.foe, foe);
  const RadialFit receding = fit_radial_flow_about(radial_samples(foe), Eigen::Vector2d(0.9, 0.0));
  EXPECT_EQ(receding.status, MotionStatus::receding);
}

TEST(RadialFit, StaticSurfaceResidualsTellAWallFromAMovingPanel) {
  const Eigen::Vector2d static_foe(0.0, 0.0);
  // A wall 2 m to the left seen while walking at 1 m/s: Z = −2 / x, u = (x − f) / Z.
  std::vector<FlowSample> wall;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 8; ++j) {
      const Eigen::Vector2d x(-1.5 + 0.1 * i, -0.3 + 0.08 * j);
      wall.push_back({x, (x - static_foe) * (-x.x() / 2.0)});
    }
  }
  const SurfaceResiduals of_wall = static_surface_residuals(wall, static_foe);
  EXPECT_LT(of_wall.static_plane, 1e-20);
  EXPECT_GT(of_wall.radial, 1e-4);

  const SurfaceResiduals of_panel =
      static_surface_residuals(radial_samples({0.3, 0.1}), static_foe);
  EXPECT_LT(of_panel.radial, 1e-20);
  EXPECT_GT(of_panel.static_plane, 1e-4);

  const std::vector<FlowSample> two(wall.begin(), wall.begin() + 2);
  EXPECT_TRUE(std::isnan(static_surface_residuals(two, static_foe).static_plane));
  // On one line through the FOE the plane's parameters cannot be told apart.
  std::vector<FlowSample> on_a_ray;
  for (int i = 1; i <= 10; ++i) {
    const Eigen::Vector2d x(0.1 * i, 0.05 * i);
    on_a_ray.push_back({x, 0.5 * x});
  }
  EXPECT_TRUE(std::isnan(static_surface_residuals(on_a_ray, static_foe).static_plane));
}

FeatureOptions with_static_foe(const Case& c) {
  FeatureOptions options;
  options.static_foe = base::CameraMount{1.0, c.pitch_rad}.forward_foe();
  return options;
}

// The test behind it accepts 99% of static objects' flows: over 20 noisy frames a few may keep
// their own FOE, which is then close to the static one.
TEST(FeatureExtractor, NoisyStaticObjectGetsTheStaticFoe) {
  for (const Case& c : {approaching_cases()[0], approaching_cases()[3]}) {
    int accepted = 0;
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const auto corrupt = [&](SceneRender& r) { corrupt_region(r, c.object.id, seed); };
      const Extracted e = extract(c, corrupt, with_static_foe(c));
      ASSERT_EQ(e.features.status, MotionStatus::approaching) << c.name << " seed " << seed;
      const double foe_error = (e.features.foe - e.truth.foe).norm();
      if (e.features.fit.static_foe) {
        ++accepted;
        EXPECT_LT(foe_error, 1e-9) << c.name << " seed " << seed;
      } else {
        EXPECT_LT(foe_error, 0.02) << c.name << " seed " << seed;
      }
      EXPECT_NEAR(e.features.ttc_s, e.truth.ttc_s, 0.05 * e.truth.ttc_s)
          << c.name << " seed " << seed;
    }
    EXPECT_GE(accepted, 17) << c.name;
  }
}

TEST(FeatureExtractor, MovingObjectKeepsItsOwnFoe) {
  const Case c = approaching_cases()[1];  // crossing from the left
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto corrupt = [&](SceneRender& r) { corrupt_region(r, c.object.id, seed); };
    const Extracted e = extract(c, corrupt, with_static_foe(c));
    ASSERT_EQ(e.features.status, MotionStatus::approaching) << "seed " << seed;
    EXPECT_FALSE(e.features.fit.static_foe) << "seed " << seed;
    EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.02) << "seed " << seed;
  }
}

// Numerical flow has no depth: the static test then also asks whether a static plane explains
// the flow (static_surface_residuals), which must not take a moving object for one. The
// oncoming agent moves along the line of sight, so its FOE is the static one either way.
TEST(FeatureExtractor, MovingObjectWithoutDepthKeepsItsOwnFoe) {
  for (const Case& c : {approaching_cases()[1], approaching_cases()[2]}) {
    FeatureOptions options = with_static_foe(c);
    options.use_depth = false;
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const auto corrupt = [&](SceneRender& r) { corrupt_region(r, c.object.id, seed); };
      const Extracted e = extract(c, corrupt, options);
      ASSERT_EQ(e.features.status, MotionStatus::approaching) << c.name << " seed " << seed;
      EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.02) << c.name << " seed " << seed;
      if (c.object.velocity_mps.y() != 0.0) {
        EXPECT_FALSE(e.features.fit.static_foe) << c.name << " seed " << seed;
      }
    }
  }
}

// A wall beside the path, 8 m long: its near end expands faster than its far end, which the
// radial model can only read as an FOE moved towards the near end.
TEST(FeatureExtractor, WallAlongThePathWithoutDepthGetsTheStaticFoe) {
  SceneObject wall;
  wall.id = 7;
  wall.position_m = {5.0, 1.6};
  wall.length_m = 8.0;
  wall.width_m = 0.1;
  const Case c{"wall on the left", 0.0, wall};
  FeatureOptions options = with_static_foe(c);
  options.use_depth = false;
  const Eigen::Vector2d static_foe = *options.static_foe;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto corrupt = [&](SceneRender& r) { corrupt_region(r, c.object.id, seed); };
    const Extracted e = extract(c, corrupt, options);
    ASSERT_EQ(e.features.status, MotionStatus::approaching) << "seed " << seed;
    EXPECT_TRUE(e.features.fit.static_foe) << "seed " << seed;
    EXPECT_EQ(e.features.foe, static_foe) << "seed " << seed;
  }
  options.static_surface_rss_ratio = 0.0;
  const Extracted radial_only = extract(
      c, [](SceneRender&) {}, options);
  EXPECT_FALSE(radial_only.features.fit.static_foe);
  EXPECT_GT((radial_only.features.foe - static_foe).norm(), 0.1);
}

// Each component moved by up to `ulps` units in its last place, as a renderer that computes flow
// in float32 (the simulator's shaders) delivers it.
void round_as_float_pipeline(FlowField& field, int ulps, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> steps(-ulps, ulps);
  for (Eigen::Vector2f& u : field.flow()) {
    for (int c = 0; c < 2; ++c) {
      const int n = steps(rng);
      const float towards =
          n > 0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
      for (int k = 0; k < std::abs(n); ++k) {
        u[c] = std::nextafter(u[c], towards);
      }
    }
  }
}

// Walls and a pillar seen while the agent turns at up to 1.5 rad/s with a 150° view, from
// simulated flow with depth: static objects, whose fit about the static FOE must pass. The
// flow rounds at its magnitude before derotation, up to 15 times the centre's rotation at the
// view's edges; measured against the derotated flow's own magnitude, rounding alone failed
// the test for some of these.
TEST(FeatureExtractor, StaticObjectsSeenWhileTurningGetTheStaticFoe) {
  AnalyticScene scene;
  scene.intrinsics = base::CameraIntrinsics::from_horizontal_fov(128, 128, 150.0 * kDeg);
  scene.mount = {1.0, 0.0};
  scene.agent_speed_mps = 1.3;
  FeatureOptions options;
  options.static_foe = scene.mount.forward_foe();
  int fits = 0;
  for (const Eigen::Vector2d& at : {Eigen::Vector2d{6.0, 1.6}, Eigen::Vector2d{6.0, -1.6},
                                    Eigen::Vector2d{3.0, 2.0}, Eigen::Vector2d{9.0, -2.5}}) {
    for (const double length_m : {0.4, 8.0}) {
      SceneObject object = panel(7, at.x(), at.y(), 0.4, {0.0, 0.0});
      object.length_m = length_m;
      scene.objects = {object};
      for (const double turn_rate : {-1.5, -0.8, 0.4, 1.1, 1.5}) {
        scene.agent_turn_rate = turn_rate;
        SceneRender render = render_scene(scene);
        round_as_float_pipeline(render.flow, 4, static_cast<unsigned>(fits + 1));
        derotate(render.flow, camera_angular_velocity(turn_rate, 0.0));
        Segmentation segmentation;
        segment_by_ids(render.ids, render.flow.width(), render.flow.height(), {}, segmentation);
        FeatureExtractor extractor(options);
        for (const ObjectFeatures& f : extractor.extract(render.flow, segmentation)) {
          if (f.source_id == object.id && f.status == MotionStatus::approaching) {
            ++fits;
            EXPECT_TRUE(f.fit.static_foe) << "object at (" << at.transpose() << "), " << length_m
                                          << " m long, turning at " << turn_rate;
          }
        }
      }
    }
  }
  EXPECT_GE(fits, 30);
}

TEST(FeatureExtractor, NonFiniteVectorsAreIgnoredAndCounted) {
  const Case c = approaching_cases().front();
  int poisoned = 0;
  const Extracted e = extract(c, [&](SceneRender& r) {
    auto flow = r.flow.flow();
    for (std::size_t i = 0; i < flow.size(); ++i) {
      if (r.ids[i] == c.object.id && i % 7 == 0) {
        flow[i].x() = (poisoned % 2 == 0) ? std::numeric_limits<float>::quiet_NaN()
                                          : std::numeric_limits<float>::infinity();
        ++poisoned;
      }
    }
  });
  ASSERT_GT(poisoned, 10);
  EXPECT_EQ(e.features.invalid_flow_count, poisoned);
  EXPECT_EQ(e.features.status, MotionStatus::approaching);
  EXPECT_LT((e.features.foe - e.truth.foe).norm(), 0.005);
  EXPECT_TRUE(std::isfinite(e.features.moments.mean_u));
}

// An 8×6 segmentation with `regions` visible regions (source ids 10, 11, ...) and no pixel
// assigned yet.
Segmentation empty_segmentation(int regions) {
  Segmentation s;
  s.width = 8;
  s.height = 6;
  s.labels.assign(48, Segmentation::kNoRegion);
  for (int r = 0; r < regions; ++r) {
    s.kinds.push_back(RegionKind::visible);
    s.source_ids.push_back(10 + r);
  }
  return s;
}

TEST(FeatureExtractor, EmptyAndOnePixelRegionsAreReportedWithoutAFit) {
  const base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(8, 6, 90.0 * kDeg);
  FlowField field(k);
  Segmentation s = empty_segmentation(2);
  s.labels[5] = 1;  // region 0 has no pixel, region 1 has one
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  ASSERT_EQ(objects.size(), 2U);
  EXPECT_EQ(objects[0].pixel_count, 0);
  EXPECT_EQ(objects[0].status, MotionStatus::no_flow);
  EXPECT_EQ(objects[1].pixel_count, 1);
  EXPECT_EQ(objects[1].status, MotionStatus::no_flow);
  EXPECT_NEAR(objects[1].centre.x(), field.x(5), 1e-12);
  EXPECT_GT(objects[1].width, 0.0);
}

// A box ahead and to the right, seen at its corner (4, -1): the region's nearest point on the
// ground is there, within a pixel, and not at either end of the region.
TEST(FeatureExtractor, ABoxSeenAtItsCornerIsNearestThere) {
  SceneObject box = panel(8, 5.0, -2.0, 2.0, {0.0, 0.0});
  box.length_m = 2.0;
  const Extracted e = extract({"box at its corner", 0.0, box});
  ASSERT_TRUE(e.features.nearest_depth_m.has_value());
  const double pixel = 1.0 / base_scene().intrinsics.fx_px;
  EXPECT_NEAR(e.features.nearest_x, 0.25, pixel);
  EXPECT_NEAR(*e.features.nearest_depth_m, 4.0, 4.0 * pixel);
  EXPECT_NEAR(*e.features.min_x_depth_m, 6.0, 0.1);
  EXPECT_NEAR(*e.features.max_x_depth_m, 4.0, 0.1);
}

// The features of a scene's objects as a camera sees them in `render`: the flow without its
// depth, the ground's depth where the objects stand on it (FeatureOptions::ground_mount), and,
// given the camera's forward speed, the depth from flow of what stands still.
std::vector<ObjectFeatures> seen_by_a_camera(const AnalyticScene& scene, const SceneRender& render,
                                             double forward_speed_mps = 0.0) {
  FlowField field(scene.intrinsics);
  std::copy(render.flow.flow().begin(), render.flow.flow().end(), field.flow().begin());
  Segmentation segmentation;
  segment_by_ids(render.ids, field.width(), field.height(), {}, segmentation);
  FeatureOptions options;
  options.use_depth = false;
  options.ground_mount = scene.mount;
  options.static_foe = scene.mount.forward_foe();
  FeatureExtractor extractor(options);
  const auto objects = extractor.extract(field, segmentation, forward_speed_mps);
  return {objects.begin(), objects.end()};
}

std::vector<ObjectFeatures> seen_by_a_camera(const AnalyticScene& scene) {
  return seen_by_a_camera(scene, render_scene(scene));
}

const ObjectFeatures& object_with_id(std::span<const ObjectFeatures> objects, std::int32_t id) {
  const auto it = std::find_if(objects.begin(), objects.end(),
                               [&](const ObjectFeatures& f) { return f.source_id == id; });
  if (it == objects.end()) {
    throw std::runtime_error("no object with id " + std::to_string(id));
  }
  return *it;
}

// Without depth, the box of the test above gets its ends' and corner's depths from where it
// stands on the ground: within what one image row spans at that depth (Z² / h per unit of y).
TEST(FeatureExtractor, ACameraGetsTheDepthWhereAnObjectStandsOnTheGround) {
  for (const double pitch_rad : {0.0, 10.0 * kDeg}) {
    AnalyticScene scene = base_scene(pitch_rad);
    SceneObject box = panel(8, 5.0, -2.0, 2.0, {0.0, 0.0});
    box.length_m = 2.0;
    scene.objects = {box};
    const ObjectFeatures f = object_with_id(seen_by_a_camera(scene), 8);
    const double row = 1.0 / scene.intrinsics.fy_px;
    const auto within_a_row = [&](double depth_m) { return 2.0 * depth_m * depth_m * row; };
    // A point of the ground `forward_m` ahead, at the camera's depth.
    const auto depth = [&](double forward_m) {
      return forward_m * std::cos(pitch_rad) + scene.mount.height_m * std::sin(pitch_rad);
    };
    ASSERT_TRUE(f.min_x_depth_m && f.max_x_depth_m && f.nearest_depth_m) << pitch_rad;
    EXPECT_FALSE(f.depth_m.has_value()) << "the mean depth is not measured";
    EXPECT_NEAR(*f.nearest_depth_m, depth(4.0), within_a_row(4.0)) << pitch_rad;
    EXPECT_NEAR(f.nearest_x, 1.0 / depth(4.0), 2.0 / scene.intrinsics.fx_px) << pitch_rad;
    EXPECT_NEAR(*f.min_x_depth_m, depth(6.0), within_a_row(6.0)) << pitch_rad;
    EXPECT_NEAR(*f.max_x_depth_m, depth(4.0), within_a_row(4.0)) << pitch_rad;
    // The contact is taken at the lowest pixel's lower edge: never further than the truth.
    EXPECT_LE(*f.nearest_depth_m, depth(4.0) + 1e-9) << pitch_rad;
  }
}

// No contact, no depth: an object whose foot is hidden behind a nearer one, or below the
// image's bottom edge. Nor for one lower than the camera: a patch of ground that the flow does
// not tell from the rest (a camera at rest sees none) looks just like it.
TEST(FeatureExtractor, ACameraGetsNoDepthWhereTheGroundIsNotSeenBelowAnObject) {
  AnalyticScene scene = base_scene();
  SceneObject low_wall = panel(1, 3.0, 0.0, 2.0, {0.0, 0.0});
  low_wall.height_m = 1.2;
  const SceneObject behind = panel(2, 6.0, 0.0, 0.6, {0.0, 0.0});
  SceneObject lower_than_the_camera = panel(4, 4.0, 2.0, 1.0, {0.0, 0.0});
  lower_than_the_camera.height_m = 0.8;
  scene.objects = {low_wall, behind, lower_than_the_camera};
  const std::vector<ObjectFeatures> objects = seen_by_a_camera(scene);
  for (const std::int32_t id : {2, 4}) {
    ASSERT_GT(object_with_id(objects, id).pixel_count, 0) << id;
    EXPECT_FALSE(object_with_id(objects, id).min_x_depth_m.has_value()) << id;
  }
  EXPECT_NEAR(object_with_id(objects, 1).min_x_depth_m.value_or(0.0), 3.0, 0.15);
}

// A camera that knows its speed gets the ends' depths of what stands still, no higher than a
// knee, from its flow where no contact shows: the box 6 m ahead, whose foot a low wall hides, at
// its depth within 1%. Not for the panels beside it that rise higher (someone walking straight at
// the camera has the flow of a static panel at half the depth), nor for one that crosses behind
// the wall (an FOE of its own), nor for a patch of floor (its rows are not at one depth), nor
// without the speed.
TEST(FeatureExtractor, ACameraThatKnowsItsSpeedGetsTheDepthOfALowStaticObjectFromItsFlow) {
  for (const double pitch_rad : {0.0, 8.0 * kDeg}) {
    AnalyticScene scene = base_scene(pitch_rad);
    scene.agent_turn_rate = 0.0;
    SceneObject low_wall = panel(1, 3.0, 0.0, 4.0, {0.0, 0.0});
    low_wall.height_m = 0.6;
    SceneObject box = panel(2, 6.0, -2.0, 1.0, {0.0, 0.0});
    box.height_m = 0.4;
    SceneObject crossing = panel(3, 6.0, 1.0, 0.3, {0.0, -1.0});
    crossing.height_m = 0.4;
    const SceneObject tall = panel(4, 6.0, 2.0, 0.4, {0.0, 0.0});
    SceneObject waist_high = panel(5, 6.0, -1.0, 0.4, {0.0, 0.0});
    waist_high.height_m = 0.8;
    scene.objects = {low_wall, box, crossing, tall, waist_high};
    SceneRender render = render_scene(scene);
    // A patch of floor on the right, below the horizon, that the ground test would have missed.
    constexpr std::int32_t kFloorPatch = 6;
    const base::CameraIntrinsics& k = scene.intrinsics;
    const int horizon_row = static_cast<int>(k.cy_px - k.fy_px * std::tan(pitch_rad));
    for (int row = horizon_row + 15; row < horizon_row + 45; ++row) {
      for (int col = 180; col < 230; ++col) {
        const std::size_t i = static_cast<std::size_t>(row * k.width_px + col);
        if (render.ids[i] == kGroundId) {
          render.ids[i] = kFloorPatch;
        }
      }
    }
    const std::vector<ObjectFeatures> objects =
        seen_by_a_camera(scene, render, scene.agent_speed_mps * std::cos(pitch_rad));
    const ObjectFeatures& seen = object_with_id(objects, 2);
    ASSERT_TRUE(seen.fit.static_foe) << pitch_rad;
    ASSERT_TRUE(seen.min_x_depth_m && seen.max_x_depth_m && seen.nearest_depth_m) << pitch_rad;
    // Seen over the low wall: the box from 0.2 m to 0.4 m up, 0.8 m to 0.6 m below the camera,
    // whose pitched axis meets it further by that height times the pitch's sine.
    const double depth_m = 6.0 * std::cos(pitch_rad) + 0.7 * std::sin(pitch_rad);
    const double tolerance_m = 0.01 * depth_m;
    EXPECT_NEAR(*seen.min_x_depth_m, depth_m, tolerance_m) << pitch_rad;
    EXPECT_NEAR(*seen.max_x_depth_m, depth_m, tolerance_m) << pitch_rad;
    EXPECT_FALSE(seen.depth_m.has_value()) << "the mean depth is not measured";
    for (const std::int32_t id : {3, 4, 5, kFloorPatch}) {
      ASSERT_GT(object_with_id(objects, id).pixel_count, 0) << id;
      EXPECT_FALSE(object_with_id(objects, id).min_x_depth_m.has_value()) << id << " " << pitch_rad;
    }
    EXPECT_FALSE(object_with_id(objects, 3).fit.static_foe) << pitch_rad;
    EXPECT_TRUE(object_with_id(objects, 4).fit.static_foe) << pitch_rad;
    EXPECT_TRUE(object_with_id(objects, 5).fit.static_foe) << pitch_rad;
    EXPECT_TRUE(object_with_id(objects, kFloorPatch).fit.static_foe) << pitch_rad;
    EXPECT_FALSE(object_with_id(seen_by_a_camera(scene, render), 2).min_x_depth_m.has_value())
        << pitch_rad;
  }
}

// The flow test that takes the ground out (mark_ground) runs below the horizon only. Far enough
// away, an upright's flow below the horizon is within the test's floor of the floor's, and all of
// it goes with the ground: its region ends at the horizon, and the floor seen just below, hundreds
// of metres away here, is not where it stands. It gets no depth from the ground. A near one, whose
// region ends below the horizon where its flow leaves the test's tolerance, keeps its contact at
// the floor's depth there, beyond its foot (the test took its lowest rows) but within a metre.
TEST(FeatureExtractor, AnUprightWhoseRowsBelowTheHorizonAllPassedAsGroundGetsNoContact) {
  for (const double pitch_rad : {0.0, 8.0 * kDeg}) {
    AnalyticScene scene = base_scene(pitch_rad);
    scene.agent_turn_rate = 0.0;
    scene.objects = {panel(1, 12.0, 0.0, 2.0, {0.0, 0.0}), panel(2, 2.0, -0.6, 0.4, {0.0, 0.0})};
    const SceneRender render = render_scene(scene);
    FlowField field(scene.intrinsics);
    std::copy(render.flow.flow().begin(), render.flow.flow().end(), field.flow().begin());
    GroundRemovalOptions test;
    test.flow_floor = 0.05;
    std::vector<std::uint8_t> ground_mask(field.size(), 0);
    mark_ground(field, scene.mount, scene.agent_speed_mps, test, ground_mask);
    Segmentation segmentation;
    segment_by_ids(render.ids, field.width(), field.height(), ground_mask, segmentation);
    FeatureOptions options;
    options.use_depth = false;
    options.ground_mount = scene.mount;
    options.static_foe = scene.mount.forward_foe();
    FeatureExtractor extractor(options);
    const auto objects =
        extractor.extract(field, segmentation, scene.agent_speed_mps * std::cos(pitch_rad));
    const ObjectFeatures& far = object_with_id(objects, 1);
    ASSERT_GT(far.pixel_count, 0);
    EXPECT_FALSE(far.min_x_depth_m.has_value()) << pitch_rad;
    EXPECT_FALSE(far.nearest_depth_m.has_value()) << pitch_rad;
    const ObjectFeatures& near = object_with_id(objects, 2);
    ASSERT_TRUE(near.nearest_depth_m.has_value()) << pitch_rad;
    const double foot_m = 2.0 * std::cos(pitch_rad) + scene.mount.height_m * std::sin(pitch_rad);
    EXPECT_GE(*near.nearest_depth_m, foot_m) << pitch_rad;
    EXPECT_LT(*near.nearest_depth_m, foot_m + 1.0) << pitch_rad;
  }
}

TEST(FeatureExtractor, AnObjectStandingBelowTheImageIsNoFurtherThanTheGroundAtItsLowerEdge) {
  // 1 m ahead of a camera 1 m up whose view reaches 0.75 below the axis: the ground seen at the
  // image's lower edge is 1.33 m away, the object's feet are below the image.
  AnalyticScene scene = base_scene();
  scene.objects = {panel(3, 1.0, -0.5, 0.6, {0.0, 0.0})};
  const ObjectFeatures f = object_with_id(seen_by_a_camera(scene), 3);
  const base::CameraIntrinsics& k = scene.intrinsics;
  const double lower_edge_y = (k.height_px - 0.5 - k.cy_px) / k.fy_px;
  const double bound_m = scene.mount.height_m / lower_edge_y;
  ASSERT_NEAR(bound_m, 1.0 / 0.75, 1e-9);
  ASSERT_TRUE(f.min_x_depth_m && f.max_x_depth_m && f.nearest_depth_m);
  for (const double depth_m : {*f.min_x_depth_m, *f.max_x_depth_m, *f.nearest_depth_m}) {
    EXPECT_NEAR(depth_m, bound_m, 1e-6);
  }
}

TEST(FeatureExtractor, RegionsReachingTheImageEdgeAreMarkedCut) {
  const base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(8, 6, 90.0 * kDeg);
  FlowField field(k);
  Segmentation s = empty_segmentation(3);
  for (int col = 0; col < 8; ++col) {
    s.labels[static_cast<std::size_t>(8 + col)] = col < 3 ? 0 : (col < 6 ? 1 : 2);
    s.labels[static_cast<std::size_t>(40 + col)] = 1;  // region 1 spans the bottom row
  }
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  ASSERT_EQ(objects.size(), 3U);
  EXPECT_TRUE(objects[0].cut_left);
  EXPECT_FALSE(objects[0].cut_right);
  EXPECT_TRUE(objects[1].cut_left);
  EXPECT_TRUE(objects[1].cut_right);
  EXPECT_FALSE(objects[2].cut_left);
  EXPECT_TRUE(objects[2].cut_right);
  EXPECT_NEAR(objects[0].min_x, field.x(0), 1e-12);
  EXPECT_NEAR(objects[0].max_x, field.x(2), 1e-12);
  EXPECT_NEAR(objects[2].min_x, field.x(6), 1e-12);
  EXPECT_NEAR(objects[2].width, field.x(7) - field.x(6) + 1.0 / k.fx_px, 1e-12);
}

TEST(FeatureExtractor, AFourPixelRegionIsFittedByDefault) {
  // A distant object at the edge of a coarse image covers a few pixels only.
  const base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(8, 6, 150.0 * kDeg);
  FlowField field(k);
  Segmentation s = empty_segmentation(2);
  const Eigen::Vector2d foe(-2.0, 0.1);
  const double ttc = 2.5;
  auto flow = field.flow();
  constexpr int kPixels[][3] = {{0, 2, 0}, {1, 2, 0}, {0, 3, 0}, {1, 3, 0},  // column, row, label
                                {6, 2, 1}, {7, 2, 1}, {7, 3, 1}};
  for (const auto& [col, row, label] : kPixels) {
    const std::size_t i = field.index(col, row);
    s.labels[i] = label;
    flow[i] = ((Eigen::Vector2d(field.x(col), field.y(row)) - foe) / ttc).cast<float>();
  }
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, s);
  ASSERT_EQ(objects.size(), 2U);
  ASSERT_EQ(objects[0].status, MotionStatus::approaching);
  EXPECT_LT((objects[0].foe - foe).norm(), 1e-4);
  EXPECT_NEAR(objects[0].ttc_s, ttc, 1e-4);
  EXPECT_EQ(objects[1].status, MotionStatus::no_flow);  // three pixels: below the floor
}

TEST(FeatureExtractor, DarkRegionsGetGeometryButNoFit) {
  const Case c = approaching_cases().front();
  AnalyticScene scene = base_scene();
  scene.objects = {c.object};
  const SceneRender render = render_scene(scene);
  Segmentation s;
  segment_by_ids(render.ids, render.flow.width(), render.flow.height(), {}, s);
  s.kinds[0] = RegionKind::dark;
  FeatureExtractor extractor;
  const auto objects = extractor.extract(render.flow, s);
  ASSERT_EQ(objects.size(), 1U);
  EXPECT_EQ(objects[0].kind, RegionKind::dark);
  EXPECT_EQ(objects[0].status, MotionStatus::no_flow);
  EXPECT_GT(objects[0].pixel_count, 100);
  EXPECT_NEAR(objects[0].centre.x(), 0.8 / 6.0, 0.01);  // y = −0.8 m is to the right
}

TEST(FeatureExtractor, MismatchedSegmentationIsRejected) {
  const base::CameraIntrinsics k = base::CameraIntrinsics::from_horizontal_fov(8, 6, 90.0 * kDeg);
  FlowField field(k);
  Segmentation s;
  s.width = 4;
  s.height = 6;
  s.labels.assign(24, Segmentation::kNoRegion);
  FeatureExtractor extractor;
  EXPECT_THROW(extractor.extract(field, s), std::invalid_argument);
}

TEST(FeatureExtractor, RejectsOptionsThatCannotFit) {
  FeatureOptions options;
  options.min_pixels = 1;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  options = {};
  options.flow_noise_correlation_px = 0.5;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  options = {};
  options.static_foe_chi2 = 0.0;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  options = {};
  options.static_surface_rss_ratio = -1.0;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
}

TEST(Segmentation, IdsBecomeRegionsAndExclusionsAreDropped) {
  const std::vector<std::int32_t> ids = {-1, 4, 4, 9, -2, 9};
  const std::vector<std::uint8_t> excluded = {0, 0, 1, 0, 0, 0};
  Segmentation s;
  segment_by_ids(ids, 3, 2, excluded, s);
  ASSERT_EQ(s.region_count(), 2);
  EXPECT_EQ(s.source_ids[0], 4);
  EXPECT_EQ(s.source_ids[1], 9);
  EXPECT_EQ(s.labels, (std::vector<std::int32_t>{-1, 0, -1, 1, -1, 1}));
  EXPECT_THROW(segment_by_ids(ids, 2, 2, {}, s), std::invalid_argument);
  EXPECT_THROW(segment_by_ids(ids, 3, 2, std::span<const std::uint8_t>(excluded).first(2), s),
               std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::servo
