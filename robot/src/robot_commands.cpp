#include "flowsteer/robot/robot_commands.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <streambuf>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/camera_io/replay_source.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/pipeline/overlay.hpp"
#include "flowsteer/robot/robot_brain.hpp"
#include "recorded_camera.hpp"

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

// The robot loop, with its recording finished however the loop ends: a run that failed is the
// one most worth looking at.
RobotLoopResult run_and_record(camera_io::FrameSource& camera, drivers::MobileBase* robot_base,
                               RobotBrain& brain, const RobotLoopOptions& options,
                               const std::atomic<bool>& stop_requested, std::ostream& events,
                               std::optional<pipeline::RunRecorder>& recorder) {
  RobotLoopResult result;
  try {
    result = run_robot_loop(camera, robot_base, brain, options, stop_requested, events);
  } catch (const std::exception& e) {
    if (recorder) {
      // The run's own error is the one to report; a recording that cannot be finished is logged.
      try {
        recorder->finish({{"ended", std::string("error: ") + e.what()}});
      } catch (const std::exception& recording_error) {
        events << "flowsteer run: the recording could not be finished: " << recording_error.what()
               << "\n";
      }
    }
    throw;
  }
  if (recorder) {
    recorder->finish({{"ended", stop_reason_name(result.reason)}});
  }
  return result;
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
         << ", fx " << k.fx_px << " px), "
         << (robot_base ? "drive " + std::string(robot_base->drive().name())
                        : std::string("no drive: commands are logged, not sent"))
         << ", flow " << servo::to_string(launch.perception.flow) << ", segmentation "
         << servo::to_string(launch.perception.segmentation);
  if (goal) {
    events << ", goal " << goal->distance_m << " m at " << goal->bearing_rad / kDeg << " deg";
  }
  events << "\n";
  std::optional<pipeline::RunRecorder> recorder;
  if (command.recording) {
    recorder.emplace(*command.recording, "monotonic", "odom");
    recorder->add_agent("", k, launch.perception.mount);
    recorder->write_mounts(recording::nanoseconds(base::monotonic_now_s()));
    options.recorder = &*recorder;
    brain.record_into(&*recorder);
  }
  const RobotLoopResult result =
      run_and_record(*camera, robot_base.get(), brain, options, stop_requested, events, recorder);
  events << "flowsteer run: " << result.frames << " frames";
  if (result.repeated_frames > 0) {
    events << " (" << result.repeated_frames << " repeated)";
  }
  events << " in " << result.duration_s << " s (" << stop_reason_name(result.reason) << ")\n";
  events.flush();
  return result;
}

namespace {

// What a replay reads: frames with the base's motion at each, the lens, the camera's mount where
// the recording says it, and the frame rate of the overlay video.
struct ReplayInput {
  base::CameraIntrinsics intrinsics;
  std::optional<base::CameraMount> mount;
  double frame_rate_hz = 30.0;
  std::function<bool(camera_io::Frame&, drivers::BodyVelocity&)> read;
};

camera_io::LensOptions lens_of(const ReplayCommand& command, std::ostream& log) {
  camera_io::LensOptions lens;
  if (command.hfov_deg) {
    if (!(*command.hfov_deg > 0.0 && *command.hfov_deg < 180.0)) {
      throw std::invalid_argument("--hfov-deg " + std::to_string(*command.hfov_deg) +
                                  ": must be in (0, 180)");
    }
    lens.horizontal_fov_rad = *command.hfov_deg * kDeg;
  }
  if (!command.camera_info.empty()) {
    std::vector<std::string> warnings;
    lens.model = calibration::read_camera_info(command.camera_info, warnings).model;
    for (const std::string& w : warnings) {
      log << "flowsteer replay: " << w << "\n";
    }
  }
  return lens;
}

// ", camera mount from /tf_static: 0.45 m high, pitched 8.0 deg down", or nothing.
std::string mount_text(const std::optional<base::CameraMount>& mount) {
  if (!mount) {
    return "";
  }
  char text[96];
  std::snprintf(text, sizeof text,
                ", camera mount from /tf_static: %.2f m high, pitched %.1f deg down",
                mount->height_m, mount->pitch_rad / kDeg);
  return text;
}

bool is_mcap(const std::string& path) {
  return std::filesystem::path(path).extension() == ".mcap";
}

// The pipeline over every frame, with the files it writes.
ReplaySummary replay(const ReplayCommand& command, const ReplayInput& input, std::ostream& log) {
  config::PerceptionSection perception;
  perception.flow = command.flow;
  perception.mount = input.mount;
  config::ControllerSection controller;
  RobotBrain robot(input.intrinsics, robot_brain_config(perception, controller), log);
  const pipeline::Brain& brain = robot.brain();

  base::OutputDir out(command.out_dir);
  std::optional<pipeline::RunRecorder> recorder;
  if (command.recording) {
    recorder.emplace(*command.recording, "recording", "odom");
    recorder->add_agent("", input.intrinsics, input.mount);
    recorder->write_mounts(0);
    robot.record_into(&*recorder);
  }
  const cv::Size size(input.intrinsics.width_px, input.intrinsics.height_px);
  std::unique_ptr<cv::VideoWriter> video = pipeline::open_video(
      out.staging_path("overlay.mp4"), pipeline::overlay_size(size), input.frame_rate_hz);

  // Exact, so that a replay can be compared with the run it replays.
  base::CsvTable features({"status", "kind", "frame", "t_s", "label", "centre_x", "centre_y",
                           "width", "foe_x", "foe_y", "ttc_s", "pixels"},
                          base::Digits::exact);
  base::CsvTable commands({"flow_status", "frame", "t_s", "speed_mps", "turn_rate_measured",
                           "objects", "goal_bearing_rad", "accel_mps2", "turn_rate", "cost"});
  const std::optional<double> bearing =
      command.goal_bearing_deg ? std::optional<double>(*command.goal_bearing_deg * kDeg)
                               : std::nullopt;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ReplaySummary summary;
  double step_ms = 0.0;
  camera_io::Frame frame;
  drivers::BodyVelocity measured;
  while (input.read(frame, measured)) {
    const base::Command c = robot.step(LoopInput{frame, measured, bearing, std::nullopt});
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
                 {seq, frame.timestamp_s, measured.speed_mps, measured.turn_rate,
                  static_cast<double>(brain.objects().size()), bearing.value_or(nan), c.accel_mps2,
                  c.turn_rate, brain.output().cost});
    video->write(pipeline::draw_overlay(frame.image, brain.flow(), brain.objects(),
                                        input.intrinsics, bearing));
  }
  video->release();
  features.write(out.staging_path("features.csv"));
  commands.write(out.staging_path("commands.csv"));
  if (recorder) {
    recorder->finish({{"replay_of", command.video}});
  }
  out.commit();
  const std::size_t seeing = summary.frames - summary.blind_frames;
  summary.mean_step_ms = seeing > 0 ? step_ms / static_cast<double>(seeing) : 0.0;
  return summary;
}

}  // namespace

