#include "flowsteer/launch/demo_scene.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "flowsteer/launch/config_error.hpp"

namespace flowsteer::launch {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Reads typed fields out of YAML nodes and reports problems at the node's position, under a
// dotted field path such as "objects[2].radius_m".
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                         const std::string& message) const {
    const YAML::Mark mark = node.Mark();
    throw ConfigError(source_, mark.line + 1, mark.column + 1, field, message);
  }

  // Fails on any key of `map` that is not in `allowed`, so that typos do not pass silently.
  void only_keys(const YAML::Node& map, const std::string& field,
                 std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) {
      fail(map, field, "expected a mapping");
    }
    const std::set<std::string> names(allowed.begin(), allowed.end());
    for (const auto& entry : map) {
      const auto key = entry.first.as<std::string>();
      if (!names.contains(key)) {
        std::string list;
        for (const char* name : allowed) {
          list += list.empty() ? name : std::string(", ") + name;
        }
        fail(entry.first, join(field, key), "unknown key (expected one of: " + list + ")");
      }
    }
  }

  double number(const YAML::Node& map, const std::string& field, const char* key,
                double fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    return number(node, join(field, key));
  }

  double number(const YAML::Node& node, const std::string& field) const {
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
      fail(node, field, "expected a finite number, got '" + text(node) + "'");
    }
    return value;
  }

  double positive(const YAML::Node& map, const std::string& field, const char* key,
                  double fallback) const {
    const double value = number(map, field, key, fallback);
    if (!(value > 0.0)) {
      fail(map[key] ? map[key] : map, join(field, key), "must be positive, got " + format(value));
    }
    return value;
  }

  double non_negative(const YAML::Node& map, const std::string& field, const char* key,
                      double fallback) const {
    const double value = number(map, field, key, fallback);
    if (value < 0.0) {
      fail(map[key], join(field, key), "must be >= 0, got " + format(value));
    }
    return value;
  }

  int integer(const YAML::Node& node, const std::string& field, int min_value) const {
    int value = 0;
    if (!node.IsScalar() || !YAML::convert<int>::decode(node, value)) {
      fail(node, field, "expected an integer, got '" + text(node) + "'");
    }
    if (value < min_value) {
      fail(node, field,
           "must be at least " + std::to_string(min_value) + ", got " + std::to_string(value));
    }
    return value;
  }

  Eigen::Vector2d pair(const YAML::Node& map, const std::string& field, const char* key,
                       const Eigen::Vector2d& fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    if (!node.IsSequence() || node.size() != 2) {
      fail(node, join(field, key), "expected a pair [x, y]");
    }
    return {number(node[0], join(field, key) + "[0]"), number(node[1], join(field, key) + "[1]")};
  }

  std::string word(const YAML::Node& map, const std::string& field, const char* key,
                   std::initializer_list<const char*> allowed, const char* fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    const std::string value = node.IsScalar() ? node.as<std::string>() : "";
    for (const char* a : allowed) {
      if (value == a) {
        return value;
      }
    }
    std::string list;
    for (const char* a : allowed) {
      list += list.empty() ? a : std::string(", ") + a;
    }
    fail(node, join(field, key), "expected one of: " + list + "; got '" + text(node) + "'");
  }

  bool boolean(const YAML::Node& map, const std::string& field, const char* key,
               bool fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
      fail(node, join(field, key), "expected true or false, got '" + text(node) + "'");
    }
    return value;
  }

  static std::string join(const std::string& field, const std::string& key) {
    return field.empty() ? key : field + "." + key;
  }

 private:
  static std::string text(const YAML::Node& node) {
    if (node.IsScalar()) {
      return node.Scalar();
    }
    return node.IsSequence() ? "a sequence" : node.IsMap() ? "a mapping" : "nothing";
  }
  static std::string format(double value) {
    std::ostringstream s;
    s << value;
    return s.str();
  }

  std::string source_;
};

