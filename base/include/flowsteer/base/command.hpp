#pragma once

namespace flowsteer::base {

// What the control law outputs: forward acceleration a_c and turn rate ω about the camera's y
// axis, which points down, so positive ω turns the agent right. A drive turns this into
// ω_z = −ω (docs/CONVENTIONS.md).
struct Command {
  double accel_mps2 = 0.0;
  double turn_rate = 0.0;
};

}  // namespace flowsteer::base
