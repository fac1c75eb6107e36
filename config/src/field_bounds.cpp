#include "flowsteer/config/field_bounds.hpp"

#include <initializer_list>
#include <string>
#include <vector>

#include "flowsteer/base/quantity_bounds.hpp"

namespace flowsteer::config {

namespace {

using base::FieldBound;
using namespace base::bounds;

// A table under construction: rows added under a prefix ("agents[].camera"), joined by the
// format's separator ('.' in YAML paths, '/' between XML elements).
class Table {
 public:
  explicit Table(char separator = '.') : separator_(separator) {}
  Table& add(const std::string& prefix, std::initializer_list<FieldBound> rows) {
    for (const FieldBound& row : rows) {
      rows_.push_back({prefix.empty() ? row.field : prefix + separator_ + row.field, row.bound});
    }
    return *this;
  }
  std::vector<FieldBound> rows() && { return std::move(rows_); }

 private:
  char separator_;
  std::vector<FieldBound> rows_;
};

// The navigation law's fields, in a scenario and in a robot launch file (controller_reader.cpp);
// follow_gap_m is for agents that follow, which a robot does not.
const std::initializer_list<FieldBound> kControllerRows = {
    {"alpha", kCostWeight},
    {"beta", kCostWeight},
    {"gamma", kCostWeight},
    {"delta", kCostWeight},
    {"braking", kCostWeight},
    {"anticipation", kCostWeight},
    {"max_speed_ratio", kSpeedRatio},
    {"lambda", kGain},
    {"max_accel_mps2", kAccel_mps2},
    {"max_turn_rate", kTurnRate_radps},
    {"clearance_margin_m", kMargin_m},
};

// type: motion_energy's own (scenarios only: a robot steers by the law).
const std::initializer_list<FieldBound> kMotionEnergyRows = {
    {"flow_weight", kFraction},
    {"steer_gain", kCostWeight},
    {"goal_gain", kCostWeight},
    {"head_on_energy", kPositiveFraction},
    {"head_on_balance", kPositiveFraction},
    {"danger_distance_m", kRange_m},
    {"danger_fraction", kPositiveFraction},
    {"corner_step", kPositiveFraction},
    {"corner_rise", kPositiveFraction},
    {"free_path_range_m", kRange_m},
};

const std::initializer_list<FieldBound> kCameraRows = {
    {"resolution", kImageSide_px},        {"hfov_deg", kHfov_deg},
    {"height_m", kCameraHeight_m},        {"pitch_deg", kCameraPitch_deg},
    {"noise_sigma", kCameraNoise_levels},
};

const std::initializer_list<FieldBound> kMaterialRows = {
    {"albedo", kFraction},
    {"scale_m", kPatternScale_m},
    {"contrast", kFraction},
};

const std::initializer_list<FieldBound> kLightRows = {
    {"intensity", kLightIntensity},
    {"range_m", kLightRange_m},
    {"height_m", kLightHeight_m},
};

// A box's or a cylinder's shape, standing or moving.
const std::initializer_list<FieldBound> kBodyRows = {
    {"size", kExtent_m},
    {"radius_m", kObjectSize_m},
    {"height_m", kObstacleHeight_m},
};

std::vector<FieldBound> make_scenario_bounds() {
  Table t;
  t.add("", {{"step_s", kStep_s}, {"duration_s", kDuration_s}})
      .add("camera", kCameraRows)
      .add("controller", kControllerRows)
      .add("controller", {{"follow_gap_m", kMargin_m}})
      .add("controller", kMotionEnergyRows)
      .add("lighting", {{"ambient", kLightIntensity}})
      .add("lighting.sun", {{"azimuth_deg", kAngle_deg},
                            {"elevation_deg", kSunElevation_deg},
                            {"intensity", kLightIntensity}})
      .add("lighting.points[]", kLightRows)
      .add("lighting.points[]", {{"position", kPosition_m}})
      .add("ground", {{"size_m", kGroundSize_m}})
      .add("ground.material", kMaterialRows)
      .add("obstacles[]", kBodyRows)
      .add("obstacles[]", {{"position", kPosition_m},
                           {"yaw_deg", kAngle_deg},
                           {"from", kPosition_m},
                           {"to", kPosition_m},
                           {"thickness_m", kObjectSize_m}})
      .add("obstacles[].material", kMaterialRows)
      .add("moving[]", kBodyRows)
      .add("moving[]", {{"waypoints", kPosition_m}, {"speed_mps", kSpeed_mps}})
      .add("moving[].material", kMaterialRows)
      .add("agents[]", {{"start", kPosition_m},
                        {"heading_deg", kAngle_deg},
                        {"speed_mps", kSpeed_mps},
                        {"preferred_speed_mps", kPreferredSpeed_mps},
                        {"max_speed_mps", kMaxSpeed_mps},
                        {"radius_m", kBodyRadius_m},
                        {"height_m", kBodyHeight_m},
                        {"goal", kPosition_m},
                        {"goals", kPosition_m},
                        {"goal_radius_m", kGoalRadius_m}})
      .add("agents[].camera", kCameraRows)
      .add("agents[].controller", kControllerRows)
      .add("agents[].controller", {{"follow_gap_m", kMargin_m}})
      .add("agents[].controller", kMotionEnergyRows)
      .add("agents[].material", kMaterialRows)
      .add("agents[].carried_light", kLightRows)
      .add("agents[].carried_light", {{"ahead_m", kCarriedAhead_m}});
  return std::move(t).rows();
}

std::vector<FieldBound> make_robot_launch_bounds() {
  const std::initializer_list<FieldBound> device_camera = {{"width_px", kImageSide_px},
                                                           {"height_px", kImageSide_px},
                                                           {"frame_rate_hz", kFrameRate_hz},
                                                           {"buffer_count", kBufferCount}};
  const std::initializer_list<FieldBound> serial = {
      {"baud", kBaud}, {"timeout_s", kDeviceTimeout_s}, {"ticks_per_wheel_rev", kEncoderTicks}};
  Table t;
  t.add("camera", {{"timeout_s", kCameraTimeout_s}, {"horizontal_fov_rad", kHfov_rad}})
      .add("camera.v4l2", device_camera)
      .add("camera.libcamera", device_camera)
      .add("camera.replay", {{"frame_rate_hz", kFrameRate_hz}})
      .add("camera.ros2", {{"domain_id", kDomainId}, {"connect_timeout_s", kConnectTimeout_s}})
      .add("drive", {{"loop_rate_hz", kLoopRate_hz}})
      .add("drive.geometry",
           {{"wheel_separation_m", kWheelSeparation_m}, {"wheel_radius_m", kWheelRadius_m}})
      .add("drive.limits", {{"max_speed_mps", kRobotSpeed_mps},
                            {"max_reverse_speed_mps", kRobotReverseSpeed_mps},
                            {"max_accel_mps2", kRobotAccel_mps2},
                            {"max_turn_rate", kRobotTurnRate_radps},
                            {"max_wheel_speed_radps", kWheelSpeed_radps}})
      .add("drive.watchdog", {{"timeout_s", kWatchdogTimeout_s}, {"ramp_s", kWatchdogRamp_s}})
      .add("drive.sim", {{"wheel_time_constant_s", kWheelTimeConstant_s}})
      .add("drive.odrive", {{"motor_turns_per_wheel_turn", kGearRatio},
                            {"timeout_s", kDeviceTimeout_s},
                            {"left.node_id", kCanNodeId},
                            {"right.node_id", kCanNodeId}})
      .add("drive.arduino_bridge", serial)
      .add("drive.arduino_bridge", {{"pid_rate_hz", kPidRate_hz}, {"boot_wait_s", kBootWait_s}})
      .add("drive.roboclaw", serial)
      .add("drive.roboclaw", {{"address", kRoboClawAddress}, {"board_timeout_s", kBoardTimeout_s}})
      .add("drive.ros2", {{"domain_id", kDomainId},
                          {"timeout_s", kDeviceTimeout_s},
                          {"connect_timeout_s", kConnectTimeout_s}})
      .add("goal", {{"bearing_rad", kBearing_rad}, {"distance_m", kGoalDistance_m}})
      .add("perception", {{"height_m", kCameraHeight_m}, {"pitch_deg", kCameraPitch_deg}})
      .add("controller", kControllerRows)
      .add("controller",
           {{"preferred_speed_mps", kRobotPreferredSpeed_mps}, {"robot_width_m", kBodyWidth_m}});
  return std::move(t).rows();
}

std::vector<FieldBound> make_demo_scene_bounds() {
  Table t;
  t.add("camera", {{"resolution", kImageSide_px},
                   {"hfov_deg", kHfov_deg},
                   {"height_m", kCameraHeight_m},
                   {"pitch_deg", kCameraPitch_deg}})
      .add("agent", {{"speed_mps", kSpeed_mps},
                     {"turn_rate", kSignedTurnRate_radps},
                     {"width_m", kBodyWidth_m}})
      .add("", {{"goal", kPosition_m}})
      .add("controller", kControllerRows)
      .add("controller",
           {{"follow_gap_m", kMargin_m}, {"preferred_speed_mps", kPreferredSpeed_mps}})
      .add("objects[]", {{"position", kPosition_m},
                         {"velocity", kVelocity_mps},
                         {"size", kObjectSize_m},
                         {"radius_m", kObjectSize_m},
                         {"height_m", kObstacleHeight_m}});
  return std::move(t).rows();
}

std::vector<FieldBound> make_steersuite_bounds() {
  Table t('/');
  for (const char* bounds_element : {"worldBounds", "regionBounds", "obstacle"}) {
    t.add(bounds_element, {{"xmin", kPosition_m},
                           {"xmax", kPosition_m},
                           {"ymin", kElevation_m},
                           {"ymax", kElevation_m},
                           {"zmin", kPosition_m},
                           {"zmax", kPosition_m}});
  }
  for (const char* tuple : {"position", "targetLocation"}) {
    t.add(tuple, {{"x", kPosition_m}, {"y", kElevation_m}, {"z", kPosition_m}});
  }
  t.add("direction", {{"x", kPosition_m}, {"y", kPosition_m}, {"z", kPosition_m}});
  t.add("size", {{"x", kExtent_m}, {"y", kHeightSpan_m}, {"z", kExtent_m}})
      .add("circleObstacle", {{"radius", kObjectSize_m}, {"height", kHeightSpan_m}})
      .add("orientedBoxObstacle", {{"thetaY", kAngle_deg}})
      .add("obstacleRegion", {{"obstacleSize", kObjectSize_m}, {"obstacleHeight", kHeightSpan_m}})
      .add("initialConditions", {{"radius", kBodyRadius_m}, {"speed", kSpeed_mps}})
      .add("seekStaticTarget",
           {{"desiredSpeed", kPreferredSpeed_mps}, {"timeDuration", kTimeDuration_s}})
      .add("idle", {{"timeDuration", kTimeDuration_s}})
      .add("color", {{"r", kFraction}, {"g", kFraction}, {"b", kFraction}});
  return std::move(t).rows();
}

}  // namespace

std::span<const base::FieldBound> scenario_bounds() {
  static const std::vector<base::FieldBound> table = make_scenario_bounds();
  return table;
}

std::span<const base::FieldBound> robot_launch_bounds() {
  static const std::vector<base::FieldBound> table = make_robot_launch_bounds();
  return table;
}

std::span<const base::FieldBound> demo_scene_bounds() {
  static const std::vector<base::FieldBound> table = make_demo_scene_bounds();
  return table;
}

std::span<const base::FieldBound> steersuite_bounds() {
  static const std::vector<base::FieldBound> table = make_steersuite_bounds();
  return table;
}

}  // namespace flowsteer::config
