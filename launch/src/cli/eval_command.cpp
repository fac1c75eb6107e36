#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/eval/flow_evaluation.hpp"
#include "flowsteer/eval/robustness.hpp"

namespace flowsteer::cli {

namespace {

struct EvalFlowCommand {
  std::string scenario = "flow_targets";
  std::vector<int> resolutions{256};
  int frames = 40;
  std::vector<std::string> methods;
  std::string segmentation = "semantic";
  bool obstacle_memory = false;
  std::string out_dir = "flowsteer_eval";
};

struct EvalRobustnessCommand {
  ScenarioChoice scenario;
  std::vector<int> resolutions;
  std::vector<std::string> flows;
  std::vector<std::string> segmentations;
  std::optional<int> steps;
  int jobs = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  std::string out_dir = "flowsteer_robustness";
};

// A built-in scenario's name, else a scenario file; a name that is neither gets the built-in
// scenarios' error, which lists them.
sim_camera::WorldSpec scenario_named(const std::string& name_or_file) {
  if (!config::is_builtin_scenario(name_or_file) && std::filesystem::exists(name_or_file)) {
    return config::load_scenario(name_or_file);
  }
  return config::builtin_scenario(name_or_file);
}

int run_eval_flow(const EvalFlowCommand& command) {
  eval::FlowEvalOptions options;
  options.resolutions = command.resolutions;
  options.frames = command.frames;
  for (const std::string& name : command.methods) {
    options.methods.push_back(
        flow_method_option("--method", name, "estimator",
                           servo::flow_method_names() + "; synthetic is the truth", true));
  }
  options.segmentation = segmentation_method_option("--segmentation", command.segmentation);
  if (command.obstacle_memory && options.segmentation == servo::SegmentationMethod::semantic) {
    throw CLI::ValidationError("--obstacle-memory",
                               "the memory keeps the ground contacts of flow segmentation's "
                               "regions: give a --segmentation other than semantic");
  }
  options.obstacle_memory = command.obstacle_memory;
  const auto rows = eval::evaluate_flow(scenario_named(command.scenario), options, std::cerr);
  eval::print_flow_table(rows, std::cout);
  eval::write_flow_evaluation(rows, command.out_dir);
  return 0;
}

int run_eval_robustness(const EvalRobustnessCommand& command) {
  const sim_camera::WorldSpec world = load_world("eval robustness", command.scenario);
  eval::RobustnessOptions options;
  options.resolutions = command.resolutions;
  for (const std::string& name : command.flows) {
    options.flows.push_back(
        flow_method_option("--flow", name, "method", servo::flow_method_names()));
  }
  for (const std::string& name : command.segmentations) {
    options.segmentations.push_back(segmentation_method_option("--segmentation", name));
  }
  options.steps = command.steps;
  options.jobs = command.jobs;
  options.out_dir = command.out_dir;
  eval::print_robustness_table(eval::evaluate_robustness(world, options, std::cerr), std::cout);
  return 0;
}

Subcommand add_eval_flow(CLI::App& eval) {
  auto command = std::make_shared<EvalFlowCommand>();
  CLI::App* flow = eval.add_subcommand(
      "flow", "Each optical-flow estimator against the renderer's flow and the exact features");
  flow->add_option("--scenario", command->scenario, "a built-in scenario or a scenario file")
      ->capture_default_str();
  flow->add_option("--resolution", command->resolutions, "N x N pixels; repeat for several")
      ->check(CLI::Range(16, 2048))
      ->capture_default_str();
  flow->add_option("--frames", command->frames, "frames rendered per resolution")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  flow->add_option(
      "--method", command->methods,
      "an estimator (default: all); repeat for several: " + servo::flow_method_names());
  flow->add_option("--segmentation", command->segmentation,
                   "how objects are found: " + servo::segmentation_method_names() +
                       " (semantic measures the flow alone)")
      ->capture_default_str();
  flow->add_flag("--obstacle-memory", command->obstacle_memory,
                 "keep each estimator's obstacle memory and score what it recalls against the "
                 "world (flow segmentation only)");
  flow->add_option("--out", command->out_dir, "folder for flow_eval.csv and flow_eval.txt")
      ->capture_default_str();
  return {flow, [command] { return run_eval_flow(*command); }};
}

Subcommand add_eval_robustness(CLI::App& eval) {
  auto command = std::make_shared<EvalRobustnessCommand>();
  CLI::App* robustness = eval.add_subcommand(
      "robustness",
      "Run a scenario at several camera resolutions, with each flow and segmentation given, and "
      "count the runs with no collision and every goal reached");
  add_scenario_options(*robustness, command->scenario);
  robustness
      ->add_option("--resolution", command->resolutions,
                   "N x N pixels; repeat for several (default: the scenario's own and 8, "
                   "16, 24, 32 pixels either side)")
      ->check(within(base::bounds::kImageSide_px));
  robustness->add_option("--flow", command->flows,
                         "every agent's flow (default: the scenario's); repeat for several: " +
                             servo::flow_method_names());
  robustness->add_option("--segmentation", command->segmentations,
                         "every agent's segmentation (default: the scenario's); repeat for "
                         "several: " +
                             servo::segmentation_method_names());
  robustness->add_option("--steps", command->steps, "stop each run after N control steps")
      ->check(within(base::bounds::kRunSteps));
  robustness->add_option("--jobs,-j", command->jobs, "runs at once, each in its own process")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  robustness->add_option("--out", command->out_dir, "folder for robustness.csv and robustness.txt")
      ->capture_default_str();
  one_value_per_use(*robustness);
  return {robustness, [command] { return run_eval_robustness(*command); }};
}

}  // namespace

std::vector<Subcommand> add_eval(CLI::App& app) {
  CLI::App* eval = app.add_subcommand(
      "eval", "Measure the pipeline: flow against the truth, robustness sweeps, benchmark suites");
  eval->require_subcommand(1);
  return {add_eval_flow(*eval), add_eval_robustness(*eval), add_eval_suite(*eval),
          add_eval_merge(*eval)};
}

}  // namespace flowsteer::cli
