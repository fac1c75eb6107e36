#include "flowsteer/report/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "csv_file.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/report/page.hpp"
#include "svg.hpp"

namespace flowsteer::report {

namespace {

// Beyond these a plot's values are drawn at the top: a time to contact of minutes, or a
// clearance of many metres, says nothing about the moments that matter.
constexpr double kTtcCapS = 10.0;
constexpr double kClearanceCapM = 3.0;

Cell agent_cell(const std::string& name, std::size_t agent) {
  Cell cell = text_cell(name);
  cell.sort_value = static_cast<double>(agent);
  cell.swatch = agent_color(agent);
  return cell;
}

// Runs `read`; an exception becomes a problem of the page and the section is left out.
void attempt(std::vector<std::string>& problems, const std::function<void()>& read) {
  try {
    read();
  } catch (const std::exception& e) {
    problems.push_back(e.what());
  }
}

// A row's agent column as an index; throws std::runtime_error naming the file and line where it
// is not one.
std::size_t agent_index(double agent, const CsvFile& csv, std::size_t row) {
  if (!(agent >= 0.0 && agent < 1e6) || agent != std::floor(agent)) {
    throw std::runtime_error(csv.path() + ":" + std::to_string(row + 2) + ": agent '" +
                             base::format_csv_number(agent) + "' is not an index");
  }
  return static_cast<std::size_t>(agent);
}

struct RunFacts {
  std::vector<std::string> names;  // by agent index
  std::string name(std::size_t agent) const {
    return agent < names.size() ? names[agent] : "agent " + std::to_string(agent);
  }
};

// summary.json: the facts under the title and the agents' table.
void add_summary(const std::filesystem::path& dir, Page& page, RunFacts& facts) {
  const std::string path = (dir / "summary.json").string();
  std::error_code unreadable;
  if (!std::filesystem::exists(path, unreadable)) {
    throw std::runtime_error(path + ": missing");
  }
  YAML::Node summary;
  try {
    summary = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  const std::string scenario = summary["scenario"].as<std::string>("?");
  page.title = "flowsteer run: " + scenario;
  page.facts.push_back("rule on arrival: " + summary["arrival"].as<std::string>("?") + ", " +
                       std::to_string(summary["steps"].as<int>(0)) + " steps, " +
                       number_cell(summary["duration_s"].as<double>(NAN), 2).text +
                       " s simulated, " + std::to_string(summary["collisions_total"].as<int>(0)) +
                       " collisions");
  Table table;
  table.heading = "Agents";
  table.columns = {"agent",         "reached goal", "time to goal", "path length",
                   "min clearance", "collisions",   "spinning"};
  table.sortable = true;
  const YAML::Node agents = summary["agents"];
  for (std::size_t i = 0; agents && i < agents.size(); ++i) {
    const YAML::Node a = agents[i];
    facts.names.push_back(a["name"].as<std::string>("agent " + std::to_string(i)));
    const bool reached = a["reached_goal"].as<bool>(false);
    const int collisions = a["collisions"].as<int>(0);
    Cell collided = number_cell(collisions, 0);
    collided.alert = collisions > 0;
    Cell arrived = number_cell(reached ? 1.0 : 0.0, 0);
    arrived.text = reached ? "yes" : "no";
    arrived.alert = !reached;
    table.rows.push_back({agent_cell(facts.names.back(), i), arrived,
                          number_cell(a["time_to_goal_s"].as<double>(NAN), 2, " s"),
                          number_cell(a["path_length_m"].as<double>(NAN), 2, " m"),
                          number_cell(a["min_clearance_m"].as<double>(NAN), 3, " m"), collided,
                          number_cell(a["spinning_s"].as<double>(NAN), 2, " s")});
  }
  page.sections.emplace_back(std::move(table));
}

// Every agent's values of one column over time, one series per agent.
std::vector<Series> per_agent(const CsvFile& csv, const std::string& column,
                              const RunFacts& facts) {
  const std::vector<double>& t = csv.numbers("t");
  const std::vector<double>& agent = csv.numbers("agent");
  const std::vector<double>& values = csv.numbers(column);
  std::vector<Series> series;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    const std::size_t i = agent_index(agent[r], csv, r);
    while (series.size() <= i) {
      series.push_back({facts.name(series.size()), agent_color(series.size()), {}, {}});
    }
    series[i].t_s.push_back(t[r]);
    series[i].values.push_back(values[r]);
  }
  return series;
}

// The run's contacts; none where collisions.csv cannot be read (a problem of the page).
std::optional<std::vector<Contact>> contacts_if_read(const std::filesystem::path& dir, Page& page) {
  std::optional<std::vector<Contact>> contacts;
  attempt(page.problems, [&] { contacts = read_contacts(dir); });
  return contacts;
}

void add_contacts(const std::optional<std::vector<Contact>>& read, Page& page,
                  const RunFacts& facts) {
  if (!read) {
    page.sections.emplace_back(Text{"Contacts", {"Unknown: collisions.csv could not be read."}});
    return;
  }
  const std::vector<Contact>& contacts = *read;
  Table table;
  table.heading = "Contacts";
  table.columns = {"t", "agent", "with"};
  for (const Contact& c : contacts) {
    Cell with = text_cell(c.with);
    with.alert = true;
    table.rows.push_back(
        {number_cell(c.t_s, 2, " s"), agent_cell(facts.name(c.agent), c.agent), with});
  }
  if (contacts.empty()) {
    page.sections.emplace_back(Text{"Contacts", {"No contact."}});
  } else {
    page.sections.emplace_back(std::move(table));
  }
}

// A plot over time with the run's contacts marked.
Plot contacts_plot(std::string title, std::string y_label, const std::vector<double>& marks_t_s) {
  Plot plot;
  plot.title = std::move(title);
  plot.y_label = std::move(y_label);
  plot.marks_t_s = marks_t_s;
  plot.marks_label = "contact";
  return plot;
}

// trajectories.csv's plots: speed, turn rate, clearance, smallest time to contact.
void add_motion_plots(const std::filesystem::path& dir, const std::vector<double>& marks_t_s,
                      Page& page, const RunFacts& facts) {
  const CsvFile csv(dir / "trajectories.csv");
  const struct {
    const char* column;
    const char* title;
    const char* y_label;
    std::optional<double> cap;
    const char* empty;
  } plots[] = {
      {"v", "Speed", "speed (m/s)", {}, "no motion recorded"},
      {"omega", "Turn rate commanded (positive: right)", "turn rate (rad/s)", {}, "no commands"},
      {"clearance_m", "Clearance to the nearest body (drawn up to 3 m)", "clearance (m)",
       kClearanceCapM, "no other body"},
      {"min_ttc_s", "Smallest time to contact seen (drawn up to 10 s)", "time to contact (s)",
       kTtcCapS, "nothing seen approaching"},
  };
  for (const auto& p : plots) {
    if (!csv.has_column(p.column)) {
      page.problems.push_back((dir / "trajectories.csv").string() + ": no column '" + p.column +
                              "' (an older flowsteer wrote it): its plot is left out");
      continue;
    }
    Plot plot = contacts_plot(p.title, p.y_label, marks_t_s);
    plot.series = per_agent(csv, p.column, facts);
    thin(plot);
    plot.y_max = p.cap;
    plot.empty_note = p.empty;
    page.sections.emplace_back(std::move(plot));
  }
}

// costs.csv's plots: each cost term and the total, per agent.
void add_cost_plots(const std::filesystem::path& dir, const std::vector<double>& marks_t_s,
                    Page& page, const RunFacts& facts) {
  const CsvFile csv(dir / "costs.csv");
  for (const std::string& column : csv.header()) {
    if (column == "t" || column == "agent") {
      continue;
    }
    Plot plot = contacts_plot("Cost term: " + column, "cost", marks_t_s);
    plot.series = per_agent(csv, column, facts);
    thin(plot);
    plot.empty_note = "no agent has this term";
    page.sections.emplace_back(std::move(plot));
  }
}

void add_videos(const std::filesystem::path& dir, Page& page, const RunFacts& facts) {
  Links videos;
  videos.heading = "The agents' views (videos)";
  for (std::size_t i = 0; i < std::max<std::size_t>(facts.names.size(), 1); ++i) {
    const std::string file = "agent_" + std::to_string(i) + ".mp4";
    std::error_code unreadable;  // a video that cannot be looked at is not linked
    if (std::filesystem::exists(dir / file, unreadable)) {
      videos.links.emplace_back(facts.name(i) + ": " + file, file);
    }
  }
  if (!videos.links.empty()) {
    page.sections.emplace_back(std::move(videos));
  }
}

}  // namespace

std::vector<Contact> read_contacts(const std::filesystem::path& run_dir) {
  const CsvFile csv(run_dir / "collisions.csv", {"with"});
  const std::vector<std::string>& with = csv.texts("with");
  const std::vector<double>& t = csv.numbers("t");
  const std::vector<double>& agent = csv.numbers("agent");
  std::vector<Contact> contacts;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    contacts.push_back({t[r], agent_index(agent[r], csv, r), with[r]});
  }
  return contacts;
}

std::vector<std::string> write_run_report(const std::filesystem::path& run_dir) {
  Page page;
  // The folder's name until summary.json names the scenario; sim writes from a staging folder.
  page.title = "flowsteer run: " + run_dir.filename().string();
  RunFacts facts;
  attempt(page.problems, [&] { add_summary(run_dir, page, facts); });
  page.sections.emplace_back(Picture{"From above", run_dir / "topview.png"});
  const std::optional<std::vector<Contact>> contacts = contacts_if_read(run_dir, page);
  add_contacts(contacts, page, facts);
  std::vector<double> marks_t_s;
  for (const Contact& c : contacts.value_or(std::vector<Contact>{})) {
    marks_t_s.push_back(c.t_s);
  }
  attempt(page.problems, [&] { add_motion_plots(run_dir, marks_t_s, page, facts); });
  attempt(page.problems, [&] { add_cost_plots(run_dir, marks_t_s, page, facts); });
  add_videos(run_dir, page, facts);
  write_page(run_dir / "report.html", page);
  return page.problems;
}

}  // namespace flowsteer::report
