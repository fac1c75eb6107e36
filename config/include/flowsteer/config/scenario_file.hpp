#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::config {

// Scenario files (YAML) describe a world for `flowsteer sim`: lights, obstacles, moving
// obstacles, agents with their goals or leader, controller and camera. The format is documented
// in config/scenarios/room.yaml. Errors throw base::ConfigError with the file, line, column and
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

// A scenario read from a file, with what the reader had to warn about (each "file:line: message").
struct LoadedCase {
  sim_camera::WorldSpec world;
  std::vector<std::string> warnings;
};

// A SteerSuite test case (XML: agents and agent regions with initial conditions and goal
// sequences, box, circle and oriented box obstacles, obstacle regions), converted to a world the
// way SteerSuite's own reader sets it up. What flowsteer cannot represent is an error, or a
// warning where ignoring it cannot change the outcome; an element it does not know is an error.
// seed: where agentRegion, obstacleRegion and random targets and directions are placed
// (SteerSuite files; ignored for YAML).
LoadedCase parse_steersuite(const std::string& xml_text, const std::string& source_name,
                            std::uint32_t seed = 1);
LoadedCase load_steersuite(const std::string& path, std::uint32_t seed = 1);
// A scenario file by its extension: .xml is a SteerSuite test case, .yaml/.yml a scenario file;
// any other extension is a base::ConfigError naming the file.
LoadedCase load_case(const std::filesystem::path& path, std::uint32_t seed = 1);

}  // namespace flowsteer::config
