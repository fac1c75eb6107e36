#pragma once

#include <filesystem>
#include <ostream>
#include <vector>

#include "flowsteer/servo/flow_segmentation.hpp"
#include "flowsteer/servo/optical_flow.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::eval {

struct FlowEvalOptions {
  std::vector<int> resolutions{256};
  std::vector<servo::FlowMethod> methods;  // empty: every numerical method
  // How each estimator's flow is split into objects: by the renderer's ids (the flow alone is
  // measured), or from the flow (what a camera without ids gets: segmentation is measured too).
  servo::SegmentationMethod segmentation = servo::SegmentationMethod::semantic;
  int frames = 40;  // control steps rendered per resolution
  // Objects smaller than this in the image are counted apart: a few of the estimators' patches
  // (8 px for DIS) across, where their flow is mostly the background's smoothed in.
  int min_object_px = 256;
  // Regions approaching sooner than this (the avoidance horizon) count as phantoms when most of
  // their pixels are the ground or the sky.
  double phantom_horizon_s = 5.0;
  // Each method's perception keeps the obstacle memory (servo::ObstacleMemory; flow
  // segmentation only), and its recalled objects are scored against the world.
  bool obstacle_memory = false;
  // A recalled object whose nearest point lies this near a body's footprint is on that body: the
  // memory's link distance, within which its points are one object.
  double recall_tolerance_m = 0.3;
};

// One estimator at one resolution, over every frame after the first.
struct FlowEvalRow {
  servo::FlowMethod method = servo::FlowMethod::dis_medium;
  servo::SegmentationMethod segmentation = servo::SegmentationMethod::semantic;
  int resolution = 0;
  int frames = 0;
  double endpoint_error_px = 0.0;  // mean |u − u_true| in pixels per frame, over pixels with flow
  double valid_fraction = 0.0;     // pixels given flow (the rest lack texture)
  // Each object approaching in truth is the region it covers most among those it is the most of;
  // without such a region, or when that region is not approaching, it is missed.
  int approaching_objects = 0;  // object-frames approaching in truth and fitted
  int missed_objects = 0;       // object-frames approaching in truth, not approaching here
  int small_objects = 0;        // object-frames below min_object_px, not in the errors
  // Over the approaching object-frames: the share of the object's pixels in its region, and the
  // share of its region that is the object (both 1 with semantic segmentation and exact flow).
  double object_recall_mean = 0.0;
  double region_purity_mean = 0.0;
  // Region-frames approaching within phantom_horizon_s that are mostly ground or sky: what the
  // agent would avoid that is not there.
  int phantom_objects = 0;
  double foe_error_median = 0.0;           // |f − f_true|, normalised
  double ttc_relative_error_median = 0.0;  // |τ − τ_true| / τ_true
  // Untextured surfaces: object pixels (not ground, not sky) whose flow was not measured. Their
  // share of the object pixels, and the share of them given flow (servo::UntexturedFill) within
  // 0.5 px + 20% of the truth, both over the flow's interval; the truth is the renderer's flow as
  // a displacement over that interval, taken for a static point.
  double untextured_fraction = 0.0;
  double untextured_correct_fraction = 0.0;
  // How often the region an object is the most of changes its track id, per object and second of
  // frames measured (objects of at least min_object_px): what the controller remembers about an
  // object is lost with each change.
  double flicker_per_s = 0.0;
  // With the obstacle memory: the objects it recalled, over the frames, and by where their
  // nearest point lies in the world: on a static obstacle, on an agent or a moving obstacle
  // (what stands there now is real, but moves), or on nothing (what stood there has gone, or
  // never was).
  int recalled_objects = 0;
  int recalled_on_obstacles = 0;
  int recalled_on_movers = 0;
  int recalled_on_nothing = 0;
  double ms_per_frame = 0.0;  // flow computation alone
};

// Renders the world's agent 0 walking (steered by its own controller on synthetic flow) and runs
// each estimator on the same frames. Truth: the renderer's flow, and the features the exact flow
// and depth give for each object (the fit is exact with depth). Objects are matched to regions
// by their pixels.
std::vector<FlowEvalRow> evaluate_flow(const sim_camera::WorldSpec& world,
                                       const FlowEvalOptions& options, std::ostream& log);

// The table as text, one line per row.
void print_flow_table(const std::vector<FlowEvalRow>& rows, std::ostream& out);
// flow_eval.csv and flow_eval.txt in out_dir, each written whole or not at all.
void write_flow_evaluation(const std::vector<FlowEvalRow>& rows,
                           const std::filesystem::path& out_dir);

}  // namespace flowsteer::eval
