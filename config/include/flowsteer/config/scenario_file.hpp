#pragma once

#include <string>
#include <vector>

#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::config {

// Scenario files (YAML) describe a world for `flowsteer sim`: lights, obstacles, moving
// obstacles, agents with their goals or leader, controller and camera. The format is documented
// in launch/scenarios/room.yaml. Errors throw base::ConfigError with the file, line, column and
// field.
sim_camera::WorldSpec parse_scenario(const std::string& yaml_text, const std::string& source_name);
sim_camera::WorldSpec load_scenario(const std::string& path);

// The scenarios built into the command, reproducing the papers' figures.
struct BuiltinScenario {
  std::string name;
  std::string description;
};
std::vector<BuiltinScenario> builtin_scenarios();
bool is_builtin_scenario(const std::string& name);
// Throws base::ConfigError listing the known names when `name` is not one of them.
sim_camera::WorldSpec builtin_scenario(const std::string& name);

// A SteerSuite test case (its XML schema: agents with initial conditions and goal sequences of
// static targets, axis-aligned box obstacles, agent regions), converted to a world.
sim_camera::WorldSpec load_steersuite(const std::string& path);
sim_camera::WorldSpec parse_steersuite(const std::string& xml_text, const std::string& source_name);

}  // namespace flowsteer::config
