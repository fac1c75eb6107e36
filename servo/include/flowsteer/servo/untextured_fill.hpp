#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::servo {

class FlatGround;

struct UntexturedFillOptions {
  bool enabled = true;
  // The floor, scanned up a column, is pixels without flow or ground, with gaps of up to this many
  // pixels with flow of their own (or of flow_spread_px, when larger): the estimators leave specks
  // of flow on a plain floor, and a band of flow along a foot's edge.
  int contact_search_px = 3;
  // How far the estimator spreads an edge's flow into the plain areas either side, in pixels:
  // half its patch at its finest scale. Perception sets it from the flow source.
  double flow_spread_px = 0.0;
  // A surface is filled only where at least this share of its column between foot and top has
  // no flow, or flow a static point as far ahead as the foot would have (within
  // agreement_px + agreement_share of it): far floor between a mark on it and the horizon has
  // flow of its own, nearer floor's.
  double min_untextured_share = 0.8;
  double agreement_px = 0.5;
  double agreement_share = 0.5;
  // A surface's foot is where the floor's grey level steps by at least this much across two
  // rows, scanning up from the floor.
  double min_edge_grey = 4.0;
  // Feet farther ahead than this are not filled: their flow is below what the estimators resolve,
  // and the sky seen over far ground would pass for a wall there.
  double max_distance_ahead_m = 6.0;
  // A surface whose foot is below the image (a wall beside the agent, or one closer than the
  // lowest row sees) stands on the line through the feet of the nearest columns of it that show
  // theirs: at least min_line_feet of them, spread over at least min_line_span_m, within
  // max_line_rms_m (plus max_line_rms_share of their distance) of one line; without such a line,
  // where its top edge's motion puts it (the flow across the edge within edge_votes_px of it).
  int min_line_feet = 4;
  int max_line_feet = 24;
  double min_line_span_m = 0.15;
  double max_line_rms_m = 0.03;
  double max_line_rms_share = 0.02;
  // The line or the top edge must put the foot nearer than the bottom row's ground, within this
  // share of its distance: farther, and the foot would be in view.
  double hidden_foot_slack = 0.05;
  // A box's edges (its top, within edge_votes_px, and its sides) must have at least this many
  // vectors nearer its foot's distance than the floor's there, and more than the other way.
  int min_edge_votes = 2;
  int edge_votes_px = 2;
};

// Gives flow to untextured surfaces that stand on the ground. Numerical flow has none on a plain
// wall, door or pillar (the texture test drops what the estimators would invent there), so
// without this a robot sees through them. Scanning a column up from the image's bottom, the floor
// (pixels without flow, or ground) ends at its last grey-level edge below the horizon: the foot of
// a surface, if above it the column has no flow, or the flow the surface would have, up to the
// surface's own top edge above the horizon (a surface taller than the camera). Every pixel of it
// without flow is as far ahead as that foot, and gets the flow the measured ego-motion gives a
// static point there (depth from derotated flow and known speed, McCarthy, Barnes and
// Srinivasan, ICRA 2007, used the other way round). A column whose surface goes down past the
// image's bottom, its foot hidden, stands on the line through the feet its neighbours show: a
// vertical plane, whose distance ahead is the same all along a column; without such a line, where
// the motion of its top edge puts it, if that is nearer than the bottom row's floor. A box lower
// than the camera is a stretch without flow between two edges of the floor whose edges move as
// something as near as its foot. A plain floor gets nothing.
// Keeps its buffers from frame to frame.
class UntexturedFill {
 public:
  explicit UntexturedFill(const UntexturedFillOptions& options = {}) : options_(options) {}

  // `derotated` is numerical flow, NaN where it has none; ground_mask marks its ground pixels
  // (mark_ground); edge_flow is empty or the flow source's across edges (FlowSource::edge_flow),
  // which tells a box's top edge from a mark on the floor. speed_mps is the base's over the
  // field's interval. Returns the pixels filled.
  int fill(FlowField& derotated, const cv::Mat& grey, double image_noise_grey,
           const base::CameraMount& mount, double speed_mps,
           std::span<const std::uint8_t> ground_mask,
           std::span<const Eigen::Vector2f> edge_flow = {});

