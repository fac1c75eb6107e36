#include "flowsteer/servo/flow_segmentation.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

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

namespace {

// Felzenszwalb–Huttenlocher segmentation (IJCV 2004) of the 4-connected grid of pixels of a
// CV_32FC4 image: OpenCV's ximgproc GraphSegmentation with sigma 0 (its edge weights, merge test,
// small-segment merge, and segments numbered in order of first appearance), with three
// differences. Its buffers are kept from call to call (OpenCV allocates its graph and its sets,
// and converts and copies the image, on every call). Each edge is taken once, not once from each
// end. And edges of equal weight go in a defined order, by pixel and direction, where OpenCV's
// order is whatever std::sort leaves them in: a stable radix sort of the weights does it in
// linear time. Where no two edges weigh the same the segments are OpenCV's to the pixel.
class GridSegmentation {
 public:
  // Writes each pixel's segment to `labels` (CV_32S, the image's size) and returns how many.
  int segment(const cv::Mat& features, float k, int min_size, cv::Mat& labels) {
    const int width = features.cols;
    const int height = features.rows;
    const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    build_edges(features);
    sort_edges();
    parent_.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
      parent_[p] = static_cast<std::int32_t>(p);
    }
    size_.assign(pixels, 1);
    threshold_.assign(pixels, k);
    // A merge when the edge is no heavier than either segment's internal difference plus
    // k / |segment|, lightest edges first.
    for (const std::uint64_t edge : edges_) {
      const auto [a, b] = ends(edge, width);
      const std::int32_t root_a = find(a);
      const std::int32_t root_b = find(b);
      const float weight = weight_of(edge);
      if (root_a != root_b && weight <= threshold_[static_cast<std::size_t>(root_a)] &&
          weight <= threshold_[static_cast<std::size_t>(root_b)]) {
        const std::int32_t root = join(root_a, root_b);
        threshold_[static_cast<std::size_t>(root)] =
            weight + k / static_cast<float>(size_[static_cast<std::size_t>(root)]);
      }
    }
    // Segments under min_size join a neighbour, again along the lightest edges first.
    for (const std::uint64_t edge : edges_) {
      const auto [a, b] = ends(edge, width);
      const std::int32_t root_a = find(a);
      const std::int32_t root_b = find(b);
      if (root_a != root_b && (size_[static_cast<std::size_t>(root_a)] < min_size ||
                               size_[static_cast<std::size_t>(root_b)] < min_size)) {
        join(root_a, root_b);
      }
    }
    labels.create(height, width, CV_32S);
    label_of_root_.assign(pixels, -1);
    std::int32_t segments = 0;
    auto* label = labels.ptr<std::int32_t>();
    for (std::size_t p = 0; p < pixels; ++p) {
      std::int32_t& of_root =
          label_of_root_[static_cast<std::size_t>(find(static_cast<std::int32_t>(p)))];
      if (of_root < 0)
        of_root = segments++;
      label[p] = of_root;
    }
    return segments;
  }

 private:
  // An edge is its weight's bits (a non-negative float's bits order as the floats do) over its
  // id, 2 p + the direction from pixel p to its neighbour (right, down).
  static float weight_of(std::uint64_t edge) {
    return std::bit_cast<float>(static_cast<std::uint32_t>(edge >> 32U));
  }
  static std::pair<std::int32_t, std::int32_t> ends(std::uint64_t edge, int width) {
    const auto id = static_cast<std::uint32_t>(edge);
    const auto a = static_cast<std::int32_t>(id / 2U);
    return {a, a + (id % 2U == 0U ? 1 : width)};
  }

