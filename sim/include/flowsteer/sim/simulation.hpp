#pragma once

#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/base/command.hpp"
#include "flowsteer/pipeline/run_recorder.hpp"
#include "flowsteer/sim/simulated_agent.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::base {
class OutputDir;
}

namespace flowsteer::sim {

// Steers one agent from outside the simulation in place of its own brain: a robot process in
// the loop (flowsteer sil). Called once per step on the simulation's thread, with that
// thread's renderer, before the world moves.
class AgentDriver {
 public:
  virtual ~AgentDriver() = default;
  // The agent's (a_c, ω) for this step, from the world as it is now.
  virtual base::Command step(const sim_camera::World& world, sim_camera::Renderer& renderer) = 0;
  // True once the driver can steer no more (its process ended): the run ends after this step.
  virtual bool finished() const = 0;
  // Once, when the run has ended: the driver ends what it runs and writes its own files into
  // out's staging folder (none without outputs), committed with the run's.
  virtual void finish(base::OutputDir* out) = 0;
};

struct SimOptions {
  std::filesystem::path out_dir = "flowsteer_out";
  std::optional<int> resolution;  // overrides every agent's camera: N×N pixels
  // Overrides every agent's camera noise (CameraSpec::noise_sigma_levels), in grey levels.
  std::optional<double> camera_noise_levels;
  std::optional<int> steps;  // stop after this many steps
  // Override every agent's perception (scenario key perception:).
  std::optional<servo::FlowMethod> flow;
  std::optional<servo::SegmentationMethod> segmentation;
  std::optional<servo::DepthSource> depth;
  std::optional<bool> obstacle_memory;  // every agent's PerceptionConfig::obstacle_memory
  bool video = false;  // an MP4 per agent of its view with the features drawn on it
  // An MCAP recording of the run (pipeline::RunRecorder; docs/RECORDINGS.md), written whether or
  // not the other outputs are.
  std::optional<pipeline::RecordingOptions> recording;
  bool progress_bar = false;  // a bar that redraws itself, for terminals
  bool write_outputs = true;  // false: only the returned result (tests, benchmarks)
  // Threads the agents are stepped on; 0: one per core. The result is the same for any number.
  int threads = 1;
  // How each thread's renderer submits its views (benchmarks compare them); the same result.
  sim_camera::ViewSubmission view_submission = sim_camera::ViewSubmission::automatic;
  // When set, agent driven_agent is steered by `driver` (which outlives the run), not by a brain.
  AgentDriver* driver = nullptr;
  std::size_t driven_agent = 0;
};

struct AgentResult {
  std::string name;
  bool reached_goal = false;
  double time_to_goal_s = -1.0;
  double path_length_m = 0.0;
  double min_clearance_m = 0.0;
  // Where the agent was (world frame, m) and when at its least clearance, the first time: the
  // top view marks it.
  Eigen::Vector2d closest_position_m = Eigen::Vector2d::Constant(std::nan(""));
  double closest_time_s = std::nan("");
  int collisions = 0;
  double final_distance_to_leader_m = -1.0;  // followers only
  // From its start through its goals in order to its last goal's circle, where it arrives; NaN
  // for followers.
  double straight_line_m = std::numeric_limits<double>::quiet_NaN();
  double preferred_speed_mps = std::numeric_limits<double>::quiet_NaN();
  // SteerSuite's effort over the steps the agent steered (see steersuite_effort).
  double active_time_s = 0.0;
  double kinetic_energy_sum = 0.0;
  // Time spent spinning (see kSpin): turning at its turn-rate limit while nearly at rest, in
  // spells longer than kSpin.spell_s.
  double spinning_s = 0.0;
  // The commanded turn rate ω (rad/s, positive right) at every step the agent was steering.
  std::vector<double> turn_rates;
  // Where the agent was (world frame, m) when it chose each of those turn rates.
  std::vector<Eigen::Vector2d> positions_m;
};

struct SimResult {
  std::string scenario;
  sim_camera::Arrival arrival = sim_camera::Arrival::stay;  // the world's rule on arrival
  int steps = 0;
  double duration_s = 0.0;
  std::vector<AgentResult> agents;
  std::vector<sim_camera::Collision> collisions;
  pipeline::StageTimes per_agent_step_ms;  // mean over agents and steps
  int threads = 1;                         // the agents were stepped on
  double world_steps_per_s = 0.0;          // wall-clock rate of the step loop
  cv::Mat topview;                         // the run from above, as topview.png (draw_topview)
};

// What SteerSuite's metrics collector sums over the steps an agent is active (steering towards
// its goals): the time T, and Σ_k ½‖v_k‖² with v_k its velocity over step k. The sum is per
// step, not an integral, as SteerSuite has it: it depends on the step (SteerSuite runs at 20 Hz,
// flowsteer's default step is 0.05 s). positions_m: where the agent was at the start of each
// active step and after the last one.
struct Effort {
  double active_time_s = 0.0;
  double kinetic_energy_sum = 0.0;  // m²/s², per unit mass
};
Effort steersuite_effort(std::span<const Eigen::Vector2d> positions_m, double step_s);

// SteerSuite's composite benchmark score 01 for one agent (SteerSuite, CompositeTechnique01;
// Singh, Kapadia, Faloutsos, Reinman, "SteerBench", CAVW 2009): 50 · collisions + T + Σ ½‖v‖².
// Collisions are the agent's contacts with other bodies, each counted once when it begins. Lower
// is better; a run's score is the mean over its agents.
double composite01(int collisions, const Effort& effort);

// What one run came to, over its agents.
struct RunSummary {
  int collisions = 0;
  int obstacle_collisions = 0;  // of those, an agent touching a static obstacle (a wall, a pillar)
  int goals_reached = 0;
  int agents = 0;
  int followers = 0;                 // agents following a leader: they have no goal to reach
  double mean_time_to_goal_s = 0.0;  // over the agents that reached their goal (NaN if none)
  double mean_path_length_m = 0.0;
  double min_clearance_m = 0.0;  // over all agents and steps
  // Path length over straight line (start through the goals), over the agents that reached
  // a goal away from their start (NaN if none).
  double mean_path_length_ratio = 0.0;
  // Time to goal over the straight line's time at the agent's preferred speed, over the same
  // agents (NaN if none): how much its start, its detours and its waits cost it.
  double mean_time_ratio = 0.0;
  double composite01 = 0.0;  // the mean of the agents' composite01 (NaN without agents)
  // Of all the agents' steps after their first, the share whose turn rate command differs from
  // the step before by kTurnFlipRadPerS or more: chatter, which a real drive cannot follow (NaN
  // without such steps).
  double turn_flip_ratio = 0.0;
  double spinning_s = 0.0;  // the agents' AgentResult::spinning_s, summed
  int agents_with_goal() const { return agents - followers; }
  // No collision, and every agent that has a goal reached it.
  bool clean() const { return collisions == 0 && goals_reached == agents_with_goal(); }
};
inline constexpr double kTurnFlipRadPerS = 1.0;
// An agent spins when it turns at 95 % of its controller's turn-rate limit or more while slower
// than 0.05 m/s for longer than 2 s: it has no way it likes and turns on the spot looking for one.
inline constexpr struct {
  double limit_share = 0.95;
  double speed_mps = 0.05;
  double spell_s = 2.0;
} kSpin;
RunSummary summarize(const SimResult& result);

// Switches `mechanism` off in every agent's controller: an ablation (`--without`). Throws
// base::ConfigError naming --without for an agent whose law is not flowsteer, which has none.
void switch_off(sim_camera::WorldSpec& world, servo::LawMechanism mechanism);

// Runs the world to its end: each agent renders its view, the servo core turns it into a
// command, the world moves. Writes trajectories.csv, costs.csv, collisions.csv, topview.png,
// summary.json and report.html (report::write_run_report, from those files) (and agent_N.mp4
// with --video) into out_dir, and the recording where asked, each file complete or not at all.
// Progress goes to `log`. Throws std::runtime_error when no renderer can be created or out_dir is
// not writable.
SimResult run_simulation(const sim_camera::WorldSpec& world, const SimOptions& options,
                         std::ostream& log);

}  // namespace flowsteer::sim
