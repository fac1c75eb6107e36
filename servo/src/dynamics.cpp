#include "flowsteer/servo/dynamics.hpp"

namespace flowsteer::servo {

FeatureRate goal_x_rate(double goal_x, double tau_goal_s) {
  return {goal_x / tau_goal_s, 0.0, -(goal_x * goal_x + 1.0)};
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

FeatureRate flow_x_rate(double x, double flow_u, double tau_s, double depth_m, double speed_mps) {
  return {2.0 * flow_u / tau_s, x / depth_m, -(speed_mps / depth_m + 2.0 * x * flow_u)};
}

FeatureRate relative_vz_rate(double relative_vx_mps) {
  return {0.0, -1.0, relative_vx_mps};
}

}  // namespace flowsteer::servo
