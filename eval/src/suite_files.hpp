#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/eval/suite.hpp"

namespace flowsteer::eval {

// A run's summary as suite.csv's score columns (agents ... composite01). A worker sends these
// as its record, so a run read back from a shard's suite.csv is the run its worker reported.
std::string summary_fields(const sim::RunSummary& summary);
// Throws std::runtime_error naming `source` when the text is not such fields.
sim::RunSummary parse_summary_fields(const std::string& text, const std::string& source);

// What a run's configuration sets, for people: "flow dis_fast, 64 px", or "the case's own
// settings" where it sets nothing.
std::string configuration_label(const SuiteConfiguration& configuration);

// Why a run is not clean ("2 collisions (1 with obstacles), goals 3/4", "failed: <its error>"),
// or "clean".
std::string run_verdict(const SuiteRun& run);

// Every run's top view (topviews/<run's folder name>.png) scaled into a grid, runs that are not
// clean framed in red; under each its case, configuration_label and run_verdict.
cv::Mat contact_sheet(const std::vector<SuiteRun>& runs, const std::filesystem::path& topviews);

// suite.csv, suite.txt, suite.json and contact_sheet.png into out's staging folder, whose
// topviews/ already holds the runs' top views; the caller commits.
void write_suite_files(const SuiteResult& result, base::OutputDir& out);

// A suite folder's suite.json and suite.csv. Throws base::ConfigError naming the file for a
// folder that is not a suite's output.
SuiteResult read_suite_files(const std::filesystem::path& dir);

}  // namespace flowsteer::eval
