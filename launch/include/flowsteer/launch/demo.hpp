#pragma once

#include <ostream>

#include "flowsteer/config/demo_scene.hpp"

namespace flowsteer::launch {

// Renders the scene's flow analytically, runs the servo core on it (derotation, ground
// removal, segmentation by object id, features, control) and prints the features beside the
// geometric truth, then the command and each cost term.
void run_demo(const config::DemoScene& demo, std::ostream& out);

}  // namespace flowsteer::launch
