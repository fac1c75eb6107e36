#include "flowsteer/servo/dynamics.hpp"

#include <cmath>

namespace flowsteer::servo {

FeatureRate goal_x_rate(double goal_x, double tau_goal_s) {
  return {goal_x / tau_goal_s, 0.0, -(goal_x * goal_x + 1.0)};
}

FeatureRate goal_bearing_rate(double bearing_rad, double goal_distance_m, double speed_mps) {
  return {speed_mps * std::sin(bearing_rad) / goal_distance_m, 0.0, -1.0};
}

FeatureRate centre_x_rate(double centre_x, double foe_x, double tau_s) {
  return {(centre_x - foe_x) / tau_s, 0.0, -(1.0 + centre_x * centre_x)};
}

FeatureRate foe_x_rate(double foe_x, double speed_mps, double relative_vz_mps) {
  return {0.0, foe_x / relative_vz_mps, -(1.0 + foe_x * foe_x + speed_mps / relative_vz_mps)};
}

FeatureRate separation_rate(double centre_x, double foe_x, double tau_s, double tau_over_depth,
                            double speed_mps) {
  return {(centre_x - foe_x) / tau_s, tau_over_depth * foe_x,
          foe_x * foe_x - centre_x * centre_x - tau_over_depth * speed_mps};
}

FeatureRate inverse_ttc_rate(double centre_x, double foe_x, double tau_s, double tau_over_depth) {
  return {1.0 / (tau_s * tau_s), tau_over_depth / tau_s, -(centre_x - foe_x) / tau_s};
}

FeatureRate flow_x_rate(double x, double flow_u, double tau_s, double depth_m, double speed_mps) {
  return {2.0 * flow_u / tau_s, x / depth_m, -(speed_mps / depth_m + 2.0 * x * flow_u)};
}

FeatureRate relative_vz_rate(double relative_vx_mps) {
  return {0.0, -1.0, relative_vx_mps};
}

FeatureRate gap_error_rate(double relative_vx_mps, double relative_vz_mps, double image_x,
                           double depth_m, double gap_time_s) {
  return {relative_vz_mps / gap_time_s, -1.0, relative_vx_mps + image_x * depth_m / gap_time_s};
}

}  // namespace flowsteer::servo
