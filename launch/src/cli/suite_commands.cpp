#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/config/case_files.hpp"
#include "flowsteer/eval/suite.hpp"

namespace flowsteer::cli {

namespace {

struct EvalSuiteCommand {
  std::vector<std::string> paths;
  std::vector<std::string> flows;
  std::vector<std::string> segmentations;
  std::vector<std::string> depths;
  std::vector<std::string> controllers;
  std::vector<std::string> laws;
  std::vector<std::string> switched_off;
  std::vector<int> resolutions;
  std::vector<double> camera_noise_levels;
  int jobs = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  std::string shard = "0/1";
  std::string keep_runs = "failed";
  std::uint32_t seed = 1;
  std::optional<int> steps;
  bool obstacle_memory = false;
  std::string arrival;
  std::string out_dir = "flowsteer_suite";
};

struct EvalMergeCommand {
  std::vector<std::string> shard_dirs;
  std::string out_dir = "flowsteer_suite";
};

// Every case the paths name (the project's suite when none), read and placed with the seed.
std::vector<eval::SuiteCase> load_cases(const std::vector<std::string>& paths, std::uint32_t seed) {
  const std::vector<config::CaseFile> files =
      paths.empty() ? config::builtin_suite()
                    : config::read_case_files({paths.begin(), paths.end()});
  std::vector<eval::SuiteCase> cases;
  for (const config::CaseFile& file : files) {
    config::LoadedCase loaded = config::parse_case(file, seed);
    for (const std::string& warning : loaded.warnings) {
      std::cerr << "flowsteer eval suite: warning: " << warning << "\n";
    }
    cases.push_back({file.name, file.path, file.text, std::move(loaded.world)});
  }
  return cases;
}

eval::SuiteOptions suite_options(const EvalSuiteCommand& command) {
  eval::SuiteOptions options;
  for (const std::string& name : command.flows) {
    options.flows.push_back(
        flow_method_option("--flow", name, "method", servo::flow_method_names()));
  }
  for (const std::string& name : command.segmentations) {
    options.segmentations.push_back(segmentation_method_option("--segmentation", name));
  }
  for (const std::string& name : command.depths) {
    options.depths.push_back(depth_source_option("--depth", name));
  }
  for (const std::string& name : command.controllers) {
    const auto model = servo::parse_steering_model(name);
    if (!model) {
      throw CLI::ValidationError("--controller", "unknown steering model '" + name + "' (known: " +
                                                     servo::steering_model_names() + ")");
    }
    options.controllers.push_back(*model);
  }
  for (const std::string& name : command.laws) {
    options.laws.push_back(navigation_law_option("--law", name));
  }
  for (const std::string& name : command.switched_off) {
    options.switched_off.push_back(law_mechanism_option("--without", name));
  }
  const auto keep = eval::parse_keep_runs(command.keep_runs);
  if (!keep) {
    throw CLI::ValidationError("--keep-runs",
                               "expected failed, all or none; got '" + command.keep_runs + "'");
  }
  options.keep_runs = *keep;
  options.resolutions = command.resolutions;
  for (const double sigma : command.camera_noise_levels) {
    options.camera_noise_levels.push_back(sigma);
  }
  options.steps = command.steps;
  options.obstacle_memory = command.obstacle_memory;
  if (!command.arrival.empty()) {
    options.arrival = arrival_option(command.arrival);
  }
  options.seed = command.seed;
  options.jobs = command.jobs;
  options.shard = eval::parse_shard(command.shard);
  options.out_dir = command.out_dir;
  options.progress_bar = isatty(STDERR_FILENO) != 0;
  return options;
}

void report(const char* command, const eval::SuiteResult& result, const std::string& out_dir) {
  eval::print_suite_table(result.runs, std::cout);
  std::cerr << "flowsteer " << command << ": " << result.runs.size() << " runs of suite "
            << result.suite_id << " (shard " << result.shard.index << "/" << result.shard.count
            << ") in " << result.wall_s << " s with " << result.jobs << " jobs -> " << out_dir
            << "\n";
}

int run_eval_suite(const EvalSuiteCommand& command) {
  const eval::SuiteOptions options = suite_options(command);
  const std::vector<eval::SuiteCase> cases = load_cases(command.paths, command.seed);
  report("eval suite", eval::run_suite(cases, options, std::cerr), command.out_dir);
  return 0;
}

int run_eval_merge(const EvalMergeCommand& command) {
  report("eval merge",
         eval::merge_suite_shards({command.shard_dirs.begin(), command.shard_dirs.end()},
                                  command.out_dir),
         command.out_dir);
  return 0;
}

}  // namespace

Subcommand add_eval_suite(CLI::App& eval) {
  auto command = std::make_shared<EvalSuiteCommand>();
  CLI::App* suite = eval.add_subcommand(
      "suite",
      "Run every case (scenario files or SteerSuite test cases) under every configuration in "
      "parallel worker processes and score the runs (docs/EVAL_SUITE.md)");
  suite->add_option("path", command->paths,
                    "case files (.xml SteerSuite, .yaml scenario) or folders of them (default: "
                    "the project's suite, config/suite/)");
  suite->add_option("--flow", command->flows,
                    "every agent's flow (default: the case's); repeat for several: " +
                        servo::flow_method_names());
  suite->add_option("--segmentation", command->segmentations,
                    "every agent's segmentation (default: the case's); repeat for several: " +
                        servo::segmentation_method_names());
  suite->add_option("--depth", command->depths,
                    "where every agent's features take depths from with synthetic flow (default: "
                    "the case's); repeat for several: " +
                        servo::depth_source_names() +
                        " (ground: only where objects stand on it, as a camera)");
  suite->add_option("--controller", command->controllers,
                    "every agent's steering model (default: the case's); repeat for several: " +
                        servo::steering_model_names());
  suite->add_option("--law", command->laws,
                    "every agent's navigation law (default: the case's); repeat for several: " +
                        servo::navigation_law_names());
  suite->add_option("--without", command->switched_off,
                    "an ablation: every agent's flowsteer law with this mechanism switched off "
                    "(default: the case's); repeat for several, none for the law as it is: " +
                        servo::law_mechanism_names());
  suite
      ->add_option("--resolution", command->resolutions,
                   "every agent's camera, N x N pixels (default: the case's); repeat for several")
      ->check(within(base::bounds::kImageSide_px));
  suite
      ->add_option("--camera-noise", command->camera_noise_levels,
                   "every agent's camera noise, σ in grey levels from 0 to 50 (default: the "
                   "case's); repeat for several")
      ->check(within(base::bounds::kCameraNoise_levels));
  suite->add_option("--jobs,-j", command->jobs, "runs at once, each in its own process")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  suite
      ->add_option("--shard", command->shard,
                   "run only the i-th of n slices of the runs, i/n (merge them with eval merge)")
      ->capture_default_str();
  suite
      ->add_option("--keep-runs", command->keep_runs,
                   "which runs keep their folder (what flowsteer sim writes): failed, all, none")
      ->capture_default_str();
  suite
      ->add_option("--seed", command->seed,
                   "where SteerSuite's agent and obstacle regions and random targets are placed")
      ->capture_default_str();
  suite->add_option("--steps", command->steps, "stop each run after N control steps")
      ->check(within(base::bounds::kRunSteps));
  suite->add_flag("--obstacle-memory", command->obstacle_memory, kObstacleMemoryHelp);
  suite->add_option("--arrival", command->arrival, kArrivalHelp);
  suite->add_option("--out", command->out_dir, "folder for the outputs")->capture_default_str();
  one_value_per_use(*suite);
  return {suite, [command] { return run_eval_suite(*command); }};
}

Subcommand add_eval_merge(CLI::App& eval) {
  auto command = std::make_shared<EvalMergeCommand>();
  CLI::App* merge = eval.add_subcommand(
      "merge", "Join the output folders of a suite's shards (eval suite --shard) into one");
  merge->add_option("shard_dirs", command->shard_dirs, "every shard's output folder")->required();
  merge->add_option("--out", command->out_dir, "folder for the merged suite")
      ->capture_default_str();
  return {merge, [command] { return run_eval_merge(*command); }};
}

}  // namespace flowsteer::cli
