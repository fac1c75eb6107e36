#pragma once

// The `flowsteer` command's subcommands, one file each. Each add_* function adds its
// subcommand (and its options struct) to the app and returns what runs it once the command line
// has been parsed; main runs the one the user chose.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "flowsteer/base/bounds.hpp"
#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/sim_camera/world_spec.hpp"

namespace flowsteer::cli {

// --obstacle-memory on sim and eval suite.
inline constexpr const char* kObstacleMemoryHelp =
    "every agent remembers what stood still and recalls it once out of view, where it applies: "
    "the flowsteer law on flow segmentation with a camera's depths (docs/NAVIGATION.md)";

// --arrival on the commands that run scenarios and on eval suite.
inline constexpr const char* kArrivalHelp =
    "what an agent does at its last goal: stay (stands there, an obstacle to the others) or leave "
    "(taken out of the world, SteerSuite's rule); default: the scenario's arrival key, leave for "
    "SteerSuite test cases, stay for scenario files";
sim_camera::Arrival arrival_option(const std::string& name);

struct Subcommand {
  const CLI::App* app;
  std::function<int()> run;  // returns the exit status
};

Subcommand add_demo(CLI::App& app);
Subcommand add_sim(CLI::App& app);
Subcommand add_compare(CLI::App& app);
Subcommand add_scenarios(CLI::App& app);
Subcommand add_bounds(CLI::App& app);
// `report FOLDER`: a run's or a suite's report.html written again from its files.
Subcommand add_report(CLI::App& app);
// `eval flow`, `eval robustness`, `eval suite` and `eval merge`.
std::vector<Subcommand> add_eval(CLI::App& app);
Subcommand add_eval_suite(CLI::App& eval);
Subcommand add_eval_merge(CLI::App& eval);
// `calibrate intrinsics`, `capture` and `mount`.
std::vector<Subcommand> add_calibrate(CLI::App& app);
Subcommand add_run(CLI::App& app);
Subcommand add_replay(CLI::App& app);
Subcommand add_sil(CLI::App& app);

// The flow method `name`, the value of `option`; CLI::ValidationError "unknown <noun> 'NAME'
// (known: <known>)" when no method has that name or, with refuse_synthetic, for synthetic.
servo::FlowMethod flow_method_option(const std::string& option, const std::string& name,
                                     const std::string& noun, const std::string& known,
                                     bool refuse_synthetic = false);
servo::SegmentationMethod segmentation_method_option(const std::string& option,
                                                     const std::string& name);
servo::DepthSource depth_source_option(const std::string& option, const std::string& name);
servo::NavigationLaw navigation_law_option(const std::string& option, const std::string& name);
servo::LawMechanism law_mechanism_option(const std::string& option, const std::string& name);
// Checks an option's value against the bound the same field has in files
// (base/quantity_bounds.hpp): "--resolution: must be from 8 to 4096 px, got 100000", exit 2.
CLI::Validator within(const base::Bound& bound);

// The scenario a command runs: the scenario file or the built-in scenario `scenario` names (a
// name of `flowsteer scenarios` first, else a file), or a SteerSuite test case; "room" when none
// is given. CLI::ValidationError when more than one is.
struct ScenarioChoice {
  std::string file;        // positional SCENARIO_FILE
  std::string name;        // --scenario
  std::string steersuite;  // --steersuite, where the command has it
  std::uint32_t seed = 1;  // --seed: the SteerSuite test case's random placements
  std::string law;         // --law: every agent's navigation law, when given
  std::string without;     // --without: the flowsteer law's mechanism switched off, when given
  std::string arrival;     // --arrival: the world's rule on arrival, when given
};
sim_camera::WorldSpec load_world(const std::string& command, const ScenarioChoice& choice);
// Makes each of the command's repeatable options take one value per use (`--flow a --flow b`),
// so that a positional argument after one is not read as another of its values.
void one_value_per_use(CLI::App& command);
// Adds SCENARIO_FILE, --scenario, --steersuite, --seed, --law and --without to a command that runs
// a scenario.
void add_scenario_options(CLI::App& command, ScenarioChoice& choice);

// --mcap FILE and --mcap-images N on sim, run, replay and sil: the run's MCAP recording.
struct RecordingChoice {
  std::string path;
  int images_every = 1;
};
void add_recording_options(CLI::App& command, RecordingChoice& choice);
// None without --mcap.
std::optional<pipeline::RecordingOptions> recording_options(const RecordingChoice& choice);

}  // namespace flowsteer::cli
