// SteerSuite test cases (XML) as flowsteer worlds, set up the way SteerSuite's own TestCaseReader
// sets them up. SteerSuite's ground is its x–z plane with y up; a SteerSuite point (x, y, z) is the
// world point (x, −z) on the ground, which keeps the frame right-handed. SteerSuite turns by θ
// about its y axis as x' = x cos θ + z sin θ, z' = z cos θ − x sin θ: that is a yaw of +θ here.
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <string_view>

#include <tinyxml2.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/config/field_bounds.hpp"
#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::config {

namespace {

using sim_camera::AgentSpec;
using sim_camera::Solid;
using tinyxml2::XMLElement;

// SteerSuite gives no camera: agents get a person's field of view, as wide as a pinhole camera
// renders well (a person's is about 200°). Two people converging at 45° at one speed see each
// other at a constant 67.5° off their heading: with a 90° camera neither would ever see the other.
constexpr double kFieldOfView_rad = 150.0 * std::numbers::pi / 180.0;

AgentSpec person() {
  AgentSpec spec;
  spec.camera.hfov_rad = kFieldOfView_rad;
  return spec;
}

// Every agent renders its own camera and keeps its frames: about 0.65 MB each with the default
// 128 x 128 camera (measured on SteerSuite's cases), so 10000 agents take some 7 GB.
constexpr int kMaxAgents = 10000;
// Obstacles cost little memory, but each is drawn in every view.
constexpr int kMaxObstacles = 100000;
// SteerSuite gives up on placing one random object after this many tries.
constexpr int kPlacementTries = 10000;
// Cameras do not see flat obstacles; SteerSuite's collisions are 2D, so a taller one blocks the
// same.
constexpr double kMinVisibleHeight_m = 0.3;
// SteerSuite's typical agent (testcases/EXAMPLE.xml), for what its schema requires and a file
// leaves out.
constexpr double kTypicalRadius_m = 0.5;
constexpr double kTypicalSpeed_mps = 1.3;
// SteerSuite's agents draw a random target this far inside the world and away from obstacles.
constexpr double kRandomTargetClearance_m = 1.0;
constexpr double kDeg = std::numbers::pi / 180.0;

std::string trimmed(const char* text) {
  const std::string s = text != nullptr ? text : "";
  const auto first = s.find_first_not_of(" \t\r\n");
  return first == std::string::npos ? ""
                                    : s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

// Warnings, each said once at its first line with how often it came up: a file of a thousand
// agents gives a handful of lines.
class Warnings {
 public:
  void add(int line, const std::string& message) {
    const auto [it, inserted] = index_.try_emplace(message, entries_.size());
    if (inserted) {
      entries_.push_back({line, message, 1});
    } else {
      ++entries_[it->second].count;
    }
  }

  std::vector<std::string> lines(const std::string& source) const {
    std::vector<std::string> out;
    for (const Entry& e : entries_) {
      out.push_back(source + ":" + std::to_string(e.line) + ": " + e.message +
                    (e.count > 1 ? " (" + std::to_string(e.count) + " times)" : ""));
    }
    return out;
  }

 private:
  struct Entry {
    int line;
    std::string message;
    int count;
  };
  std::vector<Entry> entries_;
  std::map<std::string, std::size_t> index_;
};

class XmlReader {
 public:
  explicit XmlReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const XMLElement* at, const std::string& message) const {
    throw base::ConfigError(source_, at != nullptr ? at->GetLineNum() : 1, 1,
                            at != nullptr ? at->Name() : "", message);
  }

  void warn(const XMLElement* at, const std::string& message) {
    warnings_.add(at->GetLineNum(), message);
  }

  // Fails on the first child of `parent` that is not one of `known`.
  void only_children(const XMLElement* parent,
                     std::initializer_list<std::string_view> known) const {
    for (const XMLElement* c = parent->FirstChildElement(); c != nullptr;
         c = c->NextSiblingElement()) {
      if (std::find(known.begin(), known.end(), std::string_view(c->Name())) == known.end()) {
        fail(c, unknown(c, parent));
      }
    }
  }

  static std::string unknown(const XMLElement* e, const XMLElement* parent) {
    return std::string("unknown element <") + e->Name() + "> in <" + parent->Name() + ">";
  }

  const XMLElement* child(const XMLElement* parent, const char* name) const {
    const XMLElement* e = parent->FirstChildElement(name);
    if (e == nullptr) {
      fail(parent, std::string("missing <") + name + ">");
    }
    return e;
  }

  double number(const XMLElement* e) const {
    double value = 0.0;
    if (e->QueryDoubleText(&value) != tinyxml2::XML_SUCCESS || !std::isfinite(value)) {
      fail(e, std::string("<") + e->Name() + "> is not a number: '" + trimmed(e->GetText()) + "'");
    }
    return value;
  }

  double number(const XMLElement* parent, const char* name) const {
    return number(child(parent, name));
  }

  // <name> in `parent`: a number within the row "parent/name" of steersuite_bounds().
  double bounded(const XMLElement* parent, const char* name) const {
    const std::string field = std::string(parent->Name()) + "/" + name;
    const base::Bound& bound = base::bound_of(steersuite_bounds(), field);
    const XMLElement* e = child(parent, name);
    const double value = number(e);
    if (!bound.contains(value)) {
      throw base::ConfigError(source_, e->GetLineNum(), 1, field, bound.refusal(value));
    }
    return value;
  }

  int count(const XMLElement* parent, const char* name, int limit, const std::string& why) const {
    const double value = number(parent, name);
    if (value < 0 || value > limit || value != std::floor(value)) {
      fail(parent->FirstChildElement(name),
           std::string("<") + name + "> must be a whole number from 0 to " + std::to_string(limit) +
               " (" + why + "), not " + trimmed(parent->FirstChildElement(name)->GetText()));
    }
    return static_cast<int>(value);
  }

  // SteerSuite's booleans are the literals "true" and "false".
  bool flag(const XMLElement* e) const {
    const std::string text = trimmed(e->GetText());
    if (text != "true" && text != "false") {
      fail(e, std::string("<") + e->Name() + "> must be true or false, not '" + text + "'");
    }
    return text == "true";
  }

  const std::string& source() const { return source_; }
  const Warnings& warnings() const { return warnings_; }

 private:
  std::string source_;
  Warnings warnings_;
};

// A SteerSuite <x> <y> <z> tuple, or <random>true</random> in its place.
struct Tuple {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  bool random = false;

