#include "flowsteer/eval/simulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/eval/output_files.hpp"
#include "flowsteer/eval/overlay.hpp"
#include "flowsteer/eval/simulated_agent.hpp"

namespace flowsteer::eval {

namespace {

// Everything one agent keeps from step to step.
struct AgentLoop {
  std::unique_ptr<SimulatedAgent> pipeline;
  AgentResult result;
  Eigen::Vector2d last_position;
  std::unique_ptr<cv::VideoWriter> video;
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
  CsvTable table() const {
    std::vector<std::string> header = {"t", "agent"};
    header.insert(header.end(), names_.begin(), names_.end());
    header.push_back("total");
    CsvTable csv(std::move(header));
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

// t, agent, x, y, heading, v, a_c, omega: a row of trajectories.csv.
using TrajectoryRow = std::array<double, 8>;

void write_trajectories(const std::filesystem::path& path, const std::vector<TrajectoryRow>& rows) {
  CsvTable csv({"t", "agent", "x", "y", "heading", "v", "a_c", "omega"});
  for (const TrajectoryRow& row : rows) {
    csv.add({row.begin(), row.end()});
  }
  csv.write(path);
}

}  // namespace

SimResult run_simulation(const sim_camera::WorldSpec& world_spec, const SimOptions& options,
                         std::ostream& log) {
  sim_camera::WorldSpec spec = world_spec;
  for (auto& a : spec.agents) {
    if (options.resolution)
      a.camera.width_px = a.camera.height_px = *options.resolution;
    if (options.flow)
      a.perception.flow = *options.flow;
    if (options.segmentation)
      a.perception.segmentation = *options.segmentation;
  }
  sim_camera::World world(spec);
  std::unique_ptr<sim_camera::Renderer> renderer = sim_camera::Renderer::create();
  std::optional<OutputDir> out;
  if (options.write_outputs) {
    out.emplace(options.out_dir);
  }

  std::vector<AgentLoop> loops;
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    AgentLoop loop{
        std::make_unique<SimulatedAgent>(world, *renderer, i), {}, spec.agents[i].start_m, nullptr};
    loop.result.name = spec.agents[i].name;
    loop.result.min_clearance_m = world.clearance(i);
    loops.push_back(std::move(loop));
  }

  const int max_steps = static_cast<int>(std::ceil(spec.duration_s / spec.step_s - 1e-9));
  const int total_steps = options.steps ? std::min(*options.steps, max_steps) : max_steps;
  // Room for every step up front: the loop then allocates nothing of its own per step.
  const auto steps = static_cast<std::size_t>(std::max(total_steps, 0));
  std::vector<std::vector<Eigen::Vector2d>> paths(spec.agents.size());
  for (std::size_t i = 0; i < loops.size(); ++i) {
    loops[i].result.turn_rates.reserve(steps);
    paths[i].reserve(steps);
  }
  std::vector<TrajectoryRow> trajectories;
  trajectories.reserve(steps * loops.size());
  CostLog costs(loops.size(), steps);

