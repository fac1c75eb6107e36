#include "flowsteer/servo/untextured_fill.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "flat_ground_flow.hpp"
#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {

namespace {

bool has_flow(const FlowField& field, int col, int row) {
  return field.at(col, row).allFinite();
}

// How far ahead of the camera the floor seen at (col, row) is: a foot's distance.
double ahead_of_floor_m(const FlowField& field, const FlatGround& ground, int col, int row) {
  const double y = field.y(row);
  return ground.distance_ahead_m(y, *ground.depth_at(field.x(col), y));
}

// Pixels of displacement over the field's interval per unit of its flow.
double to_px(const FlowField& field) {
  return field.intrinsics().fx_px * std::max(field.interval_s(), 1e-3);
}

// A line on the ground: the points p with normal · p = offset.
struct GroundLine {
  Eigen::Vector2d normal;
  double offset = 0.0;
};

// The total-least-squares line through `points` (body frame, metres), when they lie along one:
// spread over min_line_span_m and within the RMS the options allow.
std::optional<GroundLine> fit_line(std::span<const Eigen::Vector2d> points,
                                   const UntexturedFillOptions& options) {
  if (static_cast<int>(points.size()) < options.min_line_feet) {
    return std::nullopt;
  }
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) {
    centre += p;
  }
  centre /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& p : points) {
    scatter += (p - centre) * (p - centre).transpose();
  }
  scatter /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
  // Eigenvalues ascending: the smallest is the variance across the line, the largest along it.
  const double across = std::sqrt(std::max(solver.eigenvalues()(0), 0.0));
  const double along = std::sqrt(std::max(solver.eigenvalues()(1), 0.0));
  // The span of points spread evenly along a line is √12 times their standard deviation.
  if (std::sqrt(12.0) * along < options.min_line_span_m ||
      across > options.max_line_rms_m + options.max_line_rms_share * centre.norm()) {
    return std::nullopt;
  }
  const Eigen::Vector2d normal = solver.eigenvectors().col(0);
  return GroundLine{normal, normal.dot(centre)};
}

// The middle value of `values` (the upper one of an even count), which it reorders.
double upper_median(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// How far ahead the ray through the bottom row's ground point bottom_m meets the nearer of
// `lines`, where it meets one nearer than bottom_m (within `slack` of its distance); else 0.
double ahead_on_lines(std::span<const std::optional<GroundLine>> lines,
                      const Eigen::Vector2d& bottom_m, double slack) {
  double ahead_m = 0.0;
  for (const auto& line : lines) {
    if (!line || std::abs(line->normal.dot(bottom_m)) < 1e-9) {
      continue;
    }
    // The ray's point t · bottom_m is on the line; t < 1 is nearer than the bottom row sees.
    const double t = line->offset / line->normal.dot(bottom_m);
    if (t > 0.0 && t < 1.0 + slack) {
      const double candidate_m = t * bottom_m.x();
      ahead_m = ahead_m > 0.0 ? std::min(ahead_m, candidate_m) : candidate_m;
    }
  }
  return ahead_m;
}

}  // namespace

int UntexturedFill::fill(FlowField& derotated, const cv::Mat& grey, double image_noise_grey,
                         const base::CameraMount& mount, double speed_mps,
                         std::span<const std::uint8_t> ground_mask,
                         std::span<const Eigen::Vector2f> edge_flow) {
  if (ground_mask.size() != derotated.size() ||
      (!edge_flow.empty() && edge_flow.size() != derotated.size())) {
    throw std::invalid_argument("UntexturedFill: ground mask and edge flow have " +
                                std::to_string(ground_mask.size()) + " and " +
                                std::to_string(edge_flow.size()) + " entries for a field of " +
                                std::to_string(derotated.size()) + " pixels");
  }
  edge_flow_ = edge_flow;
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
  const FlatGround ground(mount);
  lag_m_ = speed_mps * std::cos(mount.pitch_rad) * derotated.interval_s();
  boxes_.clear();
  box_columns_.clear();
  find_feet(derotated, grey, ground, ground_mask, speed_mps);
  place_hidden_feet(derotated, ground, speed_mps);
  confirm_boxes(derotated, ground, speed_mps);

  const double interval_s = derotated.interval_s();
  int filled = 0;
  auto fill_span = [&](const Span& span) {
    for (int row = span.top_row; row <= span.bottom_row; ++row) {
      const double y = derotated.y(row);
      const auto depth_m = ground.depth_at_distance_ahead(y, span.ahead_m);
      if (has_flow(derotated, span.col, row) || !depth_m) {
        continue;
      }
      const std::size_t i = derotated.index(span.col, row);
      derotated.flow()[i] =
          ground.static_flow_at(derotated.x(span.col), y, *depth_m, speed_mps, interval_s)
              .cast<float>();
      filled_[i] = 1;
      ++filled;
    }
  };
  for (int col = 0; col < derotated.width(); ++col) {
    const Column& column = columns_[static_cast<std::size_t>(col)];
    if (column.ahead_m > 0.0) {
      fill_span({col, column.head + 1, column.bottom, column.ahead_m});
    }
  }
  for (const Span& box : boxes_) {
    fill_span(box);
  }
  return filled;
}

