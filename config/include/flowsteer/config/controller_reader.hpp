#pragma once

#include <string>

#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/servo/steering.hpp"

namespace flowsteer::config {

// The `controller:` and `perception:` settings shared by scenario files and robot launch files,
// validated alike. The caller checks the section's keys first (r.only_keys): each file allows
// its own subset and may add keys of its own. An absent node returns the defaults given.

// Weights (alpha..delta, delta <= gamma), lambda, limits, use_depth, clearance margin, the
// steering model (`type`) and kind, and type motion_energy's settings.
servo::ControllerConfig read_controller(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& field, servo::ControllerConfig c);

// The flow method, the segmentation method and the depth source, by name (the callers say which
// keys their files allow).
servo::PerceptionConfig read_perception(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& field,
                                        servo::PerceptionConfig perception);

}  // namespace flowsteer::config
