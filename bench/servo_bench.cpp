// Features + control for a 256×256 flow field with 5 objects (target: ≤ 0.5 ms on one core),
// and the stages around them:
//   build/bench/servo_bench
#include <numbers>

#include <benchmark/benchmark.h>

#include "flowsteer/servo/servo.hpp"
#include "flowsteer/servo/steering.hpp"
#include "radial_fit.hpp"

namespace {

using namespace flowsteer::servo;
namespace servo = flowsteer::servo;
namespace base = flowsteer::base;

AnalyticScene five_objects(int resolution) {
  AnalyticScene scene;
  scene.intrinsics = base::CameraIntrinsics::from_horizontal_fov(resolution, resolution,
                                                                 90.0 * std::numbers::pi / 180);
  scene.mount = {1.6, 0.0};
  scene.agent_speed_mps = 1.0;
  const Eigen::Vector2d positions[] = {{5, -0.5}, {7, 1.5}, {9, -2.5}, {12, 4.5}, {6, 3}};
  const Eigen::Vector2d velocities[] = {{0, 0}, {-1, 0}, {0, 0.5}, {0, -1.5}, {-0.5, -0.5}};
  for (int i = 0; i < 5; ++i) {
    SceneObject o;
    o.id = i + 1;
    o.shape = i % 2 == 0 ? SceneObject::Shape::cylinder : SceneObject::Shape::box;
    o.radius_m = 0.4;
    o.position_m = positions[i];
    o.velocity_mps = velocities[i];
    scene.objects.push_back(o);
  }
  return scene;
}

struct Prepared {
  SceneRender render;
  std::vector<std::uint8_t> ground;
};

Prepared prepare(int resolution) {
  const AnalyticScene scene = five_objects(resolution);
  Prepared p{render_scene(scene), {}};
  p.ground.assign(p.render.flow.size(), 0);
  mark_ground(p.render.flow, scene.mount, scene.agent_speed_mps, {}, p.ground);
  return p;
}

// The rendered flow as a FlowField, with the simulator's depth or without it (as from a camera).
servo::FlowField field_of(const Prepared& p, bool with_depth) {
  servo::FlowField field(p.render.flow.intrinsics(), with_depth);
  std::copy(p.render.flow.flow().begin(), p.render.flow.flow().end(), field.flow().begin());
  if (with_depth) {
    std::copy(p.render.flow.depth().begin(), p.render.flow.depth().end(), field.depth().begin());
  }
  return field;
}

// Features (centre, width, robust FOE/TTC fit) and the control law, on a segmentation made once.
// Arg 1: the field keeps the simulator's depth (the fit is exact); 0: flow alone, as from a real
// camera, where curved surfaces leave residuals and the robust rounds run.
void FeaturesAndControl(benchmark::State& state) {
  const Prepared p = prepare(256);
  const servo::FlowField field = field_of(p, state.range(0) == 1);
  Segmentation segmentation;
  segment_by_ids(p.render.ids, field.width(), field.height(), p.ground, segmentation);
  FeatureExtractor extractor;
  Controller controller(goal_reaching({}), 1.0, {1.0, 1.0});
  ControlOutput out;
  int iterations = 0;
  for (auto _ : state) {
    const auto objects = extractor.extract(field, segmentation);
    controller.step({objects, 0.1, 10.0, {}}, {1.0}, out);
    benchmark::DoNotOptimize(out.command);
    iterations = 0;
    for (const auto& o : objects) {
      iterations += o.fit.iterations;
    }
  }
  state.counters["objects"] = static_cast<double>(segmentation.region_count());
  state.counters["solver_iterations"] = iterations;
}
BENCHMARK(FeaturesAndControl)->ArgName("with_depth")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The controller alone, on the five objects' features at 256² (with depth): one step of each law
// as make_controller builds it. Law 0: cgf2019 (the papers'); 1: flowsteer without its turn
// check; 2: flowsteer as it steers, whose turn check costs the navigation function at four
// predicted percepts.
Controller control_step_controller(int law) {
  ControllerConfig config;
  if (law == 0) {
    config.law = NavigationLaw::cgf2019;
  } else if (law == 1) {
    config.without = LawMechanism::turn_check;
  }
  return make_controller(config, 0.5, 1.0);
}

void ControlStep(benchmark::State& state) {
  const Prepared p = prepare(256);
  const servo::FlowField field = field_of(p, true);
  Segmentation segmentation;
  segment_by_ids(p.render.ids, field.width(), field.height(), p.ground, segmentation);
  FeatureExtractor extractor;
  const auto objects = extractor.extract(field, segmentation);
  Controller controller = control_step_controller(static_cast<int>(state.range(0)));
  ControlOutput out;
  for (auto _ : state) {
    controller.step({objects, 0.1, 10.0, {}}, {1.0, 0.05}, out);
    benchmark::DoNotOptimize(out.command);
  }
  state.counters["objects"] = static_cast<double>(objects.size());
}
BENCHMARK(ControlStep)->ArgName("law")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// The stage before it: semantic segmentation from the object ids, ground excluded.
void SegmentByIds(benchmark::State& state) {
  const Prepared p = prepare(static_cast<int>(state.range(0)));
  Segmentation segmentation;
  for (auto _ : state) {
    segment_by_ids(p.render.ids, p.render.flow.width(), p.render.flow.height(), p.ground,
                   segmentation);
    benchmark::DoNotOptimize(segmentation.labels.data());
  }
}
BENCHMARK(SegmentByIds)->Arg(256)->Unit(benchmark::kMillisecond);

// The stages before it: derotation and ground removal by the flow test.
void DerotateAndGround(benchmark::State& state) {
  Prepared p = prepare(static_cast<int>(state.range(0)));
  FlowField field = p.render.flow;
  for (auto _ : state) {
    derotate(field, camera_angular_velocity(0.1, 0.0));
    std::fill(p.ground.begin(), p.ground.end(), 0);
    benchmark::DoNotOptimize(mark_ground(field, {1.6, 0.0}, 1.0, {}, p.ground));
  }
}
BENCHMARK(DerotateAndGround)->Arg(256)->Unit(benchmark::kMillisecond);

// One robust radial fit of 256 samples, with the workspace FeatureExtractor keeps (argument 1)
// or a fresh one per fit (0).
void RadialFit256(benchmark::State& state) {
  std::vector<FlowSample> samples;
  for (int i = 0; i < 256; ++i) {
    const Eigen::Vector2d x(0.1 + 0.002 * (i % 16), -0.05 + 0.004 * (i / 16));
    Eigen::Vector2d u = (x - Eigen::Vector2d(0.02, 0.0)) / 3.0;
    if (i % 5 == 0) {
      u = Eigen::Vector2d(-u.y(), u.x());  // outliers
    }
    u *= 1.0 + 0.05 * ((i * 37) % 11 - 5) / 5.0;
    samples.push_back({x, u});
  }
  RadialFitWorkspace workspace;
  for (auto _ : state) {
    if (state.range(0) != 0) {
      benchmark::DoNotOptimize(fit_radial_flow(samples, {}, workspace));
    } else {
      benchmark::DoNotOptimize(fit_radial_flow(samples));
    }
  }
}
BENCHMARK(RadialFit256)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
