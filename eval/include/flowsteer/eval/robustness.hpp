#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <vector>

#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::eval {

// A closed-loop run depends on every pixel the agents see, so one clean run at one camera
// resolution says little: nearby resolutions give other routes. `flowsteer eval robustness`
// runs a scenario over several resolutions and perception methods and counts the clean runs.
struct RobustnessOptions {
  // Empty: the resolution of the scenario's first agent and 8, 16, 24 and 32 pixels either side.
  std::vector<int> resolutions;
  // Empty: each agent's own (the scenario's perception:). Every flow is run with every
  // segmentation.
  std::vector<servo::FlowMethod> flows;
  std::vector<servo::SegmentationMethod> segmentations;
  std::optional<int> steps;  // stop each run after this many control steps
  int jobs = 1;              // runs at once, each in a worker process of its own
  std::filesystem::path out_dir = "flowsteer_robustness";
  bool write_outputs = true;
};

struct RobustnessRun {
  std::optional<servo::FlowMethod> flow;  // empty: the scenario's own
  std::optional<servo::SegmentationMethod> segmentation;
  int resolution = 0;
  sim::RunSummary summary;
};

// The resolutions a run over `world` uses: options.resolutions, or the default around the
// scenario's own. Throws base::ConfigError for one below 16 or above 4096 pixels, or given twice.
std::vector<int> robustness_resolutions(const sim_camera::WorldSpec& world,
                                        const RobustnessOptions& options);

// Every flow × segmentation × resolution, in that order, each run as `flowsteer sim` with those
// overrides and without its files, in options.jobs worker processes. Throws std::runtime_error
// naming the first run that failed, once all have ended. Then, with write_outputs, robustness.csv
// and robustness.txt (the printed table) in out_dir, each written whole or not at all; out_dir is
// created before the first run, so a folder that cannot be written fails at once. Progress goes to
// `log`.
std::vector<RobustnessRun> evaluate_robustness(const sim_camera::WorldSpec& world,
                                               const RobustnessOptions& options, std::ostream& log);

// One line per run, then per flow and segmentation how many runs were clean.
void print_robustness_table(const std::vector<RobustnessRun>& runs, std::ostream& out);

}  // namespace flowsteer::eval
