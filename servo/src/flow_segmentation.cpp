#include "flowsteer/servo/flow_segmentation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/segmentation.hpp>

namespace flowsteer::servo {

namespace {

// Pixels without flow get this in the validity channel: far from every valid pixel's 0, so the
// graph never joins them to a region with flow.
constexpr float kInvalidMark = 1e4F;

constexpr std::array kMethods{SegmentationMethod::semantic, SegmentationMethod::flow_graph,
                              SegmentationMethod::flow_graph_fast};

}  // namespace

std::string_view to_string(SegmentationMethod method) {
  switch (method) {
    case SegmentationMethod::semantic:
      return "semantic";
    case SegmentationMethod::flow_graph:
      return "flow_graph";
    case SegmentationMethod::flow_graph_fast:
      return "flow_graph_fast";
  }
  return "unknown";
}

std::optional<SegmentationMethod> parse_segmentation_method(std::string_view name) {
  for (SegmentationMethod method : kMethods) {
    if (name == to_string(method))
      return method;
  }
  return std::nullopt;
}

std::string segmentation_method_names() {
  std::string names;
  for (SegmentationMethod method : kMethods) {
    if (!names.empty())
      names += ", ";
    names += to_string(method);
  }
  return names;
}

struct FlowSegmenter::Graph {
  cv::Ptr<cv::ximgproc::segmentation::GraphSegmentation> segmentation;
};

FlowSegmenter::FlowSegmenter(SegmentationMethod method, const FlowSegmentationOptions& options)
    : method_(method), options_(options), graph_(std::make_unique<Graph>()) {
  if (method == SegmentationMethod::semantic) {
    throw std::invalid_argument("FlowSegmenter: semantic segmentation needs the renderer's ids");
  }
  if (!(options.k > 0.0) || !(options.reference_interval_s > 0.0) || options.fast_max_side_px < 8) {
    throw std::invalid_argument(
        "FlowSegmenter: k and reference_interval_s must be positive, fast_max_side_px >= 8");
  }
  // The flow is smooth already (the estimators regularise it): no pre-smoothing, which would
  // also smear the validity channel into valid pixels.
  graph_->segmentation = cv::ximgproc::segmentation::createGraphSegmentation(0.0);
}

FlowSegmenter::~FlowSegmenter() = default;
FlowSegmenter::FlowSegmenter(FlowSegmenter&&) noexcept = default;
FlowSegmenter& FlowSegmenter::operator=(FlowSegmenter&&) noexcept = default;

void FlowSegmenter::segment(const FlowField& derotated, std::span<const std::uint8_t> excluded,
                            Segmentation& out) {
  const int width = derotated.width();
  const int height = derotated.height();
  const std::size_t pixels = derotated.size();
  if (!excluded.empty() && excluded.size() != pixels) {
    throw std::invalid_argument("FlowSegmenter: exclusion mask has " +
                                std::to_string(excluded.size()) + " pixels, expected " +
                                std::to_string(pixels));
  }

  // Graph features: flow in pixels per reference interval, and a validity channel.
  features_.create(height, width, CV_32FC3);
  const auto to_px_x =
      static_cast<float>(derotated.intrinsics().fx_px * options_.reference_interval_s);
  const auto to_px_y =
      static_cast<float>(derotated.intrinsics().fy_px * options_.reference_interval_s);
  const auto flow = derotated.flow();
  for (int row = 0; row < height; ++row) {
    auto* f = features_.ptr<cv::Vec3f>(row);
    for (int col = 0; col < width; ++col) {
      const std::size_t i = derotated.index(col, row);
      const Eigen::Vector2f& u = flow[i];
      const bool valid = (excluded.empty() || excluded[i] == 0) && u.allFinite();
      f[col] = valid ? cv::Vec3f(u.x() * to_px_x, u.y() * to_px_y, 0.0F)
                     : cv::Vec3f(0.0F, 0.0F, kInvalidMark);
    }
  }

  // The fast method segments a reduced copy; k and the smallest region scale with pixel area so
  // that it finds the same regions, coarser.
  const cv::Mat* graph_input = &features_;
  double scale = 1.0;
  if (method_ == SegmentationMethod::flow_graph_fast &&
      std::max(width, height) > options_.fast_max_side_px) {
    scale = static_cast<double>(options_.fast_max_side_px) / std::max(width, height);
    const cv::Size reduced_size(std::max(1, static_cast<int>(std::lround(width * scale))),
                                std::max(1, static_cast<int>(std::lround(height * scale))));
    cv::resize(features_, reduced_, reduced_size, 0.0, 0.0, cv::INTER_NEAREST);
    graph_input = &reduced_;
  }
  const double area_scale = (static_cast<double>(graph_input->total()) / pixels);
  const int min_region_px =
      std::max(1, static_cast<int>(options_.min_region_fraction * graph_input->total()));
  graph_->segmentation->setK(static_cast<float>(options_.k * area_scale));
  graph_->segmentation->setMinSize(min_region_px);
  graph_->segmentation->processImage(*graph_input, graph_labels_);

  double max_label = 0.0;
  cv::minMaxLoc(graph_labels_, nullptr, &max_label);
  const auto segments = static_cast<std::size_t>(max_label) + 1;

  // Labels at full resolution (nearest reduced pixel), kept only for valid pixels.
  out.width = width;
  out.height = height;
  out.labels.assign(pixels, Segmentation::kNoRegion);
  valid_counts_.assign(segments, 0);
  const double col_scale = static_cast<double>(graph_labels_.cols) / width;
  const double row_scale = static_cast<double>(graph_labels_.rows) / height;
  for (int row = 0; row < height; ++row) {
    const auto* f = features_.ptr<cv::Vec3f>(row);
    const auto* g = graph_labels_.ptr<std::int32_t>(
        std::min(graph_labels_.rows - 1, static_cast<int>(row * row_scale)));
    for (int col = 0; col < width; ++col) {
      if (f[col][2] != 0.0F)
        continue;
      const std::int32_t segment =
          g[std::min(graph_labels_.cols - 1, static_cast<int>(col * col_scale))];
      out.labels[derotated.index(col, row)] = segment;
      ++valid_counts_[static_cast<std::size_t>(segment)];
    }
  }

  // Compact the segments with enough valid pixels into regions 0..n-1.
  const auto min_full_px = static_cast<std::int32_t>(options_.min_region_fraction * pixels);
  region_of_segment_.assign(segments, Segmentation::kNoRegion);
  std::int32_t regions = 0;
  for (std::size_t s = 0; s < segments; ++s) {
    if (valid_counts_[s] > 0 && valid_counts_[s] >= min_full_px)
      region_of_segment_[s] = regions++;
  }
  for (std::int32_t& label : out.labels) {
    if (label != Segmentation::kNoRegion) {
      label = region_of_segment_[static_cast<std::size_t>(label)];
    }
  }
  out.kinds.assign(static_cast<std::size_t>(regions), RegionKind::visible);
  assign_track_ids(out);
}

void FlowSegmenter::assign_track_ids(Segmentation& out) {
  const auto regions = static_cast<std::size_t>(out.region_count());
  const std::size_t previous = previous_ids_.size();
  const bool comparable = previous_labels_.size() == out.labels.size();
  overlaps_.assign(regions * previous, 0);
  region_sizes_.assign(regions, 0);
  for (std::size_t i = 0; i < out.labels.size(); ++i) {
    const std::int32_t label = out.labels[i];
    if (label == Segmentation::kNoRegion)
      continue;
    ++region_sizes_[static_cast<std::size_t>(label)];
    if (comparable && previous_labels_[i] != Segmentation::kNoRegion) {
      ++overlaps_[static_cast<std::size_t>(label) * previous +
                  static_cast<std::size_t>(previous_labels_[i])];
    }
  }
  // Each region takes the id of the previous region covering most of it, when that covers at
  // least half of it; a previous region's id goes to one region only, the one it covers most.
  out.source_ids.assign(regions, -1);
  for (std::size_t r = 0; r < regions; ++r) {
    std::int32_t best_count = 0;
    std::size_t best = previous;
    for (std::size_t p = 0; p < previous; ++p) {
      if (overlaps_[r * previous + p] > best_count) {
        best_count = overlaps_[r * previous + p];
        best = p;
      }
    }
    if (best == previous || 2 * best_count < region_sizes_[r])
      continue;
    bool taken_by_larger = false;
    for (std::size_t other = 0; other < regions && !taken_by_larger; ++other) {
      taken_by_larger = other != r && overlaps_[other * previous + best] > best_count;
    }
    if (!taken_by_larger)
      out.source_ids[r] = previous_ids_[best];
  }
  for (std::int32_t& id : out.source_ids) {
    if (id < 0)
      id = next_track_id_++;
  }
  previous_labels_.assign(out.labels.begin(), out.labels.end());
  previous_ids_.assign(out.source_ids.begin(), out.source_ids.end());
}

}  // namespace flowsteer::servo
