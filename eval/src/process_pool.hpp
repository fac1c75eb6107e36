#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace flowsteer::eval {

// How a task run in a worker process ended.
struct TaskOutcome {
  std::string record;  // what the task returned
  std::string error;   // empty on success; else its exception's message or how its process ended
  bool ok() const { return error.empty(); }
};

// Runs task(i) for every i < count, at most `jobs` at once, each in a process forked from this
// one for it: a task that crashes, aborts or leaks takes only itself down, and no state carries
// from one run to the next. A task returns a short record (at most kMaxTaskRecord bytes; longer
// ones are cut) that done(i, outcome) receives in this process, in the order the tasks end.
// With several jobs, each worker gives OpenCV one thread: the workers already fill the cores.
// Throws std::system_error when a process cannot be started, and std::runtime_error when
// SIGINT or SIGTERM arrives while it waits (it handles both meanwhile); workers still running
// are then stopped first.
inline constexpr std::size_t kMaxTaskRecord = 16384;
void run_in_processes(std::size_t count, int jobs,
                      const std::function<std::string(std::size_t)>& task,
                      const std::function<void(std::size_t, const TaskOutcome&)>& done);

}  // namespace flowsteer::eval
