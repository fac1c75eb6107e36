// A crowd's step: N agents on a ring, each walking to the point opposite, all seeing with
// synthetic flow and semantic ids (the default perception), stepped on 1 and 2 threads. Every
// configuration runs in a child process of its own, so that its peak resident memory is its own.
//   crowd_bench [--steps N] [--agents 1,10,...] [--resolutions 64,128,...] [--threads 1,2,...]
//               [--submission automatic|layered|per_view]
// First prints the renderer the runs draw with (OpenGL's description: a GPU or llvmpipe) and how
// its views are submitted (sim_camera::ViewSubmission; bench/gpu_render.sh compares them).
// Prints one row per configuration: world steps per second, wall milliseconds per agent-step
// (the step's wall time over its agents), the mean render and perception+control milliseconds
// of one agent's step as its thread saw them (the render: its share of the submissions its
// thread drew its view in), peak RSS, and CGF Fig. 14's per-agent update time
// at that resolution (UE4 on a Quadro M2000M) beside them.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/renderer.hpp"

namespace {

using namespace flowsteer;

const std::map<int, double> kPaperMs = {{64, 3.0}, {128, 6.0}, {256, 27.0}};

// People 1.5 m apart on a ring (5 m across at least), each walking to the opposite point.
sim_camera::WorldSpec ring(int agents, int resolution) {
  sim_camera::WorldSpec world;
  world.name = "ring";
  const double radius_m = std::max(5.0, 1.5 * agents / (2.0 * std::numbers::pi));
  world.ground_size_m = 4.0 * radius_m + 20.0;
  for (int i = 0; i < agents; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / agents;
    const Eigen::Vector2d at(radius_m * std::cos(angle), radius_m * std::sin(angle));
    sim_camera::AgentSpec a;
    a.name = std::to_string(i);
    a.start_m = at;
    a.heading_rad = angle + std::numbers::pi;
    a.goals = {-at};
    a.camera.width_px = a.camera.height_px = resolution;
    a.camera.hfov_rad = 150.0 * std::numbers::pi / 180.0;
    world.agents.push_back(a);
  }
  return world;
}

struct Row {
  char renderer[160] = {};  // Renderer::description(), cut to fit
  double world_steps_per_s = 0.0;
  double render_ms = 0.0;
  double think_ms = 0.0;  // flow, segmentation, features and control
};

// Runs one configuration in this (child) process and writes its row to `fd`.
[[noreturn]] void measure(int agents, int resolution, int threads, int steps,
                          sim_camera::ViewSubmission submission, int fd) {
  int status = 0;
  try {
    if (threads != 1 && agents > 1) {
      sim_camera::rasterize_on_calling_threads();  // as flowsteer sim does
    }
    sim::SimOptions options;
    options.steps = steps;
    options.threads = threads;
    options.view_submission = submission;
    options.write_outputs = false;
    std::ostringstream log;
    const sim::SimResult result = sim::run_simulation(ring(agents, resolution), options, log);
    const pipeline::StageTimes& t = result.per_agent_step_ms;
    Row row{{}, result.world_steps_per_s, t.render, t.total - t.render};
    const std::string renderer = sim_camera::Renderer::create(submission)->description();
    renderer.copy(row.renderer, sizeof row.renderer - 1);
    if (write(fd, &row, sizeof row) != static_cast<ssize_t>(sizeof row)) {
      status = 2;
    }
  } catch (const std::exception& e) {
    std::cerr << "crowd_bench: " << agents << " agents at " << resolution << ": " << e.what()
              << "\n";
    status = 1;
  }
  std::_Exit(status);
}

std::vector<int> numbers(const std::string& list, const char* what) {
  std::vector<int> values;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');) {
    try {
      values.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw std::invalid_argument(std::string(what) + ": '" + item + "' is not a number");
    }
    if (values.back() <= 0) {
      throw std::invalid_argument(std::string(what) + ": " + item + " must be positive");
    }
  }
  return values;
}