ReplaySummary run_replay_command(const ReplayCommand& command, std::ostream& log) {
  if (command.hfov_deg && !command.camera_info.empty()) {
    throw std::invalid_argument("give --hfov-deg or --camera-info, not both");
  }
  if (command.flow == servo::FlowMethod::synthetic) {
    throw std::invalid_argument("--flow synthetic needs a simulator; a recording needs one of " +
                                config::numerical_flow_method_names());
  }
  if (command.speed_mps && !(*command.speed_mps >= 0.0)) {
    throw std::invalid_argument("--speed must be >= 0");
  }
  const camera_io::LensOptions lens = lens_of(command, log);
  if (is_mcap(command.video)) {
    const bool lens_given = command.hfov_deg || !command.camera_info.empty();
    RecordedCamera camera(command.video, {command.image_topic, command.odometry_topic},
                          lens_given ? std::optional(lens) : std::nullopt);
    if (camera.has_odometry() && command.speed_mps) {
      throw std::invalid_argument("--speed: " + command.video + " has odometry (" +
                                  camera.odometry_topic() + "), which gives the speed");
    }
    const double speed_mps = command.speed_mps.value_or(0.0);
    log << "flowsteer replay: " << camera.image_topic() << ", "
        << (camera.has_odometry() ? "odometry " + camera.odometry_topic()
                                  : "no odometry: speed " + std::to_string(speed_mps) + " m/s")
        << mount_text(camera.mount()) << "\n";
    return replay(command,
                  {camera.intrinsics(), camera.mount(), camera.frame_rate_hz(),
                   [&](camera_io::Frame& frame, drivers::BodyVelocity& measured) {
                     const bool ok = camera.read(frame, measured);
                     if (!camera.has_odometry()) {
                       measured = {speed_mps, 0.0};
                     }
                     return ok;
                   }},
                  log);
  }
  if (!command.image_topic.empty() || !command.odometry_topic.empty()) {
    throw std::invalid_argument("--image-topic and --odom-topic are for an MCAP recording, not " +
                                command.video);
  }
  camera_io::ReplayOptions options;
  options.path = command.video;
  options.lens = lens;
  camera_io::ReplaySource source(options);
  const drivers::BodyVelocity assumed{command.speed_mps.value_or(0.0), 0.0};
  return replay(command,
                {source.intrinsics(), std::nullopt,
                 source.frame_rate_hz() > 0.0 ? source.frame_rate_hz() : 30.0,
                 [&](camera_io::Frame& frame, drivers::BodyVelocity& measured) {
                   measured = assumed;
                   return source.read(frame, 0.0) == camera_io::ReadStatus::ok;
                 }},
                log);
}

}  // namespace flowsteer::robot