  // Each edge once, in order of id: which of several equally light edges merges a small segment
  // changes the regions it joins, so that order is part of the result.
  void build_edges(const cv::Mat& features) {
    edges_.clear();
    const int width = features.cols;
    const int height = features.rows;
    for (int row = 0; row < height; ++row) {
      const auto* f = features.ptr<cv::Vec4f>(row);
      const auto* below = row + 1 < height ? features.ptr<cv::Vec4f>(row + 1) : nullptr;
      for (int col = 0; col < width; ++col) {
        const auto id = 2U * static_cast<std::uint32_t>(row * width + col);
        if (col + 1 < width)
          edges_.push_back(edge(f[col], f[col + 1], id));
        if (below != nullptr)
          edges_.push_back(edge(f[col], below[col], id + 1U));
      }
    }
  }
  static std::uint64_t edge(const cv::Vec4f& a, const cv::Vec4f& b, std::uint32_t id) {
    // OpenCV sums the squares in double and keeps the sum in a float: the same weights here.
    float sum = 0.0F;
    for (int c = 0; c < 4; ++c) {
      const double d = a[c] - b[c];
      sum = static_cast<float>(sum + d * d);
    }
    return (static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(std::sqrt(sum))) << 32U) | id;
  }

  // Least significant digit first, 11 bits a pass over the weight's 32: each pass is stable, so
  // edges of equal weight keep the order build_edges made them in.
  void sort_edges() {
    constexpr unsigned kDigitBits = 11U;
    constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
    sorted_.resize(edges_.size());
    for (unsigned shift = 32U; shift < 64U; shift += kDigitBits) {
      bucket_starts_.assign(kBuckets + 1, 0);
      for (const std::uint64_t edge : edges_) {
        ++bucket_starts_[((edge >> shift) & (kBuckets - 1)) + 1];
      }
      for (std::size_t b = 1; b <= kBuckets; ++b) {
        bucket_starts_[b] += bucket_starts_[b - 1];
      }
      for (const std::uint64_t edge : edges_) {
        sorted_[bucket_starts_[(edge >> shift) & (kBuckets - 1)]++] = edge;
      }
      edges_.swap(sorted_);
    }
  }

  std::int32_t find(std::int32_t p) {
    while (parent_[static_cast<std::size_t>(p)] != p) {
      // Path halving: each step also links p to its grandparent.
      std::int32_t& parent = parent_[static_cast<std::size_t>(p)];
      parent = parent_[static_cast<std::size_t>(parent)];
      p = parent;
    }
    return p;
  }
  // Joins two roots, the smaller segment under the larger; returns the new root.
  std::int32_t join(std::int32_t a, std::int32_t b) {
    if (size_[static_cast<std::size_t>(a)] < size_[static_cast<std::size_t>(b)])
      std::swap(a, b);
    parent_[static_cast<std::size_t>(b)] = a;
    size_[static_cast<std::size_t>(a)] += size_[static_cast<std::size_t>(b)];
    return a;
  }

  std::vector<std::uint64_t> edges_;
  std::vector<std::uint64_t> sorted_;
  std::vector<std::size_t> bucket_starts_;
  std::vector<std::int32_t> parent_;
  std::vector<std::int32_t> size_;
  std::vector<float> threshold_;
  std::vector<std::int32_t> label_of_root_;
};

// Counts keys into counts[key] by runs: neighbouring pixels mostly share a key, and adding one
// to the same counter pixel after pixel waits each time for the previous store.
class RunCounter {
 public:
  explicit RunCounter(std::vector<std::int32_t>& counts) : counts_(counts) {}
  void add(std::size_t key) {
    if (key != key_) {
      counts_[key_] += run_;
      key_ = key;
      run_ = 0;
    }
    ++run_;
  }
  // Adds the current run; call after the last add.
  void flush() {
    counts_[key_] += run_;
    run_ = 0;
  }

 private:
  std::vector<std::int32_t>& counts_;
  std::size_t key_ = 0;
  std::int32_t run_ = 0;
};

// Whether pixel i's flow is one to segment: not excluded, finite, and of something seen. Where a
// field with depth has none (NaN or +inf), the pixel sees nothing, the sky past the world: its
// flow, none after derotation, joined the tops of walls on either side of the view into one
// region whose outline closed the way ahead.
bool has_flow(const FlowField& derotated, std::span<const std::uint8_t> excluded, std::size_t i) {
  return (excluded.empty() || excluded[i] == 0) && derotated.flow()[i].allFinite() &&
         (!derotated.has_depth() || std::isfinite(derotated.depth()[i]));
}

// The fast method segments the features at the nearest pixels of a grid of at most
// fast_max_side_px per side; k and the smallest region scale with pixel area so that it finds
// the same regions, coarser.
cv::Size graph_size(SegmentationMethod method, const FlowSegmentationOptions& options, int width,
                    int height) {
  if (method != SegmentationMethod::flow_graph_fast ||
      std::max(width, height) <= options.fast_max_side_px) {
    return {width, height};
  }
  const double scale = static_cast<double>(options.fast_max_side_px) / std::max(width, height);
  return {std::max(1, static_cast<int>(std::lround(width * scale))),
          std::max(1, static_cast<int>(std::lround(height * scale)))};
}

