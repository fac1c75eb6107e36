// SteerSuite test cases (XML) as flowsteer worlds. SteerSuite's ground is its x–z plane with y
// up; a SteerSuite point (x, y, z) is the world point (x, −z) on the ground, which keeps the
// frame right-handed.
#include <cmath>
#include <random>
#include <string>

#include <tinyxml2.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::config {

namespace {

using tinyxml2::XMLElement;

class XmlReader {
 public:
  explicit XmlReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const XMLElement* at, const std::string& message) const {
    throw base::ConfigError(source_, at != nullptr ? at->GetLineNum() : 1, 1,
                            at != nullptr ? at->Name() : "", message);
  }

  const XMLElement* child(const XMLElement* parent, const char* name) const {
    const XMLElement* e = parent->FirstChildElement(name);
    if (e == nullptr) {
      fail(parent, std::string("missing <") + name + ">");
    }
    return e;
  }

  double number(const XMLElement* parent, const char* name) const {
    const XMLElement* e = child(parent, name);
    double value = 0.0;
    if (e->QueryDoubleText(&value) != tinyxml2::XML_SUCCESS || !std::isfinite(value)) {
      fail(e, std::string("<") + name + "> is not a number: '" +
                  (e->GetText() != nullptr ? e->GetText() : "") + "'");
    }
    return value;
  }

  double number_or(const XMLElement* parent, const char* name, double fallback) const {
    return parent->FirstChildElement(name) != nullptr ? number(parent, name) : fallback;
  }

  bool is_random(const XMLElement* e) const {
    const XMLElement* r = e->FirstChildElement("random");
    return r != nullptr && r->GetText() != nullptr && std::string(r->GetText()) == "true";
  }

  // A SteerSuite vector on the ground, as a world point.
  Eigen::Vector2d ground_point(const XMLElement* e) const {
    return {number(e, "x"), -number(e, "z")};
  }

 private:
  std::string source_;
};

struct Bounds {
  Eigen::Vector2d min;
  Eigen::Vector2d max;
};

Bounds read_bounds(const XmlReader& r, const XMLElement* e) {
  const double xmin = r.number(e, "xmin");
  const double xmax = r.number(e, "xmax");
  const double zmin = r.number(e, "zmin");
  const double zmax = r.number(e, "zmax");
  if (!(xmin < xmax) || !(zmin < zmax)) {
    r.fail(e, "empty bounds: xmin < xmax and zmin < zmax are needed");
  }
  return {{xmin, -zmax}, {xmax, -zmin}};
}

Eigen::Vector2d random_point(std::mt19937& rng, const Bounds& b) {
  std::uniform_real_distribution<double> x(b.min.x(), b.max.x());
  std::uniform_real_distribution<double> y(b.min.y(), b.max.y());
  return {x(rng), y(rng)};
}

void read_goals(const XmlReader& r, const XMLElement* sequence, const Bounds& world,
                std::mt19937& rng, sim_camera::AgentSpec& agent) {
  for (const XMLElement* g = sequence->FirstChildElement(); g != nullptr;
       g = g->NextSiblingElement()) {
    if (std::string(g->Name()) != "seekStaticTarget") {
      r.fail(g, std::string("goal type <") + g->Name() +
                    "> is not supported (only <seekStaticTarget>)");
    }
    const XMLElement* target = r.child(g, "targetLocation");
    agent.goals.push_back(r.is_random(target) ? random_point(rng, world) : r.ground_point(target));
    agent.preferred_speed_mps = r.number_or(g, "desiredSpeed", agent.preferred_speed_mps);
  }
  if (agent.goals.empty()) {
    r.fail(sequence, "an agent needs at least one <seekStaticTarget>");
  }
}

}  // namespace

