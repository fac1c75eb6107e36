// topview.png: the world from above, its paths with time marks, axes, a legend and a key.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "flowsteer/report/page.hpp"
#include "flowsteer/sim/outputs.hpp"

namespace flowsteer::sim {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kCaptionScale = 0.55;
constexpr double kLabelScale = 0.45;
constexpr int kCaptionMargin = 8;   // px, left of the top view's caption and at least as much right
constexpr double kWorldPx = 900.0;  // the world's larger extent, margins included
constexpr double kWorldMarginM = 1.5;
// Room around the plot: tick labels left and below, the axes' names above and right.
constexpr int kAxisLeftPx = 56;
constexpr int kAxisBelowPx = 24;
constexpr int kPadTopPx = 24;
constexpr int kPadRightPx = 64;
constexpr int kRowPx = 24;  // a line of the legend, the key, the caption
constexpr int kLegendMaxRows = 4;
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kPaper(250, 250, 250);
const cv::Scalar kGrid(232, 232, 232);

// Where the world lies in the picture, world y up.
struct Plot {
  Eigen::Vector2d lo_m;  // the world's corner at the plot's bottom left
  Eigen::Vector2d hi_m;
  double px_per_m = 1.0;
  cv::Rect rect;  // in the image
  cv::Point px(const Eigen::Vector2d& p) const {
    return {rect.x + static_cast<int>((p.x() - lo_m.x()) * px_per_m),
            rect.y + rect.height - static_cast<int>((p.y() - lo_m.y()) * px_per_m)};
  }
};

// The time marks along the paths: a dot every dot_s, a numbered one every label_s.
struct TimeMarks {
  double dot_s = 1.0;
  double label_s = 5.0;
};

Eigen::AlignedBox2d world_bounds(const sim_camera::WorldSpec& spec,
                                 const std::vector<std::vector<Eigen::Vector2d>>& paths) {
  Eigen::AlignedBox2d bounds;
  for (const auto& path : paths) {
    for (const auto& p : path) {
      bounds.extend(p);
    }
  }
  for (const auto& a : spec.agents) {
    bounds.extend(a.start_m);
    for (const auto& g : a.goals) {
      bounds.extend(g);
    }
  }
  for (const auto& o : spec.obstacles) {
    if (o.shape == sim_camera::Solid::Shape::box) {
      for (const Eigen::Vector2d& corner : sim_camera::box_corners(o)) {
        bounds.extend(corner);
      }
    } else {
      bounds.extend(o.centre_m - Eigen::Vector2d(o.radius_m, o.radius_m));
      bounds.extend(o.centre_m + Eigen::Vector2d(o.radius_m, o.radius_m));
    }
  }
  return bounds;
}

std::string agent_label(const sim_camera::WorldSpec& spec, std::size_t i) {
  return spec.agents[i].name.empty() ? "agent " + std::to_string(i) : spec.agents[i].name;
}

int text_width(const std::string& text, double scale) {
  return cv::getTextSize(text, kFont, scale, 1, nullptr).width;
}

// Text over paths: a paper-coloured halo keeps it readable where it crosses a line.
void put_label(cv::Mat& image, const std::string& text, cv::Point at, const cv::Scalar& color) {
  cv::putText(image, text, at, kFont, kLabelScale, kPaper, 3, cv::LINE_AA);
  cv::putText(image, text, at, kFont, kLabelScale, color, 1, cv::LINE_AA);
}

void draw_solid(cv::Mat& image, const Plot& plot, const sim_camera::Solid& s,
                const cv::Scalar& color, int thickness) {
  if (s.shape == sim_camera::Solid::Shape::cylinder) {
    cv::circle(image, plot.px(s.centre_m), static_cast<int>(s.radius_m * plot.px_per_m), color,
               thickness, cv::LINE_AA);
    return;
  }
  std::vector<cv::Point> corners;
  for (const Eigen::Vector2d& corner : sim_camera::box_corners(s)) {
    corners.push_back(plot.px(corner));
  }
  if (thickness == cv::FILLED) {
    cv::fillConvexPoly(image, corners, color, cv::LINE_AA);
  } else {
    cv::polylines(image, corners, true, color, thickness, cv::LINE_AA);
  }
}

// A light grid and, outside the plot, ticks and their labels every tick_m along its left and
// bottom edges.
void draw_axes(cv::Mat& image, const Plot& plot, double tick_m) {
  const cv::Rect& r = plot.rect;
  for (double x = std::ceil(plot.lo_m.x() / tick_m) * tick_m; x <= plot.hi_m.x(); x += tick_m) {
    const int col = plot.px({x, 0.0}).x;
    cv::line(image, {col, r.y}, {col, r.br().y}, kGrid, 1);
    cv::line(image, {col, r.br().y}, {col, r.br().y + 5}, kInk, 1);
    char label[16];
    std::snprintf(label, sizeof label, "%g", std::abs(x) < 1e-9 ? 0.0 : x);
    cv::putText(image, label, {col - text_width(label, kLabelScale) / 2, r.br().y + 20}, kFont,
                kLabelScale, kInk, 1, cv::LINE_AA);
  }
  for (double y = std::ceil(plot.lo_m.y() / tick_m) * tick_m; y <= plot.hi_m.y(); y += tick_m) {
    const int row = plot.px({0.0, y}).y;
    cv::line(image, {r.x, row}, {r.br().x, row}, kGrid, 1);
    cv::line(image, {r.x - 5, row}, {r.x, row}, kInk, 1);
    char label[16];
    std::snprintf(label, sizeof label, "%g", std::abs(y) < 1e-9 ? 0.0 : y);
    cv::putText(image, label, {r.x - 8 - text_width(label, kLabelScale), row + 5}, kFont,
                kLabelScale, kInk, 1, cv::LINE_AA);
  }
  cv::rectangle(image, r, cv::Scalar(180, 180, 180), 1);
  cv::putText(image, "y (m)", {r.x - 20, r.y - 8}, kFont, kLabelScale, kInk, 1, cv::LINE_AA);
  cv::putText(image, "x (m)", {r.br().x + 16, r.br().y + 20}, kFont, kLabelScale, kInk, 1,
              cv::LINE_AA);
}

void draw_scene(cv::Mat& image, const Plot& plot, const sim_camera::World& world) {
  const sim_camera::WorldSpec& spec = world.spec();
  for (const auto& o : spec.obstacles) {
    draw_solid(image, plot, o, cv::Scalar(150, 150, 150), cv::FILLED);
  }
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    const auto& m = spec.moving[k];
    for (std::size_t w = 1; w < m.waypoints.size(); ++w) {
      cv::line(image, plot.px(m.waypoints[w - 1]), plot.px(m.waypoints[w]),
               cv::Scalar(200, 200, 200), 1);
    }
    draw_solid(image, plot, world.moving_now(k), cv::Scalar(110, 110, 110), 2);
  }
}

