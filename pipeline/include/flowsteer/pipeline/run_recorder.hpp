#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/recording/mcap_writer.hpp"
#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::pipeline {

class Brain;

// What a run records into an MCAP file (`--mcap FILE`), and how often it keeps a camera image.
struct RecordingOptions {
  std::filesystem::path path;
  int images_every = 1;  // every Nth frame an agent sees goes in as an image; 0: none
};

// A run's MCAP recording in ROS 2's messages and Foxglove's schemas (docs/RECORDINGS.md), for the
// simulator's agents and the robot alike. Per agent, under its namespace (none for a robot, whose
// topics are ROS's usual /cmd_vel, /odom, …): cmd_vel, odom, the camera's images and
// camera_info, the features drawn on the image (camera/annotations) and the step's command,
// cost terms and features as one plottable message (step); shared: /tf (the fixed frame → each
// base) and /tf_static (each base → its camera). Times are nanoseconds on the run's clock.
class RunRecorder {
 public:
  // clock: "simulation" or "monotonic", recorded in the metadata; fixed_frame: the frame the
  // poses are in ("world" in the simulator, "odom" on a robot). Throws std::runtime_error
  // naming the file when it cannot be created.
  RunRecorder(const RecordingOptions& options, std::string clock, std::string fixed_frame);
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  // Names as ROS allows them in topics and frames, one per name given, in order: letters, digits
  // and single underscores, not led by a digit nor ending in '_'; a name that two would share gets
  // its index after it.
  static std::vector<std::string> ros_names(const std::vector<std::string>& names);

  // Adds an agent whose topics go under /`ns` ("" for a robot's plain topics); returns its index.
  // Without a mount (a robot without one, a replay of a video) its camera is left out of
  // /tf_static, so that a replay of the recording does not take one it never had.
  std::size_t add_agent(const std::string& ns, const base::CameraIntrinsics& intrinsics,
                        const std::optional<base::CameraMount>& mount);
  // /tf_static: every agent's base → camera, once the agents are added.
  void write_mounts(std::uint64_t t_ns);

  // What the base was told: speed (m/s) and turn rate ω (positive right; the yaw rate is −ω).
  void command(std::size_t agent, std::uint64_t t_ns, double speed_mps, double turn_rate);
  // Where the base is in the fixed frame and how it moves.
  void odometry(std::size_t agent, std::uint64_t t_ns, double x_m, double y_m, double yaw_rad,
                double speed_mps, double turn_rate);
  // /tf: every agent's last odometry pose.
  void write_transforms(std::uint64_t t_ns);
  // The brain's last step: annotations and step message; the image and camera_info at every
  // images_every-th call.
  void percept(std::size_t agent, std::uint64_t t_ns, const Brain& brain, const cv::Mat& image);

  // A channel of the caller's own (the simulator's world), JSON with its JSON Schema, and a
  // message on it.
  std::uint16_t json_channel(const std::string& topic, const char* schema_name,
                             const std::string& schema);
  void write_json(std::uint16_t channel, std::uint64_t t_ns, const std::string& json);

  // Writes the metadata (the clock and the agents' namespaces, with `metadata`) and the summary,
  // and gives the file its name.
  void finish(std::vector<std::pair<std::string, std::string>> metadata);

 private:
  struct Agent {
    std::string ns;
    base::CameraIntrinsics intrinsics;
    std::optional<base::CameraMount> mount;
    std::uint16_t cmd_vel, odom, image, camera_info, annotations, step;
    std::optional<recording::ros2::TransformStamped> pose;  // the last odometry's
    int percepts = 0;
  };
  std::string frame(const Agent& agent, const char* frame) const;
  template <typename Message>
  std::uint16_t ros2_channel(const std::string& topic);
  template <typename Message>
  void write(std::uint16_t channel, std::uint64_t t_ns, const Message& message);
  void write_image(const Agent& agent, std::uint64_t t_ns, const cv::Mat& image);

  recording::McapWriter writer_;
  RecordingOptions options_;
  std::string clock_;
  std::string fixed_frame_;
  std::vector<Agent> agents_;
  std::vector<std::pair<std::string, std::uint16_t>> schemas_;  // by name: its id
  std::uint16_t tf_ = 0;
  std::uint16_t tf_static_ = 0;
  std::vector<std::uint8_t> bytes_;  // a message's encoding, reused
};

}  // namespace flowsteer::pipeline
