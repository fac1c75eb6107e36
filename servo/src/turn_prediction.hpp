#pragma once

// What the agent would see after turning in place: the percept a candidate turn rate leads to
// within one control period, which Controller's turn check (control.hpp, TurnCheck) weighs.

#include <vector>

#include <Eigen/Core>

#include "flowsteer/servo/control.hpp"

namespace flowsteer::servo::detail {

// A point or direction in the agent's frame (x right, z forward) seen from the frame turned right
// by turn_rad: at bearing β − turn_rad.
Eigen::Vector2d seen_after_turn(const Eigen::Vector2d& v, double turn_rad);

// `now` as seen after the camera turns by turn_rad (positive right) about its y axis: every
// object's image columns and depths rotated with it, its FOE and τ from its relative velocity
// (contact_time.hpp) with its motion over the ground kept, the goal's bearing turned. The
// translation over the period is left out: it is the same for every turn compared. `objects`
// holds the turned objects (its storage is reused); `out` points into it.
void percept_after_turn(const Percept& now, const AgentState& agent, double turn_rad,
                        const DepthGuess& depth, double static_closing_ratio,
                        std::vector<ObjectFeatures>& objects, Percept& out);

// Whether the agent can turn onto its goal's bearing at turn_rate (rad/s, positive right; the
// goal's side) at its present speed and walk straight on to the goal, keeping further than
// clearance_m (centre to object) from every object in `now`, as it is now already: its
// extended outline (contact_time.hpp), moving over the ground during the turn as its flow shows
// (relative velocity plus the agent's own; standing where its flow gives none), standing after it.
// False without the goal's bearing and distance.
bool way_onto_goal_is_clear(const Percept& now, const AgentState& agent, double turn_rate,
                            const DepthGuess& depth, double static_closing_ratio,
                            double clearance_m);

}  // namespace flowsteer::servo::detail
