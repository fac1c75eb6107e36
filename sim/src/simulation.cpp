#include "flowsteer/sim/simulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <span>
#include <sstream>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/pipeline/overlay.hpp"
#include "flowsteer/recording/foxglove_messages.hpp"
#include "flowsteer/report/run_report.hpp"
#include "flowsteer/sim/outputs.hpp"
#include "flowsteer/sim/simulated_agent.hpp"

namespace flowsteer::sim {

namespace {

// Everything one agent keeps from step to step.
struct AgentLoop {
  std::unique_ptr<SimulatedAgent> agent;  // none for the agent an AgentDriver steers
  AgentResult result;
  Eigen::Vector2d last_position;
  std::unique_ptr<cv::VideoWriter> video;
  // This step's: whether it steered, what its stages took and, where its view was rendered with
  // others', its share of their render.
  bool steered = false;
  int spin_steps = 0;  // of the spell of spinning (kSpin) that goes on, if one does
  // Steps it steered on its way (before it arrived, or all of a leader's): SteerSuite's effort.
  int active_steps = 0;
  pipeline::StageTimes times;
  double render_ms = 0.0;
};

class Progress {
 public:
  Progress(std::ostream& log, bool bar, int total) : log_(log), bar_(bar), total_(total) {}
  void update(int step, double sim_time_s) {
    const int percent = total_ > 0 ? 100 * step / total_ : 100;
    if (bar_) {
      const int filled = percent * 30 / 100;
      log_ << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
           << std::string(static_cast<std::size_t>(30 - filled), ' ') << "] " << std::setw(3)
           << percent << "%  t = " << std::fixed << std::setprecision(1) << sim_time_s << " s"
           << std::flush;
    } else if (percent >= next_percent_) {
      log_ << "step " << step << "/" << total_ << " (" << percent << "%), t = " << std::fixed
           << std::setprecision(1) << sim_time_s << " s\n";
      next_percent_ = percent + 10;
    }
  }
  void finish() {
    if (bar_) {
      log_ << "\n";
    }
  }

 private:
  std::ostream& log_;
  bool bar_;
  int total_;
  int next_percent_ = 0;
};

// The cost terms of every agent step, for costs.csv: one column per term name, in the order the
// names first appear. Rows and cells are stored flat and reserved up front. An agent's terms come
// in the same order every step, so each (agent, term index) keeps its column and the names are
// searched only when that column's name differs.
class CostLog {
 public:
  CostLog(std::size_t agents, std::size_t steps) : columns_(agents) {
    rows_.reserve(agents * steps);
  }

  void add(double t, std::size_t agent, const servo::ControlOutput& output) {
    if (cells_.capacity() == 0) {
      cells_.reserve(rows_.capacity() * output.terms.size());
    }
    rows_.push_back({t, agent, output.cost, cells_.size()});
    for (std::size_t k = 0; k < output.terms.size(); ++k) {
      const servo::TermEvaluation& term = output.terms[k];
      cells_.push_back({column(agent, k, term.name), term.gradient.cost});
    }
  }

  // t, agent, the terms (empty where an agent's controller has no such term), total.
  base::CsvTable table() const {
    std::vector<std::string> header = {"t", "agent"};
    header.insert(header.end(), names_.begin(), names_.end());
    header.push_back("total");
    base::CsvTable csv(std::move(header));
    for (std::size_t r = 0; r < rows_.size(); ++r) {
      const Row& row = rows_[r];
      const std::size_t end = r + 1 < rows_.size() ? rows_[r + 1].first_cell : cells_.size();
      std::vector<double> values(names_.size() + 3, std::nan(""));
      values.front() = row.t;
      values[1] = static_cast<double>(row.agent);
      values.back() = row.total;
      for (std::size_t c = row.first_cell; c < end; ++c) {
        values[2 + cells_[c].column] = cells_[c].cost;
      }
      csv.add(std::move(values));
    }
    return csv;
  }

 private:
  std::size_t column(std::size_t agent, std::size_t term, const std::string& name) {
    std::vector<std::size_t>& columns = columns_[agent];
    if (term < columns.size() && names_[columns[term]] == name) {
      return columns[term];
    }
    const auto found =
        static_cast<std::size_t>(std::find(names_.begin(), names_.end(), name) - names_.begin());
    if (found == names_.size()) {
      names_.push_back(name);
    }
    columns.resize(std::max(columns.size(), term + 1));
    columns[term] = found;
    return found;
  }

