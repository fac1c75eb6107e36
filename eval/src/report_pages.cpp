#include "report_pages.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include "flowsteer/report/page.hpp"
#include "flowsteer/report/run_report.hpp"
#include "suite_files.hpp"

namespace flowsteer::eval {

namespace {

using report::Cell;
using report::number_cell;
using report::text_cell;

// A run's contacts named in its reason, at most this many, then how many more.
constexpr std::size_t kContactsNamed = 3;

// Who touched what and when, from a kept run folder's collisions.csv; empty where the folder was
// not kept or has no such file (the counts say the rest).
std::string contacts_named(const std::filesystem::path& run_dir) {
  std::vector<report::Contact> contacts;
  try {
    contacts = report::read_contacts(run_dir);
  } catch (const std::exception&) {
    return "";
  }
  std::string named;
  for (std::size_t k = 0; k < contacts.size() && k < kContactsNamed; ++k) {
    char text[96];
    std::snprintf(text, sizeof text, "%sagent %zu with %s at %.2f s", k > 0 ? "; " : "",
                  contacts[k].agent, contacts[k].with.c_str(), contacts[k].t_s);
    named += text;
  }
  if (contacts.size() > kContactsNamed) {
    named += "; " + std::to_string(contacts.size() - kContactsNamed) + " more";
  }
  return named;
}

// The run's verdict (run_verdict), with who touched what where its folder was kept.
std::string reason(const SuiteRun& run, const std::filesystem::path& run_dir) {
  std::string why = run_verdict(run);
  if (!run.failed() && run.summary.collisions > 0) {
    const std::string named = contacts_named(run_dir);
    if (!named.empty()) {
      why += "; contacts: " + named;
    }
  }
  return why;
}

std::vector<Cell> run_row(const SuiteRun& run, const std::filesystem::path& dir) {
  const std::filesystem::path run_dir = dir / "runs" / run.folder_name();
  Cell status = text_cell(run.failed() ? "failed" : run.clean() ? "clean" : "not clean");
  status.sort_value = run.failed() ? 2.0 : run.clean() ? 0.0 : 1.0;
  status.alert = !run.clean();
  Cell why = text_cell(run.clean() ? "" : reason(run, run_dir));
  why.alert = !run.clean();
  why.prose = true;
  Cell page = text_cell("not kept");
  std::error_code unreadable;  // a folder that cannot be looked into has no page to link
  if (std::filesystem::exists(run_dir / "report.html", unreadable)) {
    page.text = "run page";
    page.link = "runs/" + run.folder_name() + "/report.html";
  }
  const sim::RunSummary& s = run.summary;
  Cell goals =
      text_cell(std::to_string(s.goals_reached) + "/" + std::to_string(s.agents_with_goal()));
  goals.sort_value =
      s.agents_with_goal() > 0 ? static_cast<double>(s.goals_reached) / s.agents_with_goal() : 1.0;
  return {text_cell(run.case_name),
          text_cell(configuration_label(run.configuration)),
          status,
          why,
          goals,
          number_cell(s.collisions, 0),
          number_cell(s.obstacle_collisions, 0),
          number_cell(s.min_clearance_m, 3, " m"),
          number_cell(s.mean_time_ratio, 2),
          number_cell(s.composite01, 1),
          number_cell(s.spinning_s, 1, " s"),
          page};
}

report::Table configuration_totals(const std::vector<SuiteRun>& runs) {
  std::vector<std::string> order;
  std::map<std::string, std::pair<int, int>> clean_of;  // clean runs, runs
  for (const SuiteRun& run : runs) {
    const std::string name = configuration_label(run.configuration);
    if (!clean_of.contains(name)) {
      order.push_back(name);
    }
    clean_of[name].first += run.clean() ? 1 : 0;
    clean_of[name].second += 1;
  }
  report::Table table;
  table.heading = "Clean runs per configuration";
  table.columns = {"configuration", "clean", "runs"};
  for (const std::string& name : order) {
    table.rows.push_back({text_cell(name), number_cell(clean_of[name].first, 0),
                          number_cell(clean_of[name].second, 0)});
  }
  return table;
}

}  // namespace

std::vector<std::string> write_suite_page(const SuiteResult& result,
                                          const std::filesystem::path& dir) {
  report::Page page;
  page.title = "flowsteer suite " + result.suite_id;
  std::size_t clean = 0;
  for (const SuiteRun& run : result.runs) {
    clean += run.clean() ? 1 : 0;
  }
  page.facts.push_back(std::to_string(clean) + " of " + std::to_string(result.runs.size()) +
                       " runs clean; rule on arrival: " + result.arrival + "; shard " +
                       std::to_string(result.shard.index) + " of " +
                       std::to_string(result.shard.count) + ", seed " +
                       std::to_string(result.seed));
  report::Table runs;
  runs.heading = "Runs (click a heading to sort)";
  runs.columns = {"case",       "configuration", "status",    "reason",
                  "goals",      "collisions",    "obstacles", "min clearance",
                  "time ratio", "composite01",   "spinning",  "page"};
  runs.sortable = true;
  for (const SuiteRun& run : result.runs) {
    runs.rows.push_back(run_row(run, dir));
  }
  page.sections.emplace_back(std::move(runs));
  page.sections.emplace_back(configuration_totals(result.runs));
  page.sections.emplace_back(report::Picture{"Every run from above (not clean: framed in red)",
                                             dir / "contact_sheet.png"});
  report::write_page(dir / "report.html", page);
  return page.problems;
}

void write_compare_page(const CompareResult& result, const std::vector<CompareRow>& rows,
                        const std::filesystem::path& dir) {
  report::Page page;
  page.title = "flowsteer compare: " + result.scenario;
  report::Table table;
  table.heading = "Steering models";
  table.columns = {"controller",
                   "collisions",
                   "goals",
                   "time to goal",
                   "path length",
                   "min clearance",
                   "path vs geometric",
                   "clearance vs geometric",
                   "page"};
  table.sortable = true;
  for (const CompareRow& r : rows) {
    const std::string name(servo::to_string(r.controller));
    const sim::RunSummary& s = r.summary;
    Cell collisions = number_cell(s.collisions, 0);
    collisions.alert = s.collisions > 0;
    Cell goals = text_cell(std::to_string(s.goals_reached) + "/" + std::to_string(s.agents));
    goals.sort_value = s.goals_reached;
    Cell link = text_cell("run page");
    link.link = name + "/report.html";
    table.rows.push_back(
        {text_cell(name), collisions, goals, number_cell(s.mean_time_to_goal_s, 2, " s"),
         number_cell(s.mean_path_length_m, 2, " m"), number_cell(s.min_clearance_m, 3, " m"),
         number_cell(100.0 * r.path_length_vs_reference, 1, " %"),
         number_cell(r.min_clearance_vs_reference_m, 3, " m"), link});
  }
  page.sections.emplace_back(std::move(table));
  page.sections.emplace_back(report::Picture{"From above", dir / "topviews.png"});
  page.sections.emplace_back(
      report::Picture{"Turn rates commanded (CGF Fig. 16)", dir / "turn_rates.png"});
  report::write_page(dir / "report.html", page);
}

}  // namespace flowsteer::eval
