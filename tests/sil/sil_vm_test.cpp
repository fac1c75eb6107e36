// Boots the simulation-in-the-loop VM (tests/vm/run_sil_vm.sh), in which `flowsteer sil` runs
// the robot's own `flowsteer run` in the loop: the robot agent's view goes out through vivid's
// output node and comes back on its capture node, the robot's wheel speeds go over vcan0 to a
// simulated ODrive pair that moves the agent. Checks the run to the goal against `flowsteer sim`
// on the same scenario here (the same robot without the loop), and the run whose capture stream
// fails against candump's record of the bus. Both runs take the launch file's timeouts
// stretched to the emulated CPU's pace (tests/vm/sil_vm_probe.cpp), so that a loaded host slows
// the loop without failing it. Each test prints its figures.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "can_capture.hpp"
#include "vm_test_support.hpp"

namespace {

using flowsteer::vm_test::CanCaptureRun;
using flowsteer::vm_test::driven;
using flowsteer::vm_test::first_zero_velocity;
using flowsteer::vm_test::stamp;
using flowsteer::vm_test::stop_bound_s;

constexpr unsigned kNodes[] = {3, 5};
// The loop's robot sees its world through an emulated CPU, a few views a second, a view late by
// its rendering and the robot's perception, where `flowsteer sim` sees every step at once: its
// path may stray this far from the simulation's (measured: 1-3 cm; 0.64 m when the world moved
// by the wheels' speeds at each step instead of their angles, as did the robot's goal tracker).
constexpr double kMaxDeviationM = 0.25;
// From the camera's loss to a zero on the bus, or the loop's pass the loss came in where the
// VM's emulated CPU makes a pass longer (stop_bound_s).
constexpr double kStopWithinS = 0.5;

struct Point {
  double t;
  double x;
  double y;
};

// The robot's (agent 0's) rows of a trajectories.csv: t, agent, x, y, ...
std::vector<Point> robot_path(const std::vector<std::string>& csv) {
  std::vector<Point> path;
  for (std::size_t i = 1; i < csv.size(); ++i) {
    double t = 0.0;
    double agent = -1.0;
    double x = 0.0;
    double y = 0.0;
    if (std::sscanf(csv[i].c_str(), "%lf,%lf,%lf,%lf", &t, &agent, &x, &y) == 4 && agent == 0.0) {
      path.push_back({t, x, y});
    }
  }
  return path;
}

// The distance from p to the polyline through `path`.
double distance_to_path(const Point& p, const std::vector<Point>& path) {
  double best = INFINITY;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const double dx = path[i + 1].x - path[i].x;
    const double dy = path[i + 1].y - path[i].y;
    const double length2 = dx * dx + dy * dy;
    const double s =
        length2 > 0.0
            ? std::clamp(((p.x - path[i].x) * dx + (p.y - path[i].y) * dy) / length2, 0.0, 1.0)
            : 0.0;
    best = std::min(best, std::hypot(p.x - path[i].x - s * dx, p.y - path[i].y - s * dy));
  }
  return best;
}

// A number after "\"key\": " in a JSON text; NaN when missing.
double json_value(const std::string& json, const std::string& key) {
  const std::size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? NAN : std::atof(json.c_str() + at + key.size() + 4);
}

class SilVm
    : public flowsteer::vm_test::VmTest<CanCaptureRun, flowsteer::vm_test::parse_can_capture> {
 protected:
  // The lines the probe printed of a run's file ("log", "sil.json", "trajectories.csv").
  std::vector<std::string> file(const std::string& run, const std::string& name) {
    std::vector<std::string> lines;
    for (int k = 0;; ++k) {
      const auto it = run_.probe.find(run + "-" + name + "-" + std::to_string(k));
      if (it == run_.probe.end()) {
        return lines;
      }
      lines.push_back(it->second);
    }
  }
  std::string text(const std::string& run, const std::string& name) {
    std::string all;
    for (const std::string& line : file(run, name)) {
      all += line + "\n";
    }
    return all;
  }
  int exit_status(const std::string& run) { return std::atoi(run_.probe[run + "-exit"].c_str()); }
};

