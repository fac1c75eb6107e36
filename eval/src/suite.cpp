#include "flowsteer/eval/suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <set>
#include <sstream>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/report/run_report.hpp"
#include "process_pool.hpp"
#include "report_pages.hpp"
#include "run_choices.hpp"
#include "suite_files.hpp"

namespace flowsteer::eval {

namespace {

template <typename Method>
std::string name_or_own(const std::optional<Method>& method) {
  return method ? std::string(servo::to_string(*method)) : std::string("own");
}

// FNV-1a, 64 bits: a fingerprint of what makes a suite (not a security hash).
class Fingerprint {
 public:
  Fingerprint& add(const std::string& text) {
    for (const unsigned char c : text) {
      hash_ = (hash_ ^ c) * 1099511628211ULL;
    }
    hash_ = (hash_ ^ 0xFFU) * 1099511628211ULL;  // ends the field: "ab","c" differs from "a","bc"
    return *this;
  }
  std::string hex() const {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash_));
    return text;
  }

 private:
  std::uint64_t hash_ = 14695981039346656037ULL;
};

std::string suite_id(const std::vector<SuiteCase>& cases,
                     const std::vector<SuiteConfiguration>& configurations,
                     const SuiteOptions& options) {
  Fingerprint fingerprint;
  for (const SuiteCase& c : cases) {
    fingerprint.add(c.name).add(c.text);
  }
  for (const SuiteConfiguration& c : configurations) {
    fingerprint.add(to_string(c));
  }
  fingerprint.add(std::to_string(options.seed))
      .add(options.steps ? std::to_string(*options.steps) : "all");
  if (options.obstacle_memory) {
    fingerprint.add("obstacle memory");
  }
  if (options.arrival) {
    fingerprint.add("arrival " + std::string(sim_camera::to_string(*options.arrival)));
  }
  return fingerprint.hex();
}

void refuse_repeated_names(const std::vector<SuiteCase>& cases) {
  std::set<std::string> names;
  for (const SuiteCase& c : cases) {
    if (!names.insert(c.name).second) {
      throw base::ConfigError(c.source, "a second case named '" + c.name +
                                            "' (cases are told apart by their file names)");
    }
  }
}

// A mechanism switched off is the flowsteer law's: refused beside another law given on the command
// line (a case's own law is checked when its run starts).
void check_switched_off(const SuiteOptions& options) {
  for (const servo::LawMechanism mechanism : options.switched_off) {
    for (const servo::NavigationLaw law : options.laws) {
      if (mechanism != servo::LawMechanism::none && law != servo::NavigationLaw::flowsteer) {
        throw base::ConfigError("--without " + std::string(servo::to_string(mechanism)),
                                "switches off a mechanism of the flowsteer law, which --law " +
                                    std::string(servo::to_string(law)) + " does not have");
      }
    }
  }
}

// The case under the configuration, run as `flowsteer sim` runs it, its files into `folder`.
sim::RunSummary run_case(const SuiteCase& suite_case, const SuiteConfiguration& configuration,
                         const SuiteOptions& options, const std::filesystem::path& folder) {
  sim_camera::WorldSpec world = suite_case.world;
  world.arrival = options.arrival.value_or(world.arrival);
  for (sim_camera::AgentSpec& agent : world.agents) {
    agent.controller.model = configuration.controller.value_or(agent.controller.model);
    agent.controller.law = configuration.law.value_or(agent.controller.law);
  }
  if (configuration.without) {
    sim::switch_off(world, *configuration.without);
  }
  sim::SimOptions sim;
  sim.out_dir = folder;
  sim.resolution = configuration.resolution;
  sim.camera_noise_levels = configuration.camera_noise_levels;
  sim.steps = options.steps;
  sim.flow = configuration.flow;
  sim.segmentation = configuration.segmentation;
  sim.depth = configuration.depth;
  if (options.obstacle_memory) {
    sim.obstacle_memory = true;
  }
  std::ostream quiet(nullptr);
  return sim::summarize(sim::run_simulation(world, sim, quiet));
}