  Eigen::Vector2d ground() const { return {x, -z}; }
};

Tuple read_tuple(const XmlReader& r, const XMLElement* e) {
  r.only_children(e, {"x", "y", "z", "random"});
  Tuple t;
  const XMLElement* random = e->FirstChildElement("random");
  t.random = random != nullptr && r.flag(random);
  const bool has_xyz = e->FirstChildElement("x") != nullptr ||
                       e->FirstChildElement("y") != nullptr || e->FirstChildElement("z") != nullptr;
  if (has_xyz == t.random) {
    r.fail(e, "give either <x>, <y> and <z> or <random>true</random>");
  }
  if (has_xyz) {
    t.x = r.bounded(e, "x");
    t.y = r.bounded(e, "y");
    t.z = r.bounded(e, "z");
  }
  return t;
}

// An axis-aligned rectangle on the world's ground.
struct Bounds {
  Eigen::Vector2d min;
  Eigen::Vector2d max;
};

// SteerSuite's bounds: all six of <xmin> … <zmax>; the ground rectangle, empty when inverted.
struct RawBounds {
  Bounds ground;
  double ymin_m;
  double ymax_m;
  bool empty;
};

RawBounds read_raw_bounds(const XmlReader& r, const XMLElement* e) {
  r.only_children(e, {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"});
  const double xmin = r.bounded(e, "xmin");
  const double xmax = r.bounded(e, "xmax");
  const double zmin = r.bounded(e, "zmin");
  const double zmax = r.bounded(e, "zmax");
  return {{{xmin, -zmax}, {xmax, -zmin}},
          r.bounded(e, "ymin"),
          r.bounded(e, "ymax"),
          !(xmin < xmax) || !(zmin < zmax)};
}

Bounds read_bounds(const XmlReader& r, const XMLElement* e) {
  const RawBounds b = read_raw_bounds(r, e);
  if (b.empty) {
    r.fail(e, "empty bounds: xmin < xmax and zmin < zmax are needed");
  }
  return b.ground;
}

// A flowsteer solid stands on the ground; SteerSuite's spans [bottom, top] but collides in 2D.
double solid_height(XmlReader& r, const XMLElement* at, double bottom_m, double top_m) {
  if (bottom_m > 0.0) {
    r.warn(at,
           "an obstacle above the ground stands on it here (SteerSuite's collisions are 2D, "
           "so it blocks agents the same)");
  }
  if (top_m < kMinVisibleHeight_m) {
    r.warn(at,
           "obstacles lower than 0.3 m are raised to 0.3 m so that cameras see them "
           "(SteerSuite's collisions are 2D, so they block agents the same)");
    return kMinVisibleHeight_m;
  }
  return top_m;
}

Solid read_box_obstacle(XmlReader& r, const XMLElement* e) {
  const RawBounds b = read_raw_bounds(r, e);
  if (b.empty) {
    r.fail(e, "empty bounds: xmin < xmax and zmin < zmax are needed");
  }
  Solid s;
  s.centre_m = 0.5 * (b.ground.min + b.ground.max);
  s.size_m = b.ground.max - b.ground.min;
  if (s.size_m.minCoeff() < base::bounds::kExtent_m.min) {
    r.fail(e, "a box must be at least " + base::format_number(base::bounds::kExtent_m.min) +
                  " m wide along x and z, got " + base::format_number(s.size_m.minCoeff()));
  }
  s.height_m = solid_height(r, e, b.ymin_m, b.ymax_m);
  return s;
}

// SteerSuite places no random circle or oriented box obstacles (only <obstacleRegion> boxes).
Tuple fixed_position(const XmlReader& r, const XMLElement* e) {
  const Tuple p = read_tuple(r, r.child(e, "position"));
  if (p.random) {
    r.fail(e,
           "a random <position> is not supported for this obstacle (SteerSuite does not "
           "place it either)");
  }
  return p;
}

Solid read_circle_obstacle(XmlReader& r, const XMLElement* e) {
  r.only_children(e, {"radius", "height", "position"});
  const Tuple p = fixed_position(r, e);
  Solid s;
  s.shape = Solid::Shape::cylinder;
  s.centre_m = p.ground();
  s.radius_m = r.bounded(e, "radius");
  s.height_m = solid_height(r, e, p.y, p.y + r.bounded(e, "height"));
  return s;
}

// <size> is the box's extent along its own x, y (height) and z; <thetaY> turns it in degrees.
Solid read_oriented_box_obstacle(XmlReader& r, const XMLElement* e) {
  r.only_children(e, {"thetaY", "size", "position"});
  const Tuple p = fixed_position(r, e);
  const Tuple size = read_tuple(r, r.child(e, "size"));
  if (size.random || !(size.x > 0.0) || !(size.z > 0.0)) {
    r.fail(r.child(e, "size"), "<size> needs positive <x> and <z>");
  }
  Solid s;
  s.centre_m = p.ground();
  s.size_m = {size.x, size.z};
  s.yaw_rad = r.bounded(e, "thetaY") * kDeg;
  s.height_m = solid_height(r, e, p.y, p.y + size.y);
  return s;
}

// <numObstacles> square boxes of side <obstacleSize>, placed at random like SteerSuite does.
struct ObstacleRegion {
  const XMLElement* at;
  int count;
  double size_m;
  double height_m;
  Bounds region;
};

ObstacleRegion read_obstacle_region(XmlReader& r, const XMLElement* e) {
  r.only_children(e, {"numObstacles", "obstacleSize", "obstacleHeight", "regionBounds"});
  return {e, r.count(e, "numObstacles", kMaxObstacles, "each obstacle is drawn in every view"),
          r.bounded(e, "obstacleSize"), solid_height(r, e, 0.0, r.bounded(e, "obstacleHeight")),
          read_bounds(r, r.child(e, "regionBounds"))};
}

// A goal: a point, a random point in the world, or where the agent starts (a lone <idle>).
struct GoalSpec {
  enum class Kind { point, random, stay };
  Kind kind;
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  const XMLElement* at;
};

// An <agent>, or the <numAgents> agents of an <agentRegion>.
struct AgentTemplate {
  const XMLElement* at = nullptr;
  int count = 1;
  AgentSpec spec = person();
  std::optional<Eigen::Vector2d> start_m;  // none: at random in `region`
  std::optional<Bounds> region;
  bool random_heading = false;
  bool random_colour = false;
  std::vector<GoalSpec> goals;
};

// Goal elements SteerSuite reads but a goal flowsteer keeps has no use for.
void warn_ignored_goal_parts(XmlReader& r, const XMLElement* goal) {
  for (const XMLElement* c = goal->FirstChildElement(); c != nullptr; c = c->NextSiblingElement()) {
    const std::string name = c->Name();
    if (name == "Behaviour") {
      r.warn(c,
             "<Behaviour> ignored: flowsteer agents steer with flowsteer's controller, not the "
             "SteerSuite algorithm it names");
    } else if (name == "state") {
      r.warn(c, "<state> ignored (SteerSuite's reader ignores it too)");
    } else if (name == "targetDirection" || name == "targetName" || name == "type" ||
               name == "flowType" || name == "goalRegionBounds") {
      r.warn(c, "<" + name + "> ignored: a <" + goal->Name() + "> does not use it");
    }
  }
}

// SteerSuite moves on to the next goal after <timeDuration>; flowsteer agents keep a goal until
// they reach it, which is the same only when the run ends first.
void check_time_duration(const XmlReader& r, const XMLElement* goal, double run_s) {
  if (const XMLElement* t = goal->FirstChildElement("timeDuration");
      t != nullptr && r.bounded(goal, "timeDuration") < run_s) {
    r.fail(t, "a <timeDuration> shorter than the run (" + std::to_string(run_s) +
                  " s) is not supported: flowsteer agents keep a goal until they reach it");
  }
}

GoalSpec read_seek_goal(XmlReader& r, const XMLElement* g, double run_s,
                        std::optional<double>& speed_mps) {
  r.only_children(g, {"targetLocation", "random", "desiredSpeed", "timeDuration", "targetDirection",
                      "targetName", "type", "flowType", "goalRegionBounds", "Behaviour", "state"});
  warn_ignored_goal_parts(r, g);
  check_time_duration(r, g, run_s);
  if (g->FirstChildElement("desiredSpeed") != nullptr) {
    const double v = r.bounded(g, "desiredSpeed");
    if (!speed_mps) {
      speed_mps = v;
    } else if (v != *speed_mps) {
      r.warn(g->FirstChildElement("desiredSpeed"),
             "an agent keeps its first goal's <desiredSpeed> (flowsteer agents have one "
             "preferred speed)");
    }
  }
  // <random>true</random> beside the target is SteerSuite's other way to ask for a random one.
  if (const XMLElement* random = g->FirstChildElement("random");
      random != nullptr && r.flag(random)) {
    return {GoalSpec::Kind::random, Eigen::Vector2d::Zero(), g};
  }
  const Tuple target = read_tuple(r, r.child(g, "targetLocation"));
  return target.random ? GoalSpec{GoalSpec::Kind::random, Eigen::Vector2d::Zero(), g}
                       : GoalSpec{GoalSpec::Kind::point, target.ground(), g};
}

bool is_unsupported_goal(std::string_view name) {
  for (std::string_view known :
       {"fleeStaticTarget", "seekDynamicTarget", "fleeDynamicTarget", "flowStaticDirection",
        "flowDynamicDirection", "groupTarget", "seekAxisAlignedBoxRegion"}) {
    if (name == known) {
      return true;
    }
  }
  return false;
}

// An <idle> last is what a flowsteer agent does after its last goal; a lone one keeps it where
// it starts. It idles for its <timeDuration> (to the end of the run without one) before it
// leaves the world. Before another goal it would wait out its <timeDuration>, which flowsteer
// cannot.
void read_idle_goal(XmlReader& r, const XMLElement* g, AgentTemplate& a) {
  r.only_children(g, {"desiredSpeed", "timeDuration", "Behaviour", "state"});
  warn_ignored_goal_parts(r, g);
  const XMLElement* duration = g->FirstChildElement("timeDuration");
  a.spec.idle_s =
      duration != nullptr ? r.bounded(g, "timeDuration") : std::numeric_limits<double>::infinity();
  if (g->NextSiblingElement() != nullptr) {
    r.fail(g,
           "an <idle> before another goal is not supported: flowsteer agents stop only after "
           "their last goal");
  }
  if (a.goals.empty()) {
    a.goals.push_back({GoalSpec::Kind::stay, Eigen::Vector2d::Zero(), g});
  }
}

void read_goal_sequence(XmlReader& r, const XMLElement* e, double run_s, AgentTemplate& a) {
  std::optional<double> speed_mps;
  for (const XMLElement* g = e->FirstChildElement(); g != nullptr; g = g->NextSiblingElement()) {
    const std::string name = g->Name();
    if (name == "seekStaticTarget") {
      a.goals.push_back(read_seek_goal(r, g, run_s, speed_mps));
    } else if (name == "idle") {
      read_idle_goal(r, g, a);
    } else if (is_unsupported_goal(name)) {
      r.fail(g, "goal <" + name +
                    "> is not supported: flowsteer agents go to static targets in "
                    "order (<seekStaticTarget>) and stop after the last (<idle>)");
    } else {
      r.fail(g, XmlReader::unknown(g, e));
    }
  }
  if (a.goals.empty()) {
    r.fail(e, "an agent needs at least one goal");
  }
  if (!speed_mps && a.goals.front().kind != GoalSpec::Kind::stay) {
    r.warn(e, "no <desiredSpeed>: agents walk at SteerSuite's typical 1.3 m/s");
  }
  a.spec.preferred_speed_mps = speed_mps.value_or(kTypicalSpeed_mps);
}

void read_colour(const XmlReader& r, const XMLElement* e, AgentTemplate& a) {
  r.only_children(e, {"r", "g", "b", "random"});
  const XMLElement* random = e->FirstChildElement("random");
  a.random_colour = random != nullptr && r.flag(random);
  if (a.random_colour) {
    return;
  }
  const char* names[] = {"r", "g", "b"};
  for (int c = 0; c < 3; ++c) {
    a.spec.material.albedo[c] = static_cast<float>(r.bounded(e, names[c]));
  }
}

// <position> is read by the caller: an agent needs one, a region places its agents itself.
void read_initial_conditions(XmlReader& r, const XMLElement* e, AgentTemplate& a) {
  r.only_children(e, {"position", "direction", "radius", "speed", "color"});
  if (e->FirstChildElement("radius") != nullptr) {
    a.spec.radius_m = r.bounded(e, "radius");
  } else {
    r.warn(e, "no <radius>: agents get SteerSuite's typical 0.5 m");
    a.spec.radius_m = kTypicalRadius_m;
  }
  a.spec.start_speed_mps = 0.0;
  if (e->FirstChildElement("speed") != nullptr) {
    a.spec.start_speed_mps = r.bounded(e, "speed");
  }
  const Tuple direction = read_tuple(r, r.child(e, "direction"));
  a.random_heading = direction.random;
  if (!direction.random && direction.ground().norm() == 0.0) {
    r.fail(e->FirstChildElement("direction"), "<direction> is the zero vector");
  }
  a.spec.heading_rad = std::atan2(direction.ground().y(), direction.ground().x());
  if (const XMLElement* colour = e->FirstChildElement("color")) {
    read_colour(r, colour, a);
  }
}

AgentTemplate read_agent(XmlReader& r, const XMLElement* e, const std::optional<Bounds>& world,
                         double run_s) {
  r.only_children(e, {"name", "initialConditions", "goalSequence"});
  AgentTemplate a;
  a.at = e;
  a.spec.name = trimmed(
      e->FirstChildElement("name") != nullptr ? e->FirstChildElement("name")->GetText() : nullptr);
  const XMLElement* initial = r.child(e, "initialConditions");
  read_initial_conditions(r, initial, a);
  const Tuple position = read_tuple(r, r.child(initial, "position"));
  if (position.random) {
    if (!world) {
      r.fail(initial->FirstChildElement("position"),
             "a random <position> needs valid <worldBounds>");
    }
    a.region = world;
  } else {
    a.start_m = position.ground();
  }
  read_goal_sequence(r, r.child(e, "goalSequence"), run_s, a);
  return a;
}

AgentTemplate read_agent_region(XmlReader& r, const XMLElement* e, double run_s) {
  r.only_children(e, {"numAgents", "regionBounds", "initialConditions", "goalSequence"});
  AgentTemplate a;
  a.at = e;
  a.count = r.count(e, "numAgents", kMaxAgents, "each agent keeps its camera's frames in memory");
  a.region = read_bounds(r, r.child(e, "regionBounds"));
  const XMLElement* initial = r.child(e, "initialConditions");
  read_initial_conditions(r, initial, a);
  // SteerSuite would put every agent of the region on one fixed position, on top of each other.
  if (const XMLElement* p = initial->FirstChildElement("position");
      p != nullptr && !read_tuple(r, p).random) {
    r.fail(p, "an <agentRegion> places its agents itself: its <position> can only be random");
  }
  read_goal_sequence(r, r.child(e, "goalSequence"), run_s, a);
  return a;
}

// What the file describes, before anything random is placed.
struct TestCase {
  std::optional<Bounds> world;  // none when the file's are empty
  std::vector<Solid> obstacles;
  std::vector<ObstacleRegion> obstacle_regions;
  std::vector<AgentTemplate> agents;
};

void read_header(XmlReader& r, const XMLElement* e, sim_camera::WorldSpec& w, TestCase& tc) {
  r.only_children(e, {"version", "name", "description", "worldBounds", "passingCriteria"});
  if (const XMLElement* version = e->FirstChildElement("version")) {
    const std::string v = trimmed(version->GetText());
    if (v != "1.0" && v != "1.1" && v != "1.2") {
      r.fail(version, "version '" + v + "' is not one of SteerSuite's 1.0, 1.1 and 1.2");
    }
  }
  const XMLElement* name = e->FirstChildElement("name");
  w.name =
      name != nullptr && !trimmed(name->GetText()).empty() ? trimmed(name->GetText()) : r.source();
  w.description = "SteerSuite test case " + w.name;
  if (const XMLElement* description = e->FirstChildElement("description")) {
    w.description += ": " + trimmed(description->GetText());
  }
  if (const XMLElement* criteria = e->FirstChildElement("passingCriteria")) {
    r.warn(criteria, "<passingCriteria> ignored: it is text for people to read");
  }
  const XMLElement* bounds = r.child(e, "worldBounds");
  const RawBounds b = read_raw_bounds(r, bounds);
  if (b.empty) {
    // Published cases (circle-20.xml) have them inverted; SteerSuite runs them all the same.
    r.warn(bounds,
           "empty or inverted <worldBounds> ignored (only random positions and targets need "
           "them)");
  } else {
    tc.world = b.ground;
  }
}

void read_element(XmlReader& r, const XMLElement* e, const XMLElement* root, double run_s,
                  TestCase& tc) {
  const std::string name = e->Name();
  if (name == "agent") {
    tc.agents.push_back(read_agent(r, e, tc.world, run_s));
  } else if (name == "agentRegion") {
    tc.agents.push_back(read_agent_region(r, e, run_s));
  } else if (name == "obstacle") {
    tc.obstacles.push_back(read_box_obstacle(r, e));
  } else if (name == "circleObstacle") {
    tc.obstacles.push_back(read_circle_obstacle(r, e));
  } else if (name == "orientedBoxObstacle") {
    tc.obstacles.push_back(read_oriented_box_obstacle(r, e));
  } else if (name == "obstacleRegion") {
    tc.obstacle_regions.push_back(read_obstacle_region(r, e));
  } else if (name == "suggestedCameraView") {
    r.only_children(e, {"position", "lookat", "up", "fovy"});
    r.warn(e, "<suggestedCameraView> ignored: flowsteer's cameras are its agents' own");
  } else if (name == "agentEmitter") {
    r.fail(e,
           "<agentEmitter> is not supported: it adds agents during the run, and a flowsteer "
           "world has all its agents from the start");
  } else if (name == "polygonObstacle" || name == "orientedWallObstacle") {
    r.fail(e, "<" + name + "> is not supported: flowsteer's obstacles are boxes and cylinders");
  } else {
    r.fail(e, name == "header" ? "a second <header>" : XmlReader::unknown(e, root));
  }
}

// The first of `kPlacementTries` random points of `region`, shrunk by `radius_m` as SteerSuite
// does, that `is_free`.
template <class IsFree>
std::optional<Eigen::Vector2d> find_place(std::mt19937& rng, const Bounds& region, double radius_m,
                                          IsFree is_free) {
  const Eigen::Vector2d lo = region.min.array() + radius_m;
  const Eigen::Vector2d hi = region.max.array() - radius_m;
  if ((hi - lo).minCoeff() < 0.0) {
    return std::nullopt;
  }
  std::uniform_real_distribution<double> x(lo.x(), hi.x());
  std::uniform_real_distribution<double> y(lo.y(), hi.y());
  for (int attempt = 0; attempt < kPlacementTries; ++attempt) {
    const Eigen::Vector2d p(x(rng), y(rng));
    if (is_free(p)) {
      return p;
    }
  }
  return std::nullopt;
}

bool clear_of(const std::vector<Solid>& obstacles, const Eigen::Vector2d& p, double radius_m) {
  return std::all_of(obstacles.begin(), obstacles.end(), [&](const Solid& o) {
    return sim_camera::footprint_distance(o, p) > radius_m;
  });
}

// Like SteerSuite, a region's obstacle keeps a circle of radius <obstacleSize> free of other
// obstacles. SteerSuite lets it cover a fixed agent; a flowsteer world refuses an agent that
// starts inside an obstacle, so it keeps clear of fixed agents too.
void place_obstacle_region(const XmlReader& r, const ObstacleRegion& region,
                           const std::vector<AgentTemplate>& agents, std::mt19937& rng,
                           std::vector<Solid>& obstacles) {
  auto is_free = [&](const Eigen::Vector2d& p) {
    return clear_of(obstacles, p, region.size_m) &&
           std::all_of(agents.begin(), agents.end(), [&](const AgentTemplate& a) {
             return !a.start_m || (*a.start_m - p).norm() > region.size_m + a.spec.radius_m;
           });
  };
  for (int k = 0; k < region.count; ++k) {
    const auto centre = find_place(rng, region.region, region.size_m, is_free);
    if (!centre) {
      r.fail(region.at, "cannot place obstacle " + std::to_string(k + 1) + " of " +
                            std::to_string(region.count) + " in this region without overlaps");
    }
    Solid s;
    s.centre_m = *centre;
    s.size_m = {region.size_m, region.size_m};
    s.height_m = region.height_m;
    obstacles.push_back(s);
  }
}

// One agent of the world, with the template it comes from.
struct Placed {
  const AgentTemplate* from;
  AgentSpec spec;
  bool placed;
};

// Fixed agents first, then the random ones in file order, each clear of obstacles and of every
// agent placed before it (as SteerSuite does).
std::vector<Placed> place_agents(const XmlReader& r, const std::vector<AgentTemplate>& agents,
                                 const std::vector<Solid>& obstacles, std::mt19937& rng) {
  std::vector<Placed> out;
  for (const AgentTemplate& a : agents) {
    for (int k = 0; k < a.count; ++k) {
      out.push_back({&a, a.spec, a.start_m.has_value()});
      out.back().spec.start_m = a.start_m.value_or(Eigen::Vector2d::Zero());
    }
  }
  for (Placed& p : out) {
    if (p.placed) {
      continue;
    }
    const double radius_m = p.spec.radius_m;
    const auto start = find_place(rng, *p.from->region, radius_m, [&](const Eigen::Vector2d& q) {
      return clear_of(obstacles, q, radius_m) &&
             std::all_of(out.begin(), out.end(), [&](const Placed& o) {
               return !o.placed || (o.spec.start_m - q).norm() > o.spec.radius_m + radius_m;
             });
    });
    if (!start) {
      r.fail(p.from->at, "cannot place " + std::to_string(p.from->count) +
                             " agents in this region without overlaps");
    }
    p.spec.start_m = *start;
    p.placed = true;
  }
  return out;
}

Eigen::Vector2d goal_point(const XmlReader& r, const GoalSpec& g, const Placed& agent,
                           const TestCase& tc, const std::vector<Solid>& obstacles,
                           std::mt19937& rng) {
  switch (g.kind) {
    case GoalSpec::Kind::point:
      return g.point_m;
    case GoalSpec::Kind::stay:
      return agent.spec.start_m;
    case GoalSpec::Kind::random:
      break;
  }
  if (!tc.world) {
    r.fail(g.at, "a random target needs valid <worldBounds>");
  }
  const auto p = find_place(
      rng, *tc.world, kRandomTargetClearance_m,
      [&](const Eigen::Vector2d& q) { return clear_of(obstacles, q, kRandomTargetClearance_m); });
  if (!p) {
    r.fail(g.at, "cannot find a random target clear of the obstacles");
  }
  return *p;
}

// Random directions, colours and targets, and the speeds flowsteer's agents need.
void finish_agent(const XmlReader& r, Placed& p, const TestCase& tc,
                  const std::vector<Solid>& obstacles, std::mt19937& rng, std::size_t index) {
  AgentSpec& a = p.spec;
  if (p.from->random_heading) {
    // SteerSuite's random direction (cos φ, 0, sin φ) for φ in [0, 2π) is the heading −φ here.
    a.heading_rad = -std::uniform_real_distribution<double>(0.0, 2.0 * std::numbers::pi)(rng);
  }
  if (p.from->random_colour) {
    std::uniform_real_distribution<float> channel(0.0F, 1.0F);
    a.material.albedo = {channel(rng), channel(rng), channel(rng)};
  }
  for (const GoalSpec& g : p.from->goals) {
    a.goals.push_back(goal_point(r, g, p, tc, obstacles, rng));
  }
  a.name = a.name.empty() ? "agent" + std::to_string(index) : a.name;
  a.max_speed_mps = std::min(std::max(2.0 * a.preferred_speed_mps + 0.5, a.start_speed_mps),
                             base::bounds::kMaxSpeed_mps.max);
  a.controller.max_turn_rate = 1.5;
}

// The ground drawn around each camera: the world's bounds, or what the file puts on it.
double ground_size(const TestCase& tc, const sim_camera::WorldSpec& w) {
  if (tc.world) {
    return std::max(20.0, (tc.world->max - tc.world->min).maxCoeff());
  }
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(-10.0);
  Eigen::Vector2d hi = Eigen::Vector2d::Constant(10.0);
  auto cover = [&](const Eigen::Vector2d& p, double margin_m) {
    lo = lo.cwiseMin((p.array() - margin_m).matrix());
    hi = hi.cwiseMax((p.array() + margin_m).matrix());
  };
  for (const Solid& o : w.obstacles) {
    cover(o.centre_m, std::max(o.size_m.maxCoeff(), 2.0 * o.radius_m));
  }
  for (const AgentSpec& a : w.agents) {
    cover(a.start_m, 5.0);
    for (const Eigen::Vector2d& g : a.goals) {
      cover(g, 5.0);
    }
  }
  return (hi - lo).maxCoeff();
}

void build_world(const XmlReader& r, const TestCase& tc, std::uint32_t seed,
                 sim_camera::WorldSpec& w) {
  std::mt19937 rng(seed);
  // SteerSuite's order: fixed obstacles, random obstacles, random agents.
  w.obstacles = tc.obstacles;
  for (const ObstacleRegion& region : tc.obstacle_regions) {
    place_obstacle_region(r, region, tc.agents, rng, w.obstacles);
  }
  std::vector<Placed> agents = place_agents(r, tc.agents, w.obstacles, rng);
  for (std::size_t i = 0; i < agents.size(); ++i) {
    finish_agent(r, agents[i], tc, w.obstacles, rng, i);
    w.agents.push_back(std::move(agents[i].spec));
  }
  w.ground_size_m = ground_size(tc, w);
}

const XMLElement* read_root(const XmlReader& r, const tinyxml2::XMLDocument& doc) {
  const XMLElement* root = doc.RootElement();
  if (root == nullptr || (std::string(root->Name()) != "SteerBenchTestCase" &&
                          std::string(root->Name()) != "SteerSuiteSubSpace")) {
    r.fail(root, "the root element must be <SteerBenchTestCase>");
  }
  const XMLElement* header = root->FirstChildElement();
  if (header == nullptr || std::string(header->Name()) != "header") {
    r.fail(header != nullptr ? header : root, "<header> must come first");
  }
  return root;
}

}  // namespace

LoadedCase parse_steersuite(const std::string& xml_text, const std::string& source_name,
                            std::uint32_t seed) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml_text.c_str(), xml_text.size()) != tinyxml2::XML_SUCCESS) {
    throw base::ConfigError(source_name, doc.ErrorLineNum(), 1, "", doc.ErrorStr());
  }
  XmlReader r(source_name);
  const XMLElement* root = read_root(r, doc);
  LoadedCase out;
  sim_camera::WorldSpec& w = out.world;
  w.duration_s = 60.0;
  // SteerSuite disables an agent at its last target and takes it out of the world; its cases
  // were written for that rule.
  w.arrival = sim_camera::Arrival::leave;
  TestCase tc;
  read_header(r, root->FirstChildElement(), w, tc);
  for (const XMLElement* e = root->FirstChildElement()->NextSiblingElement(); e != nullptr;
       e = e->NextSiblingElement()) {
    read_element(r, e, root, w.duration_s, tc);
  }
  build_world(r, tc, seed, w);
  if (w.agents.empty()) {
    r.fail(root, "the test case has no agent");
  }
  try {
    sim_camera::World check(w);
  } catch (const std::invalid_argument& e) {
    throw base::ConfigError(source_name, e.what());
  }
  out.warnings = r.warnings().lines(source_name);
  return out;
}

LoadedCase load_steersuite(const std::string& path, std::uint32_t seed) {
  return parse_steersuite(base::read_text_file(path, "SteerSuite test case"), path, seed);
}

}  // namespace flowsteer::config
