#include "flowsteer/servo/untextured_fill.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {

namespace {

bool has_flow(const FlowField& field, int col, int row) {
  return field.at(col, row).allFinite();
}

}  // namespace

int UntexturedFill::fill(FlowField& derotated, const cv::Mat& grey, double image_noise_grey,
                         const base::CameraMount& mount, double speed_mps,
                         std::span<const std::uint8_t> ground_mask) {
  if (ground_mask.size() != derotated.size()) {
    throw std::invalid_argument("UntexturedFill: ground mask has " +
                                std::to_string(ground_mask.size()) + " entries for a field of " +
                                std::to_string(derotated.size()) + " pixels");
  }
  inverse_distance_.assign(derotated.size(), 0.0F);
  filled_.assign(derotated.size(), 0);
  if (!options_.enabled) {
    return 0;
  }
  if (grey.type() != CV_8UC1 || grey.cols != derotated.width() || grey.rows != derotated.height()) {
    throw std::invalid_argument("UntexturedFill: the grey image must be 8-bit, one channel, " +
                                std::to_string(derotated.width()) + "x" +
                                std::to_string(derotated.height()));
  }
  // A step of 4σ in the mean of three columns' two-row differences (each σ√2) is 5 of their
  // standard deviations: noise alone makes almost none over a column's few hundred rows.
  edge_threshold_ = std::max(options_.min_edge_grey, 4.0 * image_noise_grey);
  find_feet(derotated, grey, mount, ground_mask);

  const FlatGround ground(mount);
  const double interval_s = derotated.interval_s();
  int filled = 0;
  for (int row = 0; row < derotated.height(); ++row) {
    const double y = derotated.y(row);
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = derotated.index(col, row);
      if (inverse_distance_[i] <= 0.0F) {
        continue;
      }
      const auto depth_m = ground.depth_at_distance_ahead(y, 1.0 / inverse_distance_[i]);
      if (!depth_m) {
        continue;
      }
      derotated.flow()[i] =
          ground.static_flow_at(derotated.x(col), y, *depth_m, speed_mps, interval_s).cast<float>();
      filled_[i] = 1;
      ++filled;
    }
  }
  return filled;
}

// Per column: the floor goes up from the image's bottom (pixels without flow, or ground, with
// gaps of at most contact_search_px) to the first thing with flow of its own; its last grey-level
// edge below the horizon is a surface's foot, and the surface goes up to its own top edge, which
// one taller than the camera has above the horizon. Mostly without flow in between, it is an
// untextured surface: its pixels without flow get the foot's inverse distance.
void UntexturedFill::find_feet(const FlowField& field, const cv::Mat& grey,
                               const base::CameraMount& mount,
                               std::span<const std::uint8_t> ground_mask) {
  const FlatGround ground(mount);
  int first_ground_row = field.height();
  for (int row = 0; row < field.height(); ++row) {
    if (ground.depth_at(0.0, field.y(row))) {
      first_ground_row = row;
      break;
    }
  }
  for (int col = 0; col < field.width(); ++col) {
    const int foot = find_foot(field, grey, ground_mask, col, first_ground_row);
    if (foot < 0) {
      continue;
    }
    const double y_foot = field.y(foot);
    const double ahead_m = ground.distance_ahead_m(y_foot, *ground.depth_at(0.0, y_foot));
    if (ahead_m > options_.max_distance_ahead_m) {
      continue;
    }
    const int head = lowest_edge(grey, col, 0, first_ground_row - 1);
    int without_flow = 0;
    for (int row = head + 1; row <= foot; ++row) {
      without_flow += has_flow(field, col, row) ? 0 : 1;
    }
    if (without_flow < options_.min_untextured_share * (foot - head)) {
      continue;
    }
    for (int row = head + 1; row <= foot; ++row) {
      if (!has_flow(field, col, row)) {
        inverse_distance_[field.index(col, row)] = static_cast<float>(1.0 / ahead_m);
      }
    }
  }
}

// The highest grey-level edge of the floor below the horizon in column col; -1 when there is
// none.
int UntexturedFill::find_foot(const FlowField& field, const cv::Mat& grey,
                              std::span<const std::uint8_t> ground_mask, int col,
                              int first_ground_row) const {
  int foot = -1;
  int gap = 0;
  for (int row = field.height() - 1; row >= first_ground_row; --row) {
    const bool floor = !has_flow(field, col, row) || ground_mask[field.index(col, row)] != 0;
    gap = floor ? 0 : gap + 1;
    if (gap > options_.contact_search_px) {
      break;
    }
    if (floor && is_edge(grey, col, row)) {
      foot = row;
    }
  }
  return foot;
}

// Whether the grey level steps by at least the edge threshold across the two rows either side
// of `row` (summed over three columns): where one surface's appearance ends.
bool UntexturedFill::is_edge(const cv::Mat& grey, int col, int row) const {
  if (row < 1 || row > grey.rows - 2) {
    return false;
  }
  const int first_col = std::max(col - 1, 0);
  const int last_col = std::min(col + 1, grey.cols - 1);
  const auto* above = grey.ptr<std::uint8_t>(row - 1);
  const auto* below = grey.ptr<std::uint8_t>(row + 1);
  int step = 0;
  for (int c = first_col; c <= last_col; ++c) {
    step += static_cast<int>(below[c]) - static_cast<int>(above[c]);
  }
  return std::abs(step) >= edge_threshold_ * (last_col - first_col + 1);
}

// The lowest edge row in [top, bottom] of column col; top − 1 when there is none.
int UntexturedFill::lowest_edge(const cv::Mat& grey, int col, int top, int bottom) const {
  for (int row = bottom; row >= top; --row) {
    if (is_edge(grey, col, row)) {
      return row;
    }
  }
  return top - 1;
}

}  // namespace flowsteer::servo