// "[#####     ] 12/48 runs, 3 not clean (1 failed), 4 min left", redrawn, or a line per run.
class SuiteProgress {
 public:
  SuiteProgress(std::ostream& log, bool bar, std::size_t total)
      : log_(log), bar_(bar), total_(total) {}

  void update(const SuiteRun& run) {
    ++done_;
    not_clean_ += run.clean() ? 0 : 1;
    failed_ += run.failed() ? 1 : 0;
    const double left_s = (clock_.elapsed_ms() / 1e3) / static_cast<double>(done_) *
                          static_cast<double>(total_ - done_);
    std::ostringstream counts;
    counts << done_ << "/" << total_ << " runs, " << not_clean_ << " not clean (" << failed_
           << " failed), "
           << (left_s < 60.0 ? std::to_string(static_cast<int>(std::ceil(left_s))) + " s"
                             : std::to_string(static_cast<int>(std::ceil(left_s / 60.0))) + " min")
           << " left";
    if (bar_) {
      const std::size_t filled = 30 * done_ / std::max<std::size_t>(total_, 1);
      log_ << "\r[" << std::string(filled, '#') << std::string(30 - filled, ' ') << "] "
           << counts.str() << "   " << (done_ == total_ ? "\n" : "") << std::flush;
    } else {
      log_ << "flowsteer eval suite: " << run.folder_name() << ": "
           << (run.failed()  ? "failed: " + run.error
               : run.clean() ? "clean"
                             : "not clean")
           << " [" << counts.str() << "]\n";
    }
  }

 private:
  std::ostream& log_;
  bool bar_;
  std::size_t total_;
  std::size_t done_ = 0;
  std::size_t not_clean_ = 0;
  std::size_t failed_ = 0;
  base::Stopwatch clock_;
};

// Copies each run's top view to topviews/ and keeps or drops its folder as options ask; a
// failed run's folder gets its error. Both folders are made even when empty, so that they replace
// those of an earlier suite in the same output folder.
void file_runs(const std::vector<SuiteRun>& runs, KeepRuns keep, base::OutputDir& out) {
  const std::filesystem::path runs_dir = out.staging_path("runs");
  std::filesystem::create_directories(runs_dir);
  std::filesystem::create_directories(out.staging_path("topviews"));
  for (const SuiteRun& run : runs) {
    const std::filesystem::path folder = runs_dir / run.folder_name();
    const std::filesystem::path topview = folder / "topview.png";
    if (std::filesystem::exists(topview)) {
      std::filesystem::copy_file(topview,
                                 out.staging_path("topviews") / (run.folder_name() + ".png"));
    }
    const bool kept = keep == KeepRuns::all || (keep == KeepRuns::failed && !run.clean());
    if (!kept) {
      std::filesystem::remove_all(folder);
    } else if (run.failed()) {
      std::filesystem::create_directories(folder);
      base::write_text(folder / "error.txt", run.error + "\n");
    }
  }
}

// Two decimals and the unit; "-" where there is no value (no other body, no agent arrived).
std::string measure(double value, const char* unit) {
  if (!std::isfinite(value)) {
    return "-";
  }
  char text[48];
  std::snprintf(text, sizeof text, "%.2f%s", value, unit);
  return text;
}