// Per column: the floor goes up from the image's bottom (pixels without flow, or ground, with
// short gaps) to the first thing with flow of its own; its last grey-level edge below the horizon
// is a surface's foot, and the surface goes up to its own top edge, which one taller than the
// camera has above the horizon. A column whose floor shows no edge, and which has no flow from
// its bottom to that top edge, may be a surface whose foot is below the image.
void UntexturedFill::find_feet(const FlowField& field, const cv::Mat& grey,
                               const FlatGround& ground, std::span<const std::uint8_t> ground_mask,
                               double speed_mps) {
  first_ground_row_ = field.height();
  for (int row = 0; row < field.height(); ++row) {
    if (ground.depth_at(0.0, field.y(row))) {
      first_ground_row_ = row;
      break;
    }
  }
  columns_.assign(static_cast<std::size_t>(field.width()), Column{});
  const int last_row = field.height() - 1;
  for (int col = 0; col < field.width(); ++col) {
    Column& column = columns_[static_cast<std::size_t>(col)];
    column.head = lowest_edge(grey, col, 0, first_ground_row_ - 1);
    find_floor_edges(field, grey, ground_mask, col);
    if (edge_bands_.empty()) {
      // Hidden below the image: nothing but the surface from the bottom row up, no edge of a
      // floor below the horizon. Its distance ahead comes from its neighbours' feet.
      column.foot_hidden =
          lowest_edge(grey, col, first_ground_row_, last_row) < first_ground_row_ &&
          stands_at(field, ground, col, column.head + 1, last_row, 0.0, speed_mps);
      column.bottom = last_row;
      continue;
    }
    find_boxes(field, ground, col, speed_mps);
    const int foot = edge_bands_.back().top_row;
    const double ahead_m = ahead_of_floor_m(field, ground, col, foot);
    if (ahead_m > options_.max_distance_ahead_m ||
        !stands_at(field, ground, col, column.head + 1, foot, ahead_m, speed_mps)) {
      continue;
    }
    column.bottom = foot;
    column.ahead_m = ahead_m;
    column.foot_m = *ground.point_at(field.x(col), field.y(foot));
  }
}

// Surfaces lower than the camera (a box) between two edges of column col's floor, without flow
// between them: candidates, with the votes of the upper edge, the box's top (confirm_boxes).
void UntexturedFill::find_boxes(const FlowField& field, const FlatGround& ground, int col,
                                double speed_mps) {
  for (std::size_t k = 0; k + 1 < edge_bands_.size(); ++k) {
    const int foot = edge_bands_[k].top_row;
    const EdgeBand& top = edge_bands_[k + 1];
    const double ahead_m = ahead_of_floor_m(field, ground, col, foot);
    if (ahead_m > options_.max_distance_ahead_m ||
        !stands_at(field, ground, col, top.bottom_row + 1, foot, ahead_m, speed_mps)) {
      continue;
    }
    BoxColumn box{{col, top.top_row, foot, ahead_m}, {}};
    for (int row = std::max(top.top_row - options_.edge_votes_px, first_ground_row_);
         row <= std::min(top.bottom_row + options_.edge_votes_px, foot); ++row) {
      vote(field, ground, col, row, ahead_m, speed_mps, box.votes);
    }
    box_columns_.push_back(box);
  }
}

