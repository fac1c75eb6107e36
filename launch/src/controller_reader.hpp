#pragma once

#include <string>

#include "flowsteer/sim_camera/world.hpp"
#include "flowsteer/base/yaml_reader.hpp"

namespace flowsteer::launch {

// The `controller:` and `perception:` settings shared by scenario files and robot launch files,
// validated alike. The caller checks the section's keys first (r.only_keys): each file allows
// its own subset and may add keys of its own. An absent node returns the defaults given.

// Weights (alpha..delta, delta <= gamma), lambda, limits, use_depth, clearance margin, the
// steering model's type and kind, and type motion_energy's settings.
sim_camera::ControllerSpec read_controller(const base::YamlReader& r, const YAML::Node& node,
                                           const std::string& field, sim_camera::ControllerSpec c);

// The flow method and the segmentation method, by name.
sim_camera::PerceptionSpec read_perception(const base::YamlReader& r, const YAML::Node& node,
                                           const std::string& field,
                                           sim_camera::PerceptionSpec perception);

}  // namespace flowsteer::launch
