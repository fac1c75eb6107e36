#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/motion_energy.hpp"
#include "flowsteer/servo/optical_flow.hpp"

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
};

// Every ControllerSpec::type, in the order messages list them.
inline constexpr std::array<const char*, 3> kControllerTypes{"vision", "geometric",
                                                             "motion_energy"};

// Controller settings as the scenario gives them; launch turns them into a servo controller.
struct ControllerSpec {
  // The steering model: vision (the navigation function on features from the flow), geometric
  // (the same function on features from exact geometry, perfect perception) or motion_energy
  // (Blumberg 1997, goal reaching only).
  std::string type = "vision";
  std::string kind = "goal_reaching";  // goal_reaching, following
  double alpha = 1.0;
  double beta = 0.1;
  double gamma = 1.0;
  // Dark regions (MIG 2019): an agent with delta > 0 looks for them and avoids them; with 0 it
  // ignores them, as MIG's agents without dark-region awareness do.
  double delta = 0.0;
  double lambda = 1.0;
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;
  bool use_depth = true;
  // Added to the agent's diameter as the width it keeps clear (CGF §6.2's agent width): room
  // for the path's curvature and the step, like a person's personal space.
  double clearance_margin_m = 0.5;
  // type motion_energy: its settings, and where "mass" and "floor" come from: the renderer's
  // object ids ("ids"), or the flat-ground test on the flow as a real camera would ("ground").
  servo::MotionEnergyOptions motion_energy;
  std::string mass_from = "ids";
};

// How the agent sees: the renderer's exact flow and object ids, or flow computed from its images
// and objects found in that flow, as a robot's camera would give.
struct PerceptionSpec {
  servo::FlowMethod flow = servo::FlowMethod::synthetic;
  servo::SegmentationMethod segmentation = servo::SegmentationMethod::semantic;
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
  std::optional<int> leader;  // index of the agent to follow
  ControllerSpec controller;
  CameraSpec camera;
  PerceptionSpec perception;
  Material material{{0.2F, 0.35F, 0.8F}, Material::Pattern::stripes, 0.15F, 0.4F};
  std::optional<PointLight> carried_light;  // position_m is the offset in the agent's frame
};

// Everything a scenario describes, at t = 0.
struct WorldSpec {
  std::string name;
  std::string description;
  double step_s = 0.05;
  double duration_s = 30.0;
  double ground_size_m = 80.0;
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

struct AgentState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  double speed_mps = 0.0;
  double turn_rate = 0.0;  // ω about the camera's y axis: positive turns right (yaw rate −ω)
  std::size_t next_goal = 0;
  bool reached_goal = false;
  double time_to_goal_s = -1.0;

  Eigen::Vector2d velocity_mps() const;
};

struct MovingState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();
  std::size_t next_waypoint = 1;
  double yaw_rad = 0.0;
};

struct Collision {
  double time_s;
  std::size_t agent;
  std::string with;  // "agent N", "obstacle N", "moving N"
  Eigen::Vector2d position_m;
  std::optional<std::size_t> other_agent;  // when two agents collide: the other one
};

// The simulated world: agents move as unicycles driven by (a_c, ω), cars along waypoints.
class World {
 public:
  // Throws std::invalid_argument naming the agent or obstacle that is wrong (an agent that
  // starts inside an obstacle or another agent, a leader that does not exist...).
  explicit World(WorldSpec spec);

  const WorldSpec& spec() const { return spec_; }
  // Unique among the worlds of this process, so that caches keyed on it never mix two worlds.
  std::uint64_t serial() const { return serial_; }
  double time_s() const { return time_s_; }
  const std::vector<AgentState>& agents() const { return agents_; }
  const std::vector<MovingState>& moving() const { return moving_; }

  // Advances by one step with one command per agent; agents that reached their last goal stop.
  void step(const std::vector<std::pair<double, double>>& accel_and_turn);

  // Collisions that started during the last step (a contact counts once until it ends).
  const std::vector<Collision>& new_collisions() const { return new_collisions_; }
  // Signed distance from agent i's disc to the nearest other body (negative: overlap).
  double clearance(std::size_t agent) const;
  bool finished() const;

  // A moving obstacle's solid at its current pose, for rendering, distances and top views.
  Solid moving_now(std::size_t moving) const;

 private:
  void detect_collisions();
  void advance_goals(std::size_t agent);

  WorldSpec spec_;
  std::uint64_t serial_;
  double time_s_ = 0.0;
  std::vector<AgentState> agents_;
  std::vector<MovingState> moving_;
  std::vector<std::vector<bool>> in_contact_;  // per agent, per body
  std::vector<Collision> new_collisions_;
};

// Distance from a point to a solid's footprint (negative inside).
double footprint_distance(const Solid& solid, const Eigen::Vector2d& point);

// The corners of a box's footprint (size_m turned by yaw_rad about centre_m), counter-clockwise
// from the front left.
std::array<Eigen::Vector2d, 4> box_corners(const Solid& box);

}  // namespace flowsteer::sim_camera