  Progress progress(log, options.progress_bar, total_steps);
  pipeline::StageTimes sum;
  long agent_steps = 0;
  std::vector<std::pair<double, double>> commands(spec.agents.size());
  std::vector<sim_camera::Collision> collisions;
  int step = 0;
  for (; step < total_steps && !world.finished(); ++step) {
    for (std::size_t i = 0; i < loops.size(); ++i) {
      AgentLoop& loop = loops[i];
      const sim_camera::AgentSpec& agent = spec.agents[i];
      const sim_camera::AgentState& state = world.agents()[i];
      commands[i] = {0.0, 0.0};
      if (state.reached_goal && !agent.leader) {
        continue;
      }
      pipeline::StageTimes times;
      const servo::ControlOutput& output = loop.pipeline->step(times);
      commands[i] = {output.command.accel_mps2, output.command.turn_rate};
      loop.result.turn_rates.push_back(output.command.turn_rate);
      sum += times;
      ++agent_steps;
      costs.add(world.time_s(), i, output);

      if (options.video && out) {
        if (!loop.video) {
          loop.video =
              open_video(out->staging_path("agent_" + std::to_string(i) + ".mp4"),
                         overlay_size(loop.pipeline->frame().image.size()), 1.0 / spec.step_s);
        }
        loop.video->write(draw_overlay(*loop.pipeline));
      }
    }
    for (std::size_t i = 0; i < loops.size(); ++i) {
      const sim_camera::AgentState& s = world.agents()[i];
      trajectories.push_back({world.time_s(), static_cast<double>(i), s.position_m.x(),
                              s.position_m.y(), s.yaw_rad, s.speed_mps, commands[i].first,
                              commands[i].second});
      paths[i].push_back(s.position_m);
    }
    world.step(commands);
    for (std::size_t i = 0; i < loops.size(); ++i) {
      AgentLoop& loop = loops[i];
      const Eigen::Vector2d p = world.agents()[i].position_m;
      loop.result.path_length_m += (p - loop.last_position).norm();
      loop.last_position = p;
      loop.result.min_clearance_m = std::min(loop.result.min_clearance_m, world.clearance(i));
    }
    for (const sim_camera::Collision& c : world.new_collisions()) {
      ++loops[c.agent].result.collisions;
      if (c.other_agent) {
        ++loops[*c.other_agent].result.collisions;
      }
      collisions.push_back(c);
    }
    progress.update(step + 1, world.time_s());
  }
  progress.finish();

  SimResult result;
  result.scenario = spec.name;
  result.steps = step;
  result.duration_s = world.time_s();
  for (std::size_t i = 0; i < loops.size(); ++i) {
    AgentResult r = std::move(loops[i].result);
    // An agent steers until it reaches its goal: it chose its turn rates at its path's first
    // points.
    r.positions_m.assign(paths[i].begin(),
                         paths[i].begin() + static_cast<std::ptrdiff_t>(r.turn_rates.size()));
    const sim_camera::AgentState& s = world.agents()[i];
    r.reached_goal = s.reached_goal;
    r.time_to_goal_s = s.time_to_goal_s;
    if (const auto& leader = spec.agents[i].leader) {
      r.final_distance_to_leader_m =
          (world.agents()[static_cast<std::size_t>(*leader)].position_m - s.position_m).norm();
    }
    result.agents.push_back(std::move(r));
  }
  result.collisions = collisions;
  if (agent_steps > 0) {
    const double n = static_cast<double>(agent_steps);
    result.per_agent_step_ms = {sum.render / n,   sum.flow / n,    sum.segment / n,
                                sum.features / n, sum.control / n, sum.total / n};
  }
  result.topview = draw_topview(world, paths, result.collisions);
  if (out) {
    write_trajectories(out->staging_path("trajectories.csv"), trajectories);
    costs.table().write(out->staging_path("costs.csv"));
    for (auto& loop : loops) {
      if (loop.video) {
        loop.video->release();
      }
    }
    write_image(out->staging_path("topview.png"), result.topview);
    write_summary_json(out->staging_path("summary.json"), result);
    out->commit();
  }
  return result;
}

RunSummary summarize(const SimResult& result) {
  RunSummary summary;
  summary.collisions = static_cast<int>(result.collisions.size());
  summary.agents = static_cast<int>(result.agents.size());
  summary.min_clearance_m = std::numeric_limits<double>::infinity();
  double time_sum = 0.0;
  double path_sum = 0.0;
  for (const AgentResult& a : result.agents) {
    if (a.reached_goal) {
      ++summary.goals_reached;
      time_sum += a.time_to_goal_s;
    }
    if (a.final_distance_to_leader_m >= 0.0) {
      ++summary.followers;
    }
    path_sum += a.path_length_m;
    summary.min_clearance_m = std::min(summary.min_clearance_m, a.min_clearance_m);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  summary.mean_time_to_goal_s = summary.goals_reached > 0 ? time_sum / summary.goals_reached : nan;
  summary.mean_path_length_m = summary.agents > 0 ? path_sum / summary.agents : nan;
  return summary;
}

}  // namespace flowsteer::eval
