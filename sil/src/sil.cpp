#include "flowsteer/sil/sil.hpp"

#include <unistd.h>

#include <cmath>
#include <stdexcept>

#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "robot_in_the_loop.hpp"

namespace flowsteer::sil {

namespace {

std::size_t find_agent(const sim_camera::WorldSpec& world, const std::string& name) {
  std::string names;
  for (std::size_t i = 0; i < world.agents.size(); ++i) {
    if (world.agents[i].name == name) {
      return i;
    }
    names += (i == 0 ? "" : ", ") + world.agents[i].name;
  }
  throw std::invalid_argument("sil: scenario " + world.name + " has no agent named '" + name +
                              "' (its agents: " + names + ")");
}

const camera_io::V4l2Options& v4l2_camera(const config::RobotLaunch& launch,
                                          const std::string& file) {
  const auto* v4l2 = std::get_if<camera_io::V4l2Options>(&launch.camera.source);
  if (v4l2 == nullptr) {
    throw std::invalid_argument("sil: " + file + ": camera " +
                                config::describe_camera(launch.camera) +
                                ": the loop needs a v4l2 camera (vivid's capture node)");
  }
  if (v4l2->format != camera_io::PixelFormat::yuyv) {
    throw std::invalid_argument("sil: " + file + ": camera.v4l2.pixel_format " +
                                std::string(camera_io::fourcc_name(v4l2->format)) +
                                ": the loop shows its views in YUYV");
  }
  if (v4l2->lens.model) {
    throw std::invalid_argument("sil: " + file +
                                ": camera.calibration: the simulator renders an "
                                "ideal pinhole; give horizontal_fov_rad instead");
  }
  return *v4l2;
}

const drivers::OdriveCanConfig& odrive_drive(const config::RobotLaunch& launch,
                                             const std::string& file) {
  const auto* odrive =
      launch.drive ? std::get_if<drivers::OdriveCanConfig>(&launch.drive->drive) : nullptr;
  if (odrive == nullptr) {
    throw std::invalid_argument("sil: " + file +
                                ": the loop needs drive.type odrive_can (the simulator plays the "
                                "ODrive pair on the CAN interface)");
  }
  return *odrive;
}

// The agent as the robot is: at rest at the start, the launch file's camera, and a speed limit
// the robot's own limits decide.
void become_robot(sim_camera::AgentSpec& agent, const config::RobotLaunch& launch,
                  const camera_io::V4l2Options& camera) {
  agent.start_speed_mps = 0.0;
  const base::CameraMount& mount = *launch.perception.mount;
  agent.camera = {camera.width_px, camera.height_px, camera.lens.horizontal_fov_rad, mount.height_m,
                  mount.pitch_rad};
  agent.max_speed_mps = std::max(agent.max_speed_mps, launch.drive->stage.limits.max_speed_mps);
}

// --goal-bearing (degrees, positive right) and --goal-distance of the agent's one goal.
std::vector<std::string> goal_arguments(const sim_camera::AgentSpec& agent) {
  if (agent.goals.size() != 1 || agent.leader) {
    throw std::invalid_argument("sil: agent " + agent.name +
                                " must have exactly one goal and no leader: the robot's launch "
                                "takes one goal");
  }
  const Eigen::Vector2d to_goal = agent.goals.front() - agent.start_m;
  const double bearing_rad =
      pipeline::goal_bearing_rad(to_goal.x(), to_goal.y(), agent.heading_rad);
  return {"--goal-bearing", std::to_string(bearing_rad * 180.0 / std::numbers::pi),
          "--goal-distance", std::to_string(to_goal.norm())};
}

}  // namespace

SilResult run_sil(const sim_camera::WorldSpec& world, const SilOptions& options,
                  std::ostream& log) {
  const config::RobotLaunch launch = config::read_robot_launch(options.launch_file);
  const camera_io::V4l2Options& camera = v4l2_camera(launch, options.launch_file);
  sim_camera::WorldSpec spec = world;
  const std::size_t agent = find_agent(spec, options.robot_agent);
  become_robot(spec.agents[agent], launch, camera);

  RobotLink link;
  link.capture_device = camera.device;
  link.output_device = options.output_device;
  link.width_px = camera.width_px;
  link.height_px = camera.height_px;
  link.odrive = odrive_drive(launch, options.launch_file);
  link.geometry = launch.drive->stage.geometry;
  link.robot_log = std::filesystem::temp_directory_path() /
                   ("flowsteer-sil-robot-" + std::to_string(::getpid()) + ".log");
  // This process's own binary: the robot runs the flowsteer that simulates it.
  link.robot_argv = {"/proc/self/exe", "run", options.launch_file};
  for (std::string& arg : goal_arguments(spec.agents[agent])) {
    link.robot_argv.push_back(std::move(arg));
  }
  link.robot_argv.insert(link.robot_argv.end(), {"--log", link.robot_log.string()});
  if (options.recording) {
    link.robot_argv.insert(link.robot_argv.end(),
                           {"--mcap", robot_recording_path(options.recording->path).string(),
                            "--mcap-images", std::to_string(options.recording->images_every)});
  }
  link.agent = agent;
  link.startup_timeout_s = options.startup_timeout_s;
  RobotInTheLoop driver(std::move(link), log);

  sim::SimOptions sim;
  sim.out_dir = options.out_dir;
  sim.steps = options.steps;
  // The other agents on this thread only: the robot process needs the other cores.
  sim.threads = 1;
  sim.driver = &driver;
  sim.driven_agent = agent;
  sim.recording = options.recording;
  SilResult result;
  result.sim = sim::run_simulation(spec, sim, log);
  result.report = driver.report();
  return result;
}

std::filesystem::path robot_recording_path(const std::filesystem::path& recording) {
  std::filesystem::path robot = recording;
  robot.replace_extension(".robot" + recording.extension().string());
  return robot;
}

}  // namespace flowsteer::sil