void draw_paths(cv::Mat& image, const Plot& plot, const sim_camera::World& world,
                const std::vector<std::vector<Eigen::Vector2d>>& paths) {
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const cv::Scalar color = agent_color(i);
    const auto& path = paths[i];
    for (std::size_t k = 1; k < path.size(); ++k) {
      cv::line(image, plot.px(path[k - 1]), plot.px(path[k]), color, 2, cv::LINE_AA);
    }
    const auto& agent = world.spec().agents[i];
    const int radius_px = static_cast<int>(agent.radius_m * plot.px_per_m);
    cv::circle(image, plot.px(agent.start_m), radius_px, color, 1, cv::LINE_AA);
    if (!path.empty()) {
      // Filled where the agent ended in the world, a thick ring where it left it.
      cv::circle(image, plot.px(path.back()), radius_px, color, world.present(i) ? cv::FILLED : 3,
                 cv::LINE_AA);
    }
    for (const auto& g : agent.goals) {
      cv::drawMarker(image, plot.px(g), color, cv::MARKER_CROSS, 14, 2);
    }
  }
}

// The same moments on every path (path[k] is where the agent was at k × step_s): who was where
// when. A number where the agent stands still would cover the one before, so it is left out.
void draw_time_marks(cv::Mat& image, const Plot& plot,
                     const std::vector<std::vector<Eigen::Vector2d>>& paths, double step_s,
                     const TimeMarks& marks) {
  const auto dot_steps = std::max<std::size_t>(1, std::lround(marks.dot_s / step_s));
  const auto dots_per_label = std::max<std::size_t>(1, std::lround(marks.label_s / marks.dot_s));
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const cv::Scalar color = agent_color(i);
    cv::Point last_label(-100, -100);
    for (std::size_t k = dot_steps, n = 1; k < paths[i].size(); k += dot_steps, ++n) {
      const cv::Point at = plot.px(paths[i][k]);
      if (n % dots_per_label != 0) {
        cv::circle(image, at, 2, color, cv::FILLED, cv::LINE_AA);
        continue;
      }
      cv::circle(image, at, 5, kPaper, cv::FILLED, cv::LINE_AA);
      cv::circle(image, at, 4, color, cv::FILLED, cv::LINE_AA);
      if (cv::norm(at - last_label) >= 16.0) {
        char label[16];
        std::snprintf(label, sizeof label, "%g", static_cast<double>(k) * step_s);
        put_label(image, label, at + cv::Point(6, -6), color);
        last_label = at;
      }
    }
  }
}