  struct Row {
    double t;
    std::size_t agent;
    double total;
    std::size_t first_cell;  // its cells run to the next row's first
  };
  struct Cell {
    std::size_t column;
    double cost;
  };
  std::vector<std::string> names_;
  std::vector<std::vector<std::size_t>> columns_;  // per agent, by term index
  std::vector<Row> rows_;
  std::vector<Cell> cells_;
};

// t, agent, x, y, heading, v, a_c, omega, clearance_m, min_ttc_s: a row of trajectories.csv.
using TrajectoryRow = std::array<double, 10>;

void write_trajectories(const std::filesystem::path& path, const std::vector<TrajectoryRow>& rows) {
  // Exact: a recording's poses and other tools compare to these bit for bit.
  base::CsvTable csv(
      {"t", "agent", "x", "y", "heading", "v", "a_c", "omega", "clearance_m", "min_ttc_s"},
      base::Digits::exact);
  for (const TrajectoryRow& row : rows) {
    csv.add({row.begin(), row.end()});
  }
  csv.write(path);
}

// collisions.csv: each contact as it began (t, agent, with, x, y; "with" as World names it).
void write_collisions(const std::filesystem::path& path,
                      const std::vector<sim_camera::Collision>& collisions) {
  base::CsvTable csv({"with", "t", "agent", "x", "y"});
  for (const sim_camera::Collision& c : collisions) {
    csv.add({c.with}, {c.time_s, static_cast<double>(c.agent), c.position_m.x(), c.position_m.y()});
  }
  csv.write(path);
}

// From the agent's start through its goals in order to its last goal's circle, where it
// arrives; NaN for a follower, which has no goal of its own.
double straight_line_m(const sim_camera::AgentSpec& agent) {
  if (agent.leader || agent.goals.empty()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double length_m = 0.0;
  Eigen::Vector2d from = agent.start_m;
  for (const Eigen::Vector2d& goal : agent.goals) {
    length_m += (goal - from).norm();
    from = goal;
  }
  return std::max(0.0, length_m - agent.goal_radius_m);
}

// One run of a world: the world, its renderer, one loop per agent and what the run records for
// its result and its files. Everything that grows per step is reserved up front, so a step
// allocates nothing of its own.
class SimulationRun {
 public:
  SimulationRun(const sim_camera::WorldSpec& spec, const SimOptions& options)
      : spec_(checked(spec, options)),
        options_(options),
        world_(spec_),
        arena_(threads(options)),
        renderers_([submission = options.view_submission] {
          return sim_camera::Renderer::create(submission);
        }),
        total_steps_(total_steps(spec_, options)),
        paths_(spec_.agents.size()),
        commands_(spec_.agents.size()),
        costs_(spec_.agents.size(), static_cast<std::size_t>(total_steps_)) {
    // The calling thread's renderer now, the workers' at their first step: a machine without
    // OpenGL fails here, before the output folder is touched.
    renderers_.local();
    if (options.write_outputs) {
      out_.emplace(options.out_dir);
    }
    const auto steps = static_cast<std::size_t>(total_steps_);
    const bool recorded_images = options.recording && options.recording->images_every > 0;
    for (std::size_t i = 0; i < spec_.agents.size(); ++i) {
      const auto reads = options.video || recorded_images ? sim_camera::RenderChannels::all
                                                          : sim_camera::RenderChannels::geometry;
      AgentLoop loop;
      if (!driven(i)) {
        loop.agent = std::make_unique<SimulatedAgent>(world_, i, reads);
        if (spec_.arrival == sim_camera::Arrival::stay && !spec_.agents[i].leader &&
            loop.agent->brain().makes_room()) {
          world_.keep_steering_after_arrival(i);
        }
      }
      loop.last_position = spec_.agents[i].start_m;
      loop.result.name = spec_.agents[i].name;
      // note_clearance takes each state's, from the first step's on.
      loop.result.min_clearance_m = std::numeric_limits<double>::infinity();
      loop.result.turn_rates.reserve(steps);
      paths_[i].reserve(steps + 1);
      loops_.push_back(std::move(loop));
    }
    trajectories_.reserve(steps * loops_.size());
    if (options.recording) {
      start_recording(*options.recording);
    }
    batch_agents_.reserve(loops_.size());
    batch_views_.reserve(loops_.size());
    batch_out_.reserve(loops_.size());
  }

  int total_steps() const { return total_steps_; }
  const sim_camera::World& world() const { return world_; }

  // One control step: every agent that still steers renders, thinks and commands, in parallel
  // (each sees the same world state and keeps its own brain, so the threads change nothing of
  // the result); then, in agent order, what the step records; then the world moves.
  void step() {
    gather_views();
    arena_.execute([this] {
      render_views();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, loops_.size()),
                        [this](const tbb::blocked_range<std::size_t>& agents) {
                          sim_camera::Renderer& renderer = *renderers_.local();
                          for (std::size_t i = agents.begin(); i != agents.end(); ++i) {
                            think(i, renderer);
                          }
                        });
    });
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      commands_[i] = {0.0, 0.0};
      if (loops_[i].steered) {
        record(i);
      }
    }
    if (options_.driver != nullptr) {
      drive(options_.driven_agent);
    }
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      AgentLoop& loop = loops_[i];
      const sim_camera::AgentState& s = world_.agents()[i];
      const double clearance_m = world_.clearance(i);
      note_clearance(loop.result, clearance_m, s.position_m);
      const double ttc_s = loop.steered && loop.agent ? loop.agent->brain().min_ttc_s()
                                                      : std::numeric_limits<double>::quiet_NaN();
      trajectories_.push_back({world_.time_s(), static_cast<double>(i), s.position_m.x(),
                               s.position_m.y(), s.yaw_rad, s.speed_mps, commands_[i].accel_mps2,
                               commands_[i].turn_rate, clearance_m, ttc_s});
      paths_[i].push_back(s.position_m);
    }
    const double t_s = world_.time_s();
    record_world();
    world_.step(commands_);
    record_commands(t_s);
    account_motion();
  }

  SimResult result(int steps) {
    SimResult result;
    result.scenario = spec_.name;
    result.arrival = spec_.arrival;
    result.steps = steps;
    result.duration_s = world_.time_s();
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      paths_[i].push_back(world_.agents()[i].position_m);  // where the last step left it
      note_clearance(loops_[i].result, world_.clearance(i), world_.agents()[i].position_m);
      result.agents.push_back(agent_result(i));
    }
    result.collisions = collisions_;
    result.threads = arena_.max_concurrency();
    if (agent_steps_ > 0) {
      const double n = static_cast<double>(agent_steps_);
      result.per_agent_step_ms = {sum_.render / n,   sum_.flow / n,    sum_.segment / n,
                                  sum_.features / n, sum_.control / n, sum_.total / n};
    }
    result.topview = draw_topview(world_, paths_, result.collisions, result.agents);
    return result;
  }

  // trajectories.csv, costs.csv, collisions.csv, the videos, topview.png, summary.json and the
  // page read from them (report.html), committed together with the driver's files; nothing
  // without an output folder.
  void write(const SimResult& result) {
    if (options_.driver != nullptr) {
      options_.driver->finish(out_ ? &*out_ : nullptr);
    }
    if (recorder_) {
      recorder_->finish({{"scenario", spec_.name},
                         {"step_s", base::json_number(spec_.step_s)},
                         {"arrival", std::string(to_string(spec_.arrival))}});
    }
    if (!out_) {
      return;
    }
    write_trajectories(out_->staging_path("trajectories.csv"), trajectories_);
    write_collisions(out_->staging_path("collisions.csv"), result.collisions);
    costs_.table().write(out_->staging_path("costs.csv"));
    for (AgentLoop& loop : loops_) {
      if (loop.video) {
        loop.video->release();
      }
    }
    write_image(out_->staging_path("topview.png"), result.topview);
    write_summary_json(out_->staging_path("summary.json"), result);
    // The page reads the files just written: anything it cannot read is this run's failure.
    const std::vector<std::string> problems = report::write_run_report(out_->staging_dir());
    if (!problems.empty()) {
      throw std::runtime_error("the run's page could not read its own " + problems.front());
    }
    out_->commit();
  }

 private:
  static int total_steps(const sim_camera::WorldSpec& spec, const SimOptions& options) {
    const int max_steps = static_cast<int>(std::ceil(spec.duration_s / spec.step_s - 1e-9));
    return std::max(0, options.steps ? std::min(*options.steps, max_steps) : max_steps);
  }

  static const sim_camera::WorldSpec& checked(const sim_camera::WorldSpec& spec,
                                              const SimOptions& options) {
    if (options.driver != nullptr && options.driven_agent >= spec.agents.size()) {
      throw std::invalid_argument("simulation: the driven agent " +
                                  std::to_string(options.driven_agent) + " is not in " + spec.name +
                                  ", which has " + std::to_string(spec.agents.size()) + " agents");
    }
    return spec;
  }

  static int threads(const SimOptions& options) {
    if (options.threads < 0) {
      throw std::invalid_argument("simulation: threads must be >= 0 (0: every core), got " +
                                  std::to_string(options.threads));
    }
    return options.threads == 0 ? tbb::task_arena::automatic : options.threads;
  }

  bool driven(std::size_t i) const {
    return options_.driver != nullptr && options_.driven_agent == i;
  }

  // Which agents steer this step, and the views of those whose cameras draw the geometry
  // channels alone: these are rendered together.
  void gather_views() {
    batch_agents_.clear();
    batch_views_.clear();
    batch_out_.clear();
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      AgentLoop& loop = loops_[i];
      loop.steered = !driven(i) && world_.present(i) &&
                     (!world_.agents()[i].reached_goal || spec_.agents[i].leader ||
                      world_.steers_after_arrival(i));
      if (loop.steered && loop.agent->renders_geometry_only()) {
        batch_agents_.push_back(i);
        batch_views_.push_back(loop.agent->view());
        batch_out_.push_back(&loop.agent->rendered_view());
      }
    }
  }

  // The gathered views in as many runs as the arena has threads, each rendered by the thread
  // that takes it in one submission (Renderer::render_geometry).
  void render_views() {
    const std::size_t count = batch_views_.size();
    if (count == 0) {
      return;
    }
    const auto threads = static_cast<std::size_t>(arena_.max_concurrency());
    const std::size_t per_run = (count + threads - 1) / threads;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, per_run),
        [this](const tbb::blocked_range<std::size_t>& run) {
          const base::Stopwatch render;
          renderers_.local()->render_geometry(
              world_, std::span(batch_views_).subspan(run.begin(), run.size()),
              std::span(batch_out_).subspan(run.begin(), run.size()));
          const double per_view_ms = render.elapsed_ms() / static_cast<double>(run.size());
          for (std::size_t k = run.begin(); k != run.end(); ++k) {
            loops_[batch_agents_[k]].render_ms = per_view_ms;
          }
        },
        tbb::simple_partitioner());
  }

  // Agent i's perception and control, when it steers; touches nothing but its own loop.
  void think(std::size_t i, sim_camera::Renderer& renderer) {
    AgentLoop& loop = loops_[i];
    if (!loop.steered) {
      return;
    }
    if (loop.agent->renders_geometry_only()) {
      loop.agent->think(loop.render_ms, loop.times);
    } else {
      loop.agent->step(renderer, loop.times);
    }
  }

  void record(std::size_t i) {
    AgentLoop& loop = loops_[i];
    const servo::ControlOutput& output = loop.agent->brain().output();
    commands_[i] = output.command;
    loop.result.turn_rates.push_back(output.command.turn_rate);
    loop.active_steps += !world_.agents()[i].reached_goal || spec_.agents[i].leader ? 1 : 0;
    account_spin(i, output.command.turn_rate);
    sum_ += loop.times;
    ++agent_steps_;
    costs_.add(world_.time_s(), i, output);
    if (recorder_) {
      recorder_->percept(i, recording::nanoseconds(world_.time_s()), loop.agent->brain(),
                         loop.agent->frame().image);
    }
    if (options_.video && out_) {
      if (!loop.video) {
        loop.video = pipeline::open_video(out_->staging_path("agent_" + std::to_string(i) + ".mp4"),
                                          pipeline::overlay_size(loop.agent->frame().image.size()),
                                          1.0 / spec_.step_s);
      }
      loop.video->write(draw_overlay(*loop.agent));
    }
  }

  // The recording's agents, each under its name as ROS writes names, and their cameras' mounts.
  void start_recording(const pipeline::RecordingOptions& options) {
    recorder_.emplace(options, "simulation", "world");
    std::vector<std::string> names;
    for (const sim_camera::AgentSpec& a : spec_.agents) {
      names.push_back(a.name);
    }
    const std::vector<std::string> namespaces = pipeline::RunRecorder::ros_names(names);
    for (std::size_t i = 0; i < spec_.agents.size(); ++i) {
      const sim_camera::CameraSpec& c = spec_.agents[i].camera;
      recorder_->add_agent(
          namespaces[i],
          base::CameraIntrinsics::from_horizontal_fov(c.width_px, c.height_px, c.hfov_rad),
          base::CameraMount{c.height_m, c.pitch_rad});
    }
    recorder_->write_mounts(0);
    // The static world on a topic of its own: a viewer that seeks shows each topic's last message.
    const std::uint16_t static_channel =
        recorder_->json_channel("/world/static", recording::foxglove::kSceneUpdate,
                                recording::foxglove::scene_update_schema());
    recorder_->write_json(static_channel, 0,
                          recording::foxglove::scene_update_json(0, static_scene_entities(world_)));
    world_channel_ = recorder_->json_channel("/world", recording::foxglove::kSceneUpdate,
                                             recording::foxglove::scene_update_schema());
  }

  // Every agent's pose before the step (as trajectories.csv has it), /tf, and the world.
  void record_world() {
    if (!recorder_) {
      return;
    }
    const std::uint64_t t_ns = recording::nanoseconds(world_.time_s());
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      const sim_camera::AgentState& s = world_.agents()[i];
      recorder_->odometry(i, t_ns, s.position_m.x(), s.position_m.y(), s.yaw_rad, s.speed_mps,
                          s.turn_rate);
    }
    recorder_->write_transforms(t_ns);
    recorder_->write_json(
        world_channel_, t_ns,
        recording::foxglove::scene_update_json(t_ns, moving_scene_entities(world_)));
  }

  // What each agent was told for the step that began at t_s: the speed and turn rate the world
  // gave it from its command.
  void record_commands(double t_s) {
    if (!recorder_) {
      return;
    }
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      const sim_camera::AgentState& s = world_.agents()[i];
      recorder_->command(i, recording::nanoseconds(t_s), s.speed_mps, s.turn_rate);
    }
  }

  // Adds this step to agent i's spinning time once its spell is longer than kSpin.spell_s, and
  // the spell's earlier steps with it.
  void account_spin(std::size_t i, double turn_rate) {
    AgentLoop& loop = loops_[i];
    const double limit = spec_.agents[i].controller.max_turn_rate;
    const bool spinning = std::abs(turn_rate) >= kSpin.limit_share * limit &&
                          world_.agents()[i].speed_mps < kSpin.speed_mps;
    loop.spin_steps = spinning ? loop.spin_steps + 1 : 0;
    const int spell_steps = static_cast<int>(std::floor(kSpin.spell_s / spec_.step_s + 1e-9)) + 1;
    if (loop.spin_steps == spell_steps) {
      loop.result.spinning_s += spell_steps * spec_.step_s;
    } else if (loop.spin_steps > spell_steps) {
      loop.result.spinning_s += spec_.step_s;
    }
  }

  // The driven agent's command. The driver is asked every step, also once the agent is at its
  // goal: a robot in the loop needs its frames until it is told to stop.
  void drive(std::size_t i) {
    const base::Command command = options_.driver->step(world_, *renderers_.local());
    if (!world_.agents()[i].reached_goal) {
      commands_[i] = command;
      loops_[i].result.turn_rates.push_back(command.turn_rate);
      ++loops_[i].active_steps;
      account_spin(i, command.turn_rate);
    }
  }

  // Path lengths, clearances and the collisions the last step started.
  void account_motion() {
    for (std::size_t i = 0; i < loops_.size(); ++i) {
      AgentLoop& loop = loops_[i];
      const Eigen::Vector2d p = world_.agents()[i].position_m;
      loop.result.path_length_m += (p - loop.last_position).norm();
      loop.last_position = p;
    }
    for (const sim_camera::Collision& c : world_.new_collisions()) {
      ++loops_[c.agent].result.collisions;
      if (c.other_agent) {
        ++loops_[*c.other_agent].result.collisions;
      }
      collisions_.push_back(c);
    }
  }

  // The agent's closest approach so far: the first moment of its least clearance.
  void note_clearance(AgentResult& r, double clearance_m, const Eigen::Vector2d& position_m) const {
    if (clearance_m < r.min_clearance_m) {
      r.min_clearance_m = clearance_m;
      r.closest_position_m = position_m;
      r.closest_time_s = world_.time_s();
    }
  }

  AgentResult agent_result(std::size_t i) {
    const int active_steps = loops_[i].active_steps;
    AgentResult r = std::move(loops_[i].result);
    // An agent steers from the start, until it reaches its goal or to the end: it chose its turn
    // rates at its path's first points.
    r.positions_m.assign(paths_[i].begin(),
                         paths_[i].begin() + static_cast<std::ptrdiff_t>(r.turn_rates.size()));
    const sim_camera::AgentState& s = world_.agents()[i];
    r.reached_goal = s.reached_goal;
    r.time_to_goal_s = s.time_to_goal_s;
    const sim_camera::AgentSpec& spec = spec_.agents[i];
    if (spec.leader) {
      r.final_distance_to_leader_m =
          (world_.agents()[static_cast<std::size_t>(*spec.leader)].position_m - s.position_m)
              .norm();
    }
    r.straight_line_m = straight_line_m(spec);
    r.preferred_speed_mps = spec.preferred_speed_mps;
    const Effort effort = steersuite_effort(
        std::span(paths_[i]).first(static_cast<std::size_t>(active_steps) + 1), spec_.step_s);
    r.active_time_s = effort.active_time_s;
    r.kinetic_energy_sum = effort.kinetic_energy_sum;
    return r;
  }

  sim_camera::WorldSpec spec_;
  const SimOptions& options_;
  sim_camera::World world_;
  tbb::task_arena arena_;
  tbb::enumerable_thread_specific<std::unique_ptr<sim_camera::Renderer>> renderers_;
  std::optional<base::OutputDir> out_;             // none: no files
  std::optional<pipeline::RunRecorder> recorder_;  // none: no recording
  std::uint16_t world_channel_ = 0;
  int total_steps_;
  std::vector<AgentLoop> loops_;
  // This step's views rendered together: their agents, the views and where each goes.
  std::vector<std::size_t> batch_agents_;
  std::vector<sim_camera::View> batch_views_;
  std::vector<sim_camera::RenderedView*> batch_out_;
  std::vector<std::vector<Eigen::Vector2d>> paths_;
  std::vector<base::Command> commands_;
  std::vector<TrajectoryRow> trajectories_;
  CostLog costs_;
  std::vector<sim_camera::Collision> collisions_;
  pipeline::StageTimes sum_;
  long agent_steps_ = 0;
};

