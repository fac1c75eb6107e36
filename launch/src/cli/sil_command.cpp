#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/sil/sil.hpp"

namespace flowsteer::cli {

namespace {

struct SilCommand {
  std::string scenario;
  std::string launch_file;
  std::string robot;
  std::string output_device = "/dev/video1";
  std::string out_dir = "flowsteer_sil_out";
  std::optional<int> steps;
  RecordingChoice recording;
};

void print_report(const sil::SilResult& result, const std::string& robot, std::ostream& out) {
  const sim::RunSummary summary = sim::summarize(result.sim);
  const sil::SilReport& r = result.report;
  char line[512];
  std::snprintf(line, sizeof line,
                "scenario %s: %d steps, %.2f s simulated, %d collisions, %d/%d goals reached\n"
                "robot %s: %s with status %d at t = %.2f s, stopped at (%.2f, %.2f) m\n"
                "capture to command: mean %.1f ms, max %.1f ms over %d frames\n"
                "command to motion: mean %.1f ms, max %.1f ms over %d setpoints\n"
                "views shown: %d, dropped (the renderer behind the clock): %d, at most %.1f ms "
                "behind\n",
                result.sim.scenario.c_str(), result.sim.steps, result.sim.duration_s,
                summary.collisions, summary.goals_reached, summary.agents_with_goal(),
                robot.c_str(), r.robot_ended_itself ? "exited by itself" : "stopped by sil",
                r.robot_exit_status, r.robot_end_time_s, r.robot_stop_position_m.x(),
                r.robot_stop_position_m.y(), r.capture_to_command.mean_ms,
                r.capture_to_command.max_ms, r.capture_to_command.count,
                r.command_to_motion.mean_ms, r.command_to_motion.max_ms, r.command_to_motion.count,
                r.views_shown, r.views_dropped, r.max_behind_ms);
  out << line;
}

int run_sil_command(const SilCommand& command) {
  // A file by that name, else a built-in scenario.
  ScenarioChoice choice;
  (std::filesystem::exists(command.scenario) ? choice.file : choice.name) = command.scenario;
  const sim_camera::WorldSpec world = load_world("sil", choice);
  sil::SilOptions options;
  options.robot_agent = command.robot;
  options.launch_file = command.launch_file;
  options.output_device = command.output_device;
  options.out_dir = command.out_dir;
  options.steps = command.steps;
  options.recording = recording_options(command.recording);
  std::cerr << "flowsteer sil: " << world.name << ", robot " << command.robot << " ("
            << command.launch_file << ") -> " << command.out_dir << "\n";
  const sil::SilResult result = sil::run_sil(world, options, std::cerr);
  print_report(result, command.robot, std::cout);
  // A robot that ended by itself failed (a fault stopped it): the run says so by its status.
  return result.report.robot_ended_itself ? 1 : 0;
}

}  // namespace

Subcommand add_sil(CLI::App& app) {
  auto command = std::make_shared<SilCommand>();
  CLI::App* sil = app.add_subcommand(
      "sil", "Simulation in the loop: flowsteer run drives one agent through vivid and a CAN bus");
  sil->add_option("SCENARIO", command->scenario, "scenario file, or a built-in scenario's name")
      ->required();
  sil->add_option("LAUNCH", command->launch_file,
                  "the robot's launch file: a v4l2 camera on vivid's capture node, an odrive_can "
                  "drive")
      ->required();
  sil->add_option("--robot", command->robot, "the scenario's agent the robot is")->required();
  sil->add_option("--output", command->output_device,
                  "vivid's output node, looped to the launch file's camera")
      ->capture_default_str();
  sil->add_option("--out", command->out_dir, "folder for the outputs")->capture_default_str();
  add_recording_options(*sil, command->recording);
  sil->add_option("--steps", command->steps, "stop after N control steps")
      ->check(within(base::bounds::kRunSteps));
  return {sil, [command] { return run_sil_command(*command); }};
}

}  // namespace flowsteer::cli
