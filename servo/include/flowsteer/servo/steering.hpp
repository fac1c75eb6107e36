#pragma once

#include <numbers>
#include <optional>
#include <string>
#include <string_view>

#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/make_room.hpp"
#include "flowsteer/servo/motion_energy.hpp"
#include "flowsteer/servo/optical_flow.hpp"

namespace flowsteer::servo {

// What an agent or a robot steers by: the navigation function on features from the flow
// (vision), the same function on features from exact geometry (geometric: perfect perception,
// simulation only) or Blumberg's motion energy (goal reaching only).
enum class SteeringModel { vision, geometric, motion_energy };
// The navigation function of CGF §6.3: towards goals, or after a leader.
enum class NavigationKind { goal_reaching, following };
// The navigation function that models vision and geometric descend: the papers' as published
// (with docs/CONVENTIONS.md's sign corrections), kept exactly so that comparisons with the papers
// stay honest, or the project's own law (docs/NAVIGATION.md), the default; mig2019 is cgf2019 with
// MIG 2019's weights, dark regions included.
enum class NavigationLaw { flowsteer, cgf2019, mig2019 };
// One mechanism of the flowsteer law, switched off for an ablation (docs/NAVIGATION.md,
// "Ablation"): its braking and anticipation terms (weights 0), the passing
// convention (no side preferred), commitment to the side taken (no band, no hold at rest),
// static objects passed clear left out of the cost (kept in), giving way to fast crossers (never),
// the speed limit (none), the implicit gradient step (CGF Eq. 15's explicit step), the margin
// in proportion to speed (the full margin always), the static FOE checked against the closing
// speed (the fit's word taken), the turn checked against the cost it leads to (TurnCheck; the
// gradient's turn taken) and the acceleration checked against the contacts it leads to
// (StopCheck; the gradient's taken). none: the law as it is.
enum class LawMechanism {
  none,
  braking,
  anticipation,
  passing_convention,
  commitment,
  passed_clear,
  giving_way,
  speed_limit,
  implicit_step,
  proportional_margin,
  static_closing,
  turn_check,
  stop_check
};
// Where motion energy's "mass" and "floor" pixels come from: the renderer's object ids, or the
// flat-ground test on the flow, as a real camera would give them.
enum class MassSource { ids, ground };
// Where a simulated agent's features take objects' depths from, with the renderer's flow: its
// depth at every pixel, or only where objects stand on the ground, as a camera must
// (FeatureOptions::ground_mount). Numerical flow has no depth per pixel and always takes the
// ground's; `ground` measures what that costs the law apart from the flow's noise.
enum class DepthSource { renderer, ground };

std::string_view to_string(SteeringModel model);
std::string_view to_string(NavigationKind kind);
std::string_view to_string(MassSource source);
std::string_view to_string(DepthSource source);
std::string_view to_string(NavigationLaw law);
std::string_view to_string(LawMechanism mechanism);
std::optional<SteeringModel> parse_steering_model(std::string_view name);
std::optional<NavigationKind> parse_navigation_kind(std::string_view name);
std::optional<MassSource> parse_mass_source(std::string_view name);
std::optional<DepthSource> parse_depth_source(std::string_view name);
std::optional<NavigationLaw> parse_navigation_law(std::string_view name);
std::optional<LawMechanism> parse_law_mechanism(std::string_view name);
// "vision, geometric, motion_energy", for messages and help texts.
std::string steering_model_names();
// "flowsteer, cgf2019, mig2019".
std::string navigation_law_names();
// "none, braking, anticipation, ...".
std::string law_mechanism_names();
// "renderer, ground".
std::string depth_source_names();

// A controller's settings, as scenario files, robot launch files and demo scenes give them.
struct ControllerConfig {
  SteeringModel model = SteeringModel::vision;
  NavigationKind kind = NavigationKind::goal_reaching;
  NavigationLaw law = NavigationLaw::flowsteer;
  // The weights of the law's terms; each one not set is the law's own (navigation_weights).
  // Dark regions (MIG 2019): with delta > 0 the agent looks for them and avoids them; with 0 it
  // ignores them, as MIG's agents without dark-region awareness do. braking and anticipation: law
  // flowsteer only.
  std::optional<double> alpha;
  std::optional<double> beta;
  std::optional<double> gamma;
  std::optional<double> delta;
  std::optional<double> braking;
  std::optional<double> anticipation;
  // Law flowsteer: the mechanism switched off, for an ablation; it wins over a weight given.
  LawMechanism without = LawMechanism::none;
  // Law flowsteer, following: the gap kept behind the leader.
  double follow_gap_m = 2.0;
  double lambda = 1.0;
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;
  // Law flowsteer, goal reaching: the fastest it lets the agent go, as a multiple of its
  // preferred speed (>= 1). Without a limit, the clearance term's way to widen a gap by speeding
  // up took agents in circle_20 to 2.5 m/s for 1.3 (docs/NAVIGATION.md, "Control update").
  double max_speed_ratio = 1.1;
  // Use the depths the features carry: the renderer's per pixel with its flow; a camera's, those
  // of the ground where objects stand on it (FeatureOptions::ground_mount). False: MIG's
  // depth-free guess τ v_c / Z = 1/2 everywhere.
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
  DepthSource depth = DepthSource::renderer;
  // Remember what stood still and recall it once out of view (servo::ObstacleMemory;
  // docs/NAVIGATION.md, "Obstacle memory"). Used where it applies: the flowsteer law on flow
  // segmentation with a camera's depths; off by default: it holds walls and low boxes, but in the
  // suite's crowds agents touch each other more with it.
  bool obstacle_memory = false;
};

// A config's weights, the law's own where it sets none:
//   cgf2019  goal reaching α 1, β 0.1, γ 1, δ 0 (CGF Eq. 16); following α = β = γ = 1 (§8.2)
//   mig2019  α = β = γ = δ = 1 (MIG §7)
//   flowsteer α 1, β 1, γ 1, δ 0, braking 2, for both kinds; anticipation 1, goal reaching only
struct NavigationWeights {
  double alpha = 1.0;
  double beta = 1.0;
  double gamma = 1.0;
  double delta = 0.0;
  double braking = 0.0;
  double anticipation = 0.0;
};
NavigationWeights navigation_weights(const ControllerConfig& config);

// What an agent's percept holds of the static objects beside its way: its view's half-angle, and
// whether depths are exact at every pixel (the renderer's, with its flow). The flowsteer law's
// turn check judges the way onto the goal (TurnCheck) only where the percept holds what stands
// beside the agent within that way's clearance, and holds every object steadily: numerical
// flow's regions come and go from frame to frame, and a way judged clear in the frame one is
// missed turned agents into it (with dis_medium and flow segmentation, 28 more contacts over the
// suite at three sizes; with the obstacle memory, which keeps only what stands still, people
// converging on one goal touched 15 times against 6). Its stop check (StopCheck) predicts
// contacts from each object's ends, τ and FOE, which numerical flow gives with errors of tens of
// percent: it runs only where depths are exact (run with every percept, dis_medium and flow
// segmentation gave 55/84 clean over the suite at three sizes against 52/84, but lost a robot
// scene and an arrival case: no better than a resolution's chance; docs/NAVIGATION.md, "Control
// update").
struct StaticPercept {
  double view_half_angle_rad = 0.5 * std::numbers::pi;
  bool exact_depth = true;
};

// What the flowsteer law's agent that makes room at its last goal (MakeRoom) needs of a config:
// its width, and the depth guess and still-standing test of the law's terms.
MakeRoomOptions make_room_options(const ControllerConfig& config, double agent_width_m);

// The navigation-function controller a config asks for, for an agent agent_width_m wide that
// prefers preferred_speed_mps (goal reaching's v*), perceiving static objects as `statics` says.
Controller make_controller(const ControllerConfig& config, double agent_width_m,
                           double preferred_speed_mps, const StaticPercept& statics = {});

}  // namespace flowsteer::servo
