// The report pages: the CSV reader names what is wrong, plots draw every series (gaps where a
// value is missing, spikes kept when a long series is thinned), a page says which picture it
// could not read, and a run folder's page shows its files and names the ones missing.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "csv_file.hpp"
#include "flowsteer/report/page.hpp"
#include "flowsteer/report/run_report.hpp"

namespace {

using namespace flowsteer::report;

class Folder : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("flowsteer_report_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  std::string read(const std::string& name) {
    std::stringstream text;
    text << std::ifstream(dir_ / name).rdbuf();
    return text.str();
  }
  // A run of two agents over three steps; agent 1 touches obstacle 2 at t = 0.1 s.
  void write_run() {
    write("summary.json",
          R"({"scenario": "two", "arrival": "stay", "steps": 3, "duration_s": 0.15, "agents": [
  {"name": "ann", "reached_goal": true, "time_to_goal_s": 0.1, "path_length_m": 1,
   "min_clearance_m": 0.5, "collisions": 0, "spinning_s": 0},
  {"name": "bob", "reached_goal": false, "time_to_goal_s": null, "path_length_m": 1,
   "min_clearance_m": -0.01, "collisions": 1, "spinning_s": 0}],
 "collisions_total": 1})");
    write("trajectories.csv",
          "t,agent,x,y,heading,v,a_c,omega,clearance_m,min_ttc_s\n"
          "0,0,0,0,0,1,0,0.1,0.5,4\n0,1,1,0,0,1,0,-0.1,0.2,\n"
          "0.05,0,0,0,0,1,0,0.1,0.6,3\n0.05,1,1,0,0,1,0,-0.1,0.1,2\n"
          "0.1,0,0,0,0,1,0,0.1,0.7,\n0.1,1,1,0,0,1,0,-0.1,-0.01,1\n");
    write("costs.csv", "t,agent,heading,clearance,total\n0,0,1,2,3\n0,1,1,,1\n");
    write("collisions.csv", "with,t,agent,x,y\nobstacle 2,0.1,1,1,0\n");
  }
  static int count(const std::string& text, const std::string& what) {
    int n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
      ++n;
    }
    return n;
  }
  std::filesystem::path dir_;
};

