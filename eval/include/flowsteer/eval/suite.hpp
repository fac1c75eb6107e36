#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "flowsteer/servo/steering.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/world_spec.hpp"

namespace flowsteer::eval {

// `flowsteer eval suite`: every case of a benchmark run under every configuration, each run in a
// worker process of its own, scored, and written as one table. docs/EVAL_SUITE.md describes the
// outputs, the scores and how to run a suite on a cluster.

// A case: a scenario file's world under the file's name.
struct SuiteCase {
  std::string name;    // the file name without its extension; unique within a suite
  std::string source;  // the file, for messages
  std::string text;    // the file's content: part of the suite's identity
  sim_camera::WorldSpec world;
};

// What a run overrides in every agent of its case; empty: the case's own.
struct SuiteConfiguration {
  std::optional<servo::FlowMethod> flow;
  std::optional<servo::SegmentationMethod> segmentation;
  std::optional<servo::DepthSource> depth;
  std::optional<servo::SteeringModel> controller;
  std::optional<servo::NavigationLaw> law;
  std::optional<servo::LawMechanism> without;  // the flowsteer law's, switched off
  std::optional<int> resolution;               // N × N pixels
  std::optional<double> camera_noise_levels;   // σ, grey levels (sim::SimOptions)
  bool operator==(const SuiteConfiguration&) const = default;
};
// "flow/segmentation/depth/controller/law/without/resolution", "own" for what is not overridden,
// then "/σ" where the camera noise is: a suite without that axis keeps its names and its id.
std::string to_string(const SuiteConfiguration& configuration);

// The i-th of n slices of a suite's runs (runs i, i + n, i + 2n, ...).
struct Shard {
  int index = 0;
  int count = 1;
};
// "i/n" with 0 <= i < n; base::ConfigError naming --shard and the text otherwise.
Shard parse_shard(const std::string& text);

// Which run folders (what `flowsteer sim` writes) a suite keeps.
enum class KeepRuns { failed, all, none };
std::optional<KeepRuns> parse_keep_runs(const std::string& name);

struct SuiteOptions {
  // Every combination is run; an empty list is the case's own.
  std::vector<servo::FlowMethod> flows;
  std::vector<servo::SegmentationMethod> segmentations;
  std::vector<servo::DepthSource> depths;
  std::vector<servo::SteeringModel> controllers;
  std::vector<servo::NavigationLaw> laws;
  std::vector<servo::LawMechanism> switched_off;  // an ablation: `none` is the law as it is
  std::vector<int> resolutions;
  std::vector<double> camera_noise_levels;     // σ in grey levels, each a configuration
  std::optional<int> steps;                    // stop each run after this many steps
  bool obstacle_memory = false;                // every run's agents: PerceptionConfig's
  std::optional<sim_camera::Arrival> arrival;  // every case's rule on arrival; none: its own
  std::uint32_t seed = 1;  // the seed the cases were placed with, recorded with the suite
  int jobs = 1;            // worker processes at once
  Shard shard;
  KeepRuns keep_runs = KeepRuns::failed;
  std::filesystem::path out_dir = "flowsteer_suite";
  bool progress_bar = false;  // a bar that redraws itself, else a line per run
};

// One case under one configuration.
struct SuiteRun {
  std::size_t index = 0;  // in the whole suite's list: case-major, configurations in order
  std::string case_name;
  SuiteConfiguration configuration;
  sim::RunSummary summary;  // empty when the run failed
  std::string error;        // why the run failed (its exception, or how its process ended)
  bool failed() const { return !error.empty(); }
  bool clean() const { return !failed() && summary.clean(); }
  // The run's folder and top view are named this:
  // "case.flow.segmentation.depth.controller.law.without.resolution[.camera_noise]".
  std::string folder_name() const;
};

struct SuiteResult {
  std::string suite_id;  // the same for every shard of one suite, different for another suite
  std::uint32_t seed = 1;
  std::string arrival = "own";  // the rule on arrival every run had: stay, leave; own: its case's
  Shard shard;
  std::size_t suite_runs = 0;  // runs in the whole suite, all shards together
  std::vector<SuiteRun> runs;  // this shard's, by index
  double wall_s = 0.0;         // a merge: the shards' sum
  int jobs = 1;                // a merge: the most any shard had
};

// The suite's configurations, every flow × segmentation × depth × controller × law × mechanism
// switched off × resolution × camera noise in that nesting. Throws base::ConfigError for a
// resolution out of 16..4096, any value given twice, or a mechanism switched off under a law
// other than flowsteer.
std::vector<SuiteConfiguration> suite_configurations(const SuiteOptions& options);

// Runs the shard's runs in options.jobs worker processes, each as `flowsteer sim` runs a
// scenario (its files in the run's folder), and writes into out_dir, all at once at the end:
// suite.csv, suite.txt, suite.json, contact_sheet.png, topviews/ and runs/ (see
// docs/EVAL_SUITE.md). A run that fails is recorded with its error and the others go on.
// Progress goes to `log`. Throws base::ConfigError for two cases of one name or a bad
// configuration, std::runtime_error when out_dir cannot be written.
SuiteResult run_suite(const std::vector<SuiteCase>& cases, const SuiteOptions& options,
                      std::ostream& log);

// Joins the folders of a suite's shards into one suite in out_dir, as an unsharded run writes
// it. Throws base::ConfigError naming the folder for one that is not a shard's output, shards
// of different suites, a shard given twice or one missing.
SuiteResult merge_suite_shards(const std::vector<std::filesystem::path>& shard_dirs,
                               const std::filesystem::path& out_dir);

// The report pages of a suite's folder written again (`flowsteer report`): each kept run's
// report.html from its files, then the suite's. Returns what could not be read, each named by
// its run; throws base::ConfigError naming the folder when it is not a suite's output.
std::vector<std::string> write_suite_reports(const std::filesystem::path& dir);

// One line per run, then per configuration the clean cases and the total score.
void print_suite_table(const std::vector<SuiteRun>& runs, std::ostream& out);

}  // namespace flowsteer::eval
