#pragma once

// Shared by the robot launch file tests.

#include <string>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/robot_launch.hpp"

namespace flowsteer::robot::test_support {

// The base::ConfigError that parsing `yaml` as the launch file bad.yaml gives, "no error" if none.
inline std::string error_of(const std::string& yaml) {
  try {
    config::parse_robot_launch(yaml, "bad.yaml", "");
  } catch (const base::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace flowsteer::robot::test_support
