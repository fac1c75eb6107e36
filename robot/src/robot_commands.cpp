#include "flowsteer/robot/robot_commands.hpp"

#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <streambuf>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/camera_io/replay_source.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/pipeline/overlay.hpp"
#include "flowsteer/robot/robot_brain.hpp"

namespace flowsteer::robot {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Writes everything to two streams: the run's events to the terminal and to the log file.
class TeeBuffer final : public std::streambuf {
 public:
  TeeBuffer(std::streambuf* a, std::streambuf* b) : a_(a), b_(b) {}

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) {
      return traits_type::not_eof(c);
    }
    const bool ok = a_->sputc(static_cast<char>(c)) != traits_type::eof() &&
                    b_->sputc(static_cast<char>(c)) != traits_type::eof();
    return ok ? c : traits_type::eof();
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::streamsize written = a_->sputn(s, n);
    return std::min(written, b_->sputn(s, n));
  }
  int sync() override { return a_->pubsync() == 0 && b_->pubsync() == 0 ? 0 : -1; }

 private:
  std::streambuf* a_;
  std::streambuf* b_;
};

std::optional<config::GoalSection> goal_of(const RunCommand& command,
                                           std::optional<config::GoalSection> goal) {
  if (!command.goal_bearing_deg && !command.goal_distance_m) {
    return goal;
  }
  config::GoalSection g = goal.value_or(config::GoalSection{});
  if (command.goal_bearing_deg) {
    if (!(std::abs(*command.goal_bearing_deg) <= 180.0)) {
      throw std::invalid_argument("--goal-bearing " + std::to_string(*command.goal_bearing_deg) +
                                  ": must be within [-180, 180] degrees");
    }
    g.bearing_rad = *command.goal_bearing_deg * kDeg;
  }
  if (command.goal_distance_m) {
    if (!(*command.goal_distance_m > 0.0)) {
      throw std::invalid_argument("--goal-distance " + std::to_string(*command.goal_distance_m) +
                                  ": must be positive");
    }
    g.distance_m = *command.goal_distance_m;
  } else if (!goal) {
    throw std::invalid_argument("--goal-bearing needs --goal-distance (the launch file " +
                                command.launch_file + " has no goal: to take it from)");
  }
  return g;
}

}  // namespace

RobotLoopResult run_robot_command(const RunCommand& command,
                                  const std::atomic<bool>& stop_requested, std::ostream& log) {
  const config::RobotLaunch launch = config::read_robot_launch(command.launch_file);
  const std::optional<config::GoalSection> goal = goal_of(command, launch.goal);

  std::ofstream log_file;
  if (!command.log_file.empty()) {
    log_file.open(command.log_file, std::ios::trunc);
    if (!log_file) {
      throw std::runtime_error("cannot write the log file " + command.log_file);
    }
  }
  TeeBuffer tee(log.rdbuf(), log_file.rdbuf());
  std::ostream events(command.log_file.empty() ? log.rdbuf() : &tee);
  std::ostream* frame_log = !command.log_file.empty() ? static_cast<std::ostream*>(&log_file)
                            : !launch.drive           ? &log
                                                      : nullptr;

  for (const std::string& warning : launch.warnings) {
    events << "flowsteer run: " << warning << "\n";
  }
  const std::unique_ptr<camera_io::FrameSource> camera = config::make_camera(launch.camera);
  std::unique_ptr<drivers::MobileBase> robot_base;
  if (launch.drive) {
    robot_base = config::make_base(*launch.drive);
  }
  const bool live_camera = !std::holds_alternative<camera_io::ReplayOptions>(launch.camera.source);
  RobotBrain brain(camera->intrinsics(), robot_brain_config(launch.perception, launch.controller),
                   events, frame_log, live_camera);

  RobotLoopOptions options;
  options.camera_timeout_s = launch.camera.timeout_s;
  if (launch.drive) {
    options.drive_period_s = 1.0 / launch.drive->loop_rate_hz;
  }
  options.goal = goal;
  options.camera_name = config::describe_camera(launch.camera);
  const base::CameraIntrinsics& k = camera->intrinsics();
  events << "flowsteer run: " << options.camera_name << " (" << k.width_px << "x" << k.height_px
         << "), "
         << (robot_base ? "drive " + std::string(robot_base->drive().name())
                        : std::string("no drive: commands are logged, not sent"))
         << ", flow " << servo::to_string(launch.perception.flow) << ", segmentation "
         << servo::to_string(launch.perception.segmentation);
  if (goal) {
    events << ", goal " << goal->distance_m << " m at " << goal->bearing_rad / kDeg << " deg";
  }
  events << "\n";
  const RobotLoopResult result =
      run_robot_loop(*camera, robot_base.get(), brain, options, stop_requested, events);
  events << "flowsteer run: " << result.frames << " frames";
  if (result.repeated_frames > 0) {
    events << " (" << result.repeated_frames << " repeated)";
  }
  events << " in " << result.duration_s << " s (" << stop_reason_name(result.reason) << ")\n";
  events.flush();
  return result;
}