sim_camera::WorldSpec parse_steersuite(const std::string& xml_text,
                                       const std::string& source_name) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml_text.c_str(), xml_text.size()) != tinyxml2::XML_SUCCESS) {
    throw base::ConfigError(source_name, doc.ErrorLineNum(), 1, "", doc.ErrorStr());
  }
  const XmlReader r(source_name);
  const XMLElement* root = doc.RootElement();
  if (root == nullptr || std::string(root->Name()) != "SteerBenchTestCase") {
    r.fail(root, "the root element must be <SteerBenchTestCase>");
  }
  sim_camera::WorldSpec w;
  const XMLElement* header = r.child(root, "header");
  const XMLElement* name = header->FirstChildElement("name");
  w.name = name != nullptr && name->GetText() != nullptr ? name->GetText() : source_name;
  w.description = "SteerSuite test case " + w.name;
  const Bounds world = read_bounds(r, r.child(header, "worldBounds"));
  w.ground_size_m = std::max(20.0, (world.max - world.min).maxCoeff());
  w.duration_s = 60.0;
  std::mt19937 rng(1);  // random placements are repeatable from run to run

  for (const XMLElement* o = root->FirstChildElement("obstacle"); o != nullptr;
       o = o->NextSiblingElement("obstacle")) {
    const Bounds b = read_bounds(r, o);
    sim_camera::Solid s;
    s.centre_m = 0.5 * (b.min + b.max);
    s.size_m = b.max - b.min;
    s.height_m = std::max(0.3, r.number_or(o, "ymax", 1.0) - r.number_or(o, "ymin", 0.0));
    w.obstacles.push_back(s);
  }

  auto place = [&](sim_camera::AgentSpec& a) {
    a.name = a.name.empty() ? "agent" + std::to_string(w.agents.size()) : a.name;
    a.start_speed_mps = std::min(a.start_speed_mps, a.preferred_speed_mps);
    a.max_speed_mps = 2.0 * a.preferred_speed_mps + 0.5;
    a.controller.max_turn_rate = 1.5;
    w.agents.push_back(a);
  };
  for (const XMLElement* e = root->FirstChildElement("agent"); e != nullptr;
       e = e->NextSiblingElement("agent")) {
    sim_camera::AgentSpec a;
    if (const XMLElement* n = e->FirstChildElement("name");
        n != nullptr && n->GetText() != nullptr) {
      a.name = n->GetText();
    }
    const XMLElement* initial = r.child(e, "initialConditions");
    a.radius_m = r.number_or(initial, "radius", 0.5);
    a.start_m = r.ground_point(r.child(initial, "position"));
    const Eigen::Vector2d direction = r.ground_point(r.child(initial, "direction"));
    a.heading_rad = std::atan2(direction.y(), direction.x());
    a.start_speed_mps = r.number_or(initial, "speed", 0.0);
    read_goals(r, r.child(e, "goalSequence"), world, rng, a);
    place(a);
  }
  for (const XMLElement* e = root->FirstChildElement("agentRegion"); e != nullptr;
       e = e->NextSiblingElement("agentRegion")) {
    const double count = r.number(e, "numAgents");
    if (count < 0 || count > 1000 || count != std::floor(count)) {
      r.fail(e, "<numAgents> must be a whole number from 0 to 1000");
    }
    const Bounds region = read_bounds(r, r.child(e, "regionBounds"));
    const XMLElement* initial = r.child(e, "initialConditions");
    for (int k = 0; k < static_cast<int>(count); ++k) {
      sim_camera::AgentSpec a;
      a.radius_m = r.number_or(initial, "radius", 0.5);
      // Rejection sampling for a start that overlaps nothing placed so far.
      bool placed = false;
      for (int attempt = 0; attempt < 200 && !placed; ++attempt) {
        a.start_m = random_point(rng, region);
        placed = true;
        for (const auto& other : w.agents) {
          placed = placed && (other.start_m - a.start_m).norm() > other.radius_m + a.radius_m;
        }
        for (const auto& o : w.obstacles) {
          placed = placed && sim_camera::footprint_distance(o, a.start_m) > a.radius_m;
        }
      }
      if (!placed) {
        r.fail(e, "cannot place " + std::to_string(static_cast<int>(count)) +
                      " agents in this region without overlaps");
      }
      const XMLElement* direction = r.child(initial, "direction");
      if (r.is_random(direction)) {
        a.heading_rad = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
      } else {
        const Eigen::Vector2d d = r.ground_point(direction);
        a.heading_rad = std::atan2(d.y(), d.x());
      }
      a.start_speed_mps = r.number_or(initial, "speed", 0.0);
      read_goals(r, r.child(e, "goalSequence"), world, rng, a);
      place(a);
    }
  }
  if (w.agents.empty()) {
    r.fail(root, "the test case has no agent");
  }
  try {
    sim_camera::World check(w);
  } catch (const std::invalid_argument& e) {
    throw base::ConfigError(source_name, e.what());
  }
  return w;
}

sim_camera::WorldSpec load_steersuite(const std::string& path) {
  return parse_steersuite(base::read_text_file(path, "SteerSuite test case"), path);
}

}  // namespace flowsteer::config