void read_camera(const Reader& r, const YAML::Node& node, servo::AnalyticScene& scene) {
  r.only_keys(node, "camera", {"resolution", "hfov_deg", "height_m", "pitch_deg"});
  int width = scene.intrinsics.width_px;
  int height = scene.intrinsics.height_px;
  if (const YAML::Node res = node["resolution"]) {
    if (res.IsSequence() && res.size() == 2) {
      width = r.integer(res[0], "camera.resolution[0]", 8);
      height = r.integer(res[1], "camera.resolution[1]", 8);
    } else {
      width = height = r.integer(res, "camera.resolution", 8);
    }
  }
  const double hfov_deg = r.number(node, "camera", "hfov_deg", 90.0);
  if (!(hfov_deg > 0.0 && hfov_deg < 180.0)) {
    r.fail(node["hfov_deg"], "camera.hfov_deg", "must be in (0, 180)");
  }
  scene.intrinsics = servo::CameraIntrinsics::from_horizontal_fov(width, height, hfov_deg * kDeg);
  scene.mount.height_m = r.positive(node, "camera", "height_m", scene.mount.height_m);
  const double pitch_deg = r.number(node, "camera", "pitch_deg", 0.0);
  if (std::abs(pitch_deg) >= 89.0) {
    r.fail(node["pitch_deg"], "camera.pitch_deg", "must be within (-89, 89)");
  }
  scene.mount.pitch_rad = pitch_deg * kDeg;
}

servo::SceneObject read_object(const Reader& r, const YAML::Node& node, const std::string& field,
                               std::int32_t default_id) {
  r.only_keys(node, field, {"shape", "id", "position", "size", "radius_m", "height_m", "velocity"});
  servo::SceneObject o;
  o.shape = r.word(node, field, "shape", {"box", "cylinder"}, "box") == "box"
                ? servo::SceneObject::Shape::box
                : servo::SceneObject::Shape::cylinder;
  o.id = node["id"] ? r.integer(node["id"], field + ".id", 0) : default_id;
  if (!node["position"]) {
    r.fail(node, field + ".position", "missing: where is the object?");
  }
  o.position_m = r.pair(node, field, "position", {0.0, 0.0});
  o.velocity_mps = r.pair(node, field, "velocity", {0.0, 0.0});
  o.height_m = r.positive(node, field, "height_m", 1.8);
  if (o.shape == servo::SceneObject::Shape::box) {
    if (node["radius_m"]) {
      r.fail(node["radius_m"], field + ".radius_m",
             "a box has a size [length, width], not a radius");
    }
    const Eigen::Vector2d size = r.pair(node, field, "size", {1.0, 1.0});
    if (!(size.x() > 0.0 && size.y() > 0.0)) {
      r.fail(node["size"], field + ".size", "length and width must be positive");
    }
    o.length_m = size.x();
    o.width_m = size.y();
  } else {
    if (node["size"]) {
      r.fail(node["size"], field + ".size", "a cylinder has radius_m, not a size");
    }
    o.radius_m = r.positive(node, field, "radius_m", 0.3);
  }
  return o;
}

void read_controller(const Reader& r, const YAML::Node& node, ControllerSpec& c) {
  r.only_keys(node, "controller",
              {"kind", "alpha", "beta", "gamma", "delta", "preferred_speed_mps", "lambda",
               "max_accel_mps2", "max_turn_rate", "use_depth", "leader"});
  const std::string kind =
      r.word(node, "controller", "kind", {"goal_reaching", "following"}, "goal_reaching");
  c.lambda = r.positive(node, "controller", "lambda", c.lambda);
  c.limits.max_accel_mps2 =
      r.positive(node, "controller", "max_accel_mps2", c.limits.max_accel_mps2);
  c.limits.max_turn_rate = r.positive(node, "controller", "max_turn_rate", c.limits.max_turn_rate);
  c.avoidance.use_depth = r.boolean(node, "controller", "use_depth", c.avoidance.use_depth);
  if (kind == "goal_reaching") {
    c.kind = ControllerSpec::Kind::goal_reaching;
    auto& w = c.goal_weights;
    w.alpha = r.non_negative(node, "controller", "alpha", w.alpha);
    w.beta = r.non_negative(node, "controller", "beta", w.beta);
    w.gamma = r.non_negative(node, "controller", "gamma", w.gamma);
    w.delta = r.non_negative(node, "controller", "delta", w.delta);
    w.preferred_speed_mps =
        r.non_negative(node, "controller", "preferred_speed_mps", w.preferred_speed_mps);
    if (w.delta > w.gamma) {
      r.fail(node["delta"], "controller.delta", "must not exceed gamma (MIG 2019: γ ≥ δ)");
    }
    if (node["leader"]) {
      r.fail(node["leader"], "controller.leader", "only a following controller has a leader");
    }
  } else {
    c.kind = ControllerSpec::Kind::following;
    auto& w = c.follow_weights;
    w.alpha = r.non_negative(node, "controller", "alpha", w.alpha);
    w.beta = r.non_negative(node, "controller", "beta", w.beta);
    w.gamma = r.non_negative(node, "controller", "gamma", w.gamma);
    if (!node["leader"]) {
      r.fail(node, "controller.leader", "missing: a following controller needs the leader's id");
    }
    c.leader_id = r.integer(node["leader"], "controller.leader", 0);
  }
}

}  // namespace