ReplaySummary run_replay_command(const ReplayCommand& command, std::ostream& log) {
  if (command.hfov_deg && !command.camera_info.empty()) {
    throw std::invalid_argument("give --hfov-deg or --camera-info, not both");
  }
  camera_io::ReplayOptions options;
  options.path = command.video;
  if (command.hfov_deg) {
    if (!(*command.hfov_deg > 0.0 && *command.hfov_deg < 180.0)) {
      throw std::invalid_argument("--hfov-deg " + std::to_string(*command.hfov_deg) +
                                  ": must be in (0, 180)");
    }
    options.lens.horizontal_fov_rad = *command.hfov_deg * kDeg;
  }
  if (!command.camera_info.empty()) {
    std::vector<std::string> warnings;
    options.lens.model = calibration::read_camera_info(command.camera_info, warnings).model;
    for (const std::string& w : warnings) {
      log << "flowsteer replay: " << w << "\n";
    }
  }
  if (command.flow == servo::FlowMethod::synthetic) {
    throw std::invalid_argument("--flow synthetic needs a simulator; a recording needs one of " +
                                config::numerical_flow_method_names());
  }
  if (!(command.speed_mps >= 0.0)) {
    throw std::invalid_argument("--speed must be >= 0");
  }
  camera_io::ReplaySource source(options);
  config::PerceptionSection perception;
  perception.flow = command.flow;
  config::ControllerSection controller;
  RobotBrain robot(source.intrinsics(), robot_brain_config(perception, controller), log);
  const pipeline::Brain& brain = robot.brain();

  base::OutputDir out(command.out_dir);
  const cv::Size size(source.intrinsics().width_px, source.intrinsics().height_px);
  const double fps = source.frame_rate_hz() > 0.0 ? source.frame_rate_hz() : 30.0;
  std::unique_ptr<cv::VideoWriter> video =
      pipeline::open_video(out.staging_path("overlay.mp4"), pipeline::overlay_size(size), fps);

  base::CsvTable features({"status", "kind", "frame", "t_s", "label", "centre_x", "centre_y",
                           "width", "foe_x", "foe_y", "ttc_s", "pixels"});
  base::CsvTable commands({"flow_status", "frame", "t_s", "objects", "goal_bearing_rad",
                           "accel_mps2", "turn_rate", "cost"});
  const std::optional<double> bearing =
      command.goal_bearing_deg ? std::optional<double>(*command.goal_bearing_deg * kDeg)
                               : std::nullopt;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ReplaySummary summary;
  double step_ms = 0.0;
  camera_io::Frame frame;
  while (source.read(frame, 0.0) == camera_io::ReadStatus::ok) {
    const base::Command c =
        robot.step(LoopInput{frame, {command.speed_mps, 0.0}, bearing, std::nullopt});
    const auto seq = static_cast<double>(frame.sequence);
    ++summary.frames;
    if (brain.blind()) {
      ++summary.blind_frames;
    } else {
      step_ms += brain.times().total;
    }
    for (const servo::ObjectFeatures& o : brain.objects()) {
      features.add(
          {servo::to_string(o.status), servo::to_string(o.kind)},
          {seq, frame.timestamp_s, static_cast<double>(o.label), o.centre.x(), o.centre.y(),
           o.width, o.foe.x(), o.foe.y(), o.ttc_s, static_cast<double>(o.pixel_count)});
      ++summary.object_rows;
    }
    commands.add({servo::to_string(brain.flow_status())},
                 {seq, frame.timestamp_s, static_cast<double>(brain.objects().size()),
                  bearing.value_or(nan), c.accel_mps2, c.turn_rate, brain.output().cost});
    video->write(pipeline::draw_overlay(frame.image, brain.flow(), brain.objects(),
                                        source.intrinsics(), bearing));
  }
  video->release();
  features.write(out.staging_path("features.csv"));
  commands.write(out.staging_path("commands.csv"));
  out.commit();
  const std::size_t seeing = summary.frames - summary.blind_frames;
  summary.mean_step_ms = seeing > 0 ? step_ms / static_cast<double>(seeing) : 0.0;
  return summary;
}

}  // namespace flowsteer::robot
