#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::eval {

// The steering models named in `--controllers`, in order. Throws base::ConfigError for an unknown
// or repeated name, or for none.
std::vector<servo::SteeringModel> parse_controllers(const std::vector<std::string>& names);

struct CompareOptions {
  std::vector<servo::SteeringModel> controllers;  // in the order of the outputs
  std::filesystem::path out_dir = "flowsteer_compare";
  std::optional<int> resolution;  // as sim::SimOptions
  std::optional<int> steps;
  bool write_outputs = true;
};

// One controller's run of the scenario and its angular-velocity histogram (CGF Fig. 16: only
// non-zero adaptations, |ω| >= kStillTurnRate, are counted).
struct ControllerRun {
  servo::SteeringModel controller;
  sim::SimResult result;
  std::vector<int> turn_rate_counts;  // per bin of CompareResult::turn_rate_edges
};

inline constexpr double kStillTurnRate = 1e-3;  // rad/s

struct CompareResult {
  std::string scenario;
  std::vector<ControllerRun> runs;
  std::vector<double> turn_rate_edges;  // rad/s, bins + 1 edges from −max to +max turn rate
};

// Runs the scenario once per controller, with every agent's controller type set to it, and
// writes into out_dir, all at once at the end: one folder per controller with what `flowsteer
// sim` writes, topviews.png (the top views side by side), compare.csv (the table below),
// compare_agents.csv (per controller and agent), turn_rates.csv and turn_rates.png (the
// histograms). Throws base::ConfigError for a repeated controller, std::invalid_argument
// when a scenario's agent cannot take a controller (a follower cannot use motion_energy).
CompareResult run_compare(const sim_camera::WorldSpec& world, const CompareOptions& options,
                          std::ostream& log);

// One line of the comparison table. The differences are to the geometric reference when it is
// among the controllers (NaN otherwise): they separate what perception adds from the control law.
struct CompareRow {
  servo::SteeringModel controller;
  sim::RunSummary summary;
  double path_length_vs_reference = 0.0;  // mean path length / the reference's − 1
  double min_clearance_vs_reference_m = 0.0;
};

std::vector<CompareRow> compare_table(const CompareResult& result);
void print_compare_table(const std::vector<CompareRow>& rows, std::ostream& out);

}  // namespace flowsteer::eval
