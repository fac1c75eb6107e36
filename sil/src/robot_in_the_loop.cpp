#include "robot_in_the_loop.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/camera_io/v4l2_camera.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "vivid_loop.hpp"

namespace flowsteer::sil {

namespace {

// The mean difference, in 8-bit levels, a test card may come back with: YUYV's rounding.
constexpr double kLoopTolerance = 2.0;

void sleep_until(double monotonic_s) {
  const double left_s = monotonic_s - base::monotonic_now_s();
  if (left_s > 0.0) {
    std::this_thread::sleep_for(std::chrono::duration<double>(left_s));
  }
}

}  // namespace

void LatencyStats::add(double ms) {
  ++count;
  mean_ms += (ms - mean_ms) / count;
  max_ms = std::max(max_ms, ms);
}

RobotInTheLoop::RobotInTheLoop(RobotLink link, std::ostream& log)
    : link_(std::move(link)), log_(log) {
  // A view is shown just after an output frame, goes out on the next (the driver shows the
  // buffer queued before it first) and is captured within a frame of that: the robot's camera
  // stamps it about three frames after its step.
  view_lead_s_ = 3.0 * connect_vivid_loop(link_.capture_device, link_.output_device);
  output_.emplace(
      camera_io::V4l2OutputOptions{link_.output_device, link_.width_px, link_.height_px});
  check_loop();
  try {
    odrive_.emplace(link_.odrive.interface, link_.odrive.left.node_id, link_.odrive.right.node_id);
  } catch (const drivers::DriveError& e) {
    throw std::runtime_error(
        std::string(e.what()) + " (a virtual bus: `modprobe vcan && ip link add dev " +
        link_.odrive.interface + " type vcan && ip link set " + link_.odrive.interface + " up`)");
  }
}

// A test card through the loop and back: vivid scales between the frame size and its HDMI
// timings on both sides, and a loop that moved, stretched or blurred the picture would give the
// robot a camera other than the one its launch file describes.
void RobotInTheLoop::check_loop() {
  cv::Mat card(link_.height_px, link_.width_px, CV_8UC3);
  for (int y = 0; y < card.rows; ++y) {
    for (int x = 0; x < card.cols; ++x) {
      card.at<cv::Vec3b>(y, x) =
          cv::Vec3b::all(static_cast<std::uint8_t>(32 + (x * 7 + y * 13) % 192));
    }
  }
  output_->show(card);
  camera_io::V4l2Options options;
  options.device = link_.capture_device;
  options.width_px = link_.width_px;
  options.height_px = link_.height_px;
  options.frame_rate_hz = 0.0;
  camera_io::V4l2Camera camera(options);
  camera_io::Frame frame;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 30 && best > kLoopTolerance; ++i) {
    if (camera.read(frame, 1.0) == camera_io::ReadStatus::ok) {
      cv::Mat diff;
      cv::absdiff(frame.image, card, diff);
      best = std::min(best, cv::mean(diff)[1]);
    }
  }
  report_.loop_error_levels = best;
  log_ << "flowsteer sil: the loop gives back a test card with a mean difference of " << best
       << " levels\n";
  if (!(best <= kLoopTolerance)) {
    throw std::runtime_error(
        "vivid loop: " + link_.output_device + " to " + link_.capture_device +
        " gives back a test card changed by " + std::to_string(best) +
        " levels on average (at most " + std::to_string(kLoopTolerance) +
        " allowed): vivid's scaling or its loop is not what flowsteer sil set");
  }
}

