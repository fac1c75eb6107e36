#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/motion_energy.hpp"
#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::servo {

// What an agent or a robot steers by: the navigation function on features from the flow
// (vision), the same function on features from exact geometry (geometric: perfect perception,
// simulation only) or Blumberg's motion energy (goal reaching only).
enum class SteeringModel { vision, geometric, motion_energy };
// The navigation function of CGF §6.3: towards goals, or after a leader.
enum class NavigationKind { goal_reaching, following };
// Where motion energy's "mass" and "floor" pixels come from: the renderer's object ids, or the
// flat-ground test on the flow, as a real camera would give them.
enum class MassSource { ids, ground };

std::string_view to_string(SteeringModel model);
std::string_view to_string(NavigationKind kind);
std::string_view to_string(MassSource source);
std::optional<SteeringModel> parse_steering_model(std::string_view name);
std::optional<NavigationKind> parse_navigation_kind(std::string_view name);
std::optional<MassSource> parse_mass_source(std::string_view name);
// "vision, geometric, motion_energy", for messages and help texts.
std::string steering_model_names();

// A controller's settings, as scenario files, robot launch files and demo scenes give them.
struct ControllerConfig {
  SteeringModel model = SteeringModel::vision;
  NavigationKind kind = NavigationKind::goal_reaching;
  double alpha = 1.0;
  double beta = 0.1;
  double gamma = 1.0;
  // Dark regions (MIG 2019): with delta > 0 the agent looks for them and avoids them; with 0 it
  // ignores them, as MIG's agents without dark-region awareness do.
  double delta = 0.0;
  double lambda = 1.0;
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;
  // With the renderer's flow, fit features with its depth (a camera has none).
  bool use_depth = true;
  // Added to the agent's own width as the width it keeps clear (CGF §6.2's agent width): room
  // for the path's curvature and the step, like a person's personal space.
  double clearance_margin_m = 0.5;
  // model motion_energy only.
  MotionEnergyOptions motion_energy;
  MassSource mass_from = MassSource::ids;
};

// How an agent sees: where its flow comes from and how it finds objects in it.
struct PerceptionConfig {
  FlowMethod flow = FlowMethod::synthetic;
  SegmentationMethod segmentation = SegmentationMethod::semantic;
};

// The navigation-function controller a config asks for, for an agent agent_width_m wide that
// prefers preferred_speed_mps (goal reaching's v*).
Controller make_controller(const ControllerConfig& config, double agent_width_m,
                           double preferred_speed_mps);

}  // namespace flowsteer::servo
