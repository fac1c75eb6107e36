#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace flowsteer::sil {

// The robot's own process (`flowsteer run`), started with `argv` and its output on ours. It dies
// with us (PR_SET_PDEATHSIG), so a robot is never left driving without its simulator.
class RobotProcess {
 public:
  // Throws std::runtime_error when the process cannot be started.
  explicit RobotProcess(const std::vector<std::string>& argv);
  // Stops a process still running (stop()), errors swallowed.
  ~RobotProcess();
  RobotProcess(const RobotProcess&) = delete;
  RobotProcess& operator=(const RobotProcess&) = delete;

  // The exit status once it has ended (128 + N for signal N, as a shell shows it), else nullopt.
  std::optional<int> poll();
  // SIGINT (flowsteer run stops its base and exits), then SIGKILL if it has not ended within
  // timeout_s. Returns the exit status.
  int stop(double timeout_s);

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

}  // namespace flowsteer::sil