TEST_F(SilVm, TheRobotReachesItsGoalCleanlyNearThePureSimulation) {
  const std::string log = text("clean", "log");
  const std::string report = text("clean", "sil.json");
  ASSERT_EQ(exit_status("clean"), 0) << log;
  EXPECT_NE(log.find("0 collisions, 1/1 goals reached"), std::string::npos) << log;
  EXPECT_EQ(json_value(report, "robot_exit_status"), 0.0) << report;
  EXPECT_NE(report.find("\"robot_ended_itself\": false"), std::string::npos) << report;
  const double views = json_value(report, "views_shown");
  EXPECT_GT(views, 10.0) << report;

  // The same scenario without the loop, here.
  const std::filesystem::path out =
      std::filesystem::path(FLOWSTEER_VM_WORK_DIR) / "pure_simulation";
  int status = 0;
  const std::string sim_log = flowsteer::vm_test::run_command(
      std::string("'") + FLOWSTEER_VM_ALSO + "' sim '" + FLOWSTEER_SIL_SCENARIO + "' --out '" +
          out.string() + "' 2>&1",
      status);
  ASSERT_EQ(status, 0) << sim_log;
  std::ifstream sim_csv(out / "trajectories.csv");
  std::vector<std::string> sim_lines;
  for (std::string line; std::getline(sim_csv, line);) {
    sim_lines.push_back(line);
  }
  const std::vector<Point> simulated = robot_path(sim_lines);
  const std::vector<Point> looped = robot_path(file("clean", "trajectories.csv"));
  ASSERT_GT(simulated.size(), 10u) << sim_log;
  ASSERT_GT(looped.size(), 10u);
  double deviation_m = 0.0;
  for (const Point& p : looped) {
    deviation_m = std::max(deviation_m, distance_to_path(p, simulated));
  }
  EXPECT_LT(deviation_m, kMaxDeviationM);
  std::printf(
      "the emulated CPU's pace: %s s a step of flowsteer sim; the launch file's timeouts "
      "stretched %s times: camera %s s, watchdog %s s\n",
      run_.probe["pace-step-s"].c_str(), run_.probe["timeout-scale"].c_str(),
      run_.probe["camera-timeout-s"].c_str(), run_.probe["watchdog-timeout-s"].c_str());
  std::printf(
      "in the loop: the run ended at t = %.2f s (pure simulation %.2f s), %g views shown, %g "
      "dropped; largest distance from the pure simulation's path %.3f m; capture to command "
      "mean %.1f ms (max %.1f ms); command to motion mean %.1f ms\n",
      looped.back().t, simulated.back().t, views, json_value(report, "views_dropped"), deviation_m,
      json_value(report, "mean_ms"), json_value(report, "max_ms"),
      json_value(report.substr(report.find("command_to_motion")), "mean_ms"));
}

TEST_F(SilVm, ACameraUnpluggedStopsTheRobotAndTheSimulatorRecordsWhere) {
  const std::string log = text("fault", "log");
  const std::string report = text("fault", "sil.json");
  EXPECT_EQ(exit_status("fault"), 1) << log;
  EXPECT_NE(report.find("\"robot_ended_itself\": true"), std::string::npos) << report;
  EXPECT_EQ(json_value(report, "robot_exit_status"), 1.0) << report;
  EXPECT_NE(log.find("flowsteer run: the run failed: base odrive vcan0 stopped"), std::string::npos)
      << log;
  EXPECT_TRUE(flowsteer::vm_test::says_camera_gone(log, "/dev/video0")) << log;

  const double start_s = stamp(run_, "fault-start");
  const double fault_s = stamp(run_, "fault-fault");
  ASSERT_TRUE(std::isfinite(fault_s)) << log;
  const double stop_within_s = stop_bound_s(run_, kNodes, start_s, fault_s, kStopWithinS);
  double slowest_s = 0.0;
  for (const unsigned node : kNodes) {
    SCOPED_TRACE("node " + std::to_string(node));
    EXPECT_TRUE(driven(run_, node, start_s, fault_s)) << "not driving before the fault\n" << log;
    const std::optional<double> zero_s = first_zero_velocity(run_, node, fault_s);
    ASSERT_TRUE(zero_s) << "no zero velocity on the bus after the fault";
    EXPECT_LT(*zero_s - fault_s, stop_within_s);
    EXPECT_FALSE(driven(run_, node, *zero_s, INFINITY)) << "a wheel was driven after the stop";
    slowest_s = std::max(slowest_s, *zero_s - fault_s);
  }
  // The simulator recorded where the robot came to rest: its last step did not move it.
  const std::vector<Point> path = robot_path(file("fault", "trajectories.csv"));
  ASSERT_GE(path.size(), 2u);
  const std::size_t at = report.find("\"robot_stop_position_m\": [");
  ASSERT_NE(at, std::string::npos) << report;
  double stop_x = NAN;
  double stop_y = NAN;
  std::sscanf(report.c_str() + at, "\"robot_stop_position_m\": [%lf, %lf]", &stop_x, &stop_y);
  EXPECT_GT(stop_x, 0.05) << "the robot had not moved";
  EXPECT_LT(std::hypot(stop_x - path.back().x, stop_y - path.back().y), 1e-3) << report;
  std::printf(
      "camera unplugged, the robot ended at t = %.2f s: first zero command on the bus "
      "%.1f ms after the fault (bound %.1f ms); the robot stopped at (%.2f, %.2f) m\n",
      json_value(report, "robot_end_time_s"), 1e3 * slowest_s, 1e3 * stop_within_s, stop_x, stop_y);
}

}  // namespace
