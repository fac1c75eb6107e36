#pragma once

// ConfigError lives in calibration, the lowest module that reads user files (camera_info,
// mount files); launch names it as its own so that its readers and callers keep one spelling.
#include "flowsteer/calibration/config_error.hpp"

namespace flowsteer::launch {

using calibration::ConfigError;

}  // namespace flowsteer::launch
