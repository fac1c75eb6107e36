#include "bounds_check.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <variant>

#include "flowsteer/base/quantity_bounds.hpp"

namespace flowsteer::fuzz {

namespace {

using namespace base::bounds;

constexpr double kDeg = std::numbers::pi / 180.0;

// kAngle_deg and the like, in the radians the loaded values hold.
base::Bound in_radians(const base::Bound& degrees) {
  return {degrees.min * kDeg, degrees.max * kDeg, "rad"};
}

void expect(const base::Bound& bound, double value, const std::string& what) {
  if (!bound.contains(value)) {
    std::fprintf(stderr, "loaded out of its bounds: %s = %.17g, %s\n", what.c_str(), value,
                 bound.describe().c_str());
    std::abort();
  }
}

void expect_point(const Eigen::Vector2d& p, const std::string& what) {
  expect(kPosition_m, p.x(), what + ".x");
  expect(kPosition_m, p.y(), what + ".y");
}

void check_material(const sim_camera::Material& m, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    expect(kFraction, m.albedo[c], what + ".albedo");
  }
  expect(kPatternScale_m, m.pattern_scale_m, what + ".scale_m");
  expect(kFraction, m.pattern_contrast, what + ".contrast");
}

// A standing or moving body, however its file gave it (a wall, SteerSuite's bounds).
void check_solid(const sim_camera::Solid& s, const std::string& what) {
  expect_point(s.centre_m, what + ".centre");
  if (s.shape == sim_camera::Solid::Shape::box) {
    expect(kExtent_m, s.size_m.x(), what + ".size.x");
    expect(kExtent_m, s.size_m.y(), what + ".size.y");
  } else {
    expect(kObjectSize_m, s.radius_m, what + ".radius");
  }
  expect(kObstacleHeight_m, s.height_m, what + ".height");
  expect(in_radians(kAngle_deg), s.yaw_rad, what + ".yaw");
  check_material(s.material, what + ".material");
}

void check_light(const sim_camera::PointLight& p, const std::string& what, bool carried) {
  expect(carried ? kCarriedAhead_m : kPosition_m, p.position_m.x(), what + ".x");
  expect(carried ? kCarriedAhead_m : kPosition_m, p.position_m.y(), what + ".y");
  expect(kLightHeight_m, p.position_m.z(), what + ".height");
  expect(kLightIntensity, p.intensity, what + ".intensity");
  expect(kLightRange_m, p.range_m, what + ".range");
}

void check_controller(const servo::ControllerConfig& c, const std::string& what) {
  for (const auto& [name, weight] :
       {std::pair{"alpha", c.alpha}, std::pair{"beta", c.beta}, std::pair{"gamma", c.gamma},
        std::pair{"delta", c.delta}, std::pair{"braking", c.braking},
        std::pair{"anticipation", c.anticipation}}) {
    if (weight) {
      expect(kCostWeight, *weight, what + "." + name);
    }
  }
  expect(kMargin_m, c.follow_gap_m, what + ".follow_gap_m");
  expect(kGain, c.lambda, what + ".lambda");
  expect(kAccel_mps2, c.max_accel_mps2, what + ".max_accel_mps2");
  expect(kTurnRate_radps, c.max_turn_rate, what + ".max_turn_rate");
  expect(kSpeedRatio, c.max_speed_ratio, what + ".max_speed_ratio");
  expect(kMargin_m, c.clearance_margin_m, what + ".clearance_margin_m");
  const servo::MotionEnergyOptions& m = c.motion_energy;
  expect(kFraction, m.flow_weight, what + ".flow_weight");
  expect(kCostWeight, m.steer_gain, what + ".steer_gain");
  expect(kCostWeight, m.goal_gain, what + ".goal_gain");
  for (const auto& [name, fraction] :
       {std::pair{"head_on_energy", m.head_on_energy},
        std::pair{"head_on_balance", m.head_on_balance},
        std::pair{"danger_fraction", m.danger_fraction}, std::pair{"corner_step", m.corner_step},
        std::pair{"corner_rise", m.corner_rise}}) {
    expect(kPositiveFraction, fraction, what + "." + name);
  }
  expect(kRange_m, m.danger_distance_m, what + ".danger_distance_m");
  expect(kRange_m, m.free_path_range_m, what + ".free_path_range_m");
}

void check_camera(const sim_camera::CameraSpec& c, const std::string& what) {
  expect(kImageSide_px, c.width_px, what + ".width");
  expect(kImageSide_px, c.height_px, what + ".height");
  expect(in_radians(kHfov_deg), c.hfov_rad, what + ".hfov");
  expect(kCameraHeight_m, c.height_m, what + ".height_m");
  expect(in_radians(kCameraPitch_deg), c.pitch_rad, what + ".pitch");
  expect(kCameraNoise_levels, c.noise_sigma_levels, what + ".noise_sigma");
}

void check_agent(const sim_camera::AgentSpec& a, const std::string& what) {
  expect_point(a.start_m, what + ".start");
  expect(in_radians(kAngle_deg), a.heading_rad, what + ".heading");
  expect(kSpeed_mps, a.start_speed_mps, what + ".start_speed");
  expect(kPreferredSpeed_mps, a.preferred_speed_mps, what + ".preferred_speed");
  expect(kMaxSpeed_mps, a.max_speed_mps, what + ".max_speed");
  expect(kBodyRadius_m, a.radius_m, what + ".radius");
  expect(kBodyHeight_m, a.height_m, what + ".height");
  for (const Eigen::Vector2d& goal : a.goals) {
    expect_point(goal, what + ".goal");
  }
  expect(kGoalRadius_m, a.goal_radius_m, what + ".goal_radius");
  if (!std::isinf(a.idle_s)) {  // no <idle> duration: to the end of the run
    expect(kTimeDuration_s, a.idle_s, what + ".idle");
  }
  check_controller(a.controller, what + ".controller");
  check_camera(a.camera, what + ".camera");
  check_material(a.material, what + ".material");
  if (a.carried_light) {
    check_light(*a.carried_light, what + ".carried_light", true);
  }
}

void check_lighting(const sim_camera::Lighting& l) {
  expect(kLightIntensity, l.ambient, "lighting.ambient");
  if (l.sun) {
    expect(in_radians(kAngle_deg), l.sun->azimuth_rad, "sun.azimuth");
    expect(in_radians(kSunElevation_deg), l.sun->elevation_rad, "sun.elevation");
    expect(kLightIntensity, l.sun->intensity, "sun.intensity");
  }
  for (const sim_camera::PointLight& p : l.points) {
    check_light(p, "lighting.point", false);
  }
}

}  // namespace

