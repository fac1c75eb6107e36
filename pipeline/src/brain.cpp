#include "flowsteer/pipeline/brain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "flowsteer/base/clock.hpp"
#include "motion_energy_steering.hpp"
#include "perception.hpp"

namespace flowsteer::pipeline {

PerceptionOptions perception_options(const servo::PerceptionConfig& perception,
                                     const servo::ControllerConfig& controller,
                                     const base::CameraMount& mount) {
  PerceptionOptions options;
  options.flow = perception.flow;
  options.segmentation = perception.segmentation;
  options.depth = perception.depth;
  options.dark_regions = servo::navigation_weights(controller).delta > 0.0;
  options.use_depth = controller.use_depth;
  options.mount = mount;
  // Its points are ground contacts, which only flow segmentation with a camera's depths gives; the
  // papers' laws keep the perception they were recorded with.
  options.obstacle_memory =
      perception.obstacle_memory && controller.law == servo::NavigationLaw::flowsteer &&
      options.segmentation != servo::SegmentationMethod::semantic && !per_pixel_depth(options);
  return options;
}

double goal_bearing_rad(double dx_m, double dy_m, double yaw_rad) {
  return -std::remainder(std::atan2(dy_m, dx_m) - yaw_rad, 2.0 * std::numbers::pi);
}

namespace {

// The angle from the optical axis to the image's further side edge.
double half_view_rad(const base::CameraIntrinsics& intrinsics) {
  return std::atan(std::max(intrinsics.cx_px, intrinsics.width_px - intrinsics.cx_px) /
                   intrinsics.fx_px);
}

}  // namespace

Brain::Brain(const base::CameraIntrinsics& intrinsics, const BrainConfig& config,
             std::unique_ptr<FeatureOracle> oracle)
    : config_(config),
      perception_(std::make_unique<Perception>(intrinsics, config.perception)),
      controller_(servo::make_controller(
          config.controller, config.agent_width_m, config.preferred_speed_mps,
          {half_view_rad(intrinsics), per_pixel_depth(config.perception) || oracle != nullptr})),
      oracle_(std::move(oracle)) {
  if (model() == servo::SteeringModel::geometric && !oracle_) {
    throw std::invalid_argument(
        "the geometric model takes its features from the simulator's exact geometry; a camera "
        "has none (use vision)");
  }
  if (model() == servo::SteeringModel::motion_energy) {
    motion_energy_ = std::make_unique<MotionEnergySteering>(
        config.controller, intrinsics, config.perception.mount, config.preferred_speed_mps,
        0.5 * (config.agent_width_m + config.controller.clearance_margin_m));
  }
}

Brain::~Brain() = default;
Brain::Brain(Brain&&) noexcept = default;
Brain& Brain::operator=(Brain&&) noexcept = default;

bool Brain::reads_image() const {
  return motion_energy_ != nullptr || (!oracle_ && perception_->reads_image());
}

servo::FlowStatus Brain::flow_status() const {
  return perception_->status();
}

const servo::FlowField& Brain::flow() const {
  return perception_->flow();
}

std::span<const std::uint8_t> Brain::filled_pixels() const {
  return perception_->filled_pixels();
}

const servo::Segmentation& Brain::segmentation() const {
  return perception_->segmentation();
}

const base::CameraIntrinsics& Brain::intrinsics() const {
  return perception_->intrinsics();
}

bool Brain::makes_room() const {
  return config_.controller.law == servo::NavigationLaw::flowsteer &&
         config_.controller.kind == servo::NavigationKind::goal_reaching && !motion_energy_;
}

bool Brain::uses_flow() const {
  switch (model()) {
    case servo::SteeringModel::vision:
      return true;
    case servo::SteeringModel::geometric:
      return false;
    case servo::SteeringModel::motion_energy:
      return config_.controller.mass_from == servo::MassSource::ground;
  }
  return true;
}

const servo::ControlOutput& Brain::step(const BrainInput& input) {
  const base::Stopwatch total;
  times_ = {};
  status_ = servo::FlowStatus::ok;
  // The geometric reference perceives by exact geometry: flow would only cost it time.
  if (!oracle_) {
    const servo::FlowStatus status =
        perception_->process(input.frame, input.speed_mps, input.turn_rate, times_);
    if (uses_flow()) {
      status_ = status;
    }
  }
  const base::Stopwatch control;
  percept_ = servo::Percept{oracle_ ? oracle_->perceive(input.speed_mps) : perception_->objects(),
                            input.goal_bearing_rad, input.goal_distance_m, input.leader_id};
  // The command is held until the next frame; the last interval between frames is the best
  // guess of how long that is.
  const servo::AgentState agent{
      input.speed_mps,
      previous_frame_s_ ? std::max(0.0, input.frame.timestamp_s - *previous_frame_s_) : 0.0};
  const bool to_last_goal = input.last_goal_radius_m && makes_room();
  if (to_last_goal && !make_room_) {
    make_room_.emplace(servo::make_room_options(config_.controller, config_.agent_width_m));
  }
  std::optional<base::Command> standing;
  if (to_last_goal && input.arrived) {
    standing = make_room_->step(percept_, agent, input.turn_rate, *input.last_goal_radius_m);
  }
  if (standing) {
    output_.command = output_.unclamped = *standing;
    output_.cost = 0.0;
    output_.terms.clear();
  } else if (motion_energy_) {
    motion_energy_->step(input.frame, perception_->flow(), percept_, {input.speed_mps}, output_);
  } else {
    controller_.step(percept_, agent, output_);
    if (to_last_goal && !input.arrived) {
      output_.command =
          make_room_->approach(percept_, agent, output_.command, *input.last_goal_radius_m);
    }
  }
  if (blind()) {
    // A blind frame has no objects, so only the goal term turns; the speed term's acceleration
    // gives way to braking, only while moving: the base never backs up, and a stopped one stays.
    output_.command.accel_mps2 = input.speed_mps > 0.0 ? -config_.controller.max_accel_mps2 : 0.0;
  }
  previous_frame_s_ = input.frame.timestamp_s;
  times_.control = control.elapsed_ms();
  times_.total = total.elapsed_ms();
  return output_;
}

double Brain::min_ttc_s() const {
  double least_s = std::numeric_limits<double>::quiet_NaN();
  for (const servo::ObjectFeatures& o : percept_.objects) {
    if (o.status == servo::MotionStatus::approaching && o.ttc_s > 0.0 && !(o.ttc_s >= least_s)) {
      least_s = o.ttc_s;
    }
  }
  return least_s;
}

}  // namespace flowsteer::pipeline