// Graph features at the nearest pixel of each graph pixel: flow in pixels per reference
// interval, a validity channel, and the grey level times grey_weight (0 without a grey image).
void fill_graph_features(const FlowField& derotated, std::span<const std::uint8_t> excluded,
                         const cv::Mat& grey, const FlowSegmentationOptions& options, cv::Size size,
                         cv::Mat& features) {
  const auto to_px_x =
      static_cast<float>(derotated.intrinsics().fx_px * options.reference_interval_s);
  const auto to_px_y =
      static_cast<float>(derotated.intrinsics().fy_px * options.reference_interval_s);
  const auto grey_weight = static_cast<float>(grey.empty() ? 0.0 : options.grey_weight);
  const auto flow = derotated.flow();
  features.create(size, CV_32FC4);
  for (int row = 0; row < size.height; ++row) {
    auto* f = features.ptr<cv::Vec4f>(row);
    const int source_row = row * derotated.height() / size.height;
    const std::uint8_t* grey_row = grey.empty() ? nullptr : grey.ptr<std::uint8_t>(source_row);
    for (int col = 0; col < size.width; ++col) {
      const int source_col = col * derotated.width() / size.width;
      const std::size_t i = derotated.index(source_col, source_row);
      const float shade = grey_row == nullptr ? 0.0F : grey_weight * grey_row[source_col];
      f[col] = has_flow(derotated, excluded, i)
                   ? cv::Vec4f(flow[i].x() * to_px_x, flow[i].y() * to_px_y, 0.0F, shade)
                   : cv::Vec4f(0.0F, 0.0F, kInvalidMark, 0.0F);
    }
  }
}

// The merge test never joins pixels with and without flow (kInvalidMark, which excluded pixels
// get too), but the merge of small segments does: an island of flow under min_region_px joins
// the pixels without flow around it. Such islands (a striped agent's stripes fail the texture
// test between them) are scattered over the image and would add up to one region whose fit
// mixes every motion in view. A segment is kept only when most of its graph pixels have flow:
// `balance` gets, per segment, its graph pixels with flow less those without.
void count_flow_balance(const cv::Mat& labels, const cv::Mat& features, std::size_t segments,
                        std::vector<std::int32_t>& balance) {
  balance.assign(segments, 0);
  for (int row = 0; row < labels.rows; ++row) {
    const auto* label = labels.ptr<std::int32_t>(row);
    const auto* f = features.ptr<cv::Vec4f>(row);
    for (int col = 0; col < labels.cols; ++col) {
      balance[static_cast<std::size_t>(label[col])] += f[col][2] == 0.0F ? 1 : -1;
    }
  }
}

// Labels at full resolution (nearest graph pixel), kept only for pixels with flow, into `labels`.
// Counts go one slot up into `counts`, slot 0 counting the pixels without a label, so that no
// pixel takes a branch. `graph_cols` is scratch.
void label_full_resolution(const FlowField& derotated, std::span<const std::uint8_t> excluded,
                           const cv::Mat& graph_labels, std::vector<int>& graph_cols,
                           std::vector<std::int32_t>& labels, std::vector<std::int32_t>& counts) {
  const int width = derotated.width();
  const int height = derotated.height();
  graph_cols.resize(static_cast<std::size_t>(width));
  const double col_scale = static_cast<double>(graph_labels.cols) / width;
  const double row_scale = static_cast<double>(graph_labels.rows) / height;
  for (int col = 0; col < width; ++col) {
    graph_cols[static_cast<std::size_t>(col)] =
        std::min(graph_labels.cols - 1, static_cast<int>(col * col_scale));
  }
  RunCounter count(counts);
  for (int row = 0; row < height; ++row) {
    const auto* g = graph_labels.ptr<std::int32_t>(
        std::min(graph_labels.rows - 1, static_cast<int>(row * row_scale)));
    for (int col = 0; col < width; ++col) {
      const std::size_t i = derotated.index(col, row);
      const std::int32_t segment = has_flow(derotated, excluded, i)
                                       ? g[graph_cols[static_cast<std::size_t>(col)]]
                                       : Segmentation::kNoRegion;
      labels[i] = segment;
      count.add(static_cast<std::size_t>(segment + 1));
    }
  }
  count.flush();
}

