#pragma once

#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/config/drive_config.hpp"

namespace flowsteer::config {

// The `drive:` section of a launch file already loaded (parse_drive_section loads the text
// first): `drive` is root["drive"], present; errors are reported at its nodes.
DriveSection read_drive(const base::YamlReader& r, const YAML::Node& drive);

}  // namespace flowsteer::config
