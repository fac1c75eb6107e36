// `flowsteer eval suite` and `eval merge` (issue 20): SteerSuite's composite score on hand-made
// trajectories, a suite run in worker processes, shards merged into the unsharded result, and the
// errors of bad shards and failing runs.
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/eval/suite.hpp"
#include "process_pool.hpp"
#include "suite_files.hpp"

namespace flowsteer::eval {
namespace {

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SuiteScore, EffortIsTheActiveTimeAndTheSumOfHalfTheSquaredSpeeds) {
  // Four steps of 0.5 s: at 1 m/s, 1 m/s, 2 m/s and standing.
  const std::vector<Eigen::Vector2d> path = {
      {0.0, 0.0}, {0.5, 0.0}, {0.5, 0.5}, {1.5, 0.5}, {1.5, 0.5}};
  const sim::Effort effort = sim::steersuite_effort(path, 0.5);
  EXPECT_DOUBLE_EQ(effort.active_time_s, 2.0);
  EXPECT_DOUBLE_EQ(effort.kinetic_energy_sum, 0.5 + 0.5 + 2.0 + 0.0);
  // SteerSuite's weights: 50 per collision, 1 per second, 1 per unit of effort.
  EXPECT_DOUBLE_EQ(composite01(3, effort), 150.0 + 2.0 + 3.0);
  EXPECT_DOUBLE_EQ(
      composite01(0, sim::steersuite_effort(std::vector<Eigen::Vector2d>{{1, 1}}, 0.05)), 0.0);
}

TEST(SuiteScore, ARunsScoresAreMeansOverItsAgents) {
  sim::SimResult result;
  sim::AgentResult straight;  // reached a goal 10 m away along a 12 m path, no collision
  straight.reached_goal = true;
  straight.time_to_goal_s = 10.0;
  straight.path_length_m = 12.0;
  straight.straight_line_m = 10.0;
  straight.preferred_speed_mps = 1.25;
  straight.active_time_s = 10.0;
  straight.kinetic_energy_sum = 20.0;
  straight.min_clearance_m = 0.4;
  straight.turn_rates = {0.0, 0.2, 1.5, 0.4};  // two changes of 1 rad/s or more out of three
  sim::AgentResult bumped;                     // two collisions, did not arrive
  bumped.path_length_m = 5.0;
  bumped.straight_line_m = 8.0;
  bumped.active_time_s = 30.0;
  bumped.kinetic_energy_sum = 4.0;
  bumped.collisions = 2;
  bumped.min_clearance_m = -0.1;
  bumped.turn_rates = {0.0, 0.5};
  result.agents = {straight, bumped};
  // The bumped agent's two contacts: one with another agent, which the run counts once, and one
  // with a wall.
  result.collisions.resize(2);
  result.collisions[1].body = sim_camera::Body::obstacle;
  const sim::RunSummary s = sim::summarize(result);
  EXPECT_EQ(s.collisions, 2);
  EXPECT_EQ(s.obstacle_collisions, 1);
  EXPECT_EQ(s.goals_reached, 1);
  EXPECT_FALSE(s.clean());
  EXPECT_DOUBLE_EQ(s.mean_path_length_ratio, 1.2);  // only agents that arrived
  EXPECT_DOUBLE_EQ(s.mean_time_ratio, 1.25);        // 10 s for what takes 8 s at 1.25 m/s
  EXPECT_DOUBLE_EQ(s.min_clearance_m, -0.1);
  EXPECT_DOUBLE_EQ(s.composite01, ((0 + 10 + 20) + (100 + 30 + 4)) / 2.0);
  EXPECT_DOUBLE_EQ(s.turn_flip_ratio, 2.0 / 4.0);
}

TEST(SuiteScore, AnAgentsEffortStopsWhenItReachesItsGoal) {
  sim::SimOptions options;
  options.write_outputs = false;
  options.resolution = 32;
  const sim_camera::WorldSpec world = config::parse_scenario(
      "step_s: 0.1\nduration_s: 5\nagents:\n"
      "  - {start: [0, 0], heading_deg: 0, speed_mps: 1, goal: [2, 0]}\n"
      "  - {start: [0, 5], heading_deg: 0, speed_mps: 1, goal: [30, 5]}\n",
      "walk.yaml");
  std::ostream quiet(nullptr);
  const sim::SimResult result = sim::run_simulation(world, options, quiet);
  ASSERT_EQ(result.agents.size(), 2U);
  const sim::AgentResult& a = result.agents[0];
  ASSERT_TRUE(a.reached_goal);
  EXPECT_NEAR(a.active_time_s, a.time_to_goal_s, 0.1 + 1e-9);
  EXPECT_LT(a.active_time_s, result.duration_s);
  // 2 m to the goal, which it reaches on the goal's circle.
  EXPECT_DOUBLE_EQ(a.straight_line_m, 2.0 - world.agents[0].goal_radius_m);
  const sim::RunSummary s = sim::summarize(result);
  EXPECT_GE(s.mean_path_length_ratio, 1.0);
  EXPECT_LT(s.mean_path_length_ratio, 1.1);  // straight, overshooting the circle by a step
  // It walks at its preferred speed from the start: its time is the straight line's, and a step.
  EXPECT_DOUBLE_EQ(s.mean_time_ratio,
                   a.time_to_goal_s * world.agents[0].preferred_speed_mps / a.straight_line_m);
  EXPECT_GE(s.mean_time_ratio, 1.0);
  EXPECT_LT(s.mean_time_ratio, 1.1);
  const sim::AgentResult& b = result.agents[1];  // walks the whole run
  EXPECT_NEAR(b.active_time_s, result.duration_s, 1e-9);
  EXPECT_NEAR(s.composite01,
              (a.active_time_s + a.kinetic_energy_sum + b.active_time_s + b.kinetic_energy_sum) / 2,
              1e-9);
}

SuiteRun run_with(int collisions, int obstacle_collisions, int goals_reached) {
  SuiteRun run;
  run.case_name = "case";
  run.summary.agents = 4;
  run.summary.collisions = collisions;
  run.summary.obstacle_collisions = obstacle_collisions;
  run.summary.goals_reached = goals_reached;
  return run;
}

TEST(SuiteContactSheet, EachRunSaysWhyItIsNotClean) {
  EXPECT_EQ(run_verdict(run_with(0, 0, 4)), "clean");
  EXPECT_EQ(run_verdict(run_with(2, 1, 4)), "2 collisions (1 with obstacles)");
  EXPECT_EQ(run_verdict(run_with(1, 0, 3)), "1 collision, goals 3/4");
  EXPECT_EQ(run_verdict(run_with(0, 0, 3)), "goals 3/4");
  SuiteRun failed;
  failed.error = "worker killed by signal 9";
  EXPECT_EQ(run_verdict(failed), "failed: worker killed by signal 9");
}

TEST(SuiteContactSheet, ConfigurationsNameWhatTheySet) {
  EXPECT_EQ(configuration_label({}), "the case's own settings");
  SuiteConfiguration c;
  c.flow = servo::FlowMethod::dis_fast;
  c.resolution = 64;
  c.camera_noise_levels = 2.5;
  EXPECT_EQ(configuration_label(c), "flow dis_fast, 64 px, noise 2.5");
}

// Red (kSheetRed) pixels in `image`.
int red_pixels(const cv::Mat& image) {
  cv::Mat red;
  cv::inRange(image, cv::Scalar(0, 0, 200), cv::Scalar(60, 60, 255), red);
  return cv::countNonZero(red);
}

TEST(SuiteContactSheet, OnlyRunsThatAreNotCleanAreFramedAndCaptionedInRed) {
  SuiteRun clean = run_with(0, 0, 4);
  SuiteRun bumped = run_with(2, 0, 4);
  bumped.index = 1;
  // No top views: each tile says so in grey, so that only frames and verdicts are red.
  const cv::Mat sheet = contact_sheet({clean, bumped}, "/nonexistent");
  ASSERT_EQ(sheet.cols % 2, 0);
  const cv::Mat left = sheet.colRange(0, sheet.cols / 2);
  const cv::Mat right = sheet.colRange(sheet.cols / 2, sheet.cols);
  // The frame: 6 px wide round a 400 px tile.
  EXPECT_GT(red_pixels(right), 4 * 400 * 5);
  EXPECT_EQ(red_pixels(left), 0);
}

TEST(WorkerProcesses, EachTaskEndsOnItsOwnAndNoneStopsTheOthers) {
  std::vector<TaskOutcome> outcomes(5);
  run_in_processes(
      outcomes.size(), 3,
      [](std::size_t i) -> std::string {
        switch (i) {
          case 1:
            throw std::runtime_error("task 1 threw");
          case 2:
            std::abort();
          case 3:
            std::_Exit(3);
          default:
            return "task " + std::to_string(i) + std::string(i == 4 ? 2 * kMaxTaskRecord : 0, '!');
        }
      },
      [&](std::size_t i, const TaskOutcome& outcome) { outcomes.at(i) = outcome; });
  EXPECT_EQ(outcomes[0].record, "task 0");
  EXPECT_TRUE(outcomes[0].ok());
  EXPECT_EQ(outcomes[1].error, "task 1 threw");
  EXPECT_NE(outcomes[2].error.find("killed by signal 6"), std::string::npos) << outcomes[2].error;
  EXPECT_NE(outcomes[3].error.find("exited with status 3 without a result"), std::string::npos)
      << outcomes[3].error;
  EXPECT_EQ(outcomes[4].record.size(), kMaxTaskRecord);  // cut, not blocking the worker
}

TEST(WorkerProcesses, ATerminationRequestStopsTheWorkersAndThrows) {
  std::size_t ended = 0;
  const std::string error = error_of([&] {
    run_in_processes(
        3, 3,
        [](std::size_t i) -> std::string {
          if (i > 0) {
            ::sleep(600);  // stopped long before
          }
          return "";
        },
        [&](std::size_t, const TaskOutcome&) {
          ++ended;
          std::raise(SIGTERM);
        });
  });
  EXPECT_EQ(ended, 1U);
  EXPECT_NE(error.find("interrupted"), std::string::npos) << error;
}

TEST(SuiteShard, BadSpecsAreRefusedByName) {
  for (const char* spec : {"3/2", "x/4", "1/0", "-1/2", "1/2x", "2", "1/2/3"}) {
    const std::string error = error_of([&] { parse_shard(spec); });
    EXPECT_NE(error.find(std::string("--shard ") + spec), std::string::npos) << error;
  }
  const Shard shard = parse_shard("2/5");
  EXPECT_EQ(shard.index, 2);
  EXPECT_EQ(shard.count, 5);
}

SuiteCase walk_case(const std::string& name, double goal_x_m) {
  const std::string text =
      "step_s: 0.1\nduration_s: 3\nagents:\n"
      "  - {start: [0, 0], heading_deg: 0, speed_mps: 1, goal: [" +
      std::to_string(goal_x_m) + ", 0]}\n";
  return {name, name + ".yaml", text, config::parse_scenario(text, name + ".yaml")};
}

// A follower cannot steer by motion energy: with --controller motion_energy this case's run fails
// in its worker.
SuiteCase follower_case() {
  const std::string text =
      "step_s: 0.1\nduration_s: 3\nagents:\n"
      "  - {start: [0, 0], heading_deg: 0, goal: [3, 0]}\n"
      "  - {start: [-2, 0], heading_deg: 0, leader: 0}\n";
  return {"follow", "follow.yaml", text, config::parse_scenario(text, "follow.yaml")};
}

class SuiteRunTest : public ::testing::Test {
 protected:
  // One folder per test and process: ctest runs them in parallel, maybe two checkouts at once.
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               (std::string("flowsteer_suite_test_") +
                                ::testing::UnitTest::GetInstance()->current_test_info()->name() +
                                "_" + std::to_string(::getpid()));
  std::vector<SuiteCase> cases_ = {walk_case("near", 1.5), walk_case("far", 30.0), follower_case()};
  void SetUp() override { std::filesystem::remove_all(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  SuiteOptions options(const std::string& out) const {
    SuiteOptions o;
    o.controllers = {servo::SteeringModel::geometric, servo::SteeringModel::motion_energy};
    o.resolutions = {24};
    o.jobs = 2;
    o.out_dir = dir_ / out;
    return o;
  }
};

TEST_F(SuiteRunTest, EveryCaseRunsUnderEveryConfigurationAndAFailureStopsNoOther) {
  std::ostringstream log;
  const SuiteResult result = run_suite(cases_, options("all"), log);
  ASSERT_EQ(result.runs.size(), 6U);
  EXPECT_EQ(result.suite_runs, 6U);
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(result.runs[k].index, k);
  }
  EXPECT_TRUE(result.runs[0].clean()) << result.runs[0].error;  // near, geometric
  EXPECT_FALSE(result.runs[2].clean());                         // far: not reached in 3 s
  EXPECT_FALSE(result.runs[2].failed());
  EXPECT_TRUE(result.runs[4].clean()) << result.runs[4].error;  // follow, geometric
  ASSERT_TRUE(result.runs[5].failed());                         // follow, motion energy
  EXPECT_NE(result.runs[5].error.find("motion"), std::string::npos) << result.runs[5].error;

  const std::filesystem::path out = dir_ / "all";
  const std::string csv = file_text(out / "suite.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 7);
  EXPECT_NE(csv.find("5,follow,own,own,own,motion_energy,own,own,24,failed,"), std::string::npos)
      << csv;
  EXPECT_NE(csv.find("0,near,own,own,own,geometric,own,own,24,clean,1,1,1,0,"), std::string::npos)
      << csv;
  EXPECT_TRUE(std::filesystem::exists(out / "contact_sheet.png"));
  EXPECT_TRUE(std::filesystem::exists(out / "suite.json"));
  EXPECT_NE(file_text(out / "suite.txt").find("clean 2 of 3 cases"), std::string::npos);
  // Top views of every run that got one; folders only for the runs that are not clean.
  EXPECT_TRUE(
      std::filesystem::exists(out / "topviews" / "near.own.own.own.geometric.own.own.24.png"));
  EXPECT_FALSE(std::filesystem::exists(out / "runs" / "near.own.own.own.geometric.own.own.24"));
  EXPECT_TRUE(std::filesystem::exists(out / "runs" / "far.own.own.own.geometric.own.own.24" /
                                      "trajectories.csv"));
  EXPECT_TRUE(std::filesystem::exists(out / "runs" / "follow.own.own.own.motion_energy.own.own.24" /
                                      "error.txt"));
  for (const auto& entry : std::filesystem::directory_iterator(out)) {
    EXPECT_EQ(entry.path().filename().string().rfind(".staging", 0), std::string::npos);
  }
}

TEST_F(SuiteRunTest, ThreeShardsMergedAreTheUnshardedSuite) {
  std::ostringstream log;
  run_suite(cases_, options("whole"), log);
  std::vector<std::filesystem::path> shards;
  for (int i = 0; i < 3; ++i) {
    SuiteOptions o = options("shard" + std::to_string(i));
    o.shard = {i, 3};
    o.jobs = 1;
    EXPECT_EQ(run_suite(cases_, o, log).runs.size(), 2U);
    shards.push_back(o.out_dir);
  }
  const SuiteResult merged = merge_suite_shards({shards[2], shards[0], shards[1]}, dir_ / "merged");
  EXPECT_EQ(merged.runs.size(), 6U);
  for (const char* file : {"suite.csv", "suite.txt"}) {
    EXPECT_EQ(file_text(dir_ / "merged" / file), file_text(dir_ / "whole" / file)) << file;
  }
  EXPECT_TRUE(std::filesystem::exists(dir_ / "merged" / "contact_sheet.png"));
  EXPECT_TRUE(
      std::filesystem::exists(dir_ / "merged" / "runs" / "far.own.own.own.geometric.own.own.24"));

  // A shard missing, one given twice, or a shard of another suite are refused by name.
  EXPECT_NE(error_of([&] {
              merge_suite_shards({shards[0], shards[1]}, dir_ / "m2");
            }).find("shard 2/3 of suite"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              merge_suite_shards({shards[0], shards[0], shards[1]}, dir_ / "m3");
            }).find("is also in"),
            std::string::npos);
  SuiteOptions other = options("other");
  other.shard = {1, 3};
  other.seed = 7;
  run_suite(cases_, other, log);
  EXPECT_NE(file_text(other.out_dir / "suite.json").find("\"seed\": 7,"), std::string::npos);
  const std::string mixed = error_of([&] {
    merge_suite_shards({shards[0], other.out_dir, shards[2]}, dir_ / "m4");
  });
  EXPECT_NE(mixed.find("other"), std::string::npos) << mixed;
  EXPECT_NE(mixed.find("not of suite"), std::string::npos) << mixed;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "m4" / "suite.csv"));
  EXPECT_NE(error_of([&] { merge_suite_shards({dir_}, dir_ / "m5"); }).find("no suite.json"),
            std::string::npos);
}