// Per configuration, in the order they first appear: the clean cases and the total score.
void print_configuration_totals(const std::vector<SuiteRun>& runs, std::ostream& out) {
  std::vector<std::string> configurations;
  for (const SuiteRun& run : runs) {
    const std::string configuration = to_string(run.configuration);
    if (std::find(configurations.begin(), configurations.end(), configuration) ==
        configurations.end()) {
      configurations.push_back(configuration);
    }
  }
  for (const std::string& configuration : configurations) {
    int cases = 0;
    int clean = 0;
    int failed = 0;
    int collisions = 0;
    int obstacle_collisions = 0;
    double score = 0.0;
    double spinning_s = 0.0;
    for (const SuiteRun& run : runs) {
      if (to_string(run.configuration) != configuration) {
        continue;
      }
      ++cases;
      clean += run.clean() ? 1 : 0;
      failed += run.failed() ? 1 : 0;
      collisions += run.failed() ? 0 : run.summary.collisions;
      obstacle_collisions += run.failed() ? 0 : run.summary.obstacle_collisions;
      spinning_s += run.failed() ? 0.0 : run.summary.spinning_s;
      score +=
          run.failed() || !std::isfinite(run.summary.composite01) ? 0.0 : run.summary.composite01;
    }
    out << "configuration " << configuration << ": clean " << clean << " of " << cases
        << " cases, total composite01 " << measure(score, "") << ", " << collisions
        << " collisions (" << obstacle_collisions << " with obstacles), "
        << measure(spinning_s, " s") << " spinning";
    if (failed > 0) {
      out << " (" << failed << " failed runs not scored)";
    }
    out << "\n";
  }
}

// The runs of every shard of one suite, by index; base::ConfigError for a folder of another
// suite, a shard given twice or one missing.
SuiteResult join_shards(const std::vector<std::filesystem::path>& shard_dirs) {
  if (shard_dirs.empty()) {
    throw base::ConfigError("eval merge", "give the output folders of a suite's shards");
  }
  SuiteResult merged = read_suite_files(shard_dirs.front());
  merged.runs.clear();
  merged.wall_s = 0.0;
  const int count = merged.shard.count;
  std::vector<const std::filesystem::path*> by_index(static_cast<std::size_t>(count), nullptr);
  for (const std::filesystem::path& dir : shard_dirs) {
    const SuiteResult shard = read_suite_files(dir);
    if (shard.suite_id.empty() || shard.suite_id != merged.suite_id || shard.shard.count != count) {
      throw base::ConfigError(dir.string(), "shard " + std::to_string(shard.shard.index) + "/" +
                                                std::to_string(shard.shard.count) + " of suite " +
                                                shard.suite_id + ", not of suite " +
                                                merged.suite_id + " in " + std::to_string(count) +
                                                " shards like " + shard_dirs.front().string());
    }
    const std::filesystem::path*& slot = by_index.at(static_cast<std::size_t>(shard.shard.index));
    if (slot != nullptr) {
      throw base::ConfigError(dir.string(), "shard " + std::to_string(shard.shard.index) +
                                                " is also in " + slot->string());
    }
    slot = &dir;
    merged.wall_s += shard.wall_s;
    merged.jobs = std::max(merged.jobs, shard.jobs);
    merged.runs.insert(merged.runs.end(), shard.runs.begin(), shard.runs.end());
  }
  for (int i = 0; i < count; ++i) {
    if (by_index[static_cast<std::size_t>(i)] == nullptr) {
      throw base::ConfigError("eval merge", "shard " + std::to_string(i) + "/" +
                                                std::to_string(count) + " of suite " +
                                                merged.suite_id + " is missing");
    }
  }
  std::sort(merged.runs.begin(), merged.runs.end(),
            [](const SuiteRun& a, const SuiteRun& b) { return a.index < b.index; });
  merged.shard = {0, 1};
  return merged;
}

}  // namespace

std::string to_string(const SuiteConfiguration& c) {
  std::string text = name_or_own(c.flow) + "/" + name_or_own(c.segmentation) + "/" +
                     name_or_own(c.depth) + "/" + name_or_own(c.controller) + "/" +
                     name_or_own(c.law) + "/" + name_or_own(c.without) + "/" +
                     (c.resolution ? std::to_string(*c.resolution) : std::string("own"));
  if (c.camera_noise_levels) {
    text += "/" + base::format_csv_number(*c.camera_noise_levels);
  }
  return text;
}

