#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/renderer.hpp"

namespace flowsteer::cli {

namespace {

struct SimCommand {
  ScenarioChoice scenario;
  std::string out_dir = "flowsteer_out";
  std::optional<int> resolution;
  std::optional<double> camera_noise_levels;
  std::optional<int> steps;
  bool video = false;
  int threads = 0;
  std::string flow;
  std::string segmentation;
  std::string depth;
  bool obstacle_memory = false;
  RecordingChoice recording;
};

// Seconds and metres with two decimals, the unit after the number.
std::string measure(double value, const char* unit) {
  char text[48];
  std::snprintf(text, sizeof text, "%.2f %s", value, unit);
  return text;
}

void print_summary(const sim::SimResult& result, std::ostream& out) {
  out << "scenario " << result.scenario << ": " << result.steps << " steps, "
      << measure(result.duration_s, "s") << " simulated, " << result.collisions.size()
      << " collisions\n";
  for (const sim::AgentResult& a : result.agents) {
    out << "  " << a.name << ": "
        << (a.reached_goal ? "reached its goal in " + measure(a.time_to_goal_s, "s")
            : a.final_distance_to_leader_m >= 0.0
                ? "ended " + measure(a.final_distance_to_leader_m, "m") + " from its leader"
                : std::string("did not reach its goal"))
        << ", path " << measure(a.path_length_m, "m") << ", min clearance "
        << measure(a.min_clearance_m, "m") << ", " << a.collisions << " collisions\n";
  }
  for (const sim_camera::Collision& c : result.collisions) {
    out << "  collision at t = " << measure(c.time_s, "s") << ": " << result.agents[c.agent].name
        << " with " << c.with << " at (" << measure(c.position_m.x(), "m") << ", "
        << measure(c.position_m.y(), "m") << ")\n";
  }
  const pipeline::StageTimes& t = result.per_agent_step_ms;
  out << "per agent step: " << measure(t.total, "ms") << " (render " << measure(t.render, "ms")
      << ", flow " << measure(t.flow, "ms") << ", segment " << measure(t.segment, "ms")
      << ", features " << measure(t.features, "ms") << ", control " << measure(t.control, "ms")
      << "); " << measure(result.world_steps_per_s, "world steps/s") << " on " << result.threads
      << (result.threads == 1 ? " thread\n" : " threads\n");
}

int run_sim(const SimCommand& command) {
  const sim_camera::WorldSpec world = load_world("sim", command.scenario);
  sim::SimOptions options;
  options.out_dir = command.out_dir;
  options.resolution = command.resolution;
  if (command.camera_noise_levels) {
    options.camera_noise_levels = *command.camera_noise_levels;
  }
  options.steps = command.steps;
  if (!command.flow.empty()) {
    options.flow = flow_method_option("--flow", command.flow, "method", servo::flow_method_names());
  }
  if (!command.segmentation.empty()) {
    options.segmentation = segmentation_method_option("--segmentation", command.segmentation);
  }
  if (!command.depth.empty()) {
    options.depth = depth_source_option("--depth", command.depth);
  }
  if (command.obstacle_memory) {
    options.obstacle_memory = true;
  }
  options.video = command.video;
  options.recording = recording_options(command.recording);
  options.threads = command.threads;
  if (command.threads != 1 && world.agents.size() > 1) {
    sim_camera::rasterize_on_calling_threads();
  }
  options.progress_bar = isatty(STDERR_FILENO) != 0;
  std::cerr << "flowsteer sim: " << world.name << " (" << world.agents.size() << " agents) -> "
            << command.out_dir << "\n";
  print_summary(sim::run_simulation(world, options, std::cerr), std::cout);
  return 0;
}

}  // namespace

Subcommand add_sim(CLI::App& app) {
  auto command = std::make_shared<SimCommand>();
  CLI::App* sim = app.add_subcommand(
      "sim", "Run agents that see a rendered world and steer by its optical flow");
  add_scenario_options(*sim, command->scenario);
  sim->add_option("--out", command->out_dir, "folder for the outputs")->capture_default_str();
  sim->add_option("--resolution", command->resolution, "every agent's camera: N x N pixels")
      ->check(within(base::bounds::kImageSide_px));
  sim->add_option("--camera-noise", command->camera_noise_levels,
                  "every agent's camera noise: σ of the Gaussian noise on each channel of the "
                  "image, grey levels from 0 to 50 (scenario key camera: {noise_sigma})")
      ->check(within(base::bounds::kCameraNoise_levels));
  sim->add_option("--steps", command->steps, "stop after N control steps")
      ->check(within(base::bounds::kRunSteps));
  sim->add_flag("--video", command->video, "an MP4 per agent: its view, the flow and the features");
  sim->add_option(
         "--threads", command->threads,
         "threads the agents are stepped on, 0: one per core (results do not depend on it)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sim->add_option("--flow", command->flow, "every agent's flow: " + servo::flow_method_names());
  sim->add_option("--segmentation", command->segmentation,
                  "every agent's segmentation: " + servo::segmentation_method_names());
  sim->add_option("--depth", command->depth,
                  "where every agent's features take depths from with synthetic flow: " +
                      servo::depth_source_names() +
                      " (ground: only where objects stand on it, as a camera)");
  sim->add_flag("--obstacle-memory", command->obstacle_memory, kObstacleMemoryHelp);
  add_recording_options(*sim, command->recording);
  return {sim, [command] { return run_sim(*command); }};
}

}  // namespace flowsteer::cli
