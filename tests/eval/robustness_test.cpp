// `flowsteer eval robustness` (issue 4): a scenario over resolutions and perception methods, each
// run summarised and counted clean or not.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/eval/robustness.hpp"

namespace flowsteer::eval {
namespace {

using namespace flowsteer::config;

// One agent on open ground with its goal 3 m ahead, and one with a goal it cannot reach in the
// scenario's 4 s.
sim_camera::WorldSpec open_ground(double far_goal_x_m) {
  return parse_scenario(
      "step_s: 0.1\nduration_s: 4\ncamera: {resolution: 40}\nagents:\n"
      "  - {start: [0, 0], heading_deg: 0, speed_mps: 1, goal: [3, 0]}\n"
      "  - {start: [0, 6], heading_deg: 0, speed_mps: 1, goal: [" +
          std::to_string(far_goal_x_m) + ", 6]}\n",
      "open_ground.yaml");
}

TEST(Robustness, DefaultResolutionsAreTheScenariosOwnAndFourStepsEitherSide) {
  const std::vector<int> around_128 = robustness_resolutions(builtin_scenario("room"), {});
  EXPECT_EQ(around_128, (std::vector<int>{96, 104, 112, 120, 128, 136, 144, 152, 160}));
  // Below 16 pixels there is nothing to see: those are left out.
  const std::vector<int> around_40 = robustness_resolutions(open_ground(4.0), {});
  EXPECT_EQ(around_40, (std::vector<int>{16, 24, 32, 40, 48, 56, 64, 72}));
}

TEST(Robustness, BadResolutionsAreRefusedByName) {
  RobustnessOptions options;
  options.resolutions = {64, 8};
  try {
    robustness_resolutions(open_ground(4.0), options);
    ADD_FAILURE() << "8 pixels accepted";
  } catch (const base::ConfigError& e) {
    EXPECT_STREQ(e.what(), "--resolution 8: must be from 16 to 4096 pixels");
  }
  options.resolutions = {64, 48, 64};
  try {
    robustness_resolutions(open_ground(4.0), options);
    ADD_FAILURE() << "a repeated resolution accepted";
  } catch (const base::ConfigError& e) {
    EXPECT_STREQ(e.what(), "--resolution 64: given twice");
  }
}

TEST(Robustness, RunsEveryFlowAndResolutionAndCountsTheCleanOnes) {
  RobustnessOptions options;
  options.resolutions = {32, 40};
  options.flows = {servo::FlowMethod::synthetic, servo::FlowMethod::dis_ultrafast};
  options.write_outputs = false;
  std::ostringstream log;
  // Both goals within reach: every run is clean.
  const std::vector<RobustnessRun> reachable = evaluate_robustness(open_ground(4.0), options, log);
  ASSERT_EQ(reachable.size(), 4U);
  EXPECT_EQ(reachable[0].flow, servo::FlowMethod::synthetic);
  EXPECT_EQ(reachable[1].resolution, 40);
  EXPECT_EQ(reachable[2].flow, servo::FlowMethod::dis_ultrafast);
  EXPECT_FALSE(reachable[2].segmentation.has_value());
  for (const RobustnessRun& r : reachable) {
    EXPECT_EQ(r.summary.agents, 2);
    EXPECT_EQ(r.summary.goals_reached, 2) << r.resolution;
    EXPECT_TRUE(r.summary.clean()) << r.resolution;
  }
  // A goal 20 m away is not reached in 4 s: no run is clean.
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("flowsteer_robustness_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  options.write_outputs = true;
  options.out_dir = dir;
  const std::vector<RobustnessRun> unreachable =
      evaluate_robustness(open_ground(20.0), options, log);
  ASSERT_EQ(unreachable.size(), 4U);
  for (const RobustnessRun& r : unreachable) {
    EXPECT_EQ(r.summary.goals_reached, 1) << r.resolution;
    EXPECT_FALSE(r.summary.clean()) << r.resolution;
  }
  std::ostringstream table;
  print_robustness_table(reachable, table);
  EXPECT_NE(table.str().find("clean: 2 of 2 runs with flow synthetic, segmentation scenario"),
            std::string::npos)
      << table.str();
  EXPECT_NE(table.str().find("clean: 2 of 2 runs with flow dis_ultrafast, segmentation scenario"),
            std::string::npos)
      << table.str();

  std::ifstream csv(dir / "robustness.csv");
  std::string header;
  std::string first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_EQ(header.rfind("flow,segmentation,resolution,collisions,goals_reached", 0), 0U);
  EXPECT_EQ(first.rfind("synthetic,scenario,32,0,1,2,", 0), 0U) << first;
  EXPECT_EQ(first.substr(first.size() - 2), ",0") << first;
  EXPECT_TRUE(std::filesystem::exists(dir / "robustness.txt"));
  std::filesystem::remove_all(dir);
}

TEST(Robustness, AFolderThatCannotBeWrittenFailsBeforeTheFirstRun) {
  RobustnessOptions options;
  options.resolutions = {32};
  options.out_dir = "/dev/null/flowsteer_robustness";
  std::ostringstream log;
  EXPECT_THROW(evaluate_robustness(open_ground(4.0), options, log), std::runtime_error);
  EXPECT_EQ(log.str(), "");
}

TEST(Robustness, FollowersHaveNoGoalToReach) {
  sim::SimResult result;
  result.agents.resize(2);
  result.agents[0].reached_goal = true;
  result.agents[1].final_distance_to_leader_m = 1.2;
  const sim::RunSummary summary = sim::summarize(result);
  EXPECT_EQ(summary.followers, 1);
  EXPECT_TRUE(summary.clean());
  result.collisions.emplace_back();
  EXPECT_FALSE(sim::summarize(result).clean());
}

}  // namespace
}  // namespace flowsteer::eval
