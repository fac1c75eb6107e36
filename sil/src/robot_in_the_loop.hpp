#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "flowsteer/camera_io/v4l2_output.hpp"
#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/drivers/odrive_can.hpp"
#include "flowsteer/drivers/simulated_odrive.hpp"
#include "flowsteer/sil/sil.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "robot_process.hpp"

namespace flowsteer::sil {

// What ties the robot process to its agent in the world.
struct RobotLink {
  std::string capture_device;  // the launch file's camera
  std::string output_device;   // vivid's output node looped to it
  int width_px = 0;
  int height_px = 0;
  drivers::OdriveCanConfig odrive;  // the launch file's drive: the axes to simulate
  drivers::WheelGeometry geometry;
  std::vector<std::string> robot_argv;
  std::filesystem::path robot_log;  // where the robot writes its log (--log)
  std::size_t agent = 0;
  double startup_timeout_s = 30.0;
};

// The sim::AgentDriver of `flowsteer sil`: shows the agent's view on the output device at each
// step's time, and moves the agent by the simulated ODrive's wheel velocities. The robot process
// starts at the first step, and the world waits until it has activated its drive.
class RobotInTheLoop final : public sim::AgentDriver {
 public:
  // Connects vivid's loop and opens the output device and the CAN interface (the robot starts at
  // the first step); throws std::runtime_error saying what is missing.
  RobotInTheLoop(RobotLink link, std::ostream& log);

  base::Command step(const sim_camera::World& world, sim_camera::Renderer& renderer) override;
  bool finished() const override { return report_.robot_ended_itself; }
  void finish(base::OutputDir* out) override;

  const SilReport& report() const { return report_; }

 private:
  // The agent's view as the robot's camera will capture it; show() sends it to the output.
  void check_loop();
  void render(const sim_camera::World& world, sim_camera::Renderer& renderer);
  void show();
  // Records why the output takes no more views; the run goes on without them.
  void stop_showing(const std::string& why);
  void start_robot();
  // Waits for step k's time, then for the output's next frame.
  void wait_for_step(long k, double dt);
  // The agent's speed and turn rate over a step of dt: what the wheels turned since the last
  // step, so that the world moves as the robot's encoders say it did. Records new setpoints'
  // delays.
  drivers::BodyVelocity wheel_motion(double now_s, double dt);
  std::string read_robot_log();
  void write_report(const std::filesystem::path& path) const;

  RobotLink link_;
  std::ostream& log_;
  std::optional<camera_io::V4l2Output> output_;
  std::optional<drivers::SimulatedOdrive> odrive_;
  std::unique_ptr<RobotProcess> robot_;
  const sim_camera::World* world_ = nullptr;
  sim_camera::RenderedView view_;
  double view_lead_s_ = 0.0;       // from a view's step to its capture by the robot's camera
  std::uint64_t first_frame_ = 0;  // the output's frame count at step 0
  double start_s_ = 0.0;           // the monotonic time of step 0
  long steps_ = 0;
  std::array<double, 2> last_setpoint_s_{-1.0, -1.0};
  std::array<double, 2> last_pos_turns_{};  // the axes' positions at the last step
  SilReport report_;
};

}  // namespace flowsteer::sil
