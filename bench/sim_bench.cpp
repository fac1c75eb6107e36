// The per-agent step on the `room` scenario, as agent b sees it coasting straight from its start
// towards the obstacles ahead (kSteps steps of 0.05 s); every pass of the benchmark loop times
// the same views, however many iterations fit in its time.
//   AgentStep/<resolution>: the full step (render + flow + segment + features + control) with
//     synthetic flow and semantic segmentation, beside the per-agent update times of CGF
//     Fig. 14 (UE4, Quadro M2000M); targets on a CPU-only machine (Mesa llvmpipe): ≤ 5 ms at
//     256², ≤ 60 ms at 1024².
//   AgentStepNumerical/<flow>/<width>/<height>: the full step with flow computed from the
//     images and objects found in it (flow_graph_fast). MIG 2019's FlowNet2 step took 100 ms
//     at 256² and 200 ms at 512² on a GPU; targets here ≤ 10 ms and ≤ 25 ms.
//   RobotStepNumerical/<flow>/<width>/<height>: the same step without the renderer, on the same
//     views rendered beforehand: what a robot runs per frame (RobotBrain: flow,
//     segmentation, features, control). Perception's budget on one core (perception_ms: flow,
//     with its texture test and noise measure; segment, with the ground test and the untextured
//     fill; features): 4 ms at 128², 10 ms at 320×240. OpenCV runs on one thread here: DIS
//     otherwise spreads its work over every core.
// Counters: each stage's mean milliseconds.
//   build/bench/sim_bench --benchmark_filter=Numerical
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/robot/robot_brain.hpp"
#include "flowsteer/sim/simulated_agent.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"

namespace {

using namespace flowsteer;

const std::map<int, double> kPaperSeconds = {
    {64, 0.003}, {128, 0.006}, {256, 0.027}, {512, 0.111}, {1024, 0.48}};

// Agent b (the middle one) passes the box and the cylinders within these 6 s, before it would
// walk into the box: coasting, it does not steer.
constexpr std::size_t kAgent = 1;
constexpr int kSteps = 120;

sim_camera::WorldSpec room(int width_px, int height_px, const servo::PerceptionConfig& perception) {
  sim_camera::WorldSpec spec = config::builtin_scenario("room");
  for (auto& a : spec.agents) {
    a.camera.width_px = width_px;
    a.camera.height_px = height_px;
    a.perception = perception;
  }
  return spec;
}

// Every agent keeps its speed and heading.
void coast(sim_camera::World& world) {
  world.step(std::vector<base::Command>(world.agents().size()));
}

void report(benchmark::State& state, const pipeline::StageTimes& sum) {
  const double n = static_cast<double>(state.iterations());
  state.counters["render_ms"] = sum.render / n;
  state.counters["flow_ms"] = sum.flow / n;
  state.counters["segment_ms"] = sum.segment / n;
  state.counters["features_ms"] = sum.features / n;
  state.counters["control_ms"] = sum.control / n;
  state.counters["perception_ms"] = (sum.flow + sum.segment + sum.features) / n;
}

void run_steps(benchmark::State& state, int width_px, int height_px,
               const servo::PerceptionConfig& perception) {
  const sim_camera::WorldSpec spec = room(width_px, height_px, perception);
  const auto renderer = sim_camera::Renderer::create();
  std::optional<sim_camera::World> world;
  std::optional<sim::SimulatedAgent> pipeline;
  pipeline::StageTimes times;
  pipeline::StageTimes sum;
  int step = kSteps;
  for (auto _ : state) {
    if (step == kSteps) {
      // A fresh room; its first frame (no flow yet, the renderer's first draw) is not timed.
      state.PauseTiming();
      pipeline.reset();
      world.emplace(spec);
      pipeline.emplace(*world, kAgent);
      pipeline->step(*renderer, times);
      step = 0;
      state.ResumeTiming();
    }
    // A new world state each step, as in a run: the sun's shadow map is drawn again.
    coast(*world);
    benchmark::DoNotOptimize(pipeline->step(*renderer, times).command);
    sum += times;
    ++step;
  }
  report(state, sum);
}

void AgentStep(benchmark::State& state) {
  const int resolution = static_cast<int>(state.range(0));
  run_steps(state, resolution, resolution, {});
  state.counters["paper_ms"] = 1000.0 * kPaperSeconds.at(resolution);
}
BENCHMARK(AgentStep)
    ->Arg(64)
    ->Arg(128)
    ->Arg(256)
    ->Arg(512)
    ->Arg(1024)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

servo::PerceptionConfig numerical(const benchmark::State& state) {
  return {static_cast<servo::FlowMethod>(state.range(0)),
          servo::SegmentationMethod::flow_graph_fast};
}

void AgentStepNumerical(benchmark::State& state) {
  const servo::PerceptionConfig perception = numerical(state);
  run_steps(state, static_cast<int>(state.range(1)), static_cast<int>(state.range(2)), perception);
  state.SetLabel(std::string(servo::to_string(perception.flow)));
}

// What the robot's loop hands its brain for one frame.
struct RecordedStep {
  camera_io::Frame frame;  // the image alone: a camera has no simulator channels
  drivers::BodyVelocity measured;
  double goal_bearing_rad = 0.0;
  double goal_distance_m = 0.0;
};

struct Recording {
  base::CameraIntrinsics intrinsics;
  std::vector<RecordedStep> steps;
};

// The views run_steps times, with what the agent's base and goal tracker would report.
Recording record_steps(const sim_camera::WorldSpec& spec) {
  const auto renderer = sim_camera::Renderer::create();
  sim_camera::World world(spec);
  sim_camera::SimCamera camera(world, *renderer, kAgent);
  Recording recording{camera.intrinsics(), std::vector<RecordedStep>(kSteps + 1)};
  camera_io::Frame frame;
  for (RecordedStep& s : recording.steps) {
    camera.read(frame, 0.0);
    s.frame.image = frame.image.clone();
    s.frame.timestamp_s = frame.timestamp_s;
    s.frame.sequence = frame.sequence;
    const sim_camera::AgentState& agent = world.agents()[kAgent];
    s.measured = {agent.speed_mps, agent.turn_rate};
    const Eigen::Vector2d to_goal = spec.agents[kAgent].goals[agent.next_goal] - agent.position_m;
    s.goal_bearing_rad = pipeline::goal_bearing_rad(to_goal.x(), to_goal.y(), agent.yaw_rad);
    s.goal_distance_m = to_goal.norm();
    coast(world);
  }
  return recording;
}

// OpenCV's thread count for as long as it lives, then the one before.
class OpenCvThreads {
 public:
  explicit OpenCvThreads(int threads) : before_(cv::getNumThreads()) { cv::setNumThreads(threads); }
  ~OpenCvThreads() { cv::setNumThreads(before_); }
  OpenCvThreads(const OpenCvThreads&) = delete;
  OpenCvThreads& operator=(const OpenCvThreads&) = delete;

