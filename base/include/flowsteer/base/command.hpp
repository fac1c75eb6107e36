#pragma once

namespace flowsteer::base {

// What the control law outputs: forward acceleration a_c and turn rate ω about the camera's y
// axis, which points down, so positive ω turns the agent right. A drive turns this into
// ω_z = −ω (docs/CONVENTIONS.md).
struct Command {
  double accel_mps2 = 0.0;
  double turn_rate = 0.0;
};

// ω_z = −ω_cy: the body's yaw rate (REP 103: about z, which points up, positive left) of a turn
// rate ω about the camera's y axis, which points down, and back (docs/CONVENTIONS.md). The
// project's one conversion point: the drives' wheel speeds, odometry and the recordings' cmd_vel
// and odom go through it; everything else speaks ω.
constexpr double yaw_rate_of(double turn_rate) {
  return -turn_rate;
}
constexpr double turn_rate_of(double yaw_rate) {
  return -yaw_rate;
}

}  // namespace flowsteer::base
