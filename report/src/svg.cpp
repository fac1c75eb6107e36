#include "svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace flowsteer::report {

namespace {

constexpr double kWidthPx = 760.0;
constexpr double kHeightPx = 270.0;
constexpr double kLeftPx = 64.0;  // room for the y ticks' labels
constexpr double kRightPx = 14.0;
constexpr double kTopPx = 50.0;  // the title, and the legend under it
constexpr double kBottomPx = 40.0;
// A line of more points than its share of these is drawn as the least and greatest value of
// each of as many spans of its samples as the share allows (at least kMinPoints / 2): the page
// stays small for a long run or a crowd and keeps every spike.
constexpr std::size_t kMaxPointsPerPlot = 24000;
constexpr std::size_t kMaxPoints = 1200;
constexpr std::size_t kMinPoints = 60;
constexpr std::size_t kMaxLegend = 10;  // more series are named by the top view's legend

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", value);
  return text;
}

std::string tick_label(double value, double step) {
  char text[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(text, sizeof text, "%.*f", decimals, std::abs(value) < 1e-12 ? 0.0 : value);
  return text;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void extend(double v) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  bool empty() const { return lo > hi; }
};

// The least and greatest value of each span of the run [from, to) (no NaN in it), in time order.
void keep_extremes(const Series& s, std::size_t from, std::size_t to, double spans_per_sample,
                   std::vector<std::size_t>& kept) {
  const std::size_t length = to - from;
  const std::size_t spans = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::lround(spans_per_sample * static_cast<double>(length))), 1,
      length);
  for (std::size_t span = 0; span < spans; ++span) {
    const std::size_t begin = from + span * length / spans;
    const std::size_t end = from + (span + 1) * length / spans;
    std::size_t least = begin;
    std::size_t most = begin;
    for (std::size_t k = begin; k < end; ++k) {
      least = s.values[k] < s.values[least] ? k : least;
      most = s.values[k] > s.values[most] ? k : most;
    }
    kept.push_back(std::min(least, most));
    if (least != most) {
      kept.push_back(std::max(least, most));
    }
  }
}

double clipped(double value, const Plot& plot) {
  return plot.y_max && value > *plot.y_max ? *plot.y_max : value;
}

// The samples a series is drawn with, in time order: all of them, or, split into runs of values
// between its gaps (NaN), each run cut into spans by its share of the budget and each span's
// least and greatest kept. A gap is kept as the first NaN after a run, so the line breaks there.
std::vector<std::size_t> drawn_samples(const Series& s, std::size_t max_points) {
  const std::size_t n = std::min(s.t_s.size(), s.values.size());
  std::vector<std::size_t> kept;
  if (n <= max_points) {
    for (std::size_t k = 0; k < n; ++k) {
      kept.push_back(k);
    }
    return kept;
  }
  const double spans_per_sample = 0.5 * static_cast<double>(max_points) / static_cast<double>(n);
  for (std::size_t from = 0; from < n;) {
    if (!std::isfinite(s.values[from])) {
      kept.push_back(from);
      while (from < n && !std::isfinite(s.values[from])) {
        ++from;
      }
      continue;
    }
    std::size_t to = from;
    while (to < n && std::isfinite(s.values[to])) {
      ++to;
    }
    keep_extremes(s, from, to, spans_per_sample, kept);
    from = to;
  }
  return kept;
}

class Frame {
 public:
  Frame(Range x, Range y) : x_(x), y_(y) {}
  double x(double t) const {
    return kLeftPx + (t - x_.lo) / (x_.hi - x_.lo) * (kWidthPx - kLeftPx - kRightPx);
  }
  double y(double v) const {
    return kHeightPx - kBottomPx - (v - y_.lo) / (y_.hi - y_.lo) * (kHeightPx - kTopPx - kBottomPx);
  }
  const Range& xs() const { return x_; }
  const Range& ys() const { return y_; }

 private:
  Range x_;
  Range y_;
};