void check_bounds(const sim_camera::WorldSpec& w) {
  expect(kStep_s, w.step_s, "step_s");
  expect(kDuration_s, w.duration_s, "duration_s");
  expect(kRunSteps, std::ceil(w.duration_s / w.step_s - 1e-9), "steps");
  expect(kGroundSize_m, w.ground_size_m, "ground.size_m");
  check_material(w.ground, "ground.material");
  check_lighting(w.lighting);
  for (std::size_t k = 0; k < w.obstacles.size(); ++k) {
    check_solid(w.obstacles[k], "obstacle " + std::to_string(k));
  }
  for (std::size_t k = 0; k < w.moving.size(); ++k) {
    const std::string what = "moving " + std::to_string(k);
    check_solid(w.moving[k].body, what);
    for (const Eigen::Vector2d& p : w.moving[k].waypoints) {
      expect_point(p, what + ".waypoint");
    }
    expect(kSpeed_mps, w.moving[k].speed_mps, what + ".speed");
  }
  for (std::size_t i = 0; i < w.agents.size(); ++i) {
    check_agent(w.agents[i], "agent " + std::to_string(i));
  }
}

void check_bounds(const config::RobotLaunch& launch) {
  expect(kCameraTimeout_s, launch.camera.timeout_s, "camera.timeout_s");
  std::visit(
      [](const auto& o) {
        using O = std::decay_t<decltype(o)>;
        expect(kHfov_rad, o.lens.horizontal_fov_rad, "camera.horizontal_fov_rad");
        if constexpr (std::is_same_v<O, camera_io::Ros2CameraOptions>) {
          expect(kDomainId, o.domain_id, "camera.ros2.domain_id");
          expect(kConnectTimeout_s, o.connect_timeout_s, "camera.ros2.connect_timeout_s");
        } else {
          expect(kFrameRate_hz, o.frame_rate_hz, "camera.frame_rate_hz");
        }
        if constexpr (!std::is_same_v<O, camera_io::ReplayOptions> &&
                      !std::is_same_v<O, camera_io::Ros2CameraOptions>) {
          expect(kImageSide_px, o.width_px, "camera.width_px");
          expect(kImageSide_px, o.height_px, "camera.height_px");
          expect(kBufferCount, o.buffer_count, "camera.buffer_count");
        }
      },
      launch.camera.source);
  if (launch.drive) {
    const config::DriveSection& d = *launch.drive;
    expect(kLoopRate_hz, d.loop_rate_hz, "drive.loop_rate_hz");
    expect(kWheelSeparation_m, d.stage.geometry.wheel_separation_m, "wheel_separation_m");
    expect(kWheelRadius_m, d.stage.geometry.wheel_radius_m, "wheel_radius_m");
    const drivers::CommandLimits& l = d.stage.limits;
    expect(kRobotSpeed_mps, l.max_speed_mps, "limits.max_speed_mps");
    expect(kRobotReverseSpeed_mps, l.max_reverse_speed_mps, "limits.max_reverse_speed_mps");
    expect(kRobotAccel_mps2, l.max_accel_mps2, "limits.max_accel_mps2");
    expect(kRobotTurnRate_radps, l.max_turn_rate, "limits.max_turn_rate");
    expect(kWheelSpeed_radps, l.max_wheel_speed_radps, "limits.max_wheel_speed_radps");
    expect(kWatchdogTimeout_s, d.stage.watchdog.timeout_s, "watchdog.timeout_s");
    expect(kWatchdogRamp_s, d.stage.watchdog.ramp_s, "watchdog.ramp_s");
    if (const auto* ros2 = std::get_if<drivers::Ros2DriveConfig>(&d.drive)) {
      expect(kDomainId, ros2->domain_id, "drive.ros2.domain_id");
      expect(kDeviceTimeout_s, ros2->timeout_s, "drive.ros2.timeout_s");
      expect(kConnectTimeout_s, ros2->connect_timeout_s, "drive.ros2.connect_timeout_s");
    }
  }
  if (launch.goal) {
    expect(kBearing_rad, launch.goal->bearing_rad, "goal.bearing_rad");
    expect(kGoalDistance_m, launch.goal->distance_m, "goal.distance_m");
  }
  if (launch.perception.mount) {
    expect(kCameraHeight_m, launch.perception.mount->height_m, "mount.height_m");
    expect(in_radians(kCameraPitch_deg), launch.perception.mount->pitch_rad, "mount.pitch");
  }
  check_controller(launch.controller.spec, "controller");
  expect(kRobotPreferredSpeed_mps, launch.controller.preferred_speed_mps,
         "controller.preferred_speed_mps");
  expect(kBodyWidth_m, launch.controller.robot_width_m, "controller.robot_width_m");
}