// Numbers the segments kept (enough pixels with flow, most of its graph pixels with flow) as
// regions 0..n-1: region_of_label is indexed one up, like `counts`; region_sizes gets each
// region's pixels.
void compact_regions(std::span<const std::int32_t> counts, std::span<const std::int32_t> balance,
                     std::int32_t min_px, std::vector<std::int32_t>& region_of_label,
                     std::vector<std::int32_t>& region_sizes) {
  const std::size_t segments = balance.size();
  region_of_label.assign(segments + 1, Segmentation::kNoRegion);
  region_sizes.clear();
  for (std::size_t s = 1; s <= segments; ++s) {
    if (counts[s] > 0 && counts[s] >= min_px && balance[s - 1] > 0) {
      region_of_label[s] = static_cast<std::int32_t>(region_sizes.size());
      region_sizes.push_back(counts[s]);
    }
  }
}

// Where pixel (col, row) was `motion.since_previous_s` ago: back along its derotated flow and the
// camera's rotation, to the nearest pixel; -1 when that is outside the image.
std::int32_t pixel_before(const FlowField& derotated, const ViewMotion& motion, int col, int row) {
  const Eigen::Vector2d rate =
      derotated.flow()[derotated.index(col, row)].cast<double>() +
      rotational_flow(derotated.x(col), derotated.y(row), motion.camera_omega);
  const double was_col =
      std::round(col - derotated.intrinsics().fx_px * motion.since_previous_s * rate.x());
  const double was_row =
      std::round(row - derotated.intrinsics().fy_px * motion.since_previous_s * rate.y());
  if (!(was_col >= 0.0 && was_col < derotated.width() && was_row >= 0.0 &&
        was_row < derotated.height())) {
    return -1;
  }
  return static_cast<std::int32_t>(was_row) * derotated.width() +
         static_cast<std::int32_t>(was_col);
}

// Turns each pixel's segment in `labels` into its region, and counts in the same pass the pixels
// each region shares with each of the previous frame's `previous` regions (when that frame had as
// many pixels), one row and column up in `overlaps`: a pixel's previous region is the one where
// it was then (pixel_before).
void relabel_and_count_overlaps(const FlowField& derotated, const ViewMotion& motion,
                                std::span<const std::int32_t> region_of_label, std::size_t regions,
                                std::span<const std::int32_t> previous_labels, std::size_t previous,
                                std::vector<std::int32_t>& labels,
                                std::vector<std::int32_t>& overlaps) {
  const bool comparable = previous_labels.size() == labels.size();
  overlaps.assign((regions + 1) * (previous + 1), 0);
  RunCounter overlap(overlaps);
  for (int row = 0; row < derotated.height(); ++row) {
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = derotated.index(col, row);
      const std::int32_t region = region_of_label[static_cast<std::size_t>(labels[i] + 1)];
      labels[i] = region;
      if (!comparable || region == Segmentation::kNoRegion)
        continue;
      const std::int32_t was = pixel_before(derotated, motion, col, row);
      const std::int32_t previous_region =
          was < 0 ? Segmentation::kNoRegion : previous_labels[static_cast<std::size_t>(was)];
      overlap.add(static_cast<std::size_t>(region + 1) * (previous + 1) +
                  static_cast<std::size_t>(previous_region + 1));
    }
  }
  overlap.flush();
}

}  // namespace

struct FlowSegmenter::Graph {
  cv::Ptr<cv::ximgproc::segmentation::GraphSegmentation> opencv;  // flow_graph
  GridSegmentation own;                                           // flow_graph_fast

  // Writes each pixel's segment to `labels` (CV_32S) and returns how many.
  std::size_t segment(const cv::Mat& features, float k, int min_size, cv::Mat& labels) {
    if (opencv) {
      opencv->setK(k);
      opencv->setMinSize(min_size);
      opencv->processImage(features, labels);
      double max_label = 0.0;
      cv::minMaxLoc(labels, nullptr, &max_label);
      return static_cast<std::size_t>(max_label) + 1;
    }
    return static_cast<std::size_t>(own.segment(features, k, min_size, labels));
  }
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
  if (method == SegmentationMethod::flow_graph) {
    // The flow is smooth already (the estimators regularise it): no pre-smoothing, which would
    // also smear the validity channel into valid pixels.
    graph_->opencv = cv::ximgproc::segmentation::createGraphSegmentation(0.0);
  }
}

