#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>

#include <Eigen/Core>

#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/world_spec.hpp"

namespace flowsteer::sil {

struct SilOptions {
  std::string robot_agent;    // the scenario's agent the robot is, by name
  std::string launch_file;    // the robot's launch file, as `flowsteer run` takes it
  std::string output_device;  // vivid's output node, looped to the launch file's camera
  std::filesystem::path out_dir = "flowsteer_sil_out";
  std::optional<int> steps;         // stop after this many steps
  double startup_timeout_s = 30.0;  // for the robot process to activate its drive
  // The simulation's MCAP recording (every agent, the world), and the robot process's own
  // beside it: FILE with ".robot" before its extension (`flowsteer run --mcap`).
  std::optional<pipeline::RecordingOptions> recording;
};

// Where `sil --mcap FILE` puts the robot process's own recording: run.mcap → run.robot.mcap.
std::filesystem::path robot_recording_path(const std::filesystem::path& recording);

// Delays in the loop, in milliseconds.
struct LatencyStats {
  int count = 0;
  double mean_ms = 0.0;
  double max_ms = 0.0;
  void add(double ms);
};

struct SilReport {
  // The robot process: its exit status and when it ended, on the simulation's clock. It ends
  // either stopped by the simulator at the end of the run (SIGINT) or by itself (a fault).
  int robot_exit_status = 0;
  bool robot_ended_itself = false;
  double robot_end_time_s = 0.0;
  Eigen::Vector2d robot_stop_position_m = Eigen::Vector2d::Zero();
  // From a frame's capture (the driver's timestamp) to the command the robot computed from it,
  // from the robot's own frame log.
  LatencyStats capture_to_command;
  // From a new wheel setpoint's arrival on the bus (the kernel's receive time) to the step of
  // the simulated world that moves by it.
  LatencyStats command_to_motion;
  // The world runs on the wall clock; a step that starts a step or more behind it is not
  // rendered (its view is dropped, as a camera drops a frame), so the world keeps up with the
  // robot whatever the renderer's speed.
  int views_shown = 0;
  int views_dropped = 0;
  double max_behind_ms = 0.0;  // the most a step started after its time
  // Why the output device stopped taking views (vivid fails it with its capture stream); empty
  // while it works. The run goes on without views.
  std::string output_error;
  double wait_for_robot_s = 0.0;  // from its start until it activated its drive
  // The mean difference, in 8-bit levels, of a test card sent through the loop and captured
  // back before the run (at most 2: YUYV's rounding; more is refused).
  double loop_error_levels = 0.0;
  // The rate the output device took frames at over the run (vivid's: 59.94 Hz).
  double output_frame_rate_hz = 0.0;
};

struct SilResult {
  sim::SimResult sim;
  SilReport report;
};

// The simulator in the loop with the robot's own binary: the world is simulated as by `flowsteer
// sim`, except the agent `robot_agent`, which is the robot. Each step its view is rendered and
// shown on vivid's output node, which vivid loops to the capture node the launch file's V4L2 camera
// reads; `flowsteer run LAUNCH` runs unchanged in a process of its own and sends its wheel speeds
// over the launch file's CAN interface to a simulated ODrive pair, whose velocities move the agent.
// The world steps in real time, dropping views the renderer cannot give in time. The robot's goal
// is the agent's, given to it as --goal-bearing and --goal-distance; its camera in the world is the
// launch file's (size, field of view, mount). The run ends at the scenario's
// end, when every agent is at its goal, or when the robot process ends by itself (a fault), which
// the result records.
//
// Writes what `flowsteer sim` writes plus robot.log (the robot's log) and sil.json (the report).
// Throws std::runtime_error saying what the machine lacks (vivid, its loop, the CAN interface),
// that the loop changes the picture (a test card sent through it before the run), or what in the
// launch file or scenario cannot run in the loop.
SilResult run_sil(const sim_camera::WorldSpec& world, const SilOptions& options, std::ostream& log);

}  // namespace flowsteer::sil
