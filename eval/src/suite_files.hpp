#pragma once

#include <filesystem>
#include <string>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/eval/suite.hpp"

namespace flowsteer::eval {

// A run's summary as suite.csv's score columns (agents ... composite01). A worker sends these
// as its record, so a run read back from a shard's suite.csv is the run its worker reported.
std::string summary_fields(const sim::RunSummary& summary);
// Throws std::runtime_error naming `source` when the text is not such fields.
sim::RunSummary parse_summary_fields(const std::string& text, const std::string& source);

// suite.csv, suite.txt, suite.json and contact_sheet.png into out's staging folder, whose
// topviews/ already holds the runs' top views; the caller commits.
void write_suite_files(const SuiteResult& result, base::OutputDir& out);

// A suite folder's suite.json and suite.csv. Throws base::ConfigError naming the file for a
// folder that is not a suite's output.
SuiteResult read_suite_files(const std::filesystem::path& dir);

}  // namespace flowsteer::eval
