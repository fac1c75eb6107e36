#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/servo/steering.hpp"

namespace flowsteer::sim_camera {

// World frame (REP-103): x, y on the ground, z up, metres; yaw counter-clockwise from x.

// How a surface looks: its albedo and a procedural pattern that gives numerical flow contrast.
struct Material {
  enum class Pattern { plain, checker, noise, stripes };
  Eigen::Vector3f albedo{0.6F, 0.6F, 0.6F};  // linear RGB in [0, 1]
  Pattern pattern = Pattern::noise;
  float pattern_scale_m = 0.25F;
  float pattern_contrast = 0.35F;  // 0: plain, 1: from black to the albedo
};

// An upright box (walls are thin boxes) or cylinder standing on the ground.
struct Solid {
  enum class Shape { box, cylinder };
  Shape shape = Shape::box;
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d size_m{1.0, 1.0};  // box: extent along its own x and y
  double radius_m = 0.5;             // cylinder
  double height_m = 1.0;
  double yaw_rad = 0.0;
  Material material;
};

// An obstacle that drives along waypoints at a constant speed (a car).
struct MovingObstacle {
  Solid body;  // centre_m is where it starts: the first waypoint
  std::vector<Eigen::Vector2d> waypoints;
  double speed_mps = 1.0;
  bool loop = false;  // back to the first waypoint at the end, else it stops there
};

struct SunLight {
  double azimuth_rad = 0.6;    // direction the light comes from, counter-clockwise from x
  double elevation_rad = 0.9;  // above the horizon
  float intensity = 0.85F;
  bool shadows = true;
};

struct PointLight {
  Eigen::Vector3d position_m{0.0, 0.0, 3.0};
  float intensity = 1.0F;
  double range_m = 8.0;  // the light falls to zero here
};

// The renderer draws at most this many point lights, fixed and carried together.
inline constexpr std::size_t kMaxPointLights = 8;

struct Lighting {
  float ambient = 0.3F;
  std::optional<SunLight> sun = SunLight{};
  std::vector<PointLight> points;
};

// A head camera: aligned with the agent's direction of motion (CGF §3), at a height and pitch.
struct CameraSpec {
  int width_px = 128;
  int height_px = 128;
  double hfov_rad = 1.5707963267948966;
  double height_m = 1.6;
  double pitch_rad = 0.0;
  // σ of the sensor's Gaussian noise on each channel of the image, in grey levels (of 255): what
  // a real camera adds, which numerical flow must live with. The geometry channels stay exact.
  double noise_sigma_levels = 0.0;
};

struct AgentSpec {
  std::string name;
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  double start_speed_mps = 0.0;
  double preferred_speed_mps = 1.0;
  double max_speed_mps = 2.0;
  double radius_m = 0.25;
  double height_m = 1.8;
  std::vector<Eigen::Vector2d> goals;  // visited in order
  double goal_radius_m = 0.5;
  // Under Arrival::leave, how long it stays at its last goal before it leaves: SteerSuite's
  // trailing <idle> (infinity: to the end of the run).
  double idle_s = 0.0;
  std::optional<int> leader;           // index of the agent to follow
  servo::ControllerConfig controller;  // how it steers
  CameraSpec camera;
  servo::PerceptionConfig perception;  // how it sees
  Material material{{0.2F, 0.35F, 0.8F}, Material::Pattern::stripes, 0.15F, 0.4F};
  std::optional<PointLight> carried_light;  // position_m is the offset in the agent's frame
};

// What becomes of an agent once it has reached its last goal. An agent that others follow
// stays under either rule: its followers go on following it.
enum class Arrival {
  stay,   // it stands there, a body the others see and go round: people, robots
  leave,  // it leaves the world, seen and touched by no one: SteerSuite's rule
          // (SimpleAgent::disable), for which its published cases were written
};
std::string_view to_string(Arrival arrival);
std::optional<Arrival> parse_arrival(std::string_view name);

// Everything a scenario describes, at t = 0.
struct WorldSpec {
  std::string name;
  std::string description;
  double step_s = 0.05;
  double duration_s = 30.0;
  double ground_size_m = 80.0;
  Arrival arrival = Arrival::stay;
  Material ground{{0.45F, 0.45F, 0.42F}, Material::Pattern::noise, 0.5F, 0.45F};
  Lighting lighting;
  std::vector<Solid> obstacles;
  std::vector<MovingObstacle> moving;
  std::vector<AgentSpec> agents;
};

// Renderer ids of the things in a world: agents first, then obstacles, then moving obstacles.
// Ground and sky use servo's negative ids, which segmentation drops.
std::int32_t agent_render_id(std::size_t agent);
std::int32_t obstacle_render_id(std::size_t obstacle);
std::int32_t moving_render_id(std::size_t moving);

}  // namespace flowsteer::sim_camera