FlowSegmenter::~FlowSegmenter() = default;
FlowSegmenter::FlowSegmenter(FlowSegmenter&&) noexcept = default;
FlowSegmenter& FlowSegmenter::operator=(FlowSegmenter&&) noexcept = default;

void FlowSegmenter::segment(const FlowField& derotated, std::span<const std::uint8_t> excluded,
                            const cv::Mat& grey, Segmentation& out, const ViewMotion& motion) {
  const std::size_t pixels = derotated.size();
  if (!excluded.empty() && excluded.size() != pixels) {
    throw std::invalid_argument("FlowSegmenter: exclusion mask has " +
                                std::to_string(excluded.size()) + " pixels, expected " +
                                std::to_string(pixels));
  }
  if (!grey.empty() && (grey.type() != CV_8UC1 || grey.cols != derotated.width() ||
                        grey.rows != derotated.height())) {
    throw std::invalid_argument("FlowSegmenter: the grey image must be 8-bit, one channel, " +
                                std::to_string(derotated.width()) + "x" +
                                std::to_string(derotated.height()));
  }
  fill_graph_features(derotated, excluded, grey, options_,
                      graph_size(method_, options_, derotated.width(), derotated.height()),
                      features_);
  const double area_scale = static_cast<double>(features_.total()) / pixels;
  const int min_region_px =
      std::max(1, static_cast<int>(options_.min_region_fraction * features_.total()));
  const auto k = static_cast<float>(options_.k * area_scale);
  const std::size_t segments = graph_->segment(features_, k, min_region_px, graph_labels_);
  count_flow_balance(graph_labels_, features_, segments, flow_balance_);

  out.width = derotated.width();
  out.height = derotated.height();
  out.labels.resize(pixels);
  valid_counts_.assign(segments + 1, 0);
  label_full_resolution(derotated, excluded, graph_labels_, graph_cols_, out.labels, valid_counts_);
  compact_regions(valid_counts_, flow_balance_,
                  static_cast<std::int32_t>(options_.min_region_fraction * pixels),
                  region_of_label_, region_sizes_);
  relabel_and_count_overlaps(derotated, motion, region_of_label_, region_sizes_.size(),
                             previous_labels_, previous_ids_.size(), out.labels, overlaps_);
  out.kinds.assign(region_sizes_.size(), RegionKind::visible);
  assign_track_ids(out);
}

void FlowSegmenter::assign_track_ids(Segmentation& out) {
  const auto regions = static_cast<std::size_t>(out.region_count());
  const std::size_t previous = previous_ids_.size();
  const auto overlap = [&](std::size_t region, std::size_t previous_region) {
    return overlaps_[(region + 1) * (previous + 1) + previous_region + 1];
  };
  // Each region takes the id of the previous region covering most of it, when that covers at
  // least half of it or at least half of that region is in it (a region that grew, as when the
  // untextured middle of a wall gets flow, or that took in a neighbour); a previous region's id
  // goes to one region only, the one it covers most.
  out.source_ids.assign(regions, -1);
  for (std::size_t r = 0; r < regions; ++r) {
    std::int32_t best_count = 0;
    std::size_t best = previous;
    for (std::size_t p = 0; p < previous; ++p) {
      if (overlap(r, p) > best_count) {
        best_count = overlap(r, p);
        best = p;
      }
    }
    if (best == previous ||
        (2 * best_count < region_sizes_[r] && 2 * best_count < previous_sizes_[best]))
      continue;
    bool taken_by_larger = false;
    for (std::size_t other = 0; other < regions && !taken_by_larger; ++other) {
      taken_by_larger = other != r && overlap(other, best) > best_count;
    }
    if (!taken_by_larger)
      out.source_ids[r] = previous_ids_[best];
  }
  for (std::size_t r = 0; r < regions; ++r) {
    if (out.source_ids[r] >= 0)
      continue;
    out.source_ids[r] = next_track_id_++;
    if (options_.confirm_new_regions)
      out.kinds[r] = RegionKind::unconfirmed;
  }
  previous_labels_.assign(out.labels.begin(), out.labels.end());
  previous_ids_.assign(out.source_ids.begin(), out.source_ids.end());
  previous_sizes_.assign(region_sizes_.begin(), region_sizes_.end());
}

}  // namespace flowsteer::servo