void check_bounds(const config::DemoScene& demo) {
  const servo::AnalyticScene& s = demo.scene;
  expect(kImageSide_px, s.intrinsics.width_px, "camera.width");
  expect(kImageSide_px, s.intrinsics.height_px, "camera.height");
  expect(kCameraHeight_m, s.mount.height_m, "camera.height_m");
  expect(in_radians(kCameraPitch_deg), s.mount.pitch_rad, "camera.pitch");
  expect(kSpeed_mps, s.agent_speed_mps, "agent.speed_mps");
  expect(kSignedTurnRate_radps, s.agent_turn_rate, "agent.turn_rate");
  expect(kBodyWidth_m, demo.agent_width_m, "agent.width_m");
  if (demo.goal_m) {
    expect_point(*demo.goal_m, "goal");
  }
  check_controller(demo.controller, "controller");
  expect(kPreferredSpeed_mps, demo.preferred_speed_mps, "controller.preferred_speed_mps");
  for (const servo::SceneObject& o : s.objects) {
    expect_point(o.position_m, "object.position");
    expect(kVelocity_mps, o.velocity_mps.x(), "object.velocity.x");
    expect(kVelocity_mps, o.velocity_mps.y(), "object.velocity.y");
    expect(kObstacleHeight_m, o.height_m, "object.height");
    if (o.shape == servo::SceneObject::Shape::box) {
      expect(kObjectSize_m, o.length_m, "object.length");
      expect(kObjectSize_m, o.width_m, "object.width");
    } else {
      expect(kObjectSize_m, o.radius_m, "object.radius");
    }
  }
}

}  // namespace flowsteer::fuzz
