#pragma once

#include <atomic>
#include <optional>
#include <ostream>
#include <string>

#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/robot/robot_loop.hpp"
#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::robot {

// `flowsteer run LAUNCH.yaml`: the robot's loop as the launch file describes it.
struct RunCommand {
  std::string launch_file;
  // Override the launch file's goal; a bearing needs a distance (given or in the file).
  std::optional<double> goal_bearing_deg;  // positive to the right
  std::optional<double> goal_distance_m;
  // Besides the events on `log`, this file gets them and one line per frame (status, objects,
  // command). Without a drive the per-frame lines go to `log` too: they are all the run gives.
  std::string log_file;
  // The run's MCAP recording (/cmd_vel as the drive was told, /odom, the camera, the features),
  // finished also when the run ends by an error.
  std::optional<pipeline::RecordingOptions> recording;
};

// Builds the camera, the base (none without a drive: commands are only logged), the
// RobotBrain (the pipeline::Brain every command runs), and runs the loop until the recording ends,
// the camera times out or stop_requested becomes true. Throws base::ConfigError for a bad launch
// file (file:line:col) and std::runtime_error for a camera, drive or log file that cannot be
// opened; the base is left stopped either way.
RobotLoopResult run_robot_command(const RunCommand& command,
                                  const std::atomic<bool>& stop_requested, std::ostream& log);

// `flowsteer replay RECORDING`: the pipeline on a recording, with no drive. The recording is a
// video or an image sequence (camera_io::ReplaySource), or an MCAP file (`.mcap`: a robot's
// `ros2 bag` or flowsteer's own), whose odometry gives the speed and turn rate, whose CameraInfo
// gives the lens and whose /tf_static gives the camera's mount.
struct ReplayCommand {
  std::string video;
  std::string out_dir = "replay_out";
  // The lens: an ideal pinhole with this field of view, or a ROS camera_info file (not both);
  // for an MCAP file, in place of its CameraInfo.
  std::optional<double> hfov_deg;
  std::string camera_info;
  servo::FlowMethod flow = servo::FlowMethod::dis_medium;
  std::optional<double> goal_bearing_deg;  // positive to the right; none: no goal term
  // The speed assumed for the flat-ground test and the controller, where the recording has no
  // odometry (the turn rate is taken as 0). 0 (the default) skips the ground test: the floor
  // then shows as objects when the camera moved. Refused for a recording with odometry.
  std::optional<double> speed_mps;
  // An MCAP file's channels, where it has more than one of the kind.
  std::string image_topic;
  std::string odometry_topic;
  // The replay's own MCAP recording: the images, features and commands.
  std::optional<pipeline::RecordingOptions> recording;
};

struct ReplaySummary {
  std::size_t frames = 0;
  std::size_t blind_frames = 0;
  std::size_t object_rows = 0;
  double mean_step_ms = 0.0;  // Perception and controller, per frame with flow
};

// Writes features.csv (one row per object and frame), commands.csv (one row per frame) and
// overlay.mp4 (the view beside its flow, with FOE, centres, TTC and the goal) into out_dir, all
// at once at the end. Throws std::runtime_error naming the video, the camera_info file or the
// output that failed; out_dir then keeps what it had.
ReplaySummary run_replay_command(const ReplayCommand& command, std::ostream& log);

}  // namespace flowsteer::robot