std::string SuiteRun::folder_name() const {
  std::string name = case_name + "." + to_string(configuration);
  std::replace(name.begin(), name.end(), '/', '.');
  return name;
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  int index = 0;
  int count = 0;
  char end = 0;
  if (slash == std::string::npos ||
      std::sscanf(text.c_str(), "%d/%d%c", &index, &count, &end) != 2 || count < 1 || index < 0 ||
      index >= count) {
    throw base::ConfigError("--shard " + text,
                            "expected i/n: the i-th of n slices, 0 <= i < n (e.g. 0/4)");
  }
  return {index, count};
}

std::optional<KeepRuns> parse_keep_runs(const std::string& name) {
  if (name == "failed") {
    return KeepRuns::failed;
  }
  if (name == "all") {
    return KeepRuns::all;
  }
  if (name == "none") {
    return KeepRuns::none;
  }
  return std::nullopt;
}

std::vector<SuiteConfiguration> suite_configurations(const SuiteOptions& options) {
  refuse_repeats(options.flows, "--flow");
  refuse_repeats(options.segmentations, "--segmentation");
  refuse_repeats(options.depths, "--depth");
  refuse_repeats(options.controllers, "--controller");
  refuse_repeats(options.laws, "--law");
  refuse_repeats(options.switched_off, "--without");
  check_switched_off(options);
  check_resolutions(options.resolutions);
  refuse_repeats(options.camera_noise_levels, "--camera-noise");
  std::vector<SuiteConfiguration> configurations;
  for (const auto& flow : each_or_own(options.flows)) {
    for (const auto& segmentation : each_or_own(options.segmentations)) {
      for (const auto& depth : each_or_own(options.depths)) {
        for (const auto& controller : each_or_own(options.controllers)) {
          for (const auto& law : each_or_own(options.laws)) {
            for (const auto& without : each_or_own(options.switched_off)) {
              for (const auto& resolution : each_or_own(options.resolutions)) {
                for (const auto& noise : each_or_own(options.camera_noise_levels)) {
                  configurations.push_back(
                      {flow, segmentation, depth, controller, law, without, resolution, noise});
                }
              }
            }
          }
        }
      }
    }
  }
  return configurations;
}

SuiteResult run_suite(const std::vector<SuiteCase>& cases, const SuiteOptions& options,
                      std::ostream& log) {
  refuse_repeated_names(cases);
  const std::vector<SuiteConfiguration> configurations = suite_configurations(options);
  SuiteResult result;
  result.suite_id = suite_id(cases, configurations, options);
  result.seed = options.seed;
  if (options.arrival) {
    result.arrival = sim_camera::to_string(*options.arrival);
  }
  result.shard = options.shard;
  result.suite_runs = cases.size() * configurations.size();
  result.jobs = options.jobs;
  for (std::size_t i = static_cast<std::size_t>(options.shard.index); i < result.suite_runs;
       i += static_cast<std::size_t>(options.shard.count)) {
    result.runs.push_back({i,
                           cases[i / configurations.size()].name,
                           configurations[i % configurations.size()],
                           {},
                           ""});
  }
  base::OutputDir out(
      options.out_dir);  // before the first run: a folder that cannot be written fails now
  const std::filesystem::path runs_dir = out.staging_path("runs");
  const base::Stopwatch clock;
  SuiteProgress progress(log, options.progress_bar, result.runs.size());
  run_in_processes(
      result.runs.size(), options.jobs,
      [&](std::size_t k) {
        const SuiteRun& run = result.runs[k];
        return summary_fields(run_case(cases[run.index / configurations.size()], run.configuration,
                                       options, runs_dir / run.folder_name()));
      },
      [&](std::size_t k, const TaskOutcome& outcome) {
        SuiteRun& run = result.runs[k];
        run.error = outcome.error;
        if (outcome.ok()) {
          run.summary = parse_summary_fields(outcome.record, run.folder_name());
        }
        progress.update(run);
      });
  result.wall_s = clock.elapsed_ms() / 1e3;
  file_runs(result.runs, options.keep_runs, out);
  write_suite_files(result, out);
  write_suite_page(result, out.staging_dir());
  out.commit();
  return result;
}

