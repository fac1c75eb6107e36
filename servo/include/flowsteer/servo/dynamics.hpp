#pragma once

namespace flowsteer::servo {

// How a visual feature s moves when the agent moves: ṡ = drift + per_accel·a_c + per_turn·ω,
// with a_c the forward acceleration and ω the turn rate about the camera's y axis (positive
// turns right). These are the interactions the control terms differentiate; the signs are the
// ones docs/CONVENTIONS.md checked numerically, and tests/servo/dynamics_test.cpp pins them against
// a two-body simulation.
struct FeatureRate {
  double drift = 0.0;
  double per_accel = 0.0;
  double per_turn = 0.0;

  double at(double accel_mps2, double turn_rate) const {
    return drift + per_accel * accel_mps2 + per_turn * turn_rate;
  }
};

// Goal point t_x with time to reach it tau_goal_s (CGF Eq. 8).
FeatureRate goal_x_rate(double goal_x, double tau_goal_s);

// Bearing θ of a goal goal_distance_m away, positive to the right (θ = atan t_x, so that θ̇ =
// ṫ_x / (1 + t_x²) from CGF Eq. 8): θ̇ = v_c sin θ / d − ω. Unlike t_x it stays bounded, and
// meaningful, for a goal beside or behind the agent.
FeatureRate goal_bearing_rate(double bearing_rad, double goal_distance_m, double speed_mps);
// Centre g_x of an object whose FOE is f_x and TTC tau_s: ġ = (g − f)/τ − (1 + g²) ω.
FeatureRate centre_x_rate(double centre_x, double foe_x, double tau_s);

// FOE f_x of an object with relative velocity component v_z (m/s, < 0 when approaching) seen
// by an agent at speed_mps: ḟ = −ω (1 + f² + v_c/v_z) + (f / v_z) a_c. CGF Eq. 4 as printed
// has two sign flips.
FeatureRate foe_x_rate(double foe_x, double speed_mps, double relative_vz_mps);

// Separation Δx = g_x − f_x (CGF Eq. 10), with tau_over_depth = τ/Z in s/m:
// Δẋ = (g − f)/τ + (f² − g² − (τ/Z) v_c) ω + (τ/Z) f a_c.
FeatureRate separation_rate(double centre_x, double foe_x, double tau_s, double tau_over_depth,
                            double speed_mps);

// Inverse time to collision 1/τ = −v_z / Z of an object point at x = centre_x whose object has
// FOE foe_x, TTC tau_s and tau_over_depth = τ/Z: d(1/τ)/dt = 1/τ² + (τ/Z)/τ · a_c − u ω, with
// u = (x − f)/τ the point's derotated flow (v̇_z = −a_c + v_x ω, Ż = v_z + X ω). The drift
// leaves out the object's own acceleration.
FeatureRate inverse_ttc_rate(double centre_x, double foe_x, double tau_s, double tau_over_depth);
// Derotated horizontal flow u of a point at x, depth Z and TTC τ (CGF Eq. 6, with the
// second-order term −2 x u ω the printed equation leaves out):
// u̇ = 2u/τ − (v_c/Z + 2 x u) ω + (x/Z) a_c.
FeatureRate flow_x_rate(double x, double flow_u, double tau_s, double depth_m, double speed_mps);

// Relative velocity v_z of an object along the optical axis (CGF Eq. 13's feature), with
// v_x its lateral component: v̇_z = v_x ω − a_c. v̇_x = −(v_z + v_c) ω is not needed here.
FeatureRate relative_vz_rate(double relative_vx_mps);
// The gap error e = v_z + (Z − G)/T of a leader at depth Z and image x, for a gap G kept with
// time constant T: ė = v̇_z + Ż/T with Ż = v_z + x Z ω, so ∂ė/∂a_c = −1 and
// ∂ė/∂ω = v_x + x Z / T. The drift leaves out the leader's own acceleration.
FeatureRate gap_error_rate(double relative_vx_mps, double relative_vz_mps, double image_x,
                           double depth_m, double gap_time_s);

}  // namespace flowsteer::servo