// The data's range, widened to include 0 and to a non-empty span.
Range value_range(const Plot& plot) {
  Range y;
  y.extend(0.0);
  for (const Series& s : plot.series) {
    for (const double v : s.values) {
      y.extend(clipped(v, plot));
    }
  }
  if (y.hi - y.lo < 1e-9) {
    y.hi = y.lo + 1.0;
  }
  return y;
}

Range time_range(const Plot& plot) {
  Range x;
  for (const Series& s : plot.series) {
    for (const double t : s.t_s) {
      x.extend(t);
    }
  }
  for (const double t : plot.marks_t_s) {
    x.extend(t);
  }
  if (x.empty()) {
    x = {0.0, 1.0};
  }
  if (x.hi - x.lo < 1e-9) {
    x.hi = x.lo + 1.0;
  }
  return x;
}

void axes(std::string& svg, const Frame& f, const Plot& plot) {
  const double y_step = tick_step((f.ys().hi - f.ys().lo) / 5.0);  // about five ticks
  for (double v = std::ceil(f.ys().lo / y_step) * y_step; v <= f.ys().hi + 1e-9; v += y_step) {
    svg += "<line class=\"grid\" x1=\"" + number(kLeftPx) + "\" x2=\"" +
           number(kWidthPx - kRightPx) + "\" y1=\"" + number(f.y(v)) + "\" y2=\"" + number(f.y(v)) +
           "\"/>";
    svg += "<text class=\"tick\" x=\"" + number(kLeftPx - 6) + "\" y=\"" + number(f.y(v) + 4) +
           "\" text-anchor=\"end\">" + tick_label(v, y_step) + "</text>";
  }
  const double x_step = tick_step((f.xs().hi - f.xs().lo) / 5.0);
  for (double t = std::ceil(f.xs().lo / x_step) * x_step; t <= f.xs().hi + 1e-9; t += x_step) {
    svg += "<line class=\"axis\" x1=\"" + number(f.x(t)) + "\" x2=\"" + number(f.x(t)) +
           "\" y1=\"" + number(kHeightPx - kBottomPx) + "\" y2=\"" +
           number(kHeightPx - kBottomPx + 5) + "\"/><text class=\"tick\" x=\"" + number(f.x(t)) +
           "\" y=\"" + number(kHeightPx - kBottomPx + 18) + "\" text-anchor=\"middle\">" +
           tick_label(t, x_step) + "</text>";
  }
  svg += "<line class=\"axis\" x1=\"" + number(kLeftPx) + "\" x2=\"" + number(kWidthPx - kRightPx) +
         "\" y1=\"" + number(kHeightPx - kBottomPx) + "\" y2=\"" + number(kHeightPx - kBottomPx) +
         "\"/>";
  svg += "<line class=\"axis\" x1=\"" + number(kLeftPx) + "\" x2=\"" + number(kLeftPx) +
         "\" y1=\"" + number(kTopPx) + "\" y2=\"" + number(kHeightPx - kBottomPx) + "\"/>";
  svg += "<text class=\"label\" x=\"" + number(0.5 * (kLeftPx + kWidthPx - kRightPx)) + "\" y=\"" +
         number(kHeightPx - 6) + "\" text-anchor=\"middle\">time (s)</text>";
  svg += "<text class=\"label\" transform=\"translate(14 " +
         number(0.5 * (kTopPx + kHeightPx - kBottomPx)) +
         ") rotate(-90)\" text-anchor=\"middle\">" + escaped(plot.y_label) + "</text>";
}

// The most points svg_of draws of each of the plot's series.
std::size_t max_points(const Plot& plot) {
  return std::clamp(kMaxPointsPerPlot / std::max<std::size_t>(plot.series.size(), 1), kMinPoints,
                    kMaxPoints);
}

