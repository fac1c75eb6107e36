#include "flowsteer/config/scenario_file.hpp"

#include <filesystem>
#include <numbers>
#include <optional>

#include "builtin_scenarios.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/config/controller_reader.hpp"
#include "flowsteer/config/field_bounds.hpp"

namespace flowsteer::config {

namespace {

using sim_camera::AgentSpec;
using sim_camera::Material;
using sim_camera::Solid;

constexpr double kDeg = std::numbers::pi / 180.0;

Material read_material(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
                       Material material) {
  if (!node) {
    return material;
  }
  r.only_keys(node, field, {"albedo", "pattern", "scale_m", "contrast"});
  if (const YAML::Node albedo = node["albedo"]) {
    if (!albedo.IsSequence() || albedo.size() != 3) {
      r.fail(albedo, field + ".albedo", "expected [r, g, b] in [0, 1]");
    }
    const base::Bound& bound = base::bound_of(r.bounds(), field + ".albedo");
    for (int c = 0; c < 3; ++c) {
      material.albedo[c] = static_cast<float>(
          r.within(albedo[c], field + ".albedo[" + std::to_string(c) + "]", bound));
    }
  }
  const std::string pattern =
      r.word(node, field, "pattern", {"plain", "checker", "noise", "stripes"}, "");
  if (pattern == "plain") {
    material.pattern = Material::Pattern::plain;
  } else if (pattern == "checker") {
    material.pattern = Material::Pattern::checker;
  } else if (pattern == "noise") {
    material.pattern = Material::Pattern::noise;
  } else if (pattern == "stripes") {
    material.pattern = Material::Pattern::stripes;
  }
  material.pattern_scale_m =
      static_cast<float>(r.bounded(node, field, "scale_m", material.pattern_scale_m));
  material.pattern_contrast =
      static_cast<float>(r.bounded(node, field, "contrast", material.pattern_contrast));
  return material;
}

// A key of another shape than the body's (a box's radius_m, a wall's position) would be ignored:
// a mistake to say, not to pass over.
void refuse_other_shapes_keys(const base::YamlReader& r, const YAML::Node& node,
                              const std::string& field, const std::string& shape) {
  const std::initializer_list<const char*> box = {"radius_m", "from", "to", "thickness_m"};
  const std::initializer_list<const char*> cylinder = {"size", "from", "to", "thickness_m"};
  const std::initializer_list<const char*> wall = {"position", "size", "radius_m", "yaw_deg"};
  for (const char* key : shape == "box" ? box : shape == "cylinder" ? cylinder : wall) {
    if (node[key]) {
      r.fail(node[key], base::YamlReader::join(field, key),
             "not a setting of shape " + shape + " (a box has size, a cylinder radius_m, a wall " +
                 "from, to and thickness_m)");
    }
  }
}

// A box's or a cylinder's shape and height, without its place.
void read_body(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
               const std::string& shape, Solid& s) {
  refuse_other_shapes_keys(r, node, field, shape);
  s.height_m = r.bounded(node, field, "height_m", 1.0);
  if (shape == "cylinder") {
    s.shape = Solid::Shape::cylinder;
    s.radius_m = r.bounded(node, field, "radius_m", 0.3);
  } else {
    s.size_m = r.bounded_pair(node, field, "size", {1.0, 1.0});
  }
}

Solid read_wall(const base::YamlReader& r, const YAML::Node& node, const std::string& field) {
  refuse_other_shapes_keys(r, node, field, "wall");
  if (!node["from"] || !node["to"]) {
    r.fail(node, field, "a wall needs from: [x, y] and to: [x, y]");
  }
  const Eigen::Vector2d from = r.bounded_pair(node, field, "from", Eigen::Vector2d::Zero());
  const Eigen::Vector2d to = r.bounded_pair(node, field, "to", Eigen::Vector2d::Zero());
  if ((to - from).norm() < 1e-6) {
    r.fail(node["to"], field + ".to", "a wall needs two distinct ends");
  }
  Solid s;
  s.shape = Solid::Shape::box;
  s.centre_m = 0.5 * (from + to);
  s.size_m = {(to - from).norm(), r.bounded(node, field, "thickness_m", 0.2)};
  s.yaw_rad = std::atan2(to.y() - from.y(), to.x() - from.x());
  s.height_m = r.bounded(node, field, "height_m", 2.5);
  return s;
}

// obstacles[k]: a box, a cylinder or a wall.
Solid read_solid(const base::YamlReader& r, const YAML::Node& node, const std::string& field) {
  r.only_keys(node, field,
              {"shape", "position", "size", "radius_m", "height_m", "yaw_deg", "from", "to",
               "thickness_m", "material"});
  const std::string shape = r.word(node, field, "shape", {"box", "cylinder", "wall"}, "box");
  Solid s;
  if (shape == "wall") {
    s = read_wall(r, node, field);
  } else {
    if (!node["position"]) {
      r.fail(node, field + ".position", "missing: where is it?");
    }
    s.centre_m = r.bounded_pair(node, field, "position", Eigen::Vector2d::Zero());
    s.yaw_rad = r.bounded(node, field, "yaw_deg", 0.0) * kDeg;
    read_body(r, node, field, shape, s);
  }
  s.material = read_material(r, node["material"], field + ".material", s.material);
  return s;
}

sim_camera::CameraSpec read_camera(const base::YamlReader& r, const YAML::Node& node,
                                   const std::string& field, sim_camera::CameraSpec camera) {
  if (!node) {
    return camera;
  }
  r.only_keys(node, field, {"resolution", "hfov_deg", "height_m", "pitch_deg", "noise_sigma"});
  if (const YAML::Node res = node["resolution"]) {
    const std::string f = field + ".resolution";
    const base::Bound& bound = base::bound_of(r.bounds(), f);
    if (res.IsSequence() && res.size() == 2) {
      camera.width_px = r.within_integer(res[0], f + "[0]", bound);
      camera.height_px = r.within_integer(res[1], f + "[1]", bound);
    } else {
      camera.width_px = camera.height_px = r.bounded_integer(res, f);
    }
  }
  camera.hfov_rad = r.bounded(node, field, "hfov_deg", camera.hfov_rad / kDeg) * kDeg;
  camera.height_m = r.bounded(node, field, "height_m", camera.height_m);
  camera.pitch_rad = r.bounded(node, field, "pitch_deg", camera.pitch_rad / kDeg) * kDeg;
  camera.noise_sigma_levels = r.bounded(node, field, "noise_sigma", camera.noise_sigma_levels);
  return camera;
}

// A scenario's controller: every setting of every steering model.
servo::ControllerConfig read_scenario_controller(const base::YamlReader& r, const YAML::Node& node,
                                                 const std::string& field,
                                                 const servo::ControllerConfig& c) {
  if (node) {
    r.only_keys(node, field,
                {"type",
                 "kind",
                 "law",
                 "alpha",
                 "beta",
                 "gamma",
                 "delta",
                 "braking",
                 "anticipation",
                 "without",
                 "follow_gap_m",
                 "lambda",
                 "max_accel_mps2",
                 "max_turn_rate",
                 "max_speed_ratio",
                 "use_depth",
                 "clearance_margin_m",
                 "mass_from",
                 "flow_weight",
                 "steer_gain",
                 "goal_gain",
                 "head_on_energy",
                 "head_on_balance",
                 "danger_distance_m",
                 "danger_fraction",
                 "corner_step",
                 "corner_rise",
                 "free_path_range_m"});
  }
  return read_controller(r, node, field, c);
}

servo::PerceptionConfig read_scenario_perception(const base::YamlReader& r, const YAML::Node& node,
                                                 const std::string& field,
                                                 const servo::PerceptionConfig& p) {
  if (node) {
    r.only_keys(node, field, {"flow", "segmentation", "depth", "obstacle_memory"});
  }
  return read_perception(r, node, field, p);
}

std::vector<Eigen::Vector2d> read_points(const base::YamlReader& r, const YAML::Node& node,
                                         const std::string& field) {
  if (!node.IsSequence() || node.size() == 0) {
    r.fail(node, field, "expected a list of points [[x, y], ...]");
  }
  const base::Bound& bound = base::bound_of(r.bounds(), field);
  std::vector<Eigen::Vector2d> points;
  for (std::size_t k = 0; k < node.size(); ++k) {
    const std::string f = field + "[" + std::to_string(k) + "]";
    points.push_back(r.bounded_pair(node[k], f, bound));
  }
  return points;
}

sim_camera::PointLight read_point_light(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& field) {
  r.only_keys(node, field, {"position", "height_m", "intensity", "range_m"});
  sim_camera::PointLight p;
  const Eigen::Vector2d xy = r.bounded_pair(node, field, "position", {0.0, 0.0});
  p.position_m = {xy.x(), xy.y(), r.bounded(node, field, "height_m", 3.0)};
  p.intensity = static_cast<float>(r.bounded(node, field, "intensity", 1.0));
  p.range_m = r.bounded(node, field, "range_m", 8.0);
  return p;
}

void require_list(const base::YamlReader& r, const YAML::Node& node, const std::string& field) {
  if (!node.IsSequence()) {
    r.fail(node, field, "expected a list");
  }
}

// lighting.sun, or `none` for no sun.
std::optional<sim_camera::SunLight> read_sun(const base::YamlReader& r, const YAML::Node& sun) {
  if (sun.IsScalar() && sun.Scalar() == "none") {
    return std::nullopt;
  }
  r.only_keys(sun, "lighting.sun", {"azimuth_deg", "elevation_deg", "intensity", "shadows"});
  sim_camera::SunLight s;
  s.azimuth_rad = r.bounded(sun, "lighting.sun", "azimuth_deg", s.azimuth_rad / kDeg) * kDeg;
  s.elevation_rad = r.bounded(sun, "lighting.sun", "elevation_deg", s.elevation_rad / kDeg) * kDeg;
  s.intensity = static_cast<float>(r.bounded(sun, "lighting.sun", "intensity", s.intensity));
  s.shadows = r.boolean(sun, "lighting.sun", "shadows", s.shadows);
  return s;
}

sim_camera::Lighting read_lighting(const base::YamlReader& r, const YAML::Node& node,
                                   sim_camera::Lighting lighting) {
  r.only_keys(node, "lighting", {"ambient", "sun", "points"});
  lighting.ambient = static_cast<float>(r.bounded(node, "lighting", "ambient", lighting.ambient));
  if (const YAML::Node sun = node["sun"]) {
    lighting.sun = read_sun(r, sun);
  }
  if (const YAML::Node points = node["points"]) {
    require_list(r, points, "lighting.points");
    for (std::size_t k = 0; k < points.size(); ++k) {
      lighting.points.push_back(
          read_point_light(r, points[k], "lighting.points[" + std::to_string(k) + "]"));
    }
  }
  return lighting;
}

// A moving obstacle: a box or a cylinder that starts at the first of its waypoints.
sim_camera::MovingObstacle read_moving_obstacle(const base::YamlReader& r, const YAML::Node& node,
                                                const std::string& field) {
  r.only_keys(
      node, field,
      {"shape", "size", "radius_m", "height_m", "material", "waypoints", "speed_mps", "loop"});
  if (!node["waypoints"]) {
    r.fail(node, field + ".waypoints", "missing: a moving obstacle needs waypoints");
  }
  sim_camera::MovingObstacle m;
  m.waypoints = read_points(r, node["waypoints"], field + ".waypoints");
  if (m.waypoints.size() < 2) {
    r.fail(node["waypoints"], field + ".waypoints", "needs at least two waypoints");
  }
  read_body(r, node, field, r.word(node, field, "shape", {"box", "cylinder"}, "box"), m.body);
  m.body.centre_m = m.waypoints.front();
  m.body.material = read_material(r, node["material"], field + ".material", m.body.material);
  m.speed_mps = r.bounded(node, field, "speed_mps", 1.0);
  m.loop = r.boolean(node, field, "loop", false);
  return m;
}

// What an agent's own settings start from: the scenario's.
struct AgentDefaults {
  sim_camera::CameraSpec camera;
  servo::ControllerConfig controller;
  servo::PerceptionConfig perception;
};

// The agent's leader, agents[index] of `agent_count`. Unless its controller names its kind, an
// agent with a leader follows it.
void read_leader(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
                 std::size_t agent_count, std::size_t self, AgentSpec& a) {
  const YAML::Node leader = node["leader"];
  const int index = r.integer(leader, field + ".leader", 0);
  if (static_cast<std::size_t>(index) >= agent_count || static_cast<std::size_t>(index) == self) {
    r.fail(leader, field + ".leader", "must be the index of another agent");
  }
  a.leader = index;
  if (!node["controller"] || !node["controller"]["kind"]) {
    a.controller.kind = servo::NavigationKind::following;
  }
}

// An agent heads for goals or follows a leader, as its controller can.
void check_navigation(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
                      const AgentSpec& a) {
  if (a.controller.model == servo::SteeringModel::motion_energy && a.leader) {
    r.fail(node["leader"], field + ".leader",
           "a motion_energy controller steers to goals and cannot follow a leader");
  }
  if (a.controller.kind == servo::NavigationKind::following && !a.leader) {
    r.fail(node, field + ".leader", "missing: a following agent needs a leader");
  }
  if (!a.leader && a.goals.empty()) {
    r.fail(node, field + ".goal", "missing: the agent needs a goal or a leader");
  }
}

// A light the agent carries, placed relative to the agent.
sim_camera::PointLight read_carried_light(const base::YamlReader& r, const YAML::Node& light,
                                          const std::string& field) {
  r.only_keys(light, field, {"intensity", "range_m", "height_m", "ahead_m"});
  sim_camera::PointLight p;
  p.position_m = {r.bounded(light, field, "ahead_m", 0.4), 0.0,
                  r.bounded(light, field, "height_m", 1.2)};
  p.intensity = static_cast<float>(r.bounded(light, field, "intensity", 1.5));
  p.range_m = r.bounded(light, field, "range_m", 6.0);
  return p;
}

// agents[i], with `agents` for the leader's index.
AgentSpec read_agent(const base::YamlReader& r, const YAML::Node& agents, std::size_t i,
                     const AgentDefaults& defaults) {
  const std::string field = "agents[" + std::to_string(i) + "]";
  const YAML::Node node = agents[i];
  r.only_keys(node, field,
              {"name", "start", "heading_deg", "speed_mps", "preferred_speed_mps", "max_speed_mps",
               "radius_m", "height_m", "goal", "goals", "goal_radius_m", "leader", "controller",
               "perception", "camera", "material", "carried_light"});
  AgentSpec a;
  a.name = r.text(node, field, "name", "agent" + std::to_string(i));
  if (!node["start"]) {
    r.fail(node, field + ".start", "missing: where does the agent start?");
  }
  a.start_m = r.bounded_pair(node, field, "start", Eigen::Vector2d::Zero());
  a.heading_rad = r.bounded(node, field, "heading_deg", 0.0) * kDeg;
  a.preferred_speed_mps = r.bounded(node, field, "preferred_speed_mps", 1.0);
  a.start_speed_mps = r.bounded(node, field, "speed_mps", a.preferred_speed_mps);
  a.max_speed_mps = r.bounded(node, field, "max_speed_mps", 1.5 * a.preferred_speed_mps);
  a.radius_m = r.bounded(node, field, "radius_m", a.radius_m);
  a.height_m = r.bounded(node, field, "height_m", a.height_m);
  a.goal_radius_m = r.bounded(node, field, "goal_radius_m", a.goal_radius_m);
  if (node["goal"] && node["goals"]) {
    r.fail(node["goals"], field + ".goals", "give goal or goals, not both");
  }
  if (node["goal"]) {
    a.goals = {r.bounded_pair(node, field, "goal", Eigen::Vector2d::Zero())};
  } else if (node["goals"]) {
    a.goals = read_points(r, node["goals"], field + ".goals");
  }
  a.controller =
      read_scenario_controller(r, node["controller"], field + ".controller", defaults.controller);
  if (node["leader"]) {
    read_leader(r, node, field, agents.size(), i, a);
  }
  check_navigation(r, node, field, a);
  a.camera = read_camera(r, node["camera"], field + ".camera", defaults.camera);
  a.perception =
      read_scenario_perception(r, node["perception"], field + ".perception", defaults.perception);
  a.material = read_material(r, node["material"], field + ".material", a.material);
  if (const YAML::Node light = node["carried_light"]) {
    a.carried_light = read_carried_light(r, light, field + ".carried_light");
  }
  return a;
}
}  // namespace

sim_camera::WorldSpec parse_scenario(const std::string& yaml_text, const std::string& source_name) {
  const base::YamlReader r(source_name, scenario_bounds());
  const YAML::Node root = base::load_yaml_map(
      yaml_text, source_name, "at least agents:",
      {"name", "description", "step_s", "duration_s", "arrival", "camera", "controller",
       "perception", "lighting", "ground", "obstacles", "moving", "agents"});
  sim_camera::WorldSpec w;
  w.name = r.text(root, "", "name", source_name);
  w.description = r.text(root, "", "description", "");
  w.step_s = r.bounded(root, "", "step_s", w.step_s);
  w.duration_s = r.bounded(root, "", "duration_s", w.duration_s);
  w.arrival = *sim_camera::parse_arrival(r.word(root, "", "arrival", {"stay", "leave"}, "stay"));
  AgentDefaults defaults;
  defaults.camera = read_camera(r, root["camera"], "camera", {});
  defaults.controller = read_scenario_controller(r, root["controller"], "controller", {});
  defaults.perception = read_scenario_perception(r, root["perception"], "perception", {});

  if (const YAML::Node lighting = root["lighting"]) {
    w.lighting = read_lighting(r, lighting, w.lighting);
  }
  if (const YAML::Node ground = root["ground"]) {
    r.only_keys(ground, "ground", {"size_m", "material"});
    w.ground_size_m = r.bounded(ground, "ground", "size_m", w.ground_size_m);
    w.ground = read_material(r, ground["material"], "ground.material", w.ground);
  }
  if (const YAML::Node obstacles = root["obstacles"]) {
    require_list(r, obstacles, "obstacles");
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
      w.obstacles.push_back(read_solid(r, obstacles[k], "obstacles[" + std::to_string(k) + "]"));
    }
  }
  if (const YAML::Node moving = root["moving"]) {
    require_list(r, moving, "moving");
    for (std::size_t k = 0; k < moving.size(); ++k) {
      w.moving.push_back(read_moving_obstacle(r, moving[k], "moving[" + std::to_string(k) + "]"));
    }
  }
  const YAML::Node agents = root["agents"];
  if (!agents || !agents.IsSequence() || agents.size() == 0) {
    r.fail(agents ? agents : root, "agents", "expected a list of one agent or more");
  }
  for (std::size_t i = 0; i < agents.size(); ++i) {
    w.agents.push_back(read_agent(r, agents, i, defaults));
  }
  try {
    sim_camera::World check(w);
  } catch (const std::invalid_argument& e) {
    throw base::ConfigError(source_name, e.what());
  }
  return w;
}