 private:
  int before_;
};

void RobotStepNumerical(benchmark::State& state) {
  const OpenCvThreads one_core(1);
  const servo::PerceptionConfig perception = numerical(state);
  const sim_camera::WorldSpec spec =
      room(static_cast<int>(state.range(1)), static_cast<int>(state.range(2)), perception);
  const Recording recording = record_steps(spec);
  const std::vector<RecordedStep>& steps = recording.steps;
  const sim_camera::AgentSpec& agent = spec.agents[kAgent];
  config::PerceptionSection perception_section;
  perception_section.flow = perception.flow;
  perception_section.segmentation = perception.segmentation;
  perception_section.mount = base::CameraMount{agent.camera.height_m, agent.camera.pitch_rad};
  config::ControllerSection controller;
  controller.spec = agent.controller;
  controller.preferred_speed_mps = agent.preferred_speed_mps;
  controller.robot_width_m = 2.0 * agent.radius_m;
  std::ostringstream log;
  std::unique_ptr<robot::RobotBrain> brain;
  const auto step = [&](const RecordedStep& s) {
    return brain->step({s.frame, s.measured, s.goal_bearing_rad, s.goal_distance_m});
  };
  pipeline::StageTimes sum;
  std::size_t next = steps.size();
  for (auto _ : state) {
    if (next == steps.size()) {
      // A fresh brain; its first frame (no flow yet) is not timed.
      state.PauseTiming();
      brain = std::make_unique<robot::RobotBrain>(
          recording.intrinsics, robot::robot_brain_config(perception_section, controller), log);
      step(steps.front());
      next = 1;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(step(steps[next++]));
    sum += brain->brain().times();
  }
  report(state, sum);
  state.SetLabel(std::string(servo::to_string(perception.flow)));
}

void numerical_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"flow", "width", "height"});
  for (const servo::FlowMethod flow :
       {servo::FlowMethod::dis_ultrafast, servo::FlowMethod::dis_fast,
        servo::FlowMethod::dis_medium}) {
    for (const auto& [width_px, height_px] :
         {std::pair{128, 128}, std::pair{320, 240}, std::pair{256, 256}, std::pair{512, 512}}) {
      b->Args({static_cast<int>(flow), width_px, height_px});
    }
  }
  b->Unit(benchmark::kMillisecond)->MinTime(2.0);
}
BENCHMARK(AgentStepNumerical)->Apply(numerical_args);
BENCHMARK(RobotStepNumerical)->Apply(numerical_args);

}  // namespace

BENCHMARK_MAIN();