SuiteResult merge_suite_shards(const std::vector<std::filesystem::path>& shard_dirs,
                               const std::filesystem::path& out_dir) {
  SuiteResult merged = join_shards(shard_dirs);
  base::OutputDir out(out_dir);
  for (const char* folder : {"topviews", "runs"}) {
    std::filesystem::create_directories(out.staging_path(folder));
    for (const std::filesystem::path& dir : shard_dirs) {
      if (std::filesystem::is_directory(dir / folder)) {
        std::filesystem::copy(dir / folder, out.staging_path(folder),
                              std::filesystem::copy_options::recursive |
                                  std::filesystem::copy_options::overwrite_existing);
      }
    }
  }
  write_suite_files(merged, out);
  write_suite_page(merged, out.staging_dir());
  out.commit();
  return merged;
}

std::vector<std::string> write_suite_reports(const std::filesystem::path& dir) {
  const SuiteResult result = read_suite_files(dir);
  std::vector<std::string> problems;
  for (const SuiteRun& run : result.runs) {
    const std::filesystem::path run_dir = dir / "runs" / run.folder_name();
    if (std::filesystem::is_directory(run_dir) && !run.failed()) {
      for (const std::string& problem : report::write_run_report(run_dir)) {
        problems.push_back(run.folder_name() + ": " + problem);
      }
    }
  }
  for (const std::string& problem : write_suite_page(result, dir)) {
    problems.push_back(problem);
  }
  return problems;
}

void print_suite_table(const std::vector<SuiteRun>& runs, std::ostream& out) {
  std::size_t case_width = 6;
  std::size_t configuration_width = 15;
  for (const SuiteRun& run : runs) {
    case_width = std::max(case_width, run.case_name.size() + 2);
    configuration_width = std::max(configuration_width, to_string(run.configuration).size() + 2);
  }
  const auto w = [](std::size_t width) { return std::setw(static_cast<int>(width)); };
  std::ostringstream table;
  table << std::left << w(case_width) << "case" << w(configuration_width) << "configuration"
        << std::setw(11) << "status" << std::right << std::setw(10) << "collisions" << std::setw(11)
        << "obstacles" << std::setw(8) << "goals" << std::setw(15) << "min_clearance"
        << std::setw(14) << "time_to_goal" << std::setw(11) << "path_ratio" << std::setw(11)
        << "time_ratio" << std::setw(12) << "composite01" << std::setw(11) << "turn_flips"
        << std::setw(10) << "spinning"
        << "\n";
  for (const SuiteRun& run : runs) {
    table << std::left << w(case_width) << run.case_name << w(configuration_width)
          << to_string(run.configuration) << std::setw(11)
          << (run.failed()  ? "failed"
              : run.clean() ? "clean"
                            : "not clean")
          << std::right;
    if (run.failed()) {
      table << run.error << "\n";
      continue;
    }
    const sim::RunSummary& s = run.summary;
    table << std::setw(10) << s.collisions << std::setw(11) << s.obstacle_collisions << std::setw(8)
          << (std::to_string(s.goals_reached) + "/" + std::to_string(s.agents_with_goal()))
          << std::setw(15) << measure(s.min_clearance_m, " m") << std::setw(14)
          << measure(s.mean_time_to_goal_s, " s") << std::setw(11)
          << measure(s.mean_path_length_ratio, "") << std::setw(11)
          << measure(s.mean_time_ratio, "") << std::setw(12) << measure(s.composite01, "")
          << std::setw(11) << measure(100.0 * s.turn_flip_ratio, " %") << std::setw(10)
          << measure(s.spinning_s, " s") << "\n";
  }
  print_configuration_totals(runs, table);
  out << table.str();
}

}  // namespace flowsteer::eval