base::Command RobotInTheLoop::step(const sim_camera::World& world, sim_camera::Renderer& renderer) {
  world_ = &world;
  const double dt = world.spec().step_s;
  if (!robot_) {
    render(world, renderer);
    show();
    start_robot();
  }
  const long k = steps_++;
  const double behind_s = base::monotonic_now_s() - (start_s_ + static_cast<double>(k) * dt);
  report_.max_behind_ms = std::max(report_.max_behind_ms, 1e3 * behind_s);
  // The world keeps to the clock, which the robot's odometry and watchdog run on: a step the
  // renderer cannot show in time goes without its view, as a camera drops a frame.
  const bool view = behind_s < dt && report_.output_error.empty();
  if (view) {
    render(world, renderer);
  }
  wait_for_step(k, dt);
  if (view && report_.output_error.empty()) {
    show();
  } else {
    ++report_.views_dropped;
  }
  const double now_s = base::monotonic_now_s();
  if (const std::optional<int> status = robot_->poll()) {
    report_.robot_ended_itself = true;
    report_.robot_exit_status = *status;
    report_.robot_end_time_s = world.time_s();
  }
  const drivers::BodyVelocity motion = wheel_motion(now_s, dt);
  const sim_camera::AgentState& agent = world.agents()[link_.agent];
  // The world integrates (a_c, ω) over the step: this a_c gives the wheels' speed at once.
  return {(motion.speed_mps - agent.speed_mps) / dt, motion.turn_rate};
}

void RobotInTheLoop::render(const sim_camera::World& world, sim_camera::Renderer& renderer) {
  // The agent as it will be when the robot's camera stamps the view, moving as it moves now
  // (the world's own integration): what a camera would show at that time.
  sim_camera::View view = sim_camera::View::of_agent(world, link_.agent);
  sim_camera::AgentState ahead = world.agents()[link_.agent];
  ahead.coast(view_lead_s_);
  view.position_m = ahead.position_m;
  view.yaw_rad = ahead.yaw_rad;
  renderer.render(world, view, view_, sim_camera::RenderChannels::all);
}

void RobotInTheLoop::show() {
  try {
    output_->show(view_.image);
    ++report_.views_shown;
  } catch (const std::runtime_error& e) {
    stop_showing(e.what());
  }
}

void RobotInTheLoop::stop_showing(const std::string& why) {
  // vivid fails its output with its capture stream: the robot's camera is gone, and the run goes
  // on to record what the robot does about it.
  report_.output_error = why;
  log_ << "flowsteer sil: the views can no longer be shown: " << why << "\n";
}

void RobotInTheLoop::wait_for_step(long k, double dt) {
  sleep_until(start_s_ + static_cast<double>(k) * dt);
  // The view goes out just after the output's next frame: each view then reaches the robot's
  // capture the same number of frames after it is shown, and the time between two new pictures
  // the robot sees is the time between their views to a frame, not to two.
  if (report_.output_error.empty() && !output_->wait_for_frames(output_->frames_shown() + 1, 1.0)) {
    const std::string error = output_->error();
    stop_showing(error.empty() ? link_.output_device + ": the device showed no frame for 1 s"
                               : error);
  }
}

