// The full per-agent step (render + flow + segment + features + control) on the `room`
// scenario. AgentStep: synthetic flow and semantic segmentation, beside the per-agent update
// times of CGF Fig. 14 (UE4, Quadro M2000M); targets on a CPU-only machine (Mesa llvmpipe):
// ≤ 5 ms at 256², ≤ 60 ms at 1024². AgentStepNumerical/<flow>/<resolution>: flow computed from
// the images and objects found in it (flow_graph_fast), as a robot does; MIG 2019's FlowNet2
// step took 100 ms at 256² and 200 ms at 512² on a GPU; targets here ≤ 10 ms and ≤ 25 ms.
//   build/bench/sim_bench
#include <map>

#include <benchmark/benchmark.h>

#include "flowsteer/launch/agent_pipeline.hpp"
#include "flowsteer/launch/scenario_file.hpp"

namespace {

using namespace flowsteer;

const std::map<int, double> kPaperSeconds = {
    {64, 0.003}, {128, 0.006}, {256, 0.027}, {512, 0.111}, {1024, 0.48}};

void run_steps(benchmark::State& state, int resolution,
               const sim_camera::PerceptionSpec& perception) {
  sim_camera::WorldSpec spec = launch::builtin_scenario("room");
  for (auto& a : spec.agents) {
    a.camera.width_px = a.camera.height_px = resolution;
    a.perception = perception;
  }
  const auto renderer = sim_camera::Renderer::create();
  sim_camera::World world(spec);
  launch::AgentPipeline pipeline(world, *renderer, 1);
  const std::vector<std::pair<double, double>> coast(spec.agents.size(), {0.0, 0.0});
  launch::StageTimes times;
  launch::StageTimes sum;
  for (auto _ : state) {
    // A new world state each step, as in a run: the sun's shadow map is drawn again.
    world.step(coast);
    benchmark::DoNotOptimize(pipeline.step(times).command);
    sum += times;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["render_ms"] = sum.render / n;
  state.counters["flow_ms"] = sum.flow / n;
  state.counters["segment_ms"] = sum.segment / n;
  state.counters["features_ms"] = sum.features / n;
  state.counters["control_ms"] = sum.control / n;
}

void AgentStep(benchmark::State& state) {
  const int resolution = static_cast<int>(state.range(0));
  run_steps(state, resolution, {});
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

void AgentStepNumerical(benchmark::State& state) {
  const auto flow = static_cast<servo::FlowMethod>(state.range(0));
  run_steps(state, static_cast<int>(state.range(1)),
            {flow, servo::SegmentationMethod::flow_graph_fast});
  state.SetLabel(std::string(servo::to_string(flow)));
}
BENCHMARK(AgentStepNumerical)
    ->ArgsProduct({{static_cast<int>(servo::FlowMethod::dis_ultrafast),
                    static_cast<int>(servo::FlowMethod::dis_fast),
                    static_cast<int>(servo::FlowMethod::dis_medium)},
                   {256, 512}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
