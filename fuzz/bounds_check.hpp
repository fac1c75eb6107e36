#pragma once

// The property the reader harnesses check beside "no crash": what a reader accepts holds only
// values within the bounds of their quantities (base/quantity_bounds.hpp): finite, in bounds, a run
// of at least one step. A value outside aborts with its name and value, a finding for libFuzzer.

#include "flowsteer/config/demo_scene.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/sim_camera/world_spec.hpp"

namespace flowsteer::fuzz {

void check_bounds(const sim_camera::WorldSpec& world);
void check_bounds(const config::RobotLaunch& launch);
void check_bounds(const config::DemoScene& demo);

}  // namespace flowsteer::fuzz
