#include "flowsteer/eval/robustness.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/eval/output_files.hpp"

namespace flowsteer::eval {

namespace {

constexpr int kMinResolution = 16;
constexpr int kMaxResolution = 4096;
constexpr int kDefaultStepPx = 8;
constexpr int kDefaultSteps = 4;  // either side of the scenario's own resolution

template <typename Method>
std::string method_name(const std::optional<Method>& method) {
  return method ? std::string(servo::to_string(*method)) : std::string("scenario");
}

void write_tables(const std::vector<RobustnessRun>& runs, OutputDir& out) {
  CsvTable csv({"flow", "segmentation", "resolution", "collisions", "goals_reached",
                "agents_with_goal", "mean_time_to_goal_s", "mean_path_length_m", "min_clearance_m",
                "clean"});
  for (const RobustnessRun& r : runs) {
    const RunSummary& s = r.summary;
    csv.add(
        {method_name(r.flow), method_name(r.segmentation)},
        {static_cast<double>(r.resolution), static_cast<double>(s.collisions),
         static_cast<double>(s.goals_reached), static_cast<double>(s.agents_with_goal()),
         s.mean_time_to_goal_s, s.mean_path_length_m, s.min_clearance_m, s.clean() ? 1.0 : 0.0});
  }
  csv.write(out.staging_path("robustness.csv"));
  std::ostringstream table;
  print_robustness_table(runs, table);
  write_text(out.staging_path("robustness.txt"), table.str());
  out.commit();
}

}  // namespace

std::vector<int> robustness_resolutions(const sim_camera::WorldSpec& world,
                                        const RobustnessOptions& options) {
  if (!options.resolutions.empty()) {
    for (std::size_t i = 0; i < options.resolutions.size(); ++i) {
      const int n = options.resolutions[i];
      if (n < kMinResolution || n > kMaxResolution) {
        throw base::ConfigError("--resolution " + std::to_string(n),
                                "must be from " + std::to_string(kMinResolution) + " to " +
                                    std::to_string(kMaxResolution) + " pixels");
      }
      if (std::find(options.resolutions.begin(), options.resolutions.begin() + static_cast<long>(i),
                    n) != options.resolutions.begin() + static_cast<long>(i)) {
        throw base::ConfigError("--resolution " + std::to_string(n), "given twice");
      }
    }
    return options.resolutions;
  }
  if (world.agents.empty()) {
    throw base::ConfigError("scenario " + world.name, "has no agents to run");
  }
  const int own = world.agents.front().camera.width_px;
  std::vector<int> resolutions;
  for (int k = -kDefaultSteps; k <= kDefaultSteps; ++k) {
    const int n = own + k * kDefaultStepPx;
    if (n >= kMinResolution && n <= kMaxResolution) {
      resolutions.push_back(n);
    }
  }
  return resolutions;
}

std::vector<RobustnessRun> evaluate_robustness(const sim_camera::WorldSpec& world,
                                               const RobustnessOptions& options,
                                               std::ostream& log) {
  const std::vector<int> resolutions = robustness_resolutions(world, options);
  std::optional<OutputDir> out;
  if (options.write_outputs) {
    out.emplace(options.out_dir);
  }
  std::vector<std::optional<servo::FlowMethod>> flows(options.flows.begin(), options.flows.end());
  if (flows.empty()) {
    flows.emplace_back();
  }
  std::vector<std::optional<servo::SegmentationMethod>> segmentations(options.segmentations.begin(),
                                                                      options.segmentations.end());
  if (segmentations.empty()) {
    segmentations.emplace_back();
  }

  std::vector<RobustnessRun> runs;
  for (const auto& flow : flows) {
    for (const auto& segmentation : segmentations) {
      for (const int resolution : resolutions) {
        SimOptions sim;
        sim.resolution = resolution;
        sim.steps = options.steps;
        sim.flow = flow;
        sim.segmentation = segmentation;
        sim.write_outputs = false;
        // One line per run, not the run's own progress lines.
        std::ostream quiet(nullptr);
        const RunSummary summary = summarize(run_simulation(world, sim, quiet));
        log << "flowsteer eval robustness: " << world.name << ", flow " << method_name(flow)
            << ", segmentation " << method_name(segmentation) << ", " << resolution
            << " px: " << summary.collisions << " collisions, " << summary.goals_reached << "/"
            << summary.agents_with_goal() << " goals\n";
        runs.push_back({flow, segmentation, resolution, summary});
      }
    }
  }
  if (out) {
    write_tables(runs, *out);
  }
  return runs;
}

void print_robustness_table(const std::vector<RobustnessRun>& runs, std::ostream& out) {
  const std::ios::fmtflags flags = out.flags();
  out << std::left << std::setw(15) << "flow" << std::setw(17) << "segmentation" << std::right
      << std::setw(11) << "resolution" << std::setw(11) << "collisions" << std::setw(8) << "goals"
      << std::setw(15) << "min_clearance" << std::setw(7) << "clean"
      << "\n";
  for (const RobustnessRun& r : runs) {
    const RunSummary& s = r.summary;
    std::ostringstream clearance;
    clearance << std::fixed << std::setprecision(2) << s.min_clearance_m << " m";
    out << std::left << std::setw(15) << method_name(r.flow) << std::setw(17)
        << method_name(r.segmentation) << std::right << std::setw(11) << r.resolution
        << std::setw(11) << s.collisions << std::setw(8)
        << (std::to_string(s.goals_reached) + "/" + std::to_string(s.agents_with_goal()))
        << std::setw(15) << clearance.str() << std::setw(7) << (s.clean() ? "yes" : "no") << "\n";
  }
  // Runs come grouped by flow and segmentation (evaluate_robustness's order).
  for (std::size_t begin = 0; begin < runs.size();) {
    std::size_t end = begin;
    int clean = 0;
    while (end < runs.size() && runs[end].flow == runs[begin].flow &&
           runs[end].segmentation == runs[begin].segmentation) {
      clean += runs[end].summary.clean() ? 1 : 0;
      ++end;
    }
    out << "clean: " << clean << " of " << end - begin << " runs with flow "
        << method_name(runs[begin].flow) << ", segmentation "
        << method_name(runs[begin].segmentation) << "\n";
    begin = end;
  }
  out.flags(flags);
}

}  // namespace flowsteer::eval
