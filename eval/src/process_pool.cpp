#include "process_pool.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <iostream>
#include <map>
#include <stdexcept>
#include <system_error>
#include <utility>

#include <opencv2/core/utility.hpp>

#include "flowsteer/base/unique_fd.hpp"

namespace flowsteer::eval {

namespace {

// The first byte of a record says whether the task returned or threw.
constexpr char kReturned = 'R';
constexpr char kThrew = 'E';

void write_all(int fd, const std::string& bytes) {
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      return;  // the parent is gone: nobody is left to tell
    }
    written += static_cast<std::size_t>(n);
  }
}

std::string read_all(int fd) {
  std::string bytes;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      return bytes;
    }
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
}

// The signal that interrupted the pool (SIGINT, SIGTERM), 0 while none has.
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void note_interrupt(int signal) {
  g_interrupted = signal;
}

// While workers run, Ctrl-C or a termination request ends the wait with an exception instead of
// killing this process at once: the workers are then stopped, and the callers unwind, removing
// what they had staged, so an interrupted suite leaves its output folder as it was.
class InterruptGuard {
 public:
  InterruptGuard() {
    g_interrupted = 0;
    struct sigaction action {};
    action.sa_handler = note_interrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;  // no SA_RESTART: a waiting waitpid returns with EINTR
    ::sigaction(SIGINT, &action, &previous_int_);
    ::sigaction(SIGTERM, &action, &previous_term_);
  }
  ~InterruptGuard() {
    ::sigaction(SIGINT, &previous_int_, nullptr);
    ::sigaction(SIGTERM, &previous_term_, nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  static void throw_if_interrupted() {
    if (g_interrupted != 0) {
      throw std::runtime_error(std::string("interrupted (") + strsignal(g_interrupted) +
                               "): the runs in progress were stopped");
    }
  }

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

// SIGINT and SIGTERM held back while a worker is forked: a worker stopped before it has put
// back their default actions would otherwise run the parent's handler and go on.
class InterruptsHeld {
 public:
  InterruptsHeld() {
    sigset_t interrupts;
    sigemptyset(&interrupts);
    sigaddset(&interrupts, SIGINT);
    sigaddset(&interrupts, SIGTERM);
    ::pthread_sigmask(SIG_BLOCK, &interrupts, &previous_);
  }
  ~InterruptsHeld() { ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }
  InterruptsHeld(const InterruptsHeld&) = delete;
  InterruptsHeld& operator=(const InterruptsHeld&) = delete;

  // The mask from before, for the worker to put back.
  const sigset_t& previous() const { return previous_; }

 private:
  sigset_t previous_{};
};

// The worker: runs the task, writes its record and ends without running this process's exit
// handlers (they belong to the parent: its buffers, its GL state). Ctrl-C and SIGTERM end it,
// also one sent while it was being forked (held until here).
[[noreturn]] void run_worker(int fd, std::size_t index, int jobs,
                             const std::function<std::string(std::size_t)>& task,
                             const sigset_t& mask) {
  ::signal(SIGINT, SIG_DFL);
  ::signal(SIGTERM, SIG_DFL);
  ::pthread_sigmask(SIG_SETMASK, &mask, nullptr);
  if (jobs > 1) {
    cv::setNumThreads(1);
  }
  std::string record;
  int status = 0;
  try {
    record = kReturned + task(index);
  } catch (const std::exception& e) {
    record = kThrew + std::string(e.what());
    status = 1;
  } catch (...) {
    record = std::string(1, kThrew) + "an unknown exception";
    status = 1;
  }
  // A pipe holds 64 KiB: a record this short never blocks the worker before the parent reads.
  write_all(fd, record.substr(0, kMaxTaskRecord + 1));
  ::close(fd);
  ::_exit(status);
}

TaskOutcome outcome_of(const std::string& record, int status) {
  if (!record.empty() && record.front() == kReturned) {
    return {record.substr(1), ""};
  }
  if (!record.empty() && record.front() == kThrew) {
    return {"", record.substr(1)};
  }
  if (WIFSIGNALED(status)) {
    return {"", "the run's process was killed by signal " + std::to_string(WTERMSIG(status)) +
                    " (" + strsignal(WTERMSIG(status)) + ")"};
  }
  return {"", "the run's process exited with status " + std::to_string(WEXITSTATUS(status)) +
                  " without a result"};
}

// The workers running now, by process id; stops and reaps the rest when left by an exception.
class Workers {
 public:
  struct Running {
    std::size_t index;
    base::UniqueFd pipe;  // the read end of the worker's pipe
  };
  ~Workers() {
    for (auto& [pid, running] : running_) {
      ::kill(pid, SIGTERM);
      running.pipe.reset();
    }
    for (const auto& entry : running_) {
      int status = 0;
      ::waitpid(entry.first, &status, 0);
    }
  }
  std::size_t size() const { return running_.size(); }

  void start(std::size_t index, int jobs, const std::function<std::string(std::size_t)>& task) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      throw std::system_error(errno, std::generic_category(), "cannot create a worker's pipe");
    }
    base::UniqueFd read_end(fds[0]);
    base::UniqueFd write_end(fds[1]);
    std::cout.flush();
    std::cerr.flush();
    const InterruptsHeld held;
    const pid_t pid = ::fork();
    if (pid < 0) {
      throw std::system_error(errno, std::generic_category(), "cannot start a worker process");
    }
    if (pid == 0) {
      read_end.reset();
      run_worker(write_end.get(), index, jobs, task, held.previous());
    }
    write_end.reset();
    running_.emplace(pid, Running{index, std::move(read_end)});
  }

  // Waits for a worker to end; its index and outcome.
  std::pair<std::size_t, TaskOutcome> wait() {
    for (;;) {
      int status = 0;
      const pid_t pid = ::waitpid(-1, &status, 0);
      if (pid < 0 && errno == EINTR) {
        InterruptGuard::throw_if_interrupted();
        continue;
      }
      if (pid < 0) {
        throw std::system_error(errno, std::generic_category(), "waiting for a worker process");
      }
      const auto found = running_.find(pid);
      if (found == running_.end()) {
        continue;  // not one of ours
      }
      const Running running = std::move(found->second);
      running_.erase(found);
      const std::string record = read_all(running.pipe.get());
      return {running.index, outcome_of(record, status)};
    }
  }

 private:
  std::map<pid_t, Running> running_;
};

}  // namespace

void run_in_processes(std::size_t count, int jobs,
                      const std::function<std::string(std::size_t)>& task,
                      const std::function<void(std::size_t, const TaskOutcome&)>& done) {
  const InterruptGuard interrupts;
  Workers workers;  // after the guard: stopped before the guard restores the signal handlers
  std::size_t next = 0;
  while (next < count || workers.size() > 0) {
    InterruptGuard::throw_if_interrupted();
    while (next < count && workers.size() < static_cast<std::size_t>(std::max(jobs, 1))) {
      workers.start(next++, jobs, task);
    }
    const auto [index, outcome] = workers.wait();
    done(index, outcome);
  }
}

}  // namespace flowsteer::eval