// The scenario with the options' overrides of every agent's camera and perception.
sim_camera::WorldSpec with_overrides(sim_camera::WorldSpec spec, const SimOptions& options) {
  for (sim_camera::AgentSpec& a : spec.agents) {
    if (options.resolution)
      a.camera.width_px = a.camera.height_px = *options.resolution;
    if (options.camera_noise_levels)
      a.camera.noise_sigma_levels = *options.camera_noise_levels;
    if (options.flow)
      a.perception.flow = *options.flow;
    if (options.segmentation)
      a.perception.segmentation = *options.segmentation;
    if (options.depth)
      a.perception.depth = *options.depth;
    if (options.obstacle_memory)
      a.perception.obstacle_memory = *options.obstacle_memory;
  }
  return spec;
}

}  // namespace

void switch_off(sim_camera::WorldSpec& world, servo::LawMechanism mechanism) {
  for (sim_camera::AgentSpec& agent : world.agents) {
    if (mechanism != servo::LawMechanism::none &&
        agent.controller.law != servo::NavigationLaw::flowsteer) {
      throw base::ConfigError("--without " + std::string(servo::to_string(mechanism)),
                              "agent " + agent.name + "'s law is " +
                                  std::string(servo::to_string(agent.controller.law)) +
                                  "; only the flowsteer law's mechanisms can be switched off");
    }
    agent.controller.without = mechanism;
  }
}

