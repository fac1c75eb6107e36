// Runs inside the simulation-in-the-loop test VM (run_sil_vm.sh): `flowsteer sil` on the test's
// scenario and launch file twice, with the robot (`flowsteer run`, started by flowsteer sil) on
// vivid's looped capture node and the simulated ODrive pair on vcan0. The first run goes to its
// end; in the second, vivid's capture node goes mid-run ("Disconnect": the camera unplugged,
// which takes vivid's output node with it).
// Prints for each run "PROBE <run>-start T", "PROBE <run>-fault T" (the second),
// "PROBE <run>-exit STATUS", and what flowsteer sil printed and wrote as
// "PROBE <run>-<file>-<k> LINE" (log, sil.json, trajectories.csv, robot.log).

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "flowsteer/base/clock.hpp"
#include "probe_support.hpp"
#include "vivid_control.hpp"

namespace {

using flowsteer::base::monotonic_now_s;
using flowsteer::vm_test::realtime_s;

void print_file(const std::string& run, const std::string& name, const std::string& path) {
  std::ifstream in(path);
  std::string line;
  for (int k = 0; std::getline(in, line); ++k) {
    std::printf("PROBE %s-%s-%d %s\n", run.c_str(), name.c_str(), k, line.c_str());
  }
}

// One run; `fault_after_s` > 0 fails the capture stream that long after the world starts.
void run_case(const std::string& run, double fault_after_s) {
  const std::string out = "/tmp/" + run;
  const std::string log_path = "/tmp/" + run + ".log";
  std::printf("PROBE %s-start %.6f\n", run.c_str(), realtime_s());
  std::fflush(stdout);
  const pid_t pid = flowsteer::vm_test::start_logged(
      log_path, {"/bin/flowsteer", "sil", "/sil/scenario.yaml", "/sil/launch.yaml", "--robot",
                 "robot", "--output", "/dev/video1", "--out", out.c_str()});
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
  run_case("clean", 0.0);
  run_case("fault", 4.0);
  std::printf("PROBE done\n");
  return 0;
}

}  // namespace

int main() {
  return flowsteer::vm_test::probe_main(run);
}
