#include <iostream>
#include <optional>
#include <string>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/sim/simulation.hpp"

namespace flowsteer::cli {

servo::FlowMethod flow_method_option(const std::string& option, const std::string& name,
                                     const std::string& noun, const std::string& known,
                                     bool refuse_synthetic) {
  const auto method = servo::parse_flow_method(name);
  if (!method || (refuse_synthetic && *method == servo::FlowMethod::synthetic)) {
    throw CLI::ValidationError(option,
                               "unknown " + noun + " '" + name + "' (known: " + known + ")");
  }
  return *method;
}

servo::SegmentationMethod segmentation_method_option(const std::string& option,
                                                     const std::string& name) {
  const auto method = servo::parse_segmentation_method(name);
  if (!method) {
    throw CLI::ValidationError(option, "unknown method '" + name +
                                           "' (known: " + servo::segmentation_method_names() + ")");
  }
  return *method;
}

servo::DepthSource depth_source_option(const std::string& option, const std::string& name) {
  const auto source = servo::parse_depth_source(name);
  if (!source) {
    throw CLI::ValidationError(
        option, "unknown depth source '" + name + "' (known: " + servo::depth_source_names() + ")");
  }
  return *source;
}

servo::NavigationLaw navigation_law_option(const std::string& option, const std::string& name) {
  const auto law = servo::parse_navigation_law(name);
  if (!law) {
    throw CLI::ValidationError(option, "unknown navigation law '" + name +
                                           "' (known: " + servo::navigation_law_names() + ")");
  }
  return *law;
}

servo::LawMechanism law_mechanism_option(const std::string& option, const std::string& name) {
  const auto mechanism = servo::parse_law_mechanism(name);
  if (!mechanism) {
    throw CLI::ValidationError(
        option, "unknown mechanism '" + name + "' (known: " + servo::law_mechanism_names() + ")");
  }
  return *mechanism;
}

sim_camera::Arrival arrival_option(const std::string& name) {
  const auto arrival = sim_camera::parse_arrival(name);
  if (!arrival) {
    throw CLI::ValidationError("--arrival", "unknown rule '" + name + "' (known: stay, leave)");
  }
  return *arrival;
}

namespace {

sim_camera::WorldSpec load_chosen_world(const std::string& command, const ScenarioChoice& choice) {
  const int given = !choice.file.empty() + !choice.name.empty() + !choice.steersuite.empty();
  if (given > 1) {
    throw CLI::ValidationError(command, "give one of SCENARIO_FILE, --scenario, --steersuite");
  }
  if (!choice.file.empty()) {
    return config::load_scenario(choice.file);
  }
  if (!choice.steersuite.empty()) {
    config::LoadedCase loaded = config::load_steersuite(choice.steersuite, choice.seed);
    for (const std::string& warning : loaded.warnings) {
      std::cerr << "flowsteer " << command << ": warning: " << warning << "\n";
    }
    return std::move(loaded.world);
  }
  return config::builtin_scenario(choice.name.empty() ? "room" : choice.name);
}

}  // namespace

sim_camera::WorldSpec load_world(const std::string& command, const ScenarioChoice& choice) {
  std::optional<servo::NavigationLaw> law;
  if (!choice.law.empty()) {
    law = navigation_law_option("--law", choice.law);
  }
  std::optional<servo::LawMechanism> without;
  if (!choice.without.empty()) {
    without = law_mechanism_option("--without", choice.without);
  }
  std::optional<sim_camera::Arrival> arrival;
  if (!choice.arrival.empty()) {
    arrival = arrival_option(choice.arrival);
  }
  sim_camera::WorldSpec world = load_chosen_world(command, choice);
  world.arrival = arrival.value_or(world.arrival);
  for (sim_camera::AgentSpec& agent : world.agents) {
    agent.controller.law = law.value_or(agent.controller.law);
  }
  if (without) {
    sim::switch_off(world, *without);
  }
  return world;
}

CLI::Validator within(const base::Bound& bound) {
  return CLI::Validator(
      [bound](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) {
          return "expected a number, got " + text;
        }
        return bound.contains(value) ? std::string() : bound.refusal(value);
      },
      bound.describe());
}

void one_value_per_use(CLI::App& command) {
  for (CLI::Option* option : command.get_options()) {
    if (!option->get_positional()) {
      option->allow_extra_args(false);
    }
  }
}

void add_scenario_options(CLI::App& command, ScenarioChoice& choice) {
  command.add_option("scenario_file", choice.file,
                     "scenario YAML (see config/scenarios/room.yaml)");
  command.add_option("--scenario", choice.name,
                     "a built-in scenario (flowsteer scenarios lists them)");
  command.add_option("--steersuite", choice.steersuite, "a SteerSuite test case (XML)");
  command
      .add_option("--seed", choice.seed,
                  "where a SteerSuite test case's random agents, obstacles, targets and "
                  "directions go")
      ->capture_default_str();
  command.add_option(
      "--law", choice.law,
      "every agent's navigation law (default: the scenario's): " + servo::navigation_law_names());
  command.add_option("--without", choice.without,
                     "every agent's flowsteer law with this mechanism switched off, an ablation "
                     "(default: the scenario's): " +
                         servo::law_mechanism_names());
  command.add_option("--arrival", choice.arrival, kArrivalHelp);
}

void add_recording_options(CLI::App& command, RecordingChoice& choice) {
  command.add_option("--mcap", choice.path,
                     "also record the run into this MCAP file: ROS 2 messages and Foxglove "
                     "schemas, for Foxglove, Lichtblick or ros2 bag (docs/RECORDINGS.md)");
  command
      .add_option("--mcap-images", choice.images_every,
                  "with --mcap: every Nth camera frame goes in as an image, 0 none")
      ->check(within(base::bounds::kImagesEvery_frames))
      ->capture_default_str();
}

std::optional<pipeline::RecordingOptions> recording_options(const RecordingChoice& choice) {
  if (choice.path.empty()) {
    return std::nullopt;
  }
  return pipeline::RecordingOptions{choice.path, choice.images_every};
}

}  // namespace flowsteer::cli
