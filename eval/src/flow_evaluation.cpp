#include "flowsteer/eval/flow_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include <Eigen/Geometry>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/obstacle_memory.hpp"
#include "flowsteer/servo/segmentation.hpp"
#include "flowsteer/sim/simulated_agent.hpp"

namespace flowsteer::eval {

namespace {

double median(std::vector<double> values) {
  if (values.empty())
    return std::numeric_limits<double>::quiet_NaN();
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// The renderer object a region covers most (the most frequent id among its pixels, ground and
// sky included) and how many of the region's pixels are that object's.
struct RegionCover {
  std::int32_t id = -1;
  int object_px = 0;
  int region_px = 0;
};

// Fills `covers` with one entry per region of `segmentation`; `pairs` is scratch.
void cover_regions(const servo::Segmentation& segmentation, const cv::Mat& object_ids,
                   std::vector<std::pair<std::int32_t, std::int32_t>>& pairs,
                   std::vector<RegionCover>& covers) {
  pairs.clear();
  const auto* ids = object_ids.ptr<std::int32_t>();
  for (std::size_t i = 0; i < segmentation.labels.size(); ++i) {
    if (segmentation.labels[i] != servo::Segmentation::kNoRegion) {
      pairs.emplace_back(segmentation.labels[i], ids[i]);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  covers.assign(static_cast<std::size_t>(segmentation.region_count()), {});
  for (std::size_t begin = 0; begin < pairs.size();) {
    std::size_t end = begin;
    while (end < pairs.size() && pairs[end] == pairs[begin]) {
      ++end;
    }
    RegionCover& cover = covers[static_cast<std::size_t>(pairs[begin].first)];
    const auto count = static_cast<int>(end - begin);
    cover.region_px += count;
    if (count > cover.object_px) {
      cover.id = pairs[begin].second;
      cover.object_px = count;
    }
    begin = end;
  }
}

struct MethodRun {
  std::unique_ptr<pipeline::Brain> brain;
  FlowEvalRow row;
  double epe_sum = 0.0;
  double valid_count = 0.0;
  double total_count = 0.0;
  double ms_sum = 0.0;
  double recall_sum = 0.0;
  double purity_sum = 0.0;
  std::vector<double> foe_errors;
  std::vector<double> ttc_errors;
  std::vector<std::pair<std::int32_t, std::int32_t>> region_id_pairs;
  std::vector<RegionCover> covers;
  double object_px = 0.0;
  double untextured_px = 0.0;
  double untextured_correct_px = 0.0;
  // Renderer id → the track id of the region the object was the most of when last seen.
  std::map<std::int32_t, std::int32_t> track_of_object;
  int track_changes = 0;
  int tracked_object_frames = 0;
};

// The synthetic method first: it fits the exact flow without depth, the error the fit itself
// makes, which every estimator's row includes.
std::vector<servo::FlowMethod> methods_to_evaluate(const FlowEvalOptions& options) {
  const std::span<const servo::FlowMethod> all = servo::numerical_flow_methods();
  std::vector<servo::FlowMethod> methods{servo::FlowMethod::synthetic};
  if (options.methods.empty()) {
    methods.insert(methods.end(), all.begin(), all.end());
  } else {
    methods.insert(methods.end(), options.methods.begin(), options.methods.end());
  }
  return methods;
}

// The world with every camera at resolution² and every agent perceiving by default.
sim_camera::WorldSpec at_resolution(const sim_camera::WorldSpec& world_spec, int resolution) {
  sim_camera::WorldSpec spec = world_spec;
  for (auto& a : spec.agents) {
    a.camera.width_px = a.camera.height_px = resolution;
    a.perception = {};
  }
  return spec;
}

// A brain that sees by `perception`, for what it sees: the vision model, whose perception is all
// that is measured of it.
std::unique_ptr<pipeline::Brain> seeing_brain(const base::CameraIntrinsics& intrinsics,
                                              const pipeline::PerceptionOptions& perception) {
  pipeline::BrainConfig config;
  config.perception = perception;
  return std::make_unique<pipeline::Brain>(intrinsics, config);
}

// What a brain sees of the frame agent 0 sees, with agent 0's speed and turn rate.
void see(pipeline::Brain& brain, const camera_io::Frame& view,
         const sim_camera::AgentState& state) {
  brain.step({view, state.speed_mps, state.turn_rate, {}, {}, {}, {}, false});
}

// One run per method, each perceiving like the truth but with the method's flow, without depth.
std::vector<MethodRun> start_runs(std::span<const servo::FlowMethod> methods,
                                  const pipeline::PerceptionOptions& truth_options,
                                  const FlowEvalOptions& options,
                                  const base::CameraIntrinsics& intrinsics, int resolution) {
  std::vector<MethodRun> runs;
  for (servo::FlowMethod method : methods) {
    pipeline::PerceptionOptions o = truth_options;
    o.flow = method;
    o.use_depth = false;
    o.segmentation = options.segmentation;
    o.obstacle_memory = options.obstacle_memory;
    MethodRun run;
    run.brain = seeing_brain(intrinsics, o);
    run.row.method = method;
    run.row.segmentation = options.segmentation;
    run.row.resolution = resolution;
    runs.push_back(std::move(run));
  }
  return runs;
}

// Each agent steps on its own controller; `commands` gets what each commands.
void step_agents(std::vector<std::unique_ptr<sim::SimulatedAgent>>& agents,
                 sim_camera::Renderer& renderer, std::vector<base::Command>& commands) {
  for (std::size_t i = 0; i < agents.size(); ++i) {
    pipeline::StageTimes times;
    const servo::ControlOutput& out = agents[i]->step(renderer, times);
    commands[i] = out.command;
  }
}

// Endpoint errors over the pixels where both flows are valid; `to_px` turns flow into pixels.
void add_endpoint_errors(MethodRun& run, std::span<const Eigen::Vector2f> estimated,
                         std::span<const Eigen::Vector2f> exact, double to_px) {
  for (std::size_t p = 0; p < estimated.size(); ++p) {
    run.total_count += 1.0;
    if (!estimated[p].allFinite() || !exact[p].allFinite())
      continue;
    run.valid_count += 1.0;
    run.epe_sum += (estimated[p] - exact[p]).cast<double>().norm() * to_px;
  }
}

// Object pixels without measured flow, and how many of them the fill gave flow within 0.5 px +
// 20% of the truth's displacement over the flow's interval (a static point's, Z / (Z + v_z Δ)
// times the instantaneous flow).
void add_untextured(MethodRun& run, const servo::FlowField& truth, const cv::Mat& object_ids,
                    double approach_mps) {
  const servo::FlowField& estimated = run.brain->flow();
  const std::span<const std::uint8_t> filled = run.brain->filled_pixels();
  const double interval_s = estimated.interval_s();
  const double to_px = estimated.intrinsics().fx_px * interval_s;
  const auto* ids = object_ids.ptr<std::int32_t>();
  for (std::size_t p = 0; p < estimated.size(); ++p) {
    const bool was_filled = p < filled.size() && filled[p] != 0;
    if (ids[p] < 0) {
      continue;
    }
    run.object_px += 1.0;
    if (!was_filled && estimated.flow()[p].allFinite()) {
      continue;
    }
    run.untextured_px += 1.0;
    const double depth_m = truth.depth()[p];
    if (!was_filled || !std::isfinite(depth_m) || !truth.flow()[p].allFinite()) {
      continue;
    }
    const Eigen::Vector2d exact =
        truth.flow()[p].cast<double>() * (depth_m / (depth_m + approach_mps * interval_s));
    const double error_px = (estimated.flow()[p].cast<double>() - exact).norm() * to_px;
    run.untextured_correct_px += error_px <= 0.5 + 0.2 * exact.norm() * to_px ? 1.0 : 0.0;
  }
}

// Regions approaching within the horizon that are mostly ground or sky.
void count_phantoms(MethodRun& run, std::span<const servo::ObjectFeatures> estimated_objects,
                    double horizon_s) {
  for (const servo::ObjectFeatures& o : estimated_objects) {
    const auto label = static_cast<std::size_t>(o.label);
    if (o.kind == servo::RegionKind::visible && o.status == servo::MotionStatus::approaching &&
        o.ttc_s <= horizon_s && label < run.covers.size() &&
        (run.covers[label].id == servo::kGroundId || run.covers[label].id == servo::kSkyId)) {
      ++run.row.phantom_objects;
    }
  }
}

// The region the object with `source_id` is the most of that covers most of it; kNoRegion when
// it is the most of none.
int region_of_object(std::span<const RegionCover> covers, std::int32_t source_id) {
  int region = servo::Segmentation::kNoRegion;
  for (std::size_t r = 0; r < covers.size(); ++r) {
    if (covers[r].id == source_id &&
        (region == servo::Segmentation::kNoRegion ||
         covers[r].object_px > covers[static_cast<std::size_t>(region)].object_px)) {
      region = static_cast<int>(r);
    }
  }
  return region;
}

// Counts the objects whose region changed its track id since the object was last seen.
void add_track_changes(MethodRun& run, std::span<const servo::ObjectFeatures> truth_objects,
                       int min_object_px) {
  const servo::Segmentation& segmentation = run.brain->segmentation();
  for (const servo::ObjectFeatures& t : truth_objects) {
    if (t.kind != servo::RegionKind::visible || t.pixel_count < min_object_px) {
      continue;
    }
    const int region = region_of_object(run.covers, t.source_id);
    if (region == servo::Segmentation::kNoRegion) {
      continue;
    }
    const std::int32_t track = segmentation.source_ids[static_cast<std::size_t>(region)];
    const auto [last, first_seen] = run.track_of_object.try_emplace(t.source_id, track);
    if (!first_seen && last->second != track) {
      ++run.track_changes;
      last->second = track;
    }
    ++run.tracked_object_frames;
  }
}

// Scores the run on one object approaching in truth (`t`): small, missed, or found with the errors
// of its region's fit.
void score_object(MethodRun& run, const servo::ObjectFeatures& t,
                  std::span<const servo::ObjectFeatures> estimated_objects, int min_object_px) {
  if (t.pixel_count < min_object_px) {
    ++run.row.small_objects;
    return;
  }
  const int region = region_of_object(run.covers, t.source_id);
  // extract() gives one object per region, in label order.
  const servo::ObjectFeatures* o = region == servo::Segmentation::kNoRegion
                                       ? nullptr
                                       : &estimated_objects[static_cast<std::size_t>(region)];
  if (o == nullptr || o->kind != servo::RegionKind::visible ||
      o->status != servo::MotionStatus::approaching) {
    ++run.row.missed_objects;
    return;
  }
  const RegionCover& cover = run.covers[static_cast<std::size_t>(region)];
  ++run.row.approaching_objects;
  run.recall_sum += static_cast<double>(cover.object_px) / t.pixel_count;
  run.purity_sum += static_cast<double>(cover.object_px) / cover.region_px;
  run.foe_errors.push_back(std::abs(o->foe.x() - t.foe.x()));
  run.ttc_errors.push_back(std::abs(o->ttc_s - t.ttc_s) / t.ttc_s);
}

// Scores the run on a frame it has processed, against the truth's flow and objects.
void score_frame(MethodRun& run, double flow_ms, const pipeline::Brain& truth,
                 const camera_io::Frame& view, double to_px, double approach_mps,
                 const FlowEvalOptions& options) {
  ++run.row.frames;
  run.ms_sum += flow_ms;
  add_endpoint_errors(run, run.brain->flow().flow(), truth.flow().flow(), to_px);
  add_untextured(run, truth.flow(), view.sim->object_ids, approach_mps);
  cover_regions(run.brain->segmentation(), view.sim->object_ids, run.region_id_pairs, run.covers);
  add_track_changes(run, truth.objects(), options.min_object_px);
  const auto estimated_objects = run.brain->objects();
  count_phantoms(run, estimated_objects, options.phantom_horizon_s);
  for (const servo::ObjectFeatures& t : truth.objects()) {
    if (t.kind == servo::RegionKind::visible && t.status == servo::MotionStatus::approaching) {
      score_object(run, t, estimated_objects, options.min_object_px);
    }
  }
}

// How far `point` (world frame) lies from the nearest static obstacle's footprint, and from the
// nearest other agent's disc or moving obstacle's footprint.
std::pair<double, double> distances_to_bodies(const sim_camera::World& world,
                                              const Eigen::Vector2d& point) {
  double static_m = std::numeric_limits<double>::infinity();
  double mover_m = static_m;
  for (const sim_camera::Solid& o : world.spec().obstacles) {
    static_m = std::min(static_m, sim_camera::footprint_distance(o, point));
  }
  for (std::size_t j = 1; j < world.agents().size(); ++j) {
    if (world.present(j)) {
      mover_m = std::min(
          mover_m, (world.agents()[j].position_m - point).norm() - world.spec().agents[j].radius_m);
    }
  }
  for (std::size_t k = 0; k < world.moving().size(); ++k) {
    mover_m = std::min(mover_m, sim_camera::footprint_distance(world.moving_now(k), point));
  }
  return {static_m, mover_m};
}

// Scores the objects the memory recalled this frame by what lies at their nearest point.
void score_recalled(MethodRun& run, const sim_camera::World& world, double tolerance_m) {
  const sim_camera::AgentState& agent = world.agents()[0];
  const Eigen::Rotation2Dd body_to_world(agent.yaw_rad);
  for (const servo::ObjectFeatures& o : run.brain->objects()) {
    if (o.source_id < servo::ObstacleMemory::kFirstId || !o.nearest_depth_m) {
      continue;
    }
    // The law's ground frame: forward Z, and image x = −left / forward (CONVENTIONS.md).
    const double forward_m = *o.nearest_depth_m;
    const Eigen::Vector2d point =
        agent.position_m + body_to_world * Eigen::Vector2d(forward_m, -o.nearest_x * forward_m);
    const auto [static_m, mover_m] = distances_to_bodies(world, point);
    ++run.row.recalled_objects;
    if (static_m <= tolerance_m) {
      ++run.row.recalled_on_obstacles;
    } else if (mover_m <= tolerance_m) {
      ++run.row.recalled_on_movers;
    } else {
      ++run.row.recalled_on_nothing;
    }
  }
}

FlowEvalRow summarise(const MethodRun& run, double step_s) {
  FlowEvalRow row = run.row;
  if (run.object_px > 0.0) {
    row.untextured_fraction = run.untextured_px / run.object_px;
  }
  if (run.untextured_px > 0.0) {
    row.untextured_correct_fraction = run.untextured_correct_px / run.untextured_px;
  }
  if (run.tracked_object_frames > 0) {
    row.flicker_per_s = run.track_changes / (run.tracked_object_frames * step_s);
  }
  row.endpoint_error_px = run.valid_count > 0 ? run.epe_sum / run.valid_count : 0.0;
  row.valid_fraction = run.total_count > 0 ? run.valid_count / run.total_count : 0.0;
  if (row.approaching_objects > 0) {
    row.object_recall_mean = run.recall_sum / row.approaching_objects;
    row.region_purity_mean = run.purity_sum / row.approaching_objects;
  }
  row.foe_error_median = median(run.foe_errors);
  row.ttc_relative_error_median = median(run.ttc_errors);
  row.ms_per_frame = row.frames > 0 ? run.ms_sum / row.frames : 0.0;
  return row;
}

// Walks agent 0 through the world with its camera at resolution², every method measured on the
// same frames; appends one row per method to `rows`.
void evaluate_at_resolution(const sim_camera::WorldSpec& world_spec, int resolution,
                            std::span<const servo::FlowMethod> methods,
                            const FlowEvalOptions& options, sim_camera::Renderer& renderer,
                            std::ostream& log, std::vector<FlowEvalRow>& rows) {
  const sim_camera::WorldSpec spec = at_resolution(world_spec, resolution);
  sim_camera::World world(spec);
  std::vector<std::unique_ptr<sim::SimulatedAgent>> agents;
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    // Agent 0's images are what the estimators are measured on.
    agents.push_back(std::make_unique<sim::SimulatedAgent>(
        world, i, i == 0 ? sim_camera::RenderChannels::all : sim_camera::RenderChannels::geometry));
  }
  pipeline::PerceptionOptions truth_options = sim::brain_config(spec.agents[0]).perception;
  truth_options.dark_regions = false;
  truth_options.use_depth = true;
  const base::CameraIntrinsics& k = agents[0]->intrinsics();
  const std::unique_ptr<pipeline::Brain> truth = seeing_brain(k, truth_options);
  std::vector<MethodRun> runs = start_runs(methods, truth_options, options, k, resolution);
  const double to_px = k.fx_px * spec.step_s;
  // The estimators compare images a baseline apart: until they have one, they are not measured.
  const int warmup_frames =
      static_cast<int>(std::ceil(truth_options.optical_flow.baseline_s / spec.step_s));

  log << "flow evaluation: " << spec.name << " at " << resolution << "x" << resolution << ", "
      << options.frames << " frames\n";
  std::vector<base::Command> commands(spec.agents.size());
  for (int frame = 0; frame < options.frames && !world.finished(); ++frame) {
    step_agents(agents, renderer, commands);
    const camera_io::Frame& view = agents[0]->frame();
    const sim_camera::AgentState& state = world.agents()[0];
    see(*truth, view, state);
    for (MethodRun& run : runs) {
      see(*run.brain, view, state);
      if (run.brain->flow_status() == servo::FlowStatus::ok && frame >= warmup_frames) {
        score_frame(run, run.brain->times().flow, *truth, view, to_px,
                    state.speed_mps * std::cos(truth_options.mount.pitch_rad), options);
        if (options.obstacle_memory) {
          score_recalled(run, world, options.recall_tolerance_m);
        }
      }
    }
    world.step(commands);
  }
  for (const MethodRun& run : runs) {
    rows.push_back(summarise(run, spec.step_s));
  }
}

}  // namespace

std::vector<FlowEvalRow> evaluate_flow(const sim_camera::WorldSpec& world_spec,
                                       const FlowEvalOptions& options, std::ostream& log) {
  if (world_spec.agents.empty()) {
    throw std::invalid_argument("flow evaluation: the scenario has no agent to carry the camera");
  }
  const std::vector<servo::FlowMethod> methods = methods_to_evaluate(options);
  std::unique_ptr<sim_camera::Renderer> renderer = sim_camera::Renderer::create();
  std::vector<FlowEvalRow> rows;
  for (const int resolution : options.resolutions) {
    evaluate_at_resolution(world_spec, resolution, methods, options, *renderer, log, rows);
  }
  return rows;
}

void print_flow_table(const std::vector<FlowEvalRow>& rows, std::ostream& out) {
  out << std::left << std::setw(15) << "method" << std::setw(16) << "segmentation" << std::right
      << std::setw(6) << "res" << std::setw(8) << "frames" << std::setw(10) << "EPE px"
      << std::setw(8) << "valid" << std::setw(9) << "objects" << std::setw(8) << "missed"
      << std::setw(7) << "small" << std::setw(8) << "recall" << std::setw(8) << "purity"
      << std::setw(9) << "phantoms" << std::setw(10) << "FOE err" << std::setw(10) << "TTC err"
      << std::setw(11) << "untextured" << std::setw(9) << "filled" << std::setw(9) << "flicker"
      << std::setw(12) << "ms/frame" << std::setw(10) << "recalled" << std::setw(10) << "on obst."
      << std::setw(10) << "on movers" << std::setw(11) << "on nothing"
      << "\n";
  for (const FlowEvalRow& r : rows) {
    out << std::left << std::setw(15) << servo::to_string(r.method) << std::setw(16)
        << servo::to_string(r.segmentation) << std::right << std::fixed << std::setw(6)
        << r.resolution << std::setw(8) << r.frames << std::setw(10) << std::setprecision(3)
        << r.endpoint_error_px << std::setw(8) << std::setprecision(2) << r.valid_fraction
        << std::setw(9) << r.approaching_objects << std::setw(8) << r.missed_objects << std::setw(7)
        << r.small_objects << std::setw(8) << r.object_recall_mean << std::setw(8)
        << r.region_purity_mean << std::setw(9) << r.phantom_objects << std::setw(10)
        << std::setprecision(4) << r.foe_error_median << std::setw(9) << std::setprecision(1)
        << 100.0 * r.ttc_relative_error_median << "%" << std::setw(10) << std::setprecision(1)
        << 100.0 * r.untextured_fraction << "%" << std::setw(8)
        << 100.0 * r.untextured_correct_fraction << "%" << std::setw(9) << std::setprecision(2)
        << r.flicker_per_s << std::setw(12) << r.ms_per_frame << std::setw(10) << r.recalled_objects
        << std::setw(10) << r.recalled_on_obstacles << std::setw(10) << r.recalled_on_movers
        << std::setw(11) << r.recalled_on_nothing << "\n";
  }
}

void write_flow_evaluation(const std::vector<FlowEvalRow>& rows,
                           const std::filesystem::path& out_dir) {
  base::OutputDir out(out_dir);
  base::CsvTable csv({"method",
                      "segmentation",
                      "resolution",
                      "frames",
                      "endpoint_error_px",
                      "valid_fraction",
                      "approaching_objects",
                      "missed_objects",
                      "small_objects",
                      "object_recall_mean",
                      "region_purity_mean",
                      "phantom_objects",
                      "foe_error_median",
                      "ttc_relative_error_median",
                      "untextured_fraction",
                      "untextured_correct_fraction",
                      "flicker_per_s",
                      "ms_per_frame",
                      "recalled_objects",
                      "recalled_on_obstacles",
                      "recalled_on_movers",
                      "recalled_on_nothing"});
  for (const FlowEvalRow& r : rows) {
    csv.add(
        {std::string(servo::to_string(r.method)), std::string(servo::to_string(r.segmentation))},
        {static_cast<double>(r.resolution),
         static_cast<double>(r.frames),
         r.endpoint_error_px,
         r.valid_fraction,
         static_cast<double>(r.approaching_objects),
         static_cast<double>(r.missed_objects),
         static_cast<double>(r.small_objects),
         r.object_recall_mean,
         r.region_purity_mean,
         static_cast<double>(r.phantom_objects),
         r.foe_error_median,
         r.ttc_relative_error_median,
         r.untextured_fraction,
         r.untextured_correct_fraction,
         r.flicker_per_s,
         r.ms_per_frame,
         static_cast<double>(r.recalled_objects),
         static_cast<double>(r.recalled_on_obstacles),
         static_cast<double>(r.recalled_on_movers),
         static_cast<double>(r.recalled_on_nothing)});
  }
  csv.write(out.staging_path("flow_eval.csv"));
  std::ostringstream table;
  print_flow_table(rows, table);
  base::write_text(out.staging_path("flow_eval.txt"), table.str());
  out.commit();
}

}  // namespace flowsteer::eval
