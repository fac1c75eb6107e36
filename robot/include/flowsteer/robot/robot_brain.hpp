#pragma once

#include <optional>
#include <ostream>

#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/robot/robot_loop.hpp"

namespace flowsteer::robot {

// The brain a robot launch file's `perception:` and `controller:` sections ask for.
pipeline::BrainConfig robot_brain_config(const config::PerceptionSection& perception,
                                         const config::ControllerSection& controller);

// The robot's pipeline::Brain in the robot loop: the same brain the simulator's agents run, with
// the robot's log. Each change between seeing and blind is logged once, with the reason; with a
// frame log, each frame gets a line with the status, the objects and the command, and, when the
// frames' times are on the monotonic clock (a live camera, not a recording), latency_ms: the
// time from the frame's capture to its command.
class RobotBrain final : public FrameHandler {
 public:
  RobotBrain(const base::CameraIntrinsics& intrinsics, const pipeline::BrainConfig& config,
             std::ostream& log, std::ostream* frame_log = nullptr, bool live_camera = false);

  base::Command step(const LoopInput& input) override;
  // Records each step's percept (the image, annotations, step message) as agent 0 of `recorder`
  // from now on; null: no more.
  void record_into(pipeline::RunRecorder* recorder) { recorder_ = recorder; }

  const pipeline::Brain& brain() const { return brain_; }

 private:
  pipeline::Brain brain_;
  std::ostream& log_;
  std::ostream* frame_log_;
  bool live_camera_;
  std::optional<servo::FlowStatus> logged_status_;
  pipeline::RunRecorder* recorder_ = nullptr;
};

}  // namespace flowsteer::robot