// A box is a run of neighbouring candidate columns whose feet and tops line up. Its edges move as
// a box as near as its foot does, not as the floor behind it (a mark or a shadow on the floor has
// the floor's flow there): its top's votes and its sides', the flow across the side edges within
// two columns of the run's ends, from its top to its foot. Its sides decide where its top is near
// the FOE, at the camera's height, where flow cannot tell near from far.
void UntexturedFill::confirm_boxes(const FlowField& field, const FlatGround& ground,
                                   double speed_mps) {
  const int tolerance = options_.contact_search_px;
  auto continues = [&](const BoxColumn& a, const BoxColumn& b) {
    return b.span.col == a.span.col + 1 &&
           std::abs(b.span.bottom_row - a.span.bottom_row) <= tolerance &&
           std::abs(b.span.top_row - a.span.top_row) <= tolerance;
  };
  // Candidates come column by column, each column's bottom up.
  box_taken_.assign(box_columns_.size(), 0);
  for (std::size_t first = 0; first < box_columns_.size(); ++first) {
    if (box_taken_[first] != 0) {
      continue;
    }
    // Follow the run through the columns to its right.
    run_.assign(1, first);
    for (std::size_t next = first + 1; next < box_columns_.size(); ++next) {
      const BoxColumn& last = box_columns_[run_.back()];
      if (box_columns_[next].span.col > last.span.col + 1) {
        break;
      }
      if (box_taken_[next] == 0 && continues(last, box_columns_[next])) {
        run_.push_back(next);
      }
    }
    EdgeVotes votes;
    for (std::size_t k : run_) {
      box_taken_[k] = 1;
      votes.near += box_columns_[k].votes.near;
      votes.floor += box_columns_[k].votes.floor;
    }
    const struct {
      const Span& end;
      int outward;
    } sides[] = {{box_columns_[run_.front()].span, -1}, {box_columns_[run_.back()].span, 1}};
    for (const auto& [end, outward] : sides) {
      for (int col = end.col - 2 * outward; col != end.col + 3 * outward; col += outward) {
        if (col < 0 || col >= field.width()) {
          continue;
        }
        for (int row = end.top_row; row <= end.bottom_row; ++row) {
          // The floor beside the box, farther than its foot, is no evidence against it.
          if (!has_flow(field, col, row)) {
            vote(field, ground, col, row, end.ahead_m, speed_mps, votes);
          }
        }
      }
    }
    if (votes.near >= options_.min_edge_votes && votes.near > votes.floor) {
      for (std::size_t k : run_) {
        boxes_.push_back(box_columns_[k].span);
      }
    }
  }
}

// One vote of the flow at (col, row), measured or only across an edge there, for a static point
// ahead_m ahead against the floor seen there; none where the two cannot be told apart (at rest,
// near the FOE, or the floor right at the foot).
void UntexturedFill::vote(const FlowField& field, const FlatGround& ground, int col, int row,
                          double ahead_m, double speed_mps, EdgeVotes& votes) const {
  const std::size_t i = field.index(col, row);
  const double x = field.x(col);
  const double y = field.y(row);
  const auto near_flow =
      detail::upright_flow_at(ground, x, y, ahead_m, speed_mps, field.interval_s());
  const auto floor_flow = detail::floor_flow_at(ground, x, y, speed_mps, field.interval_s());
  if (!near_flow || !floor_flow) {
    return;
  }
  Eigen::Vector2d as_near = *near_flow;
  Eigen::Vector2d as_floor = *floor_flow;
  const auto seen = seen_flow(field, i);
  if (!seen) {
    return;
  }
  if (seen->across_edge) {
    // On an edge only the flow across it is measured: compare that component.
    const Eigen::Vector2d across = seen->flow.normalized();
    as_near = across * across.dot(as_near);
    as_floor = across * across.dot(as_floor);
  }
  if ((as_near - as_floor).norm() * to_px(field) < options_.agreement_px) {
    return;
  }
  const Eigen::Vector2d& measured = seen->flow;
  ((measured - as_near).norm() < (measured - as_floor).norm() ? votes.near : votes.floor) += 1;
}

