// Each reader against its table of bounds (config/field_bounds.hpp): every row, tried in a file
// that holds every field, at each end of its bound (accepted) and just beyond it (refused with
// "file:line:column: FIELD: must be from MIN to MAX UNIT, got VALUE"). The cases come from the
// tables; only the files and the few ends another rule refuses are written here.
#include "flowsteer/config/field_bounds.hpp"

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tinyxml2.h>
#include <yaml-cpp/yaml.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/demo_scene.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::config {
namespace {

// A value a row is tried with, and whether its bound holds it.
struct Probe {
  double value;
  bool inside;
  const char* end;  // "min", "max", "below min", "above max"
};

// Both ends, and one step beyond each: a whole step for a field the file gives as a whole
// number (a pixel count, a CAN id), else a millionth of the end (or 1e-9 at 0).
std::vector<Probe> probes(const base::Bound& b, bool whole) {
  const auto step = [whole](double end) {
    return whole ? 1.0 : std::max(1e-9, std::abs(end) * 1e-6);
  };
  return {{b.min, true, "min"},
          {b.max, true, "max"},
          {b.min - step(b.min), false, "below min"},
          {b.max + step(b.max), false, "above max"}};
}

bool is_whole(double value) {
  return std::floor(value) == value;
}

std::string text_of(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// Ends of a row that another rule refuses, with the message that says so; every other inside
// value must load.
using OtherRules = std::map<std::pair<std::string, std::string>, std::string>;

// What a row's probes should give, given the reader's message or none.
void expect_outcome(const std::string& field_written, const base::Bound& bound, const Probe& p,
                    const std::optional<std::string>& error, const OtherRules& other_rules,
                    const std::string& row) {
  SCOPED_TRACE(row + " at " + p.end + " (" + text_of(p.value) + ")");
  if (p.inside) {
    const auto other = other_rules.find({row, p.end});
    if (other != other_rules.end()) {
      ASSERT_TRUE(error.has_value());
      EXPECT_NE(error->find(other->second), std::string::npos) << *error;
    } else {
      EXPECT_FALSE(error.has_value()) << *error;
    }
    return;
  }
  ASSERT_TRUE(error.has_value()) << "accepted";
  const std::string expected = ": " + field_written + ": must be " + bound.describe() + ", got ";
  EXPECT_NE(error->find(expected), std::string::npos) << *error << "\nexpected: " << expected;
}

// --- YAML readers ---------------------------------------------------------------------------

// The node at `row` ("agents[].camera.height_m") in `root`: at "[]" the first element that has
// the rest of the path. Descends into a sequence's first element (a pair, a list of points), so
// that one number is set. `written` gets the path as the reader names it; null when the file
// does not hold the field.
std::optional<YAML::Node> find_field(YAML::Node node, const std::string& row,
                                     std::string& written) {
  const std::size_t dot = row.find('.');
  const std::string head = row.substr(0, dot);
  const std::string rest = dot == std::string::npos ? "" : row.substr(dot + 1);
  const bool each = head.ends_with("[]");
  const std::string key = each ? head.substr(0, head.size() - 2) : head;
  if (!node.IsMap() || !node[key]) {
    return std::nullopt;
  }
  YAML::Node child;
  child.reset(node[key]);
  const std::string here = written + (written.empty() ? "" : ".") + key;
  if (each) {
    for (std::size_t k = 0; k < child.size(); ++k) {
      std::string path = here + "[" + std::to_string(k) + "]";
      if (auto found = find_field(child[k], rest, path)) {
        written = path;
        return found;
      }
    }
    return std::nullopt;
  }
  written = here;
  if (!rest.empty()) {
    return find_field(child, rest, written);
  }
  while (child.IsSequence()) {
    YAML::Node first;
    first.reset(child[0]);
    child.reset(first);
    written += "[0]";
  }
  return child;
}

using YamlParse = std::function<void(const std::string& text)>;

// Walks every row of `table`, each in the first of `files` that holds its field.
void walk_yaml_table(std::span<const base::FieldBound> table, const std::vector<std::string>& files,
                     const YamlParse& parse, const OtherRules& other_rules = {}) {
  for (const std::string& file : files) {
    ASSERT_NO_THROW(parse(file)) << file;  // the files as written load
  }
  for (const base::FieldBound& row : table) {
    bool found = false;
    for (const std::string& file : files) {
      YAML::Node probe_root = YAML::Load(file);
      std::string written;
      const std::optional<YAML::Node> field = find_field(probe_root, row.field, written);
      if (!field) {
        continue;
      }
      found = true;
      const bool whole =
          is_whole(field->as<double>()) && is_whole(row.bound.min) && is_whole(row.bound.max);
      for (const Probe& p : probes(row.bound, whole)) {
        YAML::Node root = YAML::Load(file);
        std::string path;
        YAML::Node target = *find_field(root, row.field, path);
        target = text_of(p.value);
        std::optional<std::string> error;
        try {
          parse(YAML::Dump(root));
        } catch (const base::ConfigError& e) {
          error = e.what();
        }
        expect_outcome(written, row.bound, p, error, other_rules, row.field);
      }
      break;
    }
    EXPECT_TRUE(found) << "no test file holds " << row.field;
  }
}

const std::string kController =
    "alpha: 1, beta: 1, gamma: 100, delta: 0, braking: 1, anticipation: 1, max_speed_ratio: 1.1, "
    "lambda: 1, max_accel_mps2: 1, max_turn_rate: 1, clearance_margin_m: 0.5";
const std::string kMotionEnergy =
    "type: motion_energy, follow_gap_m: 2, flow_weight: 0.5, steer_gain: 3, goal_gain: 1.5, "
    "head_on_energy: 0.5, head_on_balance: 0.5, danger_distance_m: 1.5, danger_fraction: 0.5, "
    "corner_step: 0.5, corner_rise: 0.5, free_path_range_m: 10";
const std::string kMaterial = "material: {albedo: [0.5, 0.5, 0.5], scale_m: 0.25, contrast: 0.3}";
const std::string kCamera =
    "{resolution: 16, hfov_deg: 90, height_m: 1.6, pitch_deg: 0, "
    "noise_sigma: 0}";

// Every field of a scenario, placed so that each may take either end of its bound: the large
// bodies far from the agents, which stand where no body of the largest size reaches.
std::string scenario_with_every_field() {
  return "name: bounds\nstep_s: 0.05\nduration_s: 2\ncamera: " + kCamera + "\ncontroller: {" +
         kController + ", " + kMotionEnergy +
         "}\n"
         "lighting:\n"
         "  ambient: 0.3\n"
         "  sun: {azimuth_deg: 40, elevation_deg: 50, intensity: 0.7}\n"
         "  points: [{position: [-500, -400], height_m: 3, intensity: 1, range_m: 8}]\n"
         "ground: {size_m: 40, " +
         kMaterial +
         "}\n"
         "obstacles:\n"
         "  - {position: [1000, 1000], size: [1, 1], height_m: 1, yaw_deg: 0, " +
         kMaterial +
         "}\n"
         "  - {shape: cylinder, position: [900, 900], radius_m: 1, height_m: 1}\n"
         "  - {shape: wall, from: [-900, -900], to: [900, -900], thickness_m: 1, height_m: 2}\n"
         "moving:\n"
         "  - {size: [1, 1], height_m: 1, waypoints: [[-1000, 1000], [-900, 1000]], speed_mps: "
         "1, " +
         kMaterial +
         "}\n"
         "  - {shape: cylinder, radius_m: 1, waypoints: [[-800, 800], [-700, 800]]}\n"
         "agents:\n"
         "  - {name: a, start: [-500, -500], heading_deg: 0, speed_mps: 1, preferred_speed_mps: 1, "
         "max_speed_mps: 1.5, radius_m: 0.3, height_m: 1.7, goal: [3, 0], goal_radius_m: 0.5, "
         "camera: " +
         kCamera + ", controller: {" + kController + ", " + kMotionEnergy + "}, " + kMaterial +
         ", carried_light: {intensity: 1, range_m: 6, height_m: 1.2, ahead_m: 0.4}}\n"
         "  - {name: b, start: [-400, -500], goals: [[3, 0], [4, 0]]}\n";
}

TEST(FieldBounds, ScenarioFileRefusesEveryFieldJustOutsideItsBound) {
  walk_yaml_table(scenario_bounds(), {scenario_with_every_field()},
                  [](const std::string& text) { parse_scenario(text, "bounds.yaml"); });
}

// One launch file per camera type and drive type: a file holds one of each.
std::vector<std::string> launch_files_with_every_field() {
  return {
      "camera:\n"
      "  type: v4l2\n"
      "  timeout_s: 5\n"
      "  horizontal_fov_rad: 1.0\n"
      "  v4l2: {device: /dev/video0, width_px: 64, height_px: 64, frame_rate_hz: 30, "
      "buffer_count: 4}\n"
      "drive:\n"
      "  type: sim\n"
      "  loop_rate_hz: 1000\n"
      "  geometry: {wheel_separation_m: 0.4, wheel_radius_m: 0.05}\n"
      "  limits: {max_speed_mps: 0.5, max_reverse_speed_mps: 0, max_accel_mps2: 0.5, "
      "max_turn_rate: 1, max_wheel_speed_radps: 40}\n"
      "  watchdog: {timeout_s: 2, ramp_s: 0}\n"
      "  sim: {wheel_time_constant_s: 0.05}\n"
      "perception: {height_m: 0.35, pitch_deg: 0}\n"
      "controller: {" +
          kController +
          ", preferred_speed_mps: 0.3, robot_width_m: 0.4}\n"
          "goal: {bearing_rad: 0, distance_m: 5}\n",
      "camera: {type: libcamera, libcamera: {camera_id: cam, width_px: 64, height_px: 64, "
      "frame_rate_hz: 30, buffer_count: 4}}\n"
      "drive: {type: odrive_can, odrive: {can_interface: can0, left: {node_id: 10}, right: "
      "{node_id: 20}, motor_turns_per_wheel_turn: 1, timeout_s: 0.5}}\n"
      "perception: {height_m: 0.35}\n",
      "camera: {type: replay, replay: {path: a.mp4, frame_rate_hz: 30}}\n"
      "drive: {type: arduino_bridge, arduino_bridge: {device: /dev/ttyACM0, baud: 57600, "
      "timeout_s: 0.1, ticks_per_wheel_rev: 1000, pid_rate_hz: 30, boot_wait_s: 2}}\n"
      "perception: {height_m: 0.35}\n",
      "camera: {type: replay, replay: {path: a.mp4}}\n"
      "drive: {type: roboclaw, roboclaw: {device: /dev/ttyACM1, baud: 38400, timeout_s: 0.1, "
      "address: 128, ticks_per_wheel_rev: 1000, board_timeout_s: 1}}\n"
      "perception: {height_m: 0.35}\n",
      "camera: {type: ros2, ros2: {domain_id: 5, connect_timeout_s: 5}}\n"
      "drive: {type: ros2, ros2: {domain_id: 5, timeout_s: 0.5, connect_timeout_s: 5}}\n"
      "perception: {height_m: 0.35}\n"};
}

TEST(FieldBounds, RobotLaunchFileRefusesEveryFieldJustOutsideItsBound) {
  walk_yaml_table(robot_launch_bounds(), launch_files_with_every_field(),
                  [](const std::string& text) {
                    // A controller that weighs dark regions needs the perception that finds them.
                    YAML::Node root = YAML::Load(text);
                    if (root["controller"] && root["controller"]["delta"] &&
                        root["controller"]["delta"].as<double>() > 0.0) {
                      root["perception"]["dark_regions"] = true;
                    }
                    parse_robot_launch(YAML::Dump(root), "launch.yaml", "");
                  });
}

TEST(FieldBounds, DemoSceneRefusesEveryFieldJustOutsideItsBound) {
  const std::string scene =
      "camera: {resolution: 64, hfov_deg: 90, height_m: 1.6, pitch_deg: 0}\n"
      "agent: {speed_mps: 1, turn_rate: 0, width_m: 0.5}\n"
      "goal: [10, 0]\n"
      "controller: {" +
      kController +
      ", follow_gap_m: 2, preferred_speed_mps: 1}\n"
      "objects:\n"
      "  - {position: [500, 500], size: [1, 1], height_m: 1.8, velocity: [0, 0]}\n"
      "  - {shape: cylinder, position: [500, 300], radius_m: 0.3}\n";
  walk_yaml_table(demo_scene_bounds(), {scene},
                  [](const std::string& text) { parse_demo_scene(text, "scene.yaml"); },
                  {{{"goal", "min"}, "goal: must be ahead of the agent"}});
}

// --- SteerSuite XML -------------------------------------------------------------------------

// Every element SteerSuite's table bounds, placed as in the scenario above: the large bodies far
// from the agents.
const char* kSteerSuiteWithEveryField = R"(<SteerBenchTestCase>
<header><version>1.0</version><name>bounds</name>
<worldBounds><xmin>-100</xmin><xmax>100</xmax><ymin>0</ymin><ymax>0</ymax><zmin>-100</zmin><zmax>100</zmax></worldBounds>
</header>
<obstacle><xmin>500</xmin><xmax>501</xmax><ymin>0</ymin><ymax>1</ymax><zmin>500</zmin><zmax>501</zmax></obstacle>
<circleObstacle><radius>1</radius><height>1</height><position><x>-500</x><y>0</y><z>500</z></position></circleObstacle>
<orientedBoxObstacle><thetaY>0</thetaY><size><x>1</x><y>1</y><z>1</z></size><position><x>500</x><y>0</y><z>-500</z></position></orientedBoxObstacle>
<obstacleRegion><numObstacles>1</numObstacles><obstacleSize>1</obstacleSize><obstacleHeight>1</obstacleHeight>
<regionBounds><xmin>600</xmin><xmax>900</xmax><ymin>0</ymin><ymax>0</ymax><zmin>600</zmin><zmax>900</zmax></regionBounds></obstacleRegion>
<agent><name>a</name><initialConditions><radius>0.3</radius><position><x>0</x><y>0</y><z>0</z></position>
<direction><x>1</x><y>0</y><z>0</z></direction><speed>0</speed><color><r>0.5</r><g>0.5</g><b>0.5</b></color></initialConditions>
<goalSequence><seekStaticTarget><targetLocation><x>5</x><y>0</y><z>0</z></targetLocation><desiredSpeed>1.3</desiredSpeed>
<timeDuration>1000</timeDuration></seekStaticTarget></goalSequence></agent>
<agent><name>b</name><initialConditions><radius>0.3</radius><position><x>10</x><y>0</y><z>0</z></position>
<direction><x>1</x><y>0</y><z>0</z></direction><speed>0</speed></initialConditions>
<goalSequence><idle><timeDuration>5</timeDuration></idle></goalSequence></agent>
</SteerBenchTestCase>
)";

// The first <name> whose parent is <parent>, in document order.
tinyxml2::XMLElement* find_element(tinyxml2::XMLElement* e, const std::string& parent,
                                   const std::string& name) {
  for (tinyxml2::XMLElement* c = e->FirstChildElement(); c != nullptr;
       c = c->NextSiblingElement()) {
    if (parent == e->Name() && name == c->Name()) {
      return c;
    }
    if (tinyxml2::XMLElement* found = find_element(c, parent, name)) {
      return found;
    }
  }
  return nullptr;
}

TEST(FieldBounds, SteerSuiteCaseRefusesEveryElementJustOutsideItsBound) {
  const auto parse = [](const std::string& xml) { parse_steersuite(xml, "case.xml", 1); };
  ASSERT_NO_THROW(parse(kSteerSuiteWithEveryField));
  // A region's or a box's minimum at the largest position leaves no room for its maximum.
  OtherRules empty_region;
  for (const char* element : {"regionBounds", "obstacle"}) {
    for (const auto& [row, end] : {std::pair{"xmin", "max"}, std::pair{"xmax", "min"},
                                   std::pair{"zmin", "max"}, std::pair{"zmax", "min"}}) {
      empty_region[{std::string(element) + "/" + row, end}] = "empty bounds";
    }
  }
  empty_region[{"seekStaticTarget/timeDuration", "min"}] = "shorter than the run";
  for (const base::FieldBound& row : steersuite_bounds()) {
    const std::size_t slash = row.field.find('/');
    const std::string parent = row.field.substr(0, slash);
    const std::string name = row.field.substr(slash + 1);
    for (const Probe& p : probes(row.bound, false)) {
      tinyxml2::XMLDocument doc;
      ASSERT_EQ(doc.Parse(kSteerSuiteWithEveryField), tinyxml2::XML_SUCCESS);
      tinyxml2::XMLElement* e = find_element(doc.RootElement(), parent, name);
      ASSERT_NE(e, nullptr) << "the test case holds no " << row.field;
      e->SetText(text_of(p.value).c_str());
      tinyxml2::XMLPrinter printer;
      doc.Print(&printer);
      std::optional<std::string> error;
      try {
        parse(printer.CStr());
      } catch (const base::ConfigError& err) {
        error = err.what();
      }
      expect_outcome(row.field, row.bound, p, error, empty_region, row.field);
    }
  }
}

// The row the reader looks up for a path with indices, and a forgotten row said plainly.
TEST(FieldBounds, LookupLeavesOutIndicesAndRefusesAFieldNotInTheTable) {
  EXPECT_EQ(base::without_indices("agents[3].goals[12]"), "agents[].goals[]");
  EXPECT_EQ(&base::bound_of(scenario_bounds(), "agents[7].camera.height_m"),
            &base::bound_of(scenario_bounds(), "agents[].camera.height_m"));
  EXPECT_THROW(base::bound_of(scenario_bounds(), "agents[0].wingspan_m"), std::logic_error);
}

}  // namespace
}  // namespace flowsteer::config
