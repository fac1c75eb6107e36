// Runs inside the simulation-in-the-loop test VM (run_sil_vm.sh): `flowsteer sil` on the test's
// scenario and launch file twice, with the robot (`flowsteer run`, started by flowsteer sil) on
// vivid's looped capture node and the simulated ODrive pair on vcan0. The first run goes to its
// end; in the second, vivid's capture node goes mid-run ("Disconnect": the camera unplugged,
// which takes vivid's output node with it).
// Before them, the emulated CPU's pace: the launch file's timeouts follow it (pace_launch_file).
// Prints "PROBE pace-step-s S", "PROBE timeout-scale F", "PROBE camera-timeout-s T",
// "PROBE watchdog-timeout-s T"; for each run "PROBE <run>-start T", "PROBE <run>-fault T" (the
// second), "PROBE <run>-exit STATUS", and what flowsteer sil printed and wrote as
// "PROBE <run>-<file>-<k> LINE" (log, sil.json, trajectories.csv, robot.log).

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "flowsteer/base/clock.hpp"
#include "probe_support.hpp"
#include "vivid_control.hpp"

namespace {

using flowsteer::base::monotonic_now_s;
using flowsteer::vm_test::realtime_s;

// The launch file's camera timeout (`timeout_s: 1.0`, a view every 0.1 s with room for a late
// one) and watchdog timeout, and how many of the pace's steps the camera's must cover: the
// robot's first perception passes run while the emulator still translates their code, and took
// 4-5 times the later ones' time (588 ms against a mean of 127 ms under a two-core load).
constexpr double kCameraTimeoutS = 1.0;
constexpr double kWatchdogTimeoutS = 0.6;
constexpr double kStepsPerCameraTimeout = 6.0;
constexpr int kPaceSteps = 20;

// Seconds per step of `flowsteer sim` on the test's scenario here (summary.json's mean per
// agent step, without the process's start): a view rendered and perceived, what the loop's
// simulator and robot do between them for each view.
double measure_step_s() {
  const pid_t pid = flowsteer::vm_test::start_logged(
      "/tmp/pace.log", {"/bin/flowsteer", "sim", "/sil/scenario.yaml", "--steps",
                        std::to_string(kPaceSteps).c_str(), "--out", "/tmp/pace"});
  int raw = 0;
  ::waitpid(pid, &raw, 0);
  std::ostringstream text;
  if (!WIFEXITED(raw) || WEXITSTATUS(raw) != 0) {
    text << std::ifstream("/tmp/pace.log").rdbuf();
    throw std::runtime_error("the pace run (flowsteer sim) failed: " + text.str());
  }
  text << std::ifstream("/tmp/pace/summary.json").rdbuf();
  const std::string summary = text.str();
  const std::string key = "\"total\": ";
  const std::size_t at = summary.find(key, summary.find("\"per_agent_step_ms\""));
  if (at == std::string::npos) {
    throw std::runtime_error("the pace run's summary.json has no per_agent_step_ms total");
  }
  return 1e-3 * std::atof(summary.c_str() + at + key.size());
}

// Replaces the one `key` followed by `value_s` as the launch file writes it (one decimal) by the
// key and `scale` times the value.
void stretch(std::string& launch, const std::string& key, double value_s, double scale) {
  std::ostringstream from;
  from << key << std::fixed << std::setprecision(1) << value_s;
  const std::size_t at = launch.find(from.str());
  if (at == std::string::npos || launch.find(from.str(), at + 1) != std::string::npos) {
    throw std::runtime_error("/sil/launch.yaml: expected '" + from.str() + "' once");
  }
  std::ostringstream to;
  to << key << scale * value_s;
  launch.replace(at, from.str().size(), to.str());
}

// /sil/launch.yaml with its camera and watchdog timeouts stretched by the factor by which the
// emulated CPU, on a loaded host, is too slow for them: the world runs on the wall clock and
// drops the views its renderer cannot give in time, and a robot that saw one picture for its
// whole timeout would stop, as it should on a real camera that froze. The runs check where the
// robot goes and how it stops when its camera goes, not how fast the host is.
std::string pace_launch_file() {
  const double step_s = measure_step_s();
  const double scale = std::max(1.0, kStepsPerCameraTimeout * step_s / kCameraTimeoutS);
  std::ifstream in("/sil/launch.yaml");
  std::ostringstream text;
  text << in.rdbuf();
  std::string launch = text.str();
  stretch(launch, "timeout_s: ", kCameraTimeoutS, scale);
  stretch(launch, "watchdog: {timeout_s: ", kWatchdogTimeoutS, scale);
  std::ofstream("/tmp/launch.yaml") << launch;
  std::printf("PROBE pace-step-s %.4f\nPROBE timeout-scale %.3f\n", step_s, scale);
  std::printf("PROBE camera-timeout-s %.3f\nPROBE watchdog-timeout-s %.3f\n",
              scale * kCameraTimeoutS, scale * kWatchdogTimeoutS);
  return "/tmp/launch.yaml";
}

void print_file(const std::string& run, const std::string& name, const std::string& path) {
  std::ifstream in(path);
  std::string line;
  for (int k = 0; std::getline(in, line); ++k) {
    std::printf("PROBE %s-%s-%d %s\n", run.c_str(), name.c_str(), k, line.c_str());
  }
}

// One run; `fault_after_s` > 0 fails the capture stream that long after the world starts.
void run_case(const std::string& run, const std::string& launch, double fault_after_s) {
  const std::string out = "/tmp/" + run;
  const std::string log_path = "/tmp/" + run + ".log";
  std::printf("PROBE %s-start %.6f\n", run.c_str(), realtime_s());
  std::fflush(stdout);
  const pid_t pid = flowsteer::vm_test::start_logged(
      log_path, {"/bin/flowsteer", "sil", "/sil/scenario.yaml", launch.c_str(), "--robot", "robot",
                 "--output", "/dev/video1", "--out", out.c_str()});
  const double start_s = monotonic_now_s();
  bool faulted = fault_after_s <= 0.0;
  int raw = 0;
  while (::waitpid(pid, &raw, WNOHANG) == 0) {
    if (monotonic_now_s() - start_s > 300.0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &raw, 0);
      break;
    }
    if (!faulted && flowsteer::vm_test::log_has(log_path, "the world runs")) {
      std::this_thread::sleep_for(std::chrono::duration<double>(fault_after_s));
      std::printf("PROBE %s-fault %.6f\n", run.c_str(), realtime_s());
      flowsteer::vm_test::set_vivid_control("/dev/video0", "Disconnect", 1);
      faulted = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::printf("PROBE %s-exit %d\n", run.c_str(),
              WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw));
  print_file(run, "log", log_path);
  print_file(run, "sil.json", out + "/sil.json");
  print_file(run, "trajectories.csv", out + "/trajectories.csv");
  print_file(run, "robot.log", out + "/robot.log");
}

int run() {
  const std::string launch = pace_launch_file();
  run_case("clean", launch, 0.0);
  run_case("fault", launch, 4.0);
  std::printf("PROBE done\n");
  return 0;
}

}  // namespace

int main() {
  return flowsteer::vm_test::probe_main(run);
}
