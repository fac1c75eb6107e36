#pragma once

// A two-body kinematic simulation in the plane, independent of the servo code: an agent (a
// unicycle driven by forward acceleration a_c and turn rate ω about the camera's y axis, so
// yaw rate −ω) and a point moving at constant velocity. It computes the visual features from
// geometry alone, so that finite differences of them pin the feature dynamics.

#include <cmath>

#include <Eigen/Core>

namespace flowsteer::test {

struct TwoBody {
  Eigen::Vector2d agent_position{0.0, 0.0};
  double agent_yaw = 0.0;  // counter-clockwise, world frame (x forward at yaw 0, y left)
  double agent_speed = 1.0;
  Eigen::Vector2d point{5.0, -0.5};
  Eigen::Vector2d point_velocity{0.0, 0.0};

  Eigen::Vector2d forward() const { return {std::cos(agent_yaw), std::sin(agent_yaw)}; }
  Eigen::Vector2d right() const { return {std::sin(agent_yaw), -std::cos(agent_yaw)}; }

  // Advances by dt with constant controls (explicit Euler; dt is tiny in the tests).
  TwoBody advanced(double dt, double accel, double turn_rate) const {
    TwoBody next = *this;
    next.agent_position += dt * agent_speed * forward();
    next.agent_yaw -= dt * turn_rate;
    next.agent_speed += dt * accel;
    next.point += dt * point_velocity;
    return next;
  }

  double depth() const { return (point - agent_position).dot(forward()); }
  // Normalised image x of the point.
  double image_x() const { return (point - agent_position).dot(right()) / depth(); }
  // Relative velocity (point minus agent) in camera axes: x right, z forward.
  double relative_vx() const { return (point_velocity - agent_speed * forward()).dot(right()); }
  double relative_vz() const { return (point_velocity - agent_speed * forward()).dot(forward()); }
  double foe_x() const { return relative_vx() / relative_vz(); }
  double ttc() const { return -depth() / relative_vz(); }
  // Derotated horizontal flow of the point (CGF Eq. 2).
  double flow_x() const { return (relative_vx() - image_x() * relative_vz()) / depth(); }
};

// d/dt of feature(state) under controls (a_c, ω), by a forward difference.
template <typename Feature>
double rate_of(const TwoBody& state, double accel, double turn_rate, Feature feature) {
  constexpr double dt = 1e-7;
  return (feature(state.advanced(dt, accel, turn_rate)) - feature(state)) / dt;
}

}  // namespace flowsteer::test
