#include "flowsteer/eval/robustness.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/output_files.hpp"
#include "process_pool.hpp"
#include "run_choices.hpp"
#include "suite_files.hpp"

namespace flowsteer::eval {

namespace {

constexpr int kDefaultStepPx = 8;
constexpr int kDefaultSteps = 4;  // either side of the scenario's own resolution

template <typename Method>
std::string method_name(const std::optional<Method>& method) {
  return method ? std::string(servo::to_string(*method)) : std::string("scenario");
}

void write_tables(const std::vector<RobustnessRun>& runs, base::OutputDir& out) {
  base::CsvTable csv({"flow", "segmentation", "resolution", "collisions", "goals_reached",
                      "agents_with_goal", "mean_time_to_goal_s", "mean_path_length_m",
                      "min_clearance_m", "clean"});
  for (const RobustnessRun& r : runs) {
    const sim::RunSummary& s = r.summary;
    csv.add(
        {method_name(r.flow), method_name(r.segmentation)},
        {static_cast<double>(r.resolution), static_cast<double>(s.collisions),
         static_cast<double>(s.goals_reached), static_cast<double>(s.agents_with_goal()),
         s.mean_time_to_goal_s, s.mean_path_length_m, s.min_clearance_m, s.clean() ? 1.0 : 0.0});
  }
  csv.write(out.staging_path("robustness.csv"));
  std::ostringstream table;
  print_robustness_table(runs, table);
  base::write_text(out.staging_path("robustness.txt"), table.str());
  out.commit();
}

// Every flow × segmentation × resolution, in that order, not run yet.
std::vector<RobustnessRun> planned_runs(const sim_camera::WorldSpec& world,
                                        const RobustnessOptions& options) {
  const std::vector<int> resolutions = robustness_resolutions(world, options);
  std::vector<RobustnessRun> runs;
  for (const auto& flow : each_or_own(options.flows)) {
    for (const auto& segmentation : each_or_own(options.segmentations)) {
      for (const int resolution : resolutions) {
        runs.push_back({flow, segmentation, resolution, {}});
      }
    }
  }
  return runs;
}

// The run as `flowsteer sim` with its overrides, without files or progress lines.
sim::RunSummary run_once(const sim_camera::WorldSpec& world, const RobustnessRun& run,
                         std::optional<int> steps) {
  sim::SimOptions sim;
  sim.resolution = run.resolution;
  sim.steps = steps;
  sim.flow = run.flow;
  sim.segmentation = run.segmentation;
  sim.write_outputs = false;
  std::ostream quiet(nullptr);
  return sim::summarize(sim::run_simulation(world, sim, quiet));
}

}  // namespace

std::vector<int> robustness_resolutions(const sim_camera::WorldSpec& world,
                                        const RobustnessOptions& options) {
  if (!options.resolutions.empty()) {
    check_resolutions(options.resolutions);
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
  std::vector<RobustnessRun> runs = planned_runs(world, options);
  std::optional<base::OutputDir> out;
  if (options.write_outputs) {
    out.emplace(options.out_dir);
  }
  std::string first_error;
  run_in_processes(
      runs.size(), options.jobs,
      [&](std::size_t k) { return summary_fields(run_once(world, runs[k], options.steps)); },
      [&](std::size_t k, const TaskOutcome& outcome) {
        RobustnessRun& run = runs[k];
        log << "flowsteer eval robustness: " << world.name << ", flow " << method_name(run.flow)
            << ", segmentation " << method_name(run.segmentation) << ", " << run.resolution
            << " px: ";
        if (!outcome.ok()) {
          log << "failed: " << outcome.error << "\n";
          first_error = first_error.empty() ? outcome.error : first_error;
          return;
        }
        run.summary = parse_summary_fields(outcome.record, world.name);
        log << run.summary.collisions << " collisions, " << run.summary.goals_reached << "/"
            << run.summary.agents_with_goal() << " goals\n";
      });
  if (!first_error.empty()) {
    throw std::runtime_error("a robustness run failed: " + first_error);
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
    const sim::RunSummary& s = r.summary;
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
