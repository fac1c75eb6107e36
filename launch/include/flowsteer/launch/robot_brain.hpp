#pragma once

#include <cstdint>
#include <optional>
#include <ostream>

#include "flowsteer/launch/perception.hpp"
#include "flowsteer/launch/robot_launch.hpp"
#include "flowsteer/launch/robot_loop.hpp"
#include "flowsteer/servo/control.hpp"

namespace flowsteer::launch {

// The perception a robot launch file's `perception:` section asks for.
PerceptionOptions perception_options(const PerceptionSection& section);

// The robot's brain: each frame goes through Perception (numerical flow derotated with the
// measured turn rate, flat-ground removal at the measured speed, flow segmentation, features)
// and the goal-reaching controller, with the goal where the loop's GoalTracker puts it.
//
// Blind frames: when Perception gives no features (the first frame, a single-colour frame, a
// size change, no time elapsed) nothing is known about obstacles, so the brain neither
// avoids nor keeps speed: it brakes at the controller's max_accel_mps2 towards a stop (never
// below zero speed) and turns only by the goal term, holding the goal's heading. Each change
// between seeing and blind is logged once, with the reason; the controller takes over again at
// the first frame with flow.
class PerceptionBrain final : public Brain {
 public:
  // log: the changes between seeing and blind. frame_log (may be null): one line per frame
  // with the status, the objects and the command.
  PerceptionBrain(const base::CameraIntrinsics& intrinsics, const PerceptionSection& perception,
                  const ControllerSection& controller, std::ostream& log,
                  std::ostream* frame_log = nullptr);

  base::Command step(const LoopInput& input) override;

  const Perception& perception() const { return perception_; }
  // The last step's controller output (the blind command on a blind frame) and goal.
  const servo::ControlOutput& output() const { return output_; }
  const servo::Percept& percept() const { return percept_; }
  bool blind() const { return perception_.status() != servo::FlowStatus::ok; }
  const StageTimes& times() const { return times_; }

 private:
  Perception perception_;
  servo::Controller controller_;
  double max_accel_mps2_;  // controller.spec.max_accel_mps2, the braking while blind
  std::ostream& log_;
  std::ostream* frame_log_;
  servo::Percept percept_;
  servo::ControlOutput output_;
  StageTimes times_;
  std::optional<servo::FlowStatus> logged_status_;
};

}  // namespace flowsteer::launch