SimResult run_simulation(const sim_camera::WorldSpec& world, const SimOptions& options,
                         std::ostream& log) {
  SimulationRun run(with_overrides(world, options), options);
  Progress progress(log, options.progress_bar, run.total_steps());
  const base::Stopwatch wall;
  int step = 0;
  const auto driver_done = [&] { return options.driver != nullptr && options.driver->finished(); };
  for (; step < run.total_steps() && !run.world().finished() && !driver_done(); ++step) {
    run.step();
    progress.update(step + 1, run.world().time_s());
  }
  const double wall_s = 1e-3 * wall.elapsed_ms();
  progress.finish();
  SimResult result = run.result(step);
  result.world_steps_per_s = wall_s > 0.0 ? step / wall_s : 0.0;
  run.write(result);
  return result;
}

Effort steersuite_effort(std::span<const Eigen::Vector2d> positions_m, double step_s) {
  Effort effort;
  for (std::size_t k = 1; k < positions_m.size(); ++k) {
    const Eigen::Vector2d velocity_mps = (positions_m[k] - positions_m[k - 1]) / step_s;
    effort.active_time_s += step_s;
    effort.kinetic_energy_sum += 0.5 * velocity_mps.squaredNorm();
  }
  return effort;
}

double composite01(int collisions, const Effort& effort) {
  // SteerSuite's weights: α = 50 per collision, β = 1 per second, γ = 1 per unit of effort.
  return 50.0 * collisions + effort.active_time_s + effort.kinetic_energy_sum;
}

