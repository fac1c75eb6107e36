#pragma once

#include <filesystem>
#include <vector>

#include "flowsteer/eval/compare.hpp"
#include "flowsteer/eval/suite.hpp"

namespace flowsteer::eval {

// A suite folder's report.html (report::Page): the runs' table, sortable, each run's status with
// its reason (its contacts with whom, where its folder was kept; goals not reached; why it
// failed) and a link to its own page where its folder was kept; the clean runs per
// configuration; the contact sheet. Reads the run folders and contact_sheet.png under dir.
// Returns what it could not read (also on the page).
std::vector<std::string> write_suite_page(const SuiteResult& result,
                                          const std::filesystem::path& dir);

// A comparison folder's report.html: the table, a link to each controller's run page, the top
// views and the turn-rate histograms.
void write_compare_page(const CompareResult& result, const std::vector<CompareRow>& rows,
                        const std::filesystem::path& dir);

}  // namespace flowsteer::eval