std::string submission_name(sim_camera::ViewSubmission submission,
                            const std::map<std::string, sim_camera::ViewSubmission>& submissions) {
  for (const auto& [name, value] : submissions) {
    if (value == submission) {
      return name;
    }
  }
  return "?";
}

void print_row(int agents, int resolution, int threads, const Row& row, long max_rss_kb) {
  const double per_agent_ms = 1000.0 / (row.world_steps_per_s * agents);
  const auto paper = kPaperMs.find(resolution);
  char paper_ms[16] = "-";
  if (paper != kPaperMs.end()) {
    std::snprintf(paper_ms, sizeof paper_ms, "%.0f", paper->second);
  }
  std::printf("%6d %6d %7d %12.1f %14.3f %10.3f %10.3f %9.0f %11s\n", agents, resolution, threads,
              row.world_steps_per_s, per_agent_ms, row.render_ms, row.think_ms,
              static_cast<double>(max_rss_kb) / 1024.0, paper_ms);
  std::fflush(stdout);
}

int run(int argc, char** argv) {
  int steps = 30;
  std::vector<int> agent_counts = {1, 10, 25, 50, 100, 200};
  std::vector<int> resolutions = {64, 128, 256};
  std::vector<int> thread_counts = {1, 2};
  sim_camera::ViewSubmission submission = sim_camera::ViewSubmission::automatic;
  const std::map<std::string, sim_camera::ViewSubmission> submissions = {
      {"automatic", sim_camera::ViewSubmission::automatic},
      {"layered", sim_camera::ViewSubmission::layered},
      {"per_view", sim_camera::ViewSubmission::per_view}};
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (k + 1 >= argc) {
      throw std::invalid_argument(arg + " needs a value");
    }
    const std::string value = argv[++k];
    if (arg == "--steps") {
      steps = numbers(value, "--steps").at(0);
    } else if (arg == "--agents") {
      agent_counts = numbers(value, "--agents");
    } else if (arg == "--resolutions") {
      resolutions = numbers(value, "--resolutions");
    } else if (arg == "--threads") {
      thread_counts = numbers(value, "--threads");
    } else if (arg == "--submission") {
      const auto known = submissions.find(value);
      if (known == submissions.end()) {
        throw std::invalid_argument("--submission: unknown '" + value +
                                    "' (automatic, layered, per_view)");
      }
      submission = known->second;
    } else {
      throw std::invalid_argument("unknown option " + arg +
                                  " (--steps, --agents, --resolutions, --threads, --submission)");
    }
  }
  bool described = false;
  int failures = 0;
  for (const int resolution : resolutions) {
    for (const int agents : agent_counts) {
      for (const int threads : thread_counts) {
        int pipe_fds[2];
        if (pipe(pipe_fds) != 0) {
          throw std::runtime_error("pipe failed");
        }
        const pid_t child = fork();
        if (child < 0) {
          throw std::runtime_error("fork failed");
        }
        if (child == 0) {
          close(pipe_fds[0]);
          measure(agents, resolution, threads, steps, submission, pipe_fds[1]);
        }
        close(pipe_fds[1]);
        Row row;
        const bool got = read(pipe_fds[0], &row, sizeof row) == static_cast<ssize_t>(sizeof row);
        close(pipe_fds[0]);
        int status = 0;
        rusage usage{};
        wait4(child, &status, 0, &usage);
        if (got && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
          if (!described) {
            std::printf("renderer: %s; views submitted: %s\n", row.renderer,
                        submission_name(submission, submissions).c_str());
            std::printf("%6s %6s %7s %12s %14s %10s %10s %9s %11s\n", "agents", "res", "threads",
                        "world_st/s", "ms/agent-step", "render_ms", "think_ms", "rss_MB",
                        "paper_ms");
            described = true;
          }
          print_row(agents, resolution, threads, row, usage.ru_maxrss);
        } else {
          ++failures;
        }
      }
    }
  }
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "crowd_bench: " << e.what() << "\n";
    return 2;
  }
}