// The flow at pixel i: measured, else only across an edge there (FlowSource::edge_flow); empty
// where there is neither.
std::optional<UntexturedFill::SeenFlow> UntexturedFill::seen_flow(const FlowField& field,
                                                                  std::size_t i) const {
  const Eigen::Vector2d measured = field.flow()[i].cast<double>();
  if (measured.allFinite()) {
    return SeenFlow{measured, false};
  }
  if (edge_flow_.empty() || !edge_flow_[i].allFinite() || edge_flow_[i].isZero()) {
    return std::nullopt;
  }
  return SeenFlow{edge_flow_[i].cast<double>(), true};
}

// Each run of columns whose surface goes down past the image's bottom stands on the line through
// the feet seen on either side of it (the nearer where both give one): a wall beside the agent,
// or one closer than the lowest row sees, whose far part shows its foot. The line must meet the
// column's ray nearer than the bottom row's ground, or the foot would be in view.
void UntexturedFill::place_hidden_feet(const FlowField& field, const FlatGround& ground,
                                       double speed_mps) {
  const int width = field.width();
  const int last_row = field.height() - 1;
  const int max_gap = options_.contact_search_px;
  top_edge_ahead_m_.resize(static_cast<std::size_t>(width));
  auto is_hidden = [&](int col) { return columns_[static_cast<std::size_t>(col)].foot_hidden; };
  // The line through the feet found from `from` outwards in `step`, skipping gaps of max_gap.
  auto line_from = [&](int from, int step) -> std::optional<GroundLine> {
    feet_.clear();
    int gap = 0;
    for (int col = from; col >= 0 && col < width && gap <= max_gap &&
                         static_cast<int>(feet_.size()) < options_.max_line_feet;
         col += step) {
      const Column& column = columns_[static_cast<std::size_t>(col)];
      const bool footed = column.ahead_m > 0.0 && !column.foot_hidden;
      gap = footed ? 0 : gap + 1;
      if (footed) {
        feet_.push_back(column.foot_m);
      }
    }
    return fit_line(feet_, options_);
  };
  for (int first = 0; first < width;) {
    if (!is_hidden(first)) {
      ++first;
      continue;
    }
    int last = first;
    while (last + 1 < width && is_hidden(last + 1)) {
      ++last;
    }
    const std::optional<GroundLine> lines[] = {line_from(first - 1, -1), line_from(last + 1, 1)};
    // Farther than the bottom row's ground (with the slack), the foot would be in view.
    auto farthest_m = [&](int col) {
      const auto bottom_m = ground.point_at(field.x(col), field.y(last_row));
      return bottom_m ? (1.0 + options_.hidden_foot_slack) * bottom_m->x() : 0.0;
    };
    for (int col = first; col <= last; ++col) {
      top_edge_ahead_m_[static_cast<std::size_t>(col)] =
          ahead_of_top_edge(field, ground, col, farthest_m(col), speed_mps);
    }
    for (int col = first; col <= last; ++col) {
      Column& column = columns_[static_cast<std::size_t>(col)];
      const auto bottom_m = ground.point_at(field.x(col), field.y(last_row));
      if (!bottom_m) {
        continue;
      }
      double ahead_m = ahead_on_lines(lines, *bottom_m, options_.hidden_foot_slack);
      if (ahead_m == 0.0) {
        // No line: where its top edge's motion puts it, nearer than the bottom row sees.
        const double edge_m = median_top_edge_ahead(col, first, last);
        ahead_m = edge_m < farthest_m(col) ? edge_m : 0.0;
      }
      if (ahead_m > 0.0 &&
          stands_at(field, ground, col, column.head + 1, last_row, ahead_m, speed_mps)) {
        column.ahead_m = ahead_m;
      }
    }
    first = last + 1;
  }
}

