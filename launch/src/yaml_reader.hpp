#pragma once

// The YAML helpers live in calibration, the lowest module that reads YAML files; launch's
// readers use them under launch's names.
#include "flowsteer/calibration/yaml_reader.hpp"
#include "flowsteer/launch/config_error.hpp"

namespace flowsteer::launch {

using calibration::load_yaml;
using calibration::load_yaml_map;
using calibration::read_text_file;
using calibration::YamlReader;

}  // namespace flowsteer::launch