void lines(std::string& svg, const Frame& f, const Plot& plot) {
  const std::size_t most = max_points(plot);
  for (const Series& s : plot.series) {
    std::string d;
    bool pen_down = false;
    for (const std::size_t k : drawn_samples(s, most)) {
      const double v = clipped(s.values[k], plot);
      if (!std::isfinite(v) || !std::isfinite(s.t_s[k])) {
        pen_down = false;
        continue;
      }
      d += pen_down ? 'L' : 'M';
      d += number(f.x(s.t_s[k])) + " " + number(f.y(v));
      if (!pen_down) {
        d += "l0 0";  // a value alone between gaps is drawn as a dot (round line caps)
      }
      pen_down = true;
    }
    if (!d.empty()) {
      svg += "<path class=\"series\" stroke=\"" + css_color(s.color) + "\" d=\"" + d +
             "\"><title>" + escaped(s.name) + "</title></path>";
    }
  }
}

void marks(std::string& svg, const Frame& f, const Plot& plot) {
  std::vector<double> times = plot.marks_t_s;
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  for (const double t : times) {
    svg += "<line class=\"mark\" x1=\"" + number(f.x(t)) + "\" x2=\"" + number(f.x(t)) +
           "\" y1=\"" + number(kTopPx) + "\" y2=\"" + number(kHeightPx - kBottomPx) + "\"><title>" +
           escaped(plot.marks_label) + " at t = " + tick_label(t, 0.01) + " s</title></line>";
  }
}

void legend(std::string& svg, const Plot& plot) {
  double x = kWidthPx - kRightPx;
  auto entry = [&](const std::string& name, const std::string& color, const char* kind) {
    const double width = 22.0 + 6.5 * static_cast<double>(name.size());
    x -= width;
    svg += std::string("<line class=\"") + kind + "\" x1=\"" + number(x) + "\" x2=\"" +
           number(x + 14) + "\" y1=\"36\" y2=\"36\" stroke=\"" + color + "\"/>" +
           "<text class=\"tick\" x=\"" + number(x + 18) + "\" y=\"40\">" + escaped(name) +
           "</text>";
  };
  if (!plot.marks_t_s.empty()) {
    entry(plot.marks_label, "#d00000", "mark");
  }
  if (plot.series.size() <= kMaxLegend) {
    for (auto s = plot.series.rbegin(); s != plot.series.rend(); ++s) {
      entry(s->name, css_color(s->color), "series");
    }
  }
}

}  // namespace

std::string escaped(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string css_color(const Rgb& color) {
  char text[16];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", color.r, color.g, color.b);
  return text;
}

void thin(Plot& plot) {
  const std::size_t most = max_points(plot);
  for (Series& s : plot.series) {
    Series kept{s.name, s.color, {}, {}};
    for (const std::size_t k : drawn_samples(s, most)) {
      kept.t_s.push_back(s.t_s[k]);
      kept.values.push_back(s.values[k]);
    }
    s = std::move(kept);
  }
}

std::string svg_of(const Plot& plot) {
  const Frame frame(time_range(plot), value_range(plot));
  std::string svg = "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " +
                    number(kWidthPx) + " " + number(kHeightPx) + "\" width=\"" + number(kWidthPx) +
                    "\" height=\"" + number(kHeightPx) + "\" role=\"img\" aria-label=\"" +
                    escaped(plot.title) + "\">";
  svg += "<text class=\"title\" x=\"" + number(kLeftPx) + "\" y=\"20\">" + escaped(plot.title) +
         "</text>";
  axes(svg, frame, plot);
  const std::size_t before = svg.size();
  lines(svg, frame, plot);
  if (svg.size() == before && !plot.empty_note.empty()) {
    svg += "<text class=\"note\" x=\"" + number(0.5 * (kLeftPx + kWidthPx)) + "\" y=\"" +
           number(0.5 * kHeightPx) + "\" text-anchor=\"middle\">" + escaped(plot.empty_note) +
           "</text>";
  }
  marks(svg, frame, plot);
  legend(svg, plot);
  return svg + "</svg>";
}

}  // namespace flowsteer::report