// How far ahead column col's surface is by the motion of its top edge (rows within edge_votes_px
// of its head): the flow measured across the edge against a static point's there, which falls as
// 1 / (Z + v cos θ Δt) with the depth Z (FlatGround::static_flow_at). 0 where the column has no
// top edge, or where its edge, were it as far as farthest_m, would move too little across itself
// to tell (near the FOE, or along the edge).
double UntexturedFill::ahead_of_top_edge(const FlowField& field, const FlatGround& ground, int col,
                                         double farthest_m, double speed_mps) {
  const int head = columns_[static_cast<std::size_t>(col)].head;
  if (head < 0 || !(speed_mps > 0.0)) {
    return 0.0;
  }
  const double x = field.x(col);
  estimates_.clear();
  for (int row = std::max(head - options_.edge_votes_px, 0);
       row <= std::min(head + options_.edge_votes_px, first_ground_row_ - 1); ++row) {
    const auto seen = seen_flow(field, field.index(col, row));
    if (!seen) {
      continue;
    }
    const Eigen::Vector2d& measured = seen->flow;
    const double y = field.y(row);
    const auto farthest_depth_m = ground.depth_at_distance_ahead(y, farthest_m);
    if (!farthest_depth_m || measured.norm() * to_px(field) < options_.agreement_px) {
      continue;
    }
    // Flow of a static point at depth 1 m, as seen across the edge, with no lag.
    const double unit_across =
        measured.normalized().dot(ground.static_flow_at(x, y, 1.0, speed_mps, 0.0));
    if (unit_across / (*farthest_depth_m + lag_m_) * to_px(field) < options_.agreement_px) {
      continue;
    }
    const double depth_m = unit_across / measured.norm() - lag_m_;
    if (depth_m > 0.0) {
      estimates_.push_back(ground.distance_ahead_m(y, depth_m));
    }
  }
  return estimates_.empty() ? 0.0 : upper_median(estimates_);
}

// The median of the top edges' distances ahead (ahead_of_top_edge) of the columns within two of
// col in first..last, when at least three of them have one; else 0.
double UntexturedFill::median_top_edge_ahead(int col, int first, int last) {
  estimates_.clear();
  for (int c = std::max(col - 2, first); c <= std::min(col + 2, last); ++c) {
    if (const double ahead_m = top_edge_ahead_m_[static_cast<std::size_t>(c)]; ahead_m > 0.0) {
      estimates_.push_back(ahead_m);
    }
  }
  return estimates_.size() < 3 ? 0.0 : upper_median(estimates_);
}

// Whether rows top..bottom of column col look like a surface ahead_m ahead: at least
// min_untextured_share of them without flow or with the flow a static point there has
// (ahead_m 0: without flow only).
bool UntexturedFill::stands_at(const FlowField& field, const FlatGround& ground, int col, int top,
                               int bottom, double ahead_m, double speed_mps) const {
  if (bottom < top) {
    return false;
  }
  const double x = field.x(col);
  int alike = 0;
  for (int row = top; row <= bottom; ++row) {
    if (!has_flow(field, col, row)) {
      ++alike;
      continue;
    }
    const double y = field.y(row);
    const auto expected_flow =
        detail::upright_flow_at(ground, x, y, ahead_m, speed_mps, field.interval_s());
    if (!(ahead_m > 0.0) || !expected_flow) {
      continue;
    }
    const Eigen::Vector2d flow = field.at(col, row).cast<double>();
    const Eigen::Vector2d& expected = *expected_flow;
    const double error = (flow - expected).norm();
    // Below the horizon, flow nearer the floor's own there is the floor's.
    const auto floor_flow = detail::floor_flow_at(ground, x, y, speed_mps, field.interval_s());
    const bool floor_like = floor_flow && (flow - *floor_flow).norm() <= error;
    alike += !floor_like && error * to_px(field) <=
                                options_.agreement_px +
                                    options_.agreement_share * expected.norm() * to_px(field)
                 ? 1
                 : 0;
  }
  return alike >= options_.min_untextured_share * (bottom - top + 1);
}

// The grey-level edges of column col's floor below the horizon, bottom up, into edge_bands_ (each
// a run of rows that are edges). An edge's own band of flow (the estimator's spread) is a gap
// the floor may have.
void UntexturedFill::find_floor_edges(const FlowField& field, const cv::Mat& grey,
                                      std::span<const std::uint8_t> ground_mask, int col) {
  const double max_gap = std::max<double>(options_.contact_search_px, options_.flow_spread_px);
  edge_bands_.clear();
  int gap = 0;
  for (int row = field.height() - 1; row >= first_ground_row_; --row) {
    const bool floor = !has_flow(field, col, row) || ground_mask[field.index(col, row)] != 0;
    gap = floor ? 0 : gap + 1;
    if (gap > max_gap) {
      break;
    }
    if (!is_edge(grey, col, row)) {
      continue;
    }
    if (!edge_bands_.empty() && edge_bands_.back().top_row == row + 1) {
      edge_bands_.back().top_row = row;
    } else {
      edge_bands_.push_back({row, row});
    }
  }
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
