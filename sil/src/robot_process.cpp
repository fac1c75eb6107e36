#include "robot_process.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::sil {

RobotProcess::RobotProcess(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) {
    args.push_back(const_cast<char*>(a.c_str()));
  }
  args.push_back(nullptr);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0) {
    throw std::runtime_error(std::string("cannot start the robot process: fork: ") +
                             std::strerror(errno));
  }
  if (pid_ == 0) {
    // Only async-signal-safe calls between fork and exec: the parent has threads.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) {
      ::_exit(127);
    }
    ::execv(args[0], args.data());
    ::_exit(127);
  }
}

RobotProcess::~RobotProcess() {
  if (!status_) {
    stop(2.0);
  }
}

std::optional<int> RobotProcess::poll() {
  if (status_) {
    return status_;
  }
  int raw = 0;
  const pid_t done = ::waitpid(pid_, &raw, WNOHANG);
  if (done == pid_) {
    status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  }
  return status_;
}

int RobotProcess::stop(double timeout_s) {
  if (!poll()) {
    ::kill(pid_, SIGINT);
    const double deadline_s = base::monotonic_now_s() + timeout_s;
    while (!poll() && base::monotonic_now_s() < deadline_s) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!poll()) {
      ::kill(pid_, SIGKILL);
      int raw = 0;
      ::waitpid(pid_, &raw, 0);
      status_ = 128 + SIGKILL;
    }
  }
  return *status_;
}

}  // namespace flowsteer::sil
