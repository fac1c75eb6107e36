#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/eval/compare.hpp"

namespace flowsteer::cli {

namespace {

struct CompareCommand {
  ScenarioChoice scenario;
  std::string out_dir = "flowsteer_compare";
  std::vector<std::string> controllers;
  std::optional<int> resolution;
  std::optional<int> steps;
};

int run_compare(const CompareCommand& command) {
  const sim_camera::WorldSpec world = load_world("compare", command.scenario);
  eval::CompareOptions options;
  options.controllers = eval::parse_controllers(command.controllers);
  options.out_dir = command.out_dir;
  options.resolution = command.resolution;
  options.steps = command.steps;
  const eval::CompareResult result = eval::run_compare(world, options, std::cerr);
  std::cout << "scenario " << result.scenario << " -> " << command.out_dir << "\n";
  eval::print_compare_table(eval::compare_table(result), std::cout);
  return 0;
}

}  // namespace

Subcommand add_compare(CLI::App& app) {
  auto command = std::make_shared<CompareCommand>();
  CLI::App* compare = app.add_subcommand(
      "compare",
      "Run one scenario once per steering model and write the runs side by side: top views, a "
      "table of collisions, goals, path lengths and clearances, turn-rate histograms");
  add_scenario_options(*compare, command->scenario);
  compare
      ->add_option("--controllers", command->controllers,
                   "comma-separated steering models: " + servo::steering_model_names())
      ->delimiter(',')
      ->required();
  compare->add_option("--out", command->out_dir, "folder for the outputs")->capture_default_str();
  compare->add_option("--resolution", command->resolution, "every agent's camera: N x N pixels")
      ->check(within(base::bounds::kImageSide_px));
  compare->add_option("--steps", command->steps, "stop each run after N control steps")
      ->check(within(base::bounds::kRunSteps));
  return {compare, [command] { return run_compare(*command); }};
}

}  // namespace flowsteer::cli