DemoScene default_demo_scene() {
  DemoScene d;
  servo::AnalyticScene& s = d.scene;
  s.intrinsics = servo::CameraIntrinsics::from_horizontal_fov(160, 120, 90.0 * kDeg);
  s.mount = {1.6, 0.0};
  s.agent_speed_mps = 1.0;
  servo::SceneObject post;
  post.id = 1;
  post.shape = servo::SceneObject::Shape::cylinder;
  post.radius_m = 0.25;
  post.height_m = 2.5;
  post.position_m = {5.0, -0.4};
  servo::SceneObject pedestrian;
  pedestrian.id = 2;
  pedestrian.shape = servo::SceneObject::Shape::cylinder;
  pedestrian.radius_m = 0.3;
  pedestrian.position_m = {9.0, 1.5};
  pedestrian.velocity_mps = {-1.2, 0.0};
  servo::SceneObject car;
  car.id = 3;
  car.length_m = 4.2;
  car.width_m = 1.8;
  car.height_m = 1.5;
  car.position_m = {14.0, 9.0};
  car.velocity_mps = {0.0, -4.0};
  s.objects = {post, pedestrian, car};
  d.goal_m = Eigen::Vector2d(20.0, -1.0);
  d.controller.avoidance.agent_width_m = 0.5;
  return d;
}

DemoScene parse_demo_scene(const std::string& yaml_text, const std::string& source_name) {
  const Reader r(source_name);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source_name, e.mark.line + 1, e.mark.column + 1, "", e.msg);
  }
  if (!root.IsMap()) {
    throw ConfigError(source_name, 1, 1, "", "expected a mapping with camera, agent, objects");
  }
  r.only_keys(root, "", {"camera", "agent", "goal", "controller", "objects"});

  DemoScene d;
  servo::AnalyticScene& s = d.scene;
  s.intrinsics = servo::CameraIntrinsics::from_horizontal_fov(160, 120, 90.0 * kDeg);
  s.mount = {1.6, 0.0};
  if (const YAML::Node camera = root["camera"]) {
    read_camera(r, camera, s);
  }
  if (const YAML::Node agent = root["agent"]) {
    r.only_keys(agent, "agent", {"speed_mps", "turn_rate", "width_m"});
    s.agent_speed_mps = r.number(agent, "agent", "speed_mps", 1.0);
    s.agent_turn_rate = r.number(agent, "agent", "turn_rate", 0.0);
    d.controller.avoidance.agent_width_m = r.non_negative(agent, "agent", "width_m", 0.5);
  }
  if (const YAML::Node goal = root["goal"]) {
    d.goal_m = r.pair(root, "", "goal", {0.0, 0.0});
    if (d.goal_m->x() <= 0.0) {
      r.fail(goal, "goal", "must be ahead of the agent (x > 0) for the demo's single frame");
    }
  }
  if (const YAML::Node controller = root["controller"]) {
    read_controller(r, controller, d.controller);
  }
  if (const YAML::Node objects = root["objects"]) {
    if (!objects.IsSequence()) {
      r.fail(objects, "objects", "expected a list of objects");
    }
    std::set<std::int32_t> ids;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string field = "objects[" + std::to_string(i) + "]";
      s.objects.push_back(read_object(r, objects[i], field, static_cast<std::int32_t>(i + 1)));
      if (!ids.insert(s.objects.back().id).second) {
        r.fail(objects[i], field + ".id",
               "id " + std::to_string(s.objects.back().id) + " is used twice");
      }
    }
  }
  const auto is_leader = [&](const servo::SceneObject& o) {
    return o.id == *d.controller.leader_id;
  };
  if (d.controller.leader_id && std::none_of(s.objects.begin(), s.objects.end(), is_leader)) {
    r.fail(root["controller"]["leader"], "controller.leader",
           "no object has id " + std::to_string(*d.controller.leader_id));
  }
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(source_name, e.what());
  }
  return d;
}

DemoScene load_demo_scene(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    throw ConfigError(path.string(), "cannot open the scene file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw ConfigError(path.string(), "cannot read the scene file");
  }
  return parse_demo_scene(text.str(), path.string());
}

}  // namespace flowsteer::launch