  // One entry per pixel of the last field filled: 1 where fill() gave the flow.
  std::span<const std::uint8_t> filled() const { return filled_; }

 private:
  // What one column shows: a surface from `head` (exclusive) down to `bottom`, as far ahead as
  // ahead_m (0: none found).
  struct Column {
    int head = -1;
    int bottom = -1;
    double ahead_m = 0.0;
    bool foot_hidden = false;  // the surface goes down past the image's bottom
    Eigen::Vector2d foot_m = Eigen::Vector2d::Zero();  // body frame, where its foot is seen
  };
  // Rows of one grey-level edge, top_row <= bottom_row.
  struct EdgeBand {
    int bottom_row;
    int top_row;
  };
  // Rows top_row..bottom_row of column col, ahead_m ahead.
  struct Span {
    int col;
    int top_row;
    int bottom_row;
    double ahead_m;
  };
  // Vectors at a box's edges nearer its foot's distance than the floor's there, and the other way.
  struct EdgeVotes {
    int near = 0;
    int floor = 0;
  };
  // A pixel's flow: measured, or only its component across an edge there.
  struct SeenFlow {
    Eigen::Vector2d flow;
    bool across_edge;
  };
  struct BoxColumn {
    Span span;
    EdgeVotes votes;  // of its top edge
  };

  void find_feet(const FlowField& field, const cv::Mat& grey, const FlatGround& ground,
                 std::span<const std::uint8_t> ground_mask, double speed_mps);
  void find_floor_edges(const FlowField& field, const cv::Mat& grey,
                        std::span<const std::uint8_t> ground_mask, int col);
  void place_hidden_feet(const FlowField& field, const FlatGround& ground, double speed_mps);
  double ahead_of_top_edge(const FlowField& field, const FlatGround& ground, int col,
                           double farthest_m, double speed_mps);
  double median_top_edge_ahead(int col, int first, int last);
  void find_boxes(const FlowField& field, const FlatGround& ground, int col, double speed_mps);
  void confirm_boxes(const FlowField& field, const FlatGround& ground, double speed_mps);
  bool stands_at(const FlowField& field, const FlatGround& ground, int col, int top, int bottom,
                 double ahead_m, double speed_mps) const;
  void vote(const FlowField& field, const FlatGround& ground, int col, int row, double ahead_m,
            double speed_mps, EdgeVotes& votes) const;
  std::optional<SeenFlow> seen_flow(const FlowField& field, std::size_t i) const;
  bool is_edge(const cv::Mat& grey, int col, int row) const;
  int lowest_edge(const cv::Mat& grey, int col, int top, int bottom) const;

  UntexturedFillOptions options_;
  double edge_threshold_ = 0.0;  // grey levels per column, this frame's
  int first_ground_row_ = 0;     // this field's first row below the horizon
  double lag_m_ = 0.0;  // how far a static point closes in over the field's interval, v cos θ Δt
  std::span<const Eigen::Vector2f> edge_flow_;  // this frame's (fill's argument)
  std::vector<Column> columns_;
  std::vector<double> top_edge_ahead_m_;  // per column, ahead_of_top_edge's (hidden feet only)
  std::vector<double> estimates_;         // scratch
  std::vector<Eigen::Vector2d> feet_;     // one line's, scratch
  std::vector<EdgeBand> edge_bands_;      // one column's, scratch
  std::vector<BoxColumn> box_columns_;    // candidates
  std::vector<std::uint8_t> box_taken_;   // per candidate, whether a box holds it
  std::vector<std::size_t> run_;          // one box's candidates, scratch
  std::vector<Span> boxes_;               // confirmed
  std::vector<std::uint8_t> filled_;
};

}  // namespace flowsteer::servo