TEST_F(Folder, CsvFileReadsNumbersAndNamesWhatIsWrong) {
  write("a.csv", "with,t,v\nagent 1,0,2.5\nobstacle 2,0.05,\n");
  const CsvFile csv(dir_ / "a.csv", {"with"});
  EXPECT_EQ(csv.rows(), 2u);
  EXPECT_EQ(csv.numbers("v")[0], 2.5);
  EXPECT_TRUE(std::isnan(csv.numbers("v")[1]));
  EXPECT_EQ(csv.texts("with")[1], "obstacle 2");
  EXPECT_THROW(csv.numbers("omega"), std::runtime_error);
  EXPECT_THROW(csv.numbers("with"), std::runtime_error);

  auto error_of = [&](const std::string& text) {
    write("b.csv", text);
    try {
      CsvFile(dir_ / "b.csv");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("read without an error");
  };
  EXPECT_NE(error_of("t,v\n0,1\n0.05,fast\n").find("b.csv:3: column 'v': not a number: 'fast'"),
            std::string::npos);
  EXPECT_NE(error_of("t,v\n0,1,2\n").find("b.csv:2: 3 cells under a header of 2"),
            std::string::npos);
  EXPECT_NE(error_of("t,v\n0\n").find("b.csv:2: 1 cells under a header of 2"), std::string::npos);
  EXPECT_NE(error_of("").find("b.csv: empty, no header"), std::string::npos);
  EXPECT_THROW(CsvFile(dir_ / "none.csv"), std::runtime_error);
}

TEST(Plot, TickStepsAreOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_DOUBLE_EQ(tick_step(0.9), 1.0);
  EXPECT_DOUBLE_EQ(tick_step(1.2), 2.0);
  EXPECT_DOUBLE_EQ(tick_step(3.0), 5.0);
  EXPECT_DOUBLE_EQ(tick_step(0.04), 0.05);
  EXPECT_DOUBLE_EQ(tick_step(10.0), 10.0);
}

TEST(Plot, EverySeriesIsALineAndAGapBreaksIt) {
  Plot plot;
  plot.y_label = "m/s";
  plot.series.push_back({"a", agent_color(0), {0, 1, 2, 3}, {1, 2, NAN, 4}});
  plot.series.push_back({"b", agent_color(1), {0, 1}, {0.5, 0.5}});
  plot.marks_t_s = {1.5};
  plot.marks_label = "contact";
  Page page;
  page.sections = {plot};
  const std::string html = render_page(page);
  const std::regex path("<path class=\"series\" stroke=\"#[0-9a-f]{6}\" d=\"([^\"]*)\"");
  std::vector<std::string> lines;
  for (auto m = std::sregex_iterator(html.begin(), html.end(), path); m != std::sregex_iterator();
       ++m) {
    lines.push_back((*m)[1]);
  }
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(std::count(lines[0].begin(), lines[0].end(), 'M'), 2) << lines[0];  // the gap
  EXPECT_EQ(std::count(lines[1].begin(), lines[1].end(), 'M'), 1) << lines[1];
  EXPECT_NE(html.find("<line class=\"mark\""), std::string::npos);
  EXPECT_NE(html.find(">contact</text>"), std::string::npos);  // the legend names the marks
}

// One agent's series of `samples` values, one every 0.05 s.
Series series_of(int samples, double (*value)(int)) {
  Series s{"a", agent_color(0), {}, {}};
  for (int k = 0; k < samples; ++k) {
    s.t_s.push_back(0.05 * k);
    s.values.push_back(value(k));
  }
  return s;
}

TEST(Plot, AThinnedSeriesKeepsItsSpike) {
  Plot plot;
  plot.series.push_back(series_of(20000, [](int k) { return k == 12345 ? 10.0 : 1.0; }));
  Page page;
  page.sections = {plot};
  const std::string html = render_page(page);
  const std::size_t d = html.find(" d=\"");
  const std::string line = html.substr(d, html.find('"', d + 4) - d);
  const long points = std::count(line.begin(), line.end(), 'L') + 1;
  EXPECT_LE(points, 1200);
  EXPECT_GT(points, 100);
  // The spike is the plot's highest value: drawn at the top of the plot area (y = 50).
  EXPECT_NE(line.find(" 50.0"), std::string::npos) << line.substr(0, 400);
}

// A long series with gaps (a time to contact only while something approaches): each stretch
// between gaps is drawn, thinned on its own, and the spike in one of them is kept.
TEST(Plot, AThinnedSeriesWithGapsKeepsEveryStretchAndItsSpike) {
  Plot plot;
  plot.series.push_back(series_of(20000, [](int k) {
    return k % 50 < 10 ? NAN : k == 12345 ? 10.0 : 1.0;
  }));
  Page page;
  page.sections = {plot};
  const std::string html = render_page(page);
  const std::size_t d = html.find(" d=\"");
  const std::string line = html.substr(d, html.find('"', d + 4) - d);
  EXPECT_EQ(std::count(line.begin(), line.end(), 'M'), 400);  // 400 stretches between gaps
  EXPECT_LE(std::count(line.begin(), line.end(), 'L'), 1200);
  EXPECT_NE(line.find(" 50.0"), std::string::npos) << "the spike is not at the top";
}

TEST(Plot, ACrowdsPlotStaysSmall) {
  Plot plot;
  for (std::size_t i = 0; i < 200; ++i) {
    Series s{"agent", agent_color(i), {}, {}};
    for (int k = 0; k < 2400; ++k) {
      s.t_s.push_back(0.05 * k);
      s.values.push_back(std::sin(0.01 * k + static_cast<double>(i)));
    }
    plot.series.push_back(s);
  }
  Page page;
  page.sections = {plot};
  const std::string html = render_page(page);
  const long points = std::count(html.begin(), html.end(), 'L') + 200;
  EXPECT_LE(points, 24000 + 200);  // the plot's 24000 points shared by its 200 lines
  EXPECT_LT(html.size(), 1'000'000u);
}

TEST_F(Folder, APictureThatCannotBeReadIsNamedOnThePage) {
  Page page;
  page.sections = {Picture{"From above", dir_ / "topview.png"}};
  const std::string html = render_page(page);
  ASSERT_EQ(page.problems.size(), 1u);
  EXPECT_EQ(page.problems[0], "topview.png: missing or unreadable");
  EXPECT_NE(html.find("topview.png: missing or unreadable"), std::string::npos);
}

TEST_F(Folder, ARunsPageShowsItsFiles) {
  write_run();
  const std::vector<std::string> problems = write_run_report(dir_);
  ASSERT_EQ(problems.size(), 1u);  // no topview.png in this folder
  EXPECT_EQ(problems[0], "topview.png: missing or unreadable");
  const std::string html = read("report.html");
  EXPECT_NE(html.find("<title>flowsteer run: two</title>"), std::string::npos);
  // Speed, turn rate, clearance, time to contact, and heading, clearance, total from costs.csv.
  EXPECT_EQ(count(html, "<svg class=\"plot\""), 7);
  EXPECT_EQ(count(html, "<title>contact at t = 0.10 s</title>"), 7);  // on every plot
  EXPECT_NE(html.find(">obstacle 2</td>"), std::string::npos);
  EXPECT_NE(html.find(">bob</td>"), std::string::npos);
  EXPECT_NE(html.find("table class=\"sortable\""), std::string::npos);
  EXPECT_NE(html.find("data-sort="), std::string::npos);
}

TEST_F(Folder, ARunFolderMissingAFileGivesAPageThatSaysWhich) {
  write_run();
  std::filesystem::remove(dir_ / "costs.csv");
  write("trajectories.csv", "t,agent,x,y,heading,v,a_c,omega\n0,0,0,0,0,1,0,0\n");
  const std::vector<std::string> problems = write_run_report(dir_);
  const std::string html = read("report.html");
  for (const std::string& expected :
       {std::string("costs.csv: missing or unreadable"),
        std::string("trajectories.csv: no column 'clearance_m'"), std::string("topview.png")}) {
    EXPECT_TRUE(std::any_of(problems.begin(), problems.end(), [&](const std::string& p) {
      return p.find(expected) != std::string::npos;
    })) << expected;
    EXPECT_NE(html.find(expected), std::string::npos) << expected;
  }
  EXPECT_EQ(count(html, "<svg class=\"plot\""), 2);  // speed and turn rate
}

TEST_F(Folder, ContactsAreReadAndABadRowIsNamed) {
  write("collisions.csv", "with,t,agent,x,y\nagent 3,1.5,0,0,0\nobstacle 1,2,2,0,0\n");
  const std::vector<Contact> contacts = read_contacts(dir_);
  ASSERT_EQ(contacts.size(), 2u);
  EXPECT_EQ(contacts[1].with, "obstacle 1");
  EXPECT_EQ(contacts[1].agent, 2u);
  EXPECT_EQ(contacts[0].t_s, 1.5);
  write("collisions.csv", "with,t,agent,x,y\nagent 3,1.5,-1,0,0\n");
  try {
    read_contacts(dir_);
    FAIL() << "a negative agent index was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("collisions.csv:2: agent '-1' is not an index"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
