#include "flowsteer/eval/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/eval/simulated_agent.hpp"
#include "flowsteer/eval/output_files.hpp"
#include "flowsteer/eval/overlay.hpp"

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

  CsvTable trajectories({"t", "agent", "x", "y", "heading", "v", "a_c", "omega"});
  // The cost terms by column, in the order they first appear; a row's terms[k] is the cost of
  // term_names[k] (NaN where the agent's controller has no such term).
  std::vector<std::string> term_names;
  struct CostRow {
    double t;
    std::size_t agent;
    std::vector<double> terms;
    double total;
  };
  std::vector<CostRow> cost_rows;

  const int max_steps = static_cast<int>(std::ceil(spec.duration_s / spec.step_s - 1e-9));
  const int total_steps = options.steps ? std::min(*options.steps, max_steps) : max_steps;
  Progress progress(log, options.progress_bar, total_steps);
  pipeline::StageTimes sum;
  long agent_steps = 0;
  std::vector<std::pair<double, double>> commands(spec.agents.size());
  std::vector<sim_camera::Collision> collisions;
  std::vector<std::vector<Eigen::Vector2d>> paths(spec.agents.size());
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
      loop.result.positions_m.push_back(state.position_m);
      sum += times;
      ++agent_steps;

      CostRow row{world.time_s(), i, {}, output.cost};
      for (const servo::TermEvaluation& t : output.terms) {
        const auto column = static_cast<std::size_t>(
            std::find(term_names.begin(), term_names.end(), t.name) - term_names.begin());
        if (column == term_names.size()) {
          term_names.push_back(t.name);
        }
        row.terms.resize(std::max(row.terms.size(), column + 1), std::nan(""));
        row.terms[column] = t.gradient.cost;
      }
      cost_rows.push_back(std::move(row));

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
      trajectories.add({world.time_s(), static_cast<double>(i), s.position_m.x(), s.position_m.y(),
                        s.yaw_rad, s.speed_mps, commands[i].first, commands[i].second});
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
    AgentResult r = loops[i].result;
    const sim_camera::AgentState& s = world.agents()[i];
    r.reached_goal = s.reached_goal;
    r.time_to_goal_s = s.time_to_goal_s;
    if (const auto& leader = spec.agents[i].leader) {
      r.final_distance_to_leader_m =
          (world.agents()[static_cast<std::size_t>(*leader)].position_m - s.position_m).norm();
    }
    result.agents.push_back(r);
  }
  result.collisions = collisions;
  if (agent_steps > 0) {
    const double n = static_cast<double>(agent_steps);
    result.per_agent_step_ms = {sum.render / n,   sum.flow / n,    sum.segment / n,
                                sum.features / n, sum.control / n, sum.total / n};
  }
  result.topview = draw_topview(world, paths, result.collisions);
  if (out) {
    trajectories.write(out->staging_path("trajectories.csv"));
    CsvTable costs([&] {
      std::vector<std::string> header = {"t", "agent"};
      header.insert(header.end(), term_names.begin(), term_names.end());
      header.push_back("total");
      return header;
    }());
    for (const CostRow& row : cost_rows) {
      std::vector<double> values = {row.t, static_cast<double>(row.agent)};
      values.insert(values.end(), row.terms.begin(), row.terms.end());
      values.resize(2 + term_names.size(), std::nan(""));
      values.push_back(row.total);
      costs.add(values);
    }
    costs.write(out->staging_path("costs.csv"));
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
