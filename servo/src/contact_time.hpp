#pragma once

// When an object will touch the agent if both go straight on, from the object's visual features:
// its outline on the ground and the relative velocity its flow shows. The anticipation term
// (anticipation_term.cpp) weighs what will touch the agent by this; the clearance term
// (clearance_terms.cpp) leaves out what will not come near; the controller's stop check
// (control.hpp, StopCheck) brakes for what it could not otherwise stop for.

#include <array>
#include <limits>
#include <optional>

#include <Eigen/Core>

#include "flowsteer/servo/control.hpp"

namespace flowsteer::servo::detail {

// When an object moving at relative velocity V first comes within R of the agent (at the
// origin), and the unit normal n from the agent to where it touches.
struct Contact {
  double time_s = std::numeric_limits<double>::infinity();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
};

// The segment [a, b] moving at V (agent frame: x right, z forward, m): its ends as points, and
// its inside, whose line comes within R when m·(a + V t) = R, m its unit normal towards the line,
// if the foot of the perpendicular from the agent then lies between the ends. Keeps `first` if
// it is earlier.
void segment_contact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& v,
                     double radius_m, Contact& first);

// The point of the segment [a, b] nearest the agent, and its distance.
Eigen::Vector2d nearest_on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b);
double distance_to_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b);

// An object on the ground in the agent's frame (x right, z forward, m): a polyline through its
// left end, its nearest point where the features have one between the ends, and its right end.
struct Outline {
  std::array<Eigen::Vector2d, 3> points;
  int count = 0;
};

// segment_contact over each of the outline's segments.
void outline_contact(const Outline& outline, const Eigen::Vector2d& v, double radius_m,
                     Contact& first);
double distance_to_outline(const Outline& outline);
// The distance from the point `from` (agent frame) to the outline, and from the segment [from, to].
double distance_to_outline(const Outline& outline, const Eigen::Vector2d& from);
double distance_to_outline(const Outline& outline, const Eigen::Vector2d& from,
                           const Eigen::Vector2d& to);

// When the outline, moving over the ground at `ground_velocity` (agent frame, m/s), first comes
// within R of an agent that brakes at decel_mps2 from speed_mps to a stop along its course: the
// gap checked every step_s up to until_s; infinity if it stays wider until then (or step_s is not
// positive).
double contact_while_braking_s(const Outline& outline, const Eigen::Vector2d& ground_velocity,
                               double speed_mps, double decel_mps2, double radius_m, double step_s,
                               double until_s);

// How far along the agent's course (its z axis) the band that the outline sweeps, moving over
// the ground at velocity v (agent frame), begins: the nearest point where a point of the outline
// crosses the course, less half_width_m measured along the course. Negative where the agent is
// on the band already; infinity for v along the course.
double distance_to_path_m(const Outline& outline, const Eigen::Vector2d& v, double half_width_m);

// The object's velocity relative to the agent (x right, z forward, m/s) from its flow: V_z =
// −Z/τ and V_x = f V_z at the depth the fit used (CGF Eq. 2–3), V_z = −v_c for an object that
// stands still (stands_still); for lateral motion, the derotated flow u = V_x / Z gives V_x =
// mean(u) / mean(1/Z). Nothing for an object without a usable fit.
std::optional<Eigen::Vector2d> relative_velocity(const ObjectFeatures& object,
                                                 const AgentState& agent, const DepthGuess& depth,
                                                 double static_closing_ratio);

// The object's outline, (x Z, Z) at each point's depth; without depths, its two ends at the depth
// its τ gives (depth_scale).
void outline_of(const ObjectFeatures& object, const AgentState& agent, const DepthGuess& depth,
                Outline& outline);

// What going straight on leads to, for the agent and a visible object: the object's outline, its
// velocity relative to the agent, R (radius_m, or 0.99 of the distance now where the object is
// nearer already: the contact is then its coming nearer still, R holding a margin) and the
// contact. Nothing for an object out of view or without a usable fit.
struct StraightOn {
  Outline outline;
  Eigen::Vector2d velocity;
  double radius_m;
  Contact contact;
};
std::optional<StraightOn> straight_on(const ObjectFeatures& object, const AgentState& agent,
                                      const DepthGuess& depth, double static_closing_ratio,
                                      double radius_m);

// outline_of, with an end the image cuts taken to go on along its segment's line (a wall beside
// the agent, of which only the part ahead is in view) further than the agent stops from.
void extended_outline_of(const ObjectFeatures& object, const AgentState& agent,
                         const DepthGuess& depth, Outline& outline);

// How far the agent can walk straight on before it comes within R of the object's extended
// outline, taken as standing still; infinity if it never does. Within R
// already, the distance until it comes nearer still (R taken at 0.99 of the distance now).
double course_room_m(const ObjectFeatures& object, const AgentState& agent, const DepthGuess& depth,
                     double radius_m);

}  // namespace flowsteer::servo::detail
