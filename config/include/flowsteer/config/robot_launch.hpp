#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/camera_io/libcamera_camera.hpp"
#include "flowsteer/camera_io/replay_source.hpp"
#include "flowsteer/camera_io/ros2_camera.hpp"
#include "flowsteer/camera_io/v4l2_camera.hpp"
#include "flowsteer/config/drive_config.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::config {

// The `camera:` section of a robot launch file (fields in launch/launch_files/README.md).
struct CameraSection {
  std::variant<camera_io::V4l2Options, camera_io::LibcameraOptions, camera_io::ReplayOptions,
               camera_io::Ros2CameraOptions>
      source;
  // No frame for this long stops the base.
  double timeout_s = 0.5;
  // The camera_info file the lens options were read from (resolved against the launch file's
  // folder); empty without one.
  std::string calibration_file;
};

// A goal given as where it lies from the robot's start: bearing from the heading, positive to
// the right (as servo::Percept), and distance.
struct GoalSection {
  double bearing_rad = 0.0;
  double distance_m = 0.0;
};

// The `perception:` section: how the robot sees (numerical flow and flow segmentation; a camera
// has neither the simulator's flow nor its object ids) and where the camera sits.
struct PerceptionSection {
  servo::FlowMethod flow = servo::FlowMethod::dis_fast;
  servo::SegmentationMethod segmentation = servo::SegmentationMethod::flow_graph_fast;
  bool dark_regions = false;     // MIG 2019's dark regions; needs controller.delta > 0
  bool obstacle_memory = false;  // servo::PerceptionConfig::obstacle_memory
  // From `mount: FILE` (calibration's camera mount file) or inline height_m / pitch_deg; none
  // when the file gives neither. Required with a drive: the flat-ground test predicts the
  // floor's flow from it. Without a drive the measured speed is zero and the test is skipped,
  // so any mount serves.
  std::optional<base::CameraMount> mount;
  std::string mount_file;  // resolved against the launch file's folder; empty when inline
};

// The `controller:` section: goal reaching (CGF's navigation function on the features), with
// the robot's preferred speed and width.
struct ControllerSection {
  // Model vision, kind goal_reaching. use_depth: the depths a camera's features carry, those of
  // the ground where objects stand on it (servo::FeatureOptions::ground_mount).
  servo::ControllerConfig spec;
  double preferred_speed_mps = 0.3;
  // The robot's own width in the avoidance terms (CGF §6.2's agent width, plus
  // spec.clearance_margin_m).
  double robot_width_m = 0.4;
};

struct RobotLaunch {
  CameraSection camera;
  std::optional<DriveSection> drive;  // none: perception and commands without a drive
  std::optional<GoalSection> goal;
  PerceptionSection perception;
  ControllerSection controller;
  std::vector<std::string> warnings;  // from the camera_info reader
};

// Reads a robot launch file. Throws base::ConfigError naming the file, line, column and field of
// the first problem: an unknown key or type, a value out of range, a calibration file that cannot
// be read (its own file:line:col) or is for another image size.
RobotLaunch read_robot_launch(const std::string& path);
// The same for launch-file text; relative paths resolve against base_dir.
RobotLaunch parse_robot_launch(const std::string& yaml_text, const std::string& source_name,
                               const std::string& base_dir);

// "dis_ultrafast, dis_fast, ...": the flow methods a camera can use (all but synthetic).
std::string numerical_flow_method_names();

// Opens the camera the section describes. Throws std::runtime_error naming the device or file
// (a missing device, no camera found, an unreadable recording).
std::unique_ptr<camera_io::FrameSource> make_camera(const CameraSection& section);
// "v4l2 /dev/video0", "replay run.mp4", for logs.
std::string describe_camera(const CameraSection& section);

}  // namespace flowsteer::config
