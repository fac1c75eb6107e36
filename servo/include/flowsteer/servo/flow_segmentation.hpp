#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

// How an agent splits its view into objects: by the renderer's object ids (semantic, MIG 2019),
// or from the flow alone with Felzenszwalb–Huttenlocher graph segmentation (CGF §4): flow_graph
// at full resolution with OpenCV's GraphSegmentation, flow_graph_fast with our own
// implementation, which keeps its buffers, on the flow sampled at most fast_max_side_px per side.
enum class SegmentationMethod { semantic, flow_graph, flow_graph_fast };

std::string_view to_string(SegmentationMethod method);
std::optional<SegmentationMethod> parse_segmentation_method(std::string_view name);
// Every name parse_segmentation_method accepts, for messages.
std::string segmentation_method_names();

struct FlowSegmentationOptions {
  // Flow is compared in pixels per reference_interval_s (one frame at 20 Hz): the units the
  // graph's threshold k is set in, whatever the image size.
  double reference_interval_s = 0.05;
  // Felzenszwalb–Huttenlocher scale: larger k, larger regions. With grey_weight, which parts what
  // moves alike, 12 gave whole people (docs/NAVIGATION.md, "Regions and their tracks").
  double k = 4.0;
  // Regions with fewer valid pixels than this fraction of the image are merged into a
  // neighbour by the graph, or dropped.
  double min_region_fraction = 0.002;
  int fast_max_side_px = 96;
  // Weight of the image's grey level in the graph's edge weights, in flow pixels per reference
  // interval per grey level: a person and the wall behind move alike far off, but seldom look
  // alike. 0 (flow alone) by default: measured, not yet better in closed loop.
  double grey_weight = 0.0;
  // A region whose track begins in this frame is RegionKind::unconfirmed, visible from its second
  // frame on: numerical flow's errors on the floor come and go as one-frame regions. Off by
  // default: it delays people too.
  bool confirm_new_regions = false;
};

// How the view moved since the previous segmentation: each pixel was, that long ago, where its
// derotated flow plus the camera's rotation at camera_omega (rad/s, camera frame) bring it back
// to. Zero: where it is now.
struct ViewMotion {
  Eigen::Vector3d camera_omega = Eigen::Vector3d::Zero();
  double since_previous_s = 0.0;
};

// Segmentation from the flow alone, which is what a real camera has. Regions are connected sets
// of pixels whose derotated flow varies smoothly; pixels set in `excluded` (the ground) and
// pixels without flow (NaN) belong to no region, as do, in a field with depth (a simulator's),
// pixels without depth, which see nothing (the sky). Each region's source id follows it from frame
// to frame (the previous region it overlaps most, each pixel followed back along its flow), so that
// what the controller remembers about an object (its side, commit_band) stays with it; ids start at
// kFirstTrackId, clear of the renderer's.
class FlowSegmenter {
 public:
  static constexpr std::int32_t kFirstTrackId = 1 << 24;

  // Throws std::invalid_argument for SegmentationMethod::semantic, which needs object ids.
  explicit FlowSegmenter(SegmentationMethod method, const FlowSegmentationOptions& options = {});
  ~FlowSegmenter();
  FlowSegmenter(FlowSegmenter&&) noexcept;
  FlowSegmenter& operator=(FlowSegmenter&&) noexcept;

  // `excluded` is empty or has one entry per pixel; `grey` is empty or the 8-bit grey image the
  // flow was measured on, the field's size (used when options.grey_weight > 0). Reuses out's
  // storage.
  void segment(const FlowField& derotated, std::span<const std::uint8_t> excluded,
               const cv::Mat& grey, Segmentation& out, const ViewMotion& motion = {});

 private:
  struct Graph;
  SegmentationMethod method_;
  FlowSegmentationOptions options_;
  std::unique_ptr<Graph> graph_;
  cv::Mat features_;  // one per pixel of the graph
  cv::Mat graph_labels_;
  std::vector<int> graph_cols_;             // the graph's column of each column
  std::vector<std::int32_t> flow_balance_;  // per segment: graph pixels with flow − without
  std::vector<std::int32_t> valid_counts_;
  std::vector<std::int32_t> region_of_label_;

  // From overlaps_ and region_sizes_, which segment() counts.
  void assign_track_ids(Segmentation& out);
  std::vector<std::int32_t> previous_labels_;
  std::vector<std::int32_t> previous_ids_;
  std::vector<std::int32_t> previous_sizes_;
  std::vector<std::int32_t> overlaps_;  // new region × previous region pixel counts
  std::vector<std::int32_t> region_sizes_;
  std::int32_t next_track_id_ = kFirstTrackId;
};

}  // namespace flowsteer::servo