// A diamond in the agent's colour where each agent came closest to another body; the run's
// closest approach, where some clearance was finite, ringed and labelled with it and its time.
void draw_closest_approaches(cv::Mat& image, const Plot& plot,
                             std::span<const AgentResult> agents) {
  const AgentResult* closest = nullptr;
  for (std::size_t i = 0; i < agents.size(); ++i) {
    const AgentResult& a = agents[i];
    if (!std::isfinite(a.min_clearance_m) || !a.closest_position_m.allFinite()) {
      continue;
    }
    const cv::Point at = plot.px(a.closest_position_m);
    cv::drawMarker(image, at, kPaper, cv::MARKER_DIAMOND, 15, 4, cv::LINE_AA);
    cv::drawMarker(image, at, agent_color(i), cv::MARKER_DIAMOND, 13, 2, cv::LINE_AA);
    if (closest == nullptr || a.min_clearance_m < closest->min_clearance_m) {
      closest = &a;
    }
  }
  if (closest == nullptr) {
    return;
  }
  const cv::Point at = plot.px(closest->closest_position_m);
  cv::circle(image, at, 14, kInk, 1, cv::LINE_AA);
  char label[64];
  std::snprintf(label, sizeof label, "closest: %.2f m at %.1f s", closest->min_clearance_m,
                closest->closest_time_s);
  put_label(image, label, at + cv::Point(16, 18), kInk);
}

// A swatch and a name per agent, in as many columns as fit, column by column; what does not
// fit in kLegendMaxRows rows is counted in the last cell.
struct LegendGrid {
  int rows = 1;
  int columns = 1;
  int cell_px = 1;
};

LegendGrid legend_grid(const sim_camera::WorldSpec& spec, int width_px) {
  int name_px = text_width("+999 more", kLabelScale);
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    name_px = std::max(name_px, text_width(agent_label(spec, i), kLabelScale));
  }
  LegendGrid grid;
  grid.cell_px = 30 + name_px + 16;
  grid.columns = std::max(1, (width_px - 2 * kCaptionMargin) / grid.cell_px);
  const int agents = static_cast<int>(spec.agents.size());
  grid.rows = std::clamp((agents + grid.columns - 1) / grid.columns, 1, kLegendMaxRows);
  return grid;
}

void draw_legend(cv::Mat& image, const sim_camera::WorldSpec& spec, int top_px) {
  const LegendGrid grid = legend_grid(spec, image.cols);
  const auto cells = static_cast<std::size_t>(grid.rows * grid.columns);
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    const cv::Point at(kCaptionMargin + static_cast<int>(i) / grid.rows * grid.cell_px,
                       top_px + static_cast<int>(i) % grid.rows * kRowPx);
    if (i + 1 == cells && spec.agents.size() > cells) {
      char more[32];
      std::snprintf(more, sizeof more, "+%zu more", spec.agents.size() - i);
      cv::putText(image, more, at + cv::Point(0, 16), kFont, kLabelScale, kInk, 1, cv::LINE_AA);
      return;
    }
    cv::rectangle(image, cv::Rect(at.x, at.y + 4, 22, 14), agent_color(i), cv::FILLED);
    cv::putText(image, agent_label(spec, i), at + cv::Point(30, 16), kFont, kLabelScale, kInk, 1,
                cv::LINE_AA);
  }
}

// What the time marks mean and, where there are more agents than colours, that they repeat.
std::string key_text(const TimeMarks& marks, std::size_t agents) {
  char text[128];
  std::snprintf(text, sizeof text,
                "time marks: a dot every %g s, numbered every %g s; diamond: closest approach",
                marks.dot_s, marks.label_s);
  if (agents <= report::kAgentColors) {
    return text;
  }
  char repeat[64];
  std::snprintf(repeat, sizeof repeat, "; colours repeat after %zu agents", report::kAgentColors);
  return std::string(text) + repeat;
}

// A scale bar, then key_text.
void draw_key(cv::Mat& image, int top_px, double bar_m, double px_per_m, const std::string& text) {
  const int bar_px = static_cast<int>(bar_m * px_per_m);
  const int row = top_px + 12;
  const cv::Point a(kCaptionMargin, row);
  const cv::Point b(kCaptionMargin + bar_px, row);
  cv::line(image, a, b, kInk, 3);
  cv::line(image, a - cv::Point(0, 6), a + cv::Point(0, 6), kInk, 2);
  cv::line(image, b - cv::Point(0, 6), b + cv::Point(0, 6), kInk, 2);
  char bar[16];
  std::snprintf(bar, sizeof bar, "%g m", bar_m);
  cv::putText(image, bar, b + cv::Point(8, 5), kFont, kLabelScale, kInk, 1, cv::LINE_AA);
  cv::putText(image, text, b + cv::Point(24 + text_width(bar, kLabelScale), 5), kFont, kLabelScale,
              kInk, 1, cv::LINE_AA);
}