sim_camera::WorldSpec load_scenario(const std::string& path) {
  return parse_scenario(base::read_text_file(path, "scenario file"), path);
}

LoadedCase load_case(const std::filesystem::path& path, std::uint32_t seed) {
  const std::string extension = path.extension().string();
  if (extension == ".xml") {
    return load_steersuite(path.string(), seed);
  }
  if (extension == ".yaml" || extension == ".yml") {
    return {load_scenario(path.string()), {}};
  }
  throw base::ConfigError(
      path.string(), "unknown kind of scenario: .xml (SteerSuite) and .yaml or .yml are known");
}

std::vector<BuiltinScenario> builtin_scenarios() {
  std::vector<BuiltinScenario> out;
  for (const auto& [name, text] : builtin::kScenarios) {
    out.push_back({name, parse_scenario(text, std::string("builtin:") + name).description});
  }
  return out;
}

bool is_builtin_scenario(const std::string& name) {
  for (const auto& [builtin_name, text] : builtin::kScenarios) {
    if (name == builtin_name) {
      return true;
    }
  }
  return false;
}

sim_camera::WorldSpec builtin_scenario(const std::string& name) {
  std::string known;
  for (const auto& [builtin_name, text] : builtin::kScenarios) {
    if (name == builtin_name) {
      return parse_scenario(text, std::string("builtin:") + builtin_name);
    }
    known += known.empty() ? builtin_name : std::string(", ") + builtin_name;
  }
  throw base::ConfigError("--scenario " + name, "unknown scenario (built-in ones: " + known + ")");
}

}  // namespace flowsteer::config
