#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace flowsteer::report {

// The page of one run folder, as `flowsteer sim` writes it (docs/COMMANDS.md): its agents'
// outcomes (summary.json), the top view, and plots over time of every agent's speed, turn rate,
// clearance and smallest time to contact (trajectories.csv) and of each cost term
// (costs.csv), with the contacts (collisions.csv) marked. Written to run_dir/report.html. A
// file missing or unreadable does not stop the page: the page says which and why, and shows
// the rest. Returns those problems (empty when every file was read).
std::vector<std::string> write_run_report(const std::filesystem::path& run_dir);

// A contact as collisions.csv records it: when it began, the agent and what it touched.
struct Contact {
  double t_s = 0.0;
  std::size_t agent = 0;
  std::string with;  // "agent N", "obstacle N", "moving N"
};
// collisions.csv of a run folder. Throws std::runtime_error naming the file (and line) when it
// is missing or malformed.
std::vector<Contact> read_contacts(const std::filesystem::path& run_dir);

}  // namespace flowsteer::report