RunSummary summarize(const SimResult& result) {
  RunSummary summary;
  summary.collisions = static_cast<int>(result.collisions.size());
  summary.obstacle_collisions = static_cast<int>(std::count_if(
      result.collisions.begin(), result.collisions.end(),
      [](const sim_camera::Collision& c) { return c.body == sim_camera::Body::obstacle; }));
  summary.agents = static_cast<int>(result.agents.size());
  summary.min_clearance_m = std::numeric_limits<double>::infinity();
  double time_sum = 0.0;
  double path_sum = 0.0;
  double ratio_sum = 0.0;
  double time_ratio_sum = 0.0;
  int ratios = 0;
  double score_sum = 0.0;
  int flips = 0;
  int turn_changes = 0;
  for (const AgentResult& a : result.agents) {
    for (std::size_t k = 1; k < a.turn_rates.size(); ++k) {
      flips += std::abs(a.turn_rates[k] - a.turn_rates[k - 1]) >= kTurnFlipRadPerS ? 1 : 0;
      ++turn_changes;
    }
    if (a.reached_goal) {
      ++summary.goals_reached;
      time_sum += a.time_to_goal_s;
      // An agent whose goal is its start (one standing still) has no ratio.
      if (a.straight_line_m > 0.0) {
        ratio_sum += a.path_length_m / a.straight_line_m;
        time_ratio_sum += a.time_to_goal_s * a.preferred_speed_mps / a.straight_line_m;
        ++ratios;
      }
    }
    score_sum += composite01(a.collisions, {a.active_time_s, a.kinetic_energy_sum});
    summary.spinning_s += a.spinning_s;
    if (a.final_distance_to_leader_m >= 0.0) {
      ++summary.followers;
    }
    path_sum += a.path_length_m;
    summary.min_clearance_m = std::min(summary.min_clearance_m, a.min_clearance_m);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  summary.mean_time_to_goal_s = summary.goals_reached > 0 ? time_sum / summary.goals_reached : nan;
  summary.mean_path_length_m = summary.agents > 0 ? path_sum / summary.agents : nan;
  summary.mean_path_length_ratio = ratios > 0 ? ratio_sum / ratios : nan;
  summary.mean_time_ratio = ratios > 0 ? time_ratio_sum / ratios : nan;
  summary.composite01 = summary.agents > 0 ? score_sum / summary.agents : nan;
  summary.turn_flip_ratio = turn_changes > 0 ? static_cast<double>(flips) / turn_changes : nan;
  return summary;
}

}  // namespace flowsteer::sim
