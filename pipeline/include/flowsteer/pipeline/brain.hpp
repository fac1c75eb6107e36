#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/camera_io/frame_source.hpp"
#include "flowsteer/pipeline/perception_options.hpp"
#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/make_room.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::pipeline {

class MotionEnergySteering;
class Perception;

// Features that come from elsewhere than the flow: the simulator's exact geometry, for the
// geometric model (perfect perception, the reference the vision model is compared with).
class FeatureOracle {
 public:
  virtual ~FeatureOracle() = default;
  virtual std::span<const servo::ObjectFeatures> perceive(double speed_mps) = 0;
};

// What a brain is: how it steers and sees, and the body it steers.
struct BrainConfig {
  servo::ControllerConfig controller;
  PerceptionOptions perception;
  double agent_width_m = 0.5;  // its own width, without the controller's clearance margin
  double preferred_speed_mps = 1.0;
};

// The perception a brain of this controller asks for, with a camera at `mount`: flow and
// segmentation as chosen, dark regions when the controller weighs them (delta > 0), the
// renderer's depth when the controller uses depth (a camera has none, whatever it says).
PerceptionOptions perception_options(const servo::PerceptionConfig& perception,
                                     const servo::ControllerConfig& controller,
                                     const base::CameraMount& mount);

// One frame's input: the frame and what the base measured while it was taken.
struct BrainInput {
  const camera_io::Frame& frame;
  double speed_mps = 0.0;
  double turn_rate = 0.0;                  // ω, positive to the right
  std::optional<double> goal_bearing_rad;  // positive to the right
  std::optional<double> goal_distance_m;
  std::optional<std::int32_t> leader_id;  // ObjectFeatures::source_id of the leader
  // Given when the goal above is the last one: how near it counts as at it. Where the brain
  // makes room (makes_room()), it then waits its turn at a goal someone stands on and, once
  // `arrived` there, makes room for others.
  std::optional<double> last_goal_radius_m;
  bool arrived = false;  // at the last goal, where it stays
};

// The bearing of a goal dx_m ahead and dy_m to the left (a frame with x forward, y left, such as
// the world's or a start pose's) from a heading of yaw_rad (counter-clockwise from x), as
// BrainInput::goal_bearing_rad wants it: positive to the right, in [-pi, pi].
double goal_bearing_rad(double dx_m, double dy_m, double yaw_rad);

// Everything from a frame to a command, for every steering model: the simulator's agents
// (flowsteer sim, compare, the evaluations) and the robot (flowsteer run, replay) call this one
// type, so that a clean simulation vouches for the robot.
//
// Blind frames: when the perception the model uses gives no features (the first frame of
// numerical flow, a single-colour frame, a size change, no time elapsed) nothing is known about
// obstacles, so the brain neither avoids nor keeps speed: it brakes at the controller's
// max_accel_mps2 towards a stop (never below zero speed) and turns only by the goal term,
// holding the goal's heading. The geometric model, and motion energy with mass from the
// renderer's ids, perceive without flow and are never blind.
class Brain {
 public:
  // `oracle` gives the features of the geometric model, which needs one (a simulator's).
  // Throws std::invalid_argument when the model cannot run: geometric without an oracle,
  // motion energy following a leader.
  Brain(const base::CameraIntrinsics& intrinsics, const BrainConfig& config,
        std::unique_ptr<FeatureOracle> oracle = nullptr);
  ~Brain();
  Brain(Brain&&) noexcept;
  Brain& operator=(Brain&&) noexcept;

  // Throws std::invalid_argument when the frame lacks what the perception needs (the renderer's
  // channels for synthetic flow or semantic segmentation).
  const servo::ControlOutput& step(const BrainInput& input);

  servo::SteeringModel model() const { return config_.controller.model; }
  // Whether it waits its turn at a taken last goal and, once arrived (BrainInput), makes room
  // for others (servo::MakeRoom): with the flowsteer law reaching a goal, perceiving by flow or
  // geometry. Otherwise an arrived agent has nothing to steer: the papers' laws keep their
  // recorded runs.
  bool makes_room() const;
  // Whether a step reads the frame's image (numerical flow, dark regions, motion energy); with
  // synthetic flow and no image term it reads only the simulator's channels, and a simulator
  // can leave the image out.
  bool reads_image() const;
  // The last step's perception status: FlowStatus::ok when the model had features to steer by.
  servo::FlowStatus status() const { return status_; }
  bool blind() const { return status_ != servo::FlowStatus::ok; }
  // What became of the last frame's flow, whether or not the model steers by it:
  // no_previous_frame before the first step and with the geometric model, which computes none.
  servo::FlowStatus flow_status() const;
  // The last frame's flow, derotated (valid when flow_status() is ok), and its segmentation.
  const servo::FlowField& flow() const;
  const servo::Segmentation& segmentation() const;
  // One entry per pixel of the last numerical flow: 1 where the flow was filled in on an
  // untextured surface rather than measured (servo::UntexturedFill).
  std::span<const std::uint8_t> filled_pixels() const;
  // The features the controller saw: from the flow, or from the oracle (model geometric).
  std::span<const servo::ObjectFeatures> objects() const { return percept_.objects; }
  // The smallest time to contact among those features that approach; NaN when none does.
  double min_ttc_s() const;
  // The goal the last step steered for, as BrainInput gave it.
  std::optional<double> goal_bearing_rad() const { return percept_.goal_bearing_rad; }
  std::optional<double> goal_distance_m() const { return percept_.goal_distance_m; }
  const servo::ControlOutput& output() const { return output_; }
  // What each stage of the last step took (render stays 0: the caller times its camera).
  const StageTimes& times() const { return times_; }
  const base::CameraIntrinsics& intrinsics() const;

 private:
  bool uses_flow() const;

  BrainConfig config_;
  std::unique_ptr<Perception> perception_;
  servo::Controller controller_;
  std::unique_ptr<FeatureOracle> oracle_;
  std::unique_ptr<MotionEnergySteering> motion_energy_;
  std::optional<servo::MakeRoom> make_room_;  // from the first step towards its last goal
  servo::Percept percept_;
  servo::ControlOutput output_;
  servo::FlowStatus status_ = servo::FlowStatus::ok;
  StageTimes times_;
  std::optional<double> previous_frame_s_;  // for the control period
};

}  // namespace flowsteer::pipeline
