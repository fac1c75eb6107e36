#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/eval/suite.hpp"
#include "flowsteer/report/run_report.hpp"

namespace flowsteer::cli {

namespace {

bool is_run_folder(const std::filesystem::path& dir) {
  for (const char* file : {"summary.json", "trajectories.csv", "costs.csv", "topview.png"}) {
    if (std::filesystem::exists(dir / file)) {
      return true;
    }
  }
  return false;
}

}  // namespace

Subcommand add_report(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "report",
      "Write report.html again in a run's folder (what sim writes) or a suite's (and its kept "
      "runs'): a page that names the files it could not read");
  auto dir = std::make_shared<std::string>();
  command->add_option("FOLDER", *dir, "the output folder of flowsteer sim or eval suite")
      ->required();
  return {command, [dir] {
            const std::filesystem::path folder = *dir;
            std::vector<std::string> problems;
            if (std::filesystem::exists(folder / "suite.json")) {
              problems = eval::write_suite_reports(folder);
            } else if (is_run_folder(folder)) {
              problems = report::write_run_report(folder);
            } else {
              throw base::ConfigError(folder.string(),
                                      "not the output folder of flowsteer sim or eval suite (it "
                                      "has no summary.json, trajectories.csv, costs.csv, "
                                      "topview.png or suite.json)");
            }
            std::cout << "flowsteer report: wrote " << (folder / "report.html").string() << "\n";
            for (const std::string& problem : problems) {
              std::cerr << "flowsteer report: could not read " << problem << "\n";
            }
            return problems.empty() ? 0 : 1;
          }};
}

}  // namespace flowsteer::cli