TEST_F(SuiteRunTest, RepeatedConfigurationsAndCaseNamesAreRefused) {
  std::ostringstream log;
  SuiteOptions o = options("bad");
  o.resolutions = {24, 24};
  EXPECT_NE(error_of([&] { run_suite(cases_, o, log); }).find("--resolution 24: given twice"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              run_suite({walk_case("a", 1.0), walk_case("a", 2.0)}, options("bad"), log);
            }).find("a second case named 'a'"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad" / "suite.csv"));
}

// An ablation: each mechanism switched off is a configuration of its own, beside the law as it is
// (none), read back by a merge; only the flowsteer law has them.
TEST_F(SuiteRunTest, EachMechanismSwitchedOffIsAConfigurationOfItsOwn) {
  std::ostringstream log;
  SuiteOptions o = options("ablation");
  o.controllers = {servo::SteeringModel::geometric};
  o.switched_off = {servo::LawMechanism::none, servo::LawMechanism::braking};
  const SuiteResult result = run_suite({walk_case("near", 1.5)}, o, log);
  ASSERT_EQ(result.runs.size(), 2U);
  EXPECT_TRUE(result.runs[0].clean()) << result.runs[0].error;
  const std::string csv = file_text(o.out_dir / "suite.csv");
  EXPECT_NE(csv.find("0,near,own,own,own,geometric,own,none,24,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("1,near,own,own,own,geometric,own,braking,24,"), std::string::npos) << csv;
  const SuiteResult merged = merge_suite_shards({o.out_dir}, dir_ / "merged");
  ASSERT_EQ(merged.runs.size(), 2U);
  EXPECT_EQ(merged.runs[1].configuration.without, servo::LawMechanism::braking);
  EXPECT_EQ(merged.runs[1].folder_name(), "near.own.own.own.geometric.own.braking.24");

  o.laws = {servo::NavigationLaw::flowsteer, servo::NavigationLaw::cgf2019};
  EXPECT_NE(error_of([&] { run_suite(cases_, o, log); })
                .find("--without braking: switches off a mechanism of the flowsteer law, which "
                      "--law cgf2019 does not have"),
            std::string::npos);
}

// The depth a simulated agent's features get (the renderer's per pixel, or the ground's as a
// camera's) is a dimension of its own, after the segmentation, read back by a merge.
TEST_F(SuiteRunTest, TheDepthSourceIsAConfigurationOfItsOwn) {
  std::ostringstream log;
  SuiteOptions o = options("depth");
  o.controllers = {};
  o.depths = {servo::DepthSource::renderer, servo::DepthSource::ground};
  const SuiteResult result = run_suite({walk_case("near", 1.5)}, o, log);
  ASSERT_EQ(result.runs.size(), 2U);
  EXPECT_TRUE(result.runs[0].clean()) << result.runs[0].error;
  EXPECT_TRUE(result.runs[1].clean()) << result.runs[1].error;
  const std::string csv = file_text(o.out_dir / "suite.csv");
  EXPECT_NE(csv.find("0,near,own,own,renderer,own,own,own,24,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("1,near,own,own,ground,own,own,own,24,"), std::string::npos) << csv;
  const SuiteResult merged = merge_suite_shards({o.out_dir}, dir_ / "merged");
  ASSERT_EQ(merged.runs.size(), 2U);
  EXPECT_EQ(merged.runs[1].configuration.depth, servo::DepthSource::ground);
  EXPECT_EQ(merged.runs[1].folder_name(), "near.own.own.ground.own.own.own.24");

  o.depths = {servo::DepthSource::ground, servo::DepthSource::ground};
  EXPECT_NE(error_of([&] { run_suite(cases_, o, log); }).find("--depth ground: given twice"),
            std::string::npos);
}

// The camera noise is a configuration of its own, after the resolution, with a column of its own
// that a suite without it does not have (its suite.csv is the one it wrote before the axis was).
TEST_F(SuiteRunTest, TheCameraNoiseIsAConfigurationOfItsOwn) {
  std::ostringstream log;
  SuiteOptions o = options("noise");
  o.controllers = {servo::SteeringModel::geometric};
  o.camera_noise_levels = {0.0, 2.5};
  const SuiteResult result = run_suite({walk_case("near", 1.5)}, o, log);
  ASSERT_EQ(result.runs.size(), 2U);
  EXPECT_TRUE(result.runs[1].clean()) << result.runs[1].error;
  const std::string csv = file_text(o.out_dir / "suite.csv");
  EXPECT_EQ(csv.rfind("run,case,flow,segmentation,depth,controller,law,without,resolution,"
                      "camera_noise,status,",
                      0),
            0U)
      << csv;
  EXPECT_NE(csv.find("0,near,own,own,own,geometric,own,own,24,0,clean,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("1,near,own,own,own,geometric,own,own,24,2.5,clean,"), std::string::npos)
      << csv;
  const SuiteResult merged = merge_suite_shards({o.out_dir}, dir_ / "merged");
  ASSERT_EQ(merged.runs.size(), 2U);
  EXPECT_EQ(merged.runs[1].configuration.camera_noise_levels, 2.5);
  EXPECT_EQ(merged.runs[1].folder_name(), "near.own.own.own.geometric.own.own.24.2.5");
  EXPECT_EQ(file_text(dir_ / "merged" / "suite.csv"), csv);

  SuiteOptions plain = options("plain");
  plain.controllers = {servo::SteeringModel::geometric};
  run_suite({walk_case("near", 1.5)}, plain, log);
  EXPECT_EQ(file_text(plain.out_dir / "suite.csv")
                .rfind("run,case,flow,segmentation,depth,controller,law,without,resolution,"
                       "status,agents,",
                       0),
            0U);

  o.camera_noise_levels = {2.0, 2.0};
  EXPECT_NE(error_of([&] { run_suite(cases_, o, log); }).find("--camera-noise 2: given twice"),
            std::string::npos);
}

}  // namespace
}  // namespace flowsteer::eval