std::string caption_text(const sim_camera::World& world, std::size_t collisions, double px_per_m) {
  const sim_camera::WorldSpec& spec = world.spec();
  char caption[200];
  std::snprintf(caption, sizeof caption, "%s  t = %.1f s  collisions: %zu  (1 m = %.0f px)%s",
                spec.name.c_str(), world.time_s(), collisions, px_per_m,
                spec.arrival == sim_camera::Arrival::leave ? "  ring: left on arrival" : "");
  return caption;
}

double path_duration_s(const std::vector<std::vector<Eigen::Vector2d>>& paths, double step_s) {
  std::size_t steps = 0;
  for (const auto& path : paths) {
    steps = std::max(steps, path.empty() ? 0 : path.size() - 1);
  }
  return static_cast<double>(steps) * step_s;
}

// Where everything goes: the plot, its ticks and time marks, the rows under it.
struct Layout {
  Plot plot;
  double tick_m = 1.0;
  TimeMarks marks;
  std::string key;  // key_text
  std::string caption;
  cv::Size size;
  int legend_top_px = 0;
  int key_top_px = 0;
};

Layout layout(const sim_camera::World& world,
              const std::vector<std::vector<Eigen::Vector2d>>& paths, std::size_t collisions) {
  const sim_camera::WorldSpec& spec = world.spec();
  const Eigen::AlignedBox2d bounds = world_bounds(spec, paths);
  Layout l;
  l.plot.lo_m = bounds.min() - Eigen::Vector2d::Constant(kWorldMarginM);
  l.plot.hi_m = bounds.max() + Eigen::Vector2d::Constant(kWorldMarginM);
  const Eigen::Vector2d extent = l.plot.hi_m - l.plot.lo_m;
  l.plot.px_per_m = kWorldPx / extent.maxCoeff();
  l.tick_m = report::tick_step(45.0 / l.plot.px_per_m);
  // Both in whole steps, the paths' samples, so the key says where the marks are.
  const double label_s = time_mark_interval_s(path_duration_s(paths, spec.step_s));
  const double dot_steps =
      std::max(1.0, std::round(report::tick_step(label_s / 5.0) / spec.step_s));
  l.marks.dot_s = dot_steps * spec.step_s;
  l.marks.label_s = std::max(1.0, std::round(label_s / l.marks.dot_s)) * l.marks.dot_s;
  l.key = key_text(l.marks, spec.agents.size());
  l.caption = caption_text(world, collisions, l.plot.px_per_m);
  const cv::Size plot_px(static_cast<int>(extent.x() * l.plot.px_per_m),
                         static_cast<int>(extent.y() * l.plot.px_per_m));
  const int framed_px = kAxisLeftPx + plot_px.width + kPadRightPx;
  const int key_px = static_cast<int>(l.tick_m * l.plot.px_per_m) + 40 +
                     text_width(l.key, kLabelScale) + text_width("99 m", kLabelScale);
  // A narrow world (a corridor) is centred in an image wide enough for the texts under it.
  l.size.width = std::max({framed_px, text_width(l.caption, kCaptionScale) + 2 * kCaptionMargin,
                           key_px + 2 * kCaptionMargin});
  l.plot.rect = cv::Rect(kAxisLeftPx + (l.size.width - framed_px) / 2, kPadTopPx, plot_px.width,
                         plot_px.height);
  l.legend_top_px = l.plot.rect.br().y + kAxisBelowPx + 6;
  l.key_top_px = l.legend_top_px + legend_grid(spec, l.size.width).rows * kRowPx + 4;
  l.size.height = l.key_top_px + kRowPx + 30;
  return l;
}

}  // namespace

double time_mark_interval_s(double duration_s) {
  return report::tick_step(std::max(duration_s, 1.0) / 10.0);
}

cv::Mat draw_topview(const sim_camera::World& world,
                     const std::vector<std::vector<Eigen::Vector2d>>& paths,
                     const std::vector<sim_camera::Collision>& collisions,
                     std::span<const AgentResult> agents) {
  const Layout l = layout(world, paths, collisions.size());
  cv::Mat image(l.size, CV_8UC3, kPaper);
  draw_axes(image, l.plot, l.tick_m);
  draw_scene(image, l.plot, world);
  draw_paths(image, l.plot, world, paths);
  draw_time_marks(image, l.plot, paths, world.spec().step_s, l.marks);
  draw_closest_approaches(image, l.plot, agents);
  for (const auto& c : collisions) {
    cv::drawMarker(image, l.plot.px(c.position_m), cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS,
                   18, 3);
  }
  draw_legend(image, world.spec(), l.legend_top_px);
  draw_key(image, l.key_top_px, l.tick_m, l.plot.px_per_m, l.key);
  cv::putText(image, l.caption, {kCaptionMargin, image.rows - 10}, kFont, kCaptionScale, kInk, 1,
              cv::LINE_AA);
  return image;
}

}  // namespace flowsteer::sim
