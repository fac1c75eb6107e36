#include <atomic>
#include <csignal>
#include <iostream>
#include <string>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/robot/robot_commands.hpp"

namespace flowsteer::cli {

namespace {

// Set by SIGINT / SIGTERM: the robot loop sees it, stops the base and returns.
std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free);

void request_stop(int) {
  g_stop_requested.store(true);
}

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

struct RunCommand {
  robot::RunCommand run;
  RecordingChoice recording;
};

int run_robot(const RunCommand& command) {
  install_stop_handlers();
  robot::RunCommand run = command.run;
  run.recording = recording_options(command.recording);
  const robot::RobotLoopResult result = robot::run_robot_command(run, g_stop_requested, std::cerr);
  // After a camera timeout the base was stopped; the run still failed at what it was asked to do.
  return result.reason == robot::StopReason::camera_timeout ? 3 : 0;
}

struct ReplayCommand {
  robot::ReplayCommand replay;
  std::string flow = "dis_medium";
  RecordingChoice recording;
};

int run_replay(const ReplayCommand& command) {
  robot::ReplayCommand replay = command.replay;
  replay.recording = recording_options(command.recording);
  // run_replay_command refuses synthetic flow, saying why.
  replay.flow =
      flow_method_option("--flow", command.flow, "method", config::numerical_flow_method_names());
  const robot::ReplaySummary summary = robot::run_replay_command(replay, std::cerr);
  std::cout << "replay " << replay.video << " -> " << replay.out_dir << ": " << summary.frames
            << " frames (" << summary.blind_frames << " without flow), " << summary.object_rows
            << " object rows, " << summary.mean_step_ms
            << " ms per frame (perception and controller)\n";
  return 0;
}

}  // namespace

Subcommand add_run(CLI::App& app) {
  auto both = std::make_shared<RunCommand>();
  robot::RunCommand* command = &both->run;
  CLI::App* run = app.add_subcommand(
      "run",
      "The robot's loop from a launch file: camera -> flow -> features -> controller -> drive "
      "(launch/launch_files/README.md); Ctrl-C stops the base and ends the run");
  run->add_option("LAUNCH", command->launch_file, "robot launch file (YAML)")->required();
  run->add_option(
         "--goal-bearing", command->goal_bearing_deg,
         "goal bearing from the start heading, degrees, positive to the right (overrides goal:)")
      ->check(within(base::bounds::kBearing_deg));
  run->add_option("--goal-distance", command->goal_distance_m, "goal distance, metres")
      ->check(within(base::bounds::kGoalDistance_m));
  run->add_option("--log", command->log_file,
                  "also write the events and one line per frame (status, objects, command) here");
  add_recording_options(*run, both->recording);
  return {run, [both] { return run_robot(*both); }};
}

Subcommand add_replay(CLI::App& app) {
  auto command = std::make_shared<ReplayCommand>();
  robot::ReplayCommand& r = command->replay;
  CLI::App* replay = app.add_subcommand(
      "replay",
      "The pipeline on a recording without a drive: features.csv, commands.csv and "
      "overlay.mp4 in a folder");
  replay
      ->add_option("RECORDING", r.video,
                   "video file, image pattern, or MCAP file (.mcap: its images, odometry, "
                   "CameraInfo and /tf_static camera mount)")
      ->required();
  replay->add_option("--out", r.out_dir, "folder for the outputs")->capture_default_str();
  CLI::Option* hfov =
      replay->add_option("--hfov-deg", r.hfov_deg, "horizontal field of view (default 60)")
          ->check(within(base::bounds::kHfov_deg));
  replay->add_option("--camera-info", r.camera_info, "ROS camera_info YAML")->excludes(hfov);
  replay->add_option("--flow", command->flow, "numerical flow method")->capture_default_str();
  replay
      ->add_option("--goal-bearing", r.goal_bearing_deg,
                   "goal bearing, degrees, positive to the right")
      ->check(within(base::bounds::kBearing_deg));
  replay
      ->add_option("--speed", r.speed_mps,
                   "assumed camera speed, m/s, for a recording without odometry (default 0, "
                   "which skips the flat-ground test)")
      ->check(within(base::bounds::kSpeed_mps));
  replay->add_option("--image-topic", r.image_topic,
                     "an MCAP file's image topic, where it has more than one");
  replay->add_option("--odom-topic", r.odometry_topic,
                     "an MCAP file's odometry topic, where it has more than one");
  add_recording_options(*replay, command->recording);
  return {replay, [command] { return run_replay(*command); }};
}

}  // namespace flowsteer::cli