void RobotInTheLoop::start_robot() {
  log_ << "flowsteer sil: starting the robot:";
  for (const std::string& arg : link_.robot_argv) {
    log_ << " " << arg;
  }
  log_ << "\n";
  const double started_s = base::monotonic_now_s();
  robot_ = std::make_unique<RobotProcess>(link_.robot_argv);
  for (;;) {
    const auto axes = odrive_->axes();
    if (axes[0].state == drivers::odrive::kAxisStateClosedLoop &&
        axes[1].state == drivers::odrive::kAxisStateClosedLoop) {
      break;
    }
    if (const std::optional<int> status = robot_->poll()) {
      throw std::runtime_error(
          "the robot process exited with status " + std::to_string(*status) +
          " before it activated its drive (its log: " + link_.robot_log.string() + ")");
    }
    if (base::monotonic_now_s() - started_s > link_.startup_timeout_s) {
      throw std::runtime_error(
          "the robot process did not activate its drive (both axes in "
          "closed-loop control) within " +
          std::to_string(link_.startup_timeout_s) + " s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  start_s_ = base::monotonic_now_s();
  first_frame_ = output_->frames_shown();
  const auto axes = odrive_->axes();
  last_pos_turns_ = {axes[0].pos_turns, axes[1].pos_turns};
  report_.wait_for_robot_s = start_s_ - started_s;
  log_ << "flowsteer sil: the robot activated its drive after " << report_.wait_for_robot_s
       << " s; the world runs\n";
}

drivers::BodyVelocity RobotInTheLoop::wheel_motion(double now_s, double dt) {
  const auto axes = odrive_->axes();
  const std::array<const drivers::OdriveAxisConfig*, 2> configs{&link_.odrive.left,
                                                                &link_.odrive.right};
  std::array<double, 2> wheel_radps{};
  for (std::size_t i = 0; i < 2; ++i) {
    // Sampling the velocity once a step would turn the agent by other angles than the encoders
    // report when the robot changes its command between steps: its odometry would drift from
    // the world by the loop, not by the robot.
    const double turned = axes[i].pos_turns - last_pos_turns_[i];
    last_pos_turns_[i] = axes[i].pos_turns;
    wheel_radps[i] = turned / dt * link_.odrive.wheel_rad_per_turn(*configs[i]);
    if (axes[i].setpoint_changed_s && *axes[i].setpoint_changed_s > last_setpoint_s_[i]) {
      last_setpoint_s_[i] = *axes[i].setpoint_changed_s;
      report_.command_to_motion.add(1e3 * (now_s - last_setpoint_s_[i]));
    }
  }
  return drivers::from_wheels({wheel_radps[0], wheel_radps[1]}, link_.geometry);
}

void RobotInTheLoop::finish(base::OutputDir* out) {
  if (robot_) {
    report_.output_frame_rate_hz = static_cast<double>(output_->frames_shown() - first_frame_) /
                                   (base::monotonic_now_s() - start_s_);
  }
  if (robot_ && !report_.robot_ended_itself) {
    report_.robot_exit_status = robot_->stop(5.0);
    report_.robot_end_time_s = world_ != nullptr ? world_->time_s() : 0.0;
  }
  if (world_ != nullptr) {
    report_.robot_stop_position_m = world_->agents()[link_.agent].position_m;
  }
  const std::string robot_log = read_robot_log();
  if (out != nullptr) {
    base::write_text(out->staging_path("robot.log"), robot_log);
    write_report(out->staging_path("sil.json"));
  }
  std::error_code ignored;
  std::filesystem::remove(link_.robot_log, ignored);
}

// The robot's frame log has a line per frame with "latency_ms X", the delay from the frame's
// capture to its command (robot/src/robot_brain.cpp). Returns the log's text; none when the
// robot never started.
std::string RobotInTheLoop::read_robot_log() {
  std::ostringstream text;
  text << std::ifstream(link_.robot_log).rdbuf();
  std::istringstream in(text.str());
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t at = line.find(" latency_ms ");
    if (line.rfind("frame ", 0) == 0 && at != std::string::npos) {
      report_.capture_to_command.add(std::stod(line.substr(at + 12)));
    }
  }
  return text.str();
}

void RobotInTheLoop::write_report(const std::filesystem::path& path) const {
  const auto latency = [](const LatencyStats& s) {
    return "{\"count\": " + std::to_string(s.count) +
           ", \"mean_ms\": " + base::json_number(s.mean_ms) +
           ", \"max_ms\": " + base::json_number(s.max_ms) + "}";
  };
  const SilReport& r = report_;
  std::ostringstream json;
  json << "{\n  \"robot_exit_status\": " << r.robot_exit_status
       << ",\n  \"robot_ended_itself\": " << (r.robot_ended_itself ? "true" : "false")
       << ",\n  \"robot_end_time_s\": " << base::json_number(r.robot_end_time_s)
       << ",\n  \"robot_stop_position_m\": [" << base::json_number(r.robot_stop_position_m.x())
       << ", " << base::json_number(r.robot_stop_position_m.y())
       << "],\n  \"capture_to_command\": " << latency(r.capture_to_command)
       << ",\n  \"command_to_motion\": " << latency(r.command_to_motion)
       << ",\n  \"views_shown\": " << r.views_shown << ",\n  \"views_dropped\": " << r.views_dropped
       << ",\n  \"max_behind_ms\": " << base::json_number(r.max_behind_ms)
       << ",\n  \"output_error\": " << base::json_string(r.output_error)
       << ",\n  \"loop_error_levels\": " << base::json_number(r.loop_error_levels)
       << ",\n  \"wait_for_robot_s\": " << base::json_number(r.wait_for_robot_s)
       << ",\n  \"output_frame_rate_hz\": " << base::json_number(r.output_frame_rate_hz) << "\n}\n";
  base::write_text(path, json.str());
}

}  // namespace flowsteer::sil
