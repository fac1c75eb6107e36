// A suite's page: each run's status with its reason (with whom it collided, from its kept
// folder; why it failed), a link to each kept run's page and to no other, the configurations
// in words; a comparison's page links each controller's run.

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "flowsteer/eval/suite.hpp"
#include "report_pages.hpp"

namespace flowsteer::eval {
namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

std::string read(const std::filesystem::path& path) {
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  return text.str();
}

TEST(SuitePage, SaysWhyEachRunIsNotCleanAndLinksTheKeptOnes) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("flowsteer_suite_page_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  SuiteResult result;
  result.suite_id = "0123456789abcdef";
  SuiteConfiguration dis;
  dis.flow = servo::FlowMethod::dis_medium;
  dis.resolution = 64;
  SuiteRun clean{0, "crossing_45", dis, {}, ""};
  clean.summary.agents = 2;
  clean.summary.goals_reached = 2;
  SuiteRun touched{1, "bottleneck", dis, {}, ""};
  touched.summary.agents = 3;
  touched.summary.goals_reached = 2;
  touched.summary.collisions = 1;
  touched.summary.obstacle_collisions = 1;
  SuiteRun failed{2, "circle_8", {}, {}, "the worker was killed by signal 9"};
  result.runs = {clean, touched, failed};
  // Only the run that touched something was kept, with its contacts and its page.
  const std::filesystem::path kept = dir / "runs" / touched.folder_name();
  std::filesystem::create_directories(kept);
  std::ofstream(kept / "collisions.csv") << "with,t,agent,x,y\nobstacle 2,4.3,1,0,0\n";
  std::ofstream(kept / "report.html") << "<html></html>\n";

  write_suite_page(result, dir);
  const std::string html = read(dir / "report.html");
  EXPECT_NE(
      html.find(
          "1 collision (1 with obstacles), goals 2/3; contacts: agent 1 with obstacle 2 at 4.30 s"),
      std::string::npos)
      << html;
  EXPECT_NE(html.find("failed: the worker was killed by signal 9"), std::string::npos);
  EXPECT_EQ(count(html, "<a href="), 1);
  EXPECT_NE(html.find("<a href=\"runs/" + touched.folder_name() + "/report.html\">"),
            std::string::npos);
  EXPECT_EQ(count(html, ">not kept</td>"), 2);
  EXPECT_NE(html.find("flow dis_medium, 64 px"), std::string::npos);
  EXPECT_NE(html.find("the case's own settings"), std::string::npos) << "failed run's label";
  EXPECT_NE(html.find("1 of 3 runs clean"), std::string::npos);
  // No contact sheet in this folder: the page says so.
  EXPECT_NE(html.find("contact_sheet.png: missing"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace flowsteer::eval
