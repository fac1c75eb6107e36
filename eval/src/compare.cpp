#include "flowsteer/eval/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/report/page.hpp"
#include "flowsteer/sim/outputs.hpp"
#include "report_pages.hpp"
#include "run_choices.hpp"

namespace flowsteer::eval {

namespace {

constexpr int kTurnRateBins = 21;  // odd: one bin centred on ω = 0
constexpr servo::SteeringModel kReference = servo::SteeringModel::geometric;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_controllers(const std::vector<servo::SteeringModel>& models) {
  if (models.empty()) {
    throw base::ConfigError(
        "--controllers", "no controller given (known ones: " + servo::steering_model_names() + ")");
  }
  refuse_repeats(models, "--controllers");
}

// A caption band above an image.
cv::Mat with_title(const cv::Mat& image, const std::string& title) {
  cv::Mat out(image.rows + 36, image.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  image.copyTo(out(cv::Rect(0, 36, image.cols, image.rows)));
  cv::putText(out, title, {10, 26}, cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(30, 30, 30), 2,
              cv::LINE_AA);
  return out;
}

// The panels side by side, scaled to the height of the first.
cv::Mat side_by_side(const std::vector<cv::Mat>& panels) {
  std::vector<cv::Mat> scaled;
  const int height = panels.front().rows;
  for (const cv::Mat& p : panels) {
    cv::Mat s;
    cv::resize(p, s, {std::max(1, p.cols * height / p.rows), height}, 0, 0, cv::INTER_AREA);
    scaled.push_back(s);
  }
  cv::Mat out;
  cv::hconcat(scaled, out);
  return out;
}

// A histogram panel's plot area; the rest holds the axes' labels.
const cv::Rect kHistogramPlot(64, 30, 370, 200);
const cv::Size kHistogramPx(470, 290);
const cv::Scalar kAxisInk(0, 0, 0);

void put_axis_text(cv::Mat& image, const std::string& text, cv::Point at) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, kAxisInk, 1, cv::LINE_AA);
}

int axis_text_px(const std::string& text) {
  return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, nullptr).width;
}

// The share of samples per bin, 0 to max_share, ticked and labelled in percent.
void draw_share_axis(cv::Mat& image, double max_share) {
  const cv::Rect& r = kHistogramPlot;
  cv::line(image, {r.x, r.y}, {r.x, r.br().y}, kAxisInk, 1);
  const double tick = report::tick_step(max_share / 5.0);
  for (double share = 0.0; share <= max_share + 1e-12; share += tick) {
    const int row = r.br().y - static_cast<int>(std::lround(share / max_share * r.height));
    cv::line(image, {r.x - 5, row}, {r.x, row}, kAxisInk, 1);
    char label[16];
    std::snprintf(label, sizeof label, "%g %%", 100.0 * share);
    put_axis_text(image, label, {r.x - 8 - axis_text_px(label), row + 5});
  }
  put_axis_text(image, "share of samples", {8, r.y - 12});
}

// The turn rate from the first bin's edge to the last one's, ticked at both ends and at 0.
void draw_rate_axis(cv::Mat& image, const std::vector<double>& edges) {
  const cv::Rect& r = kHistogramPlot;
  cv::line(image, {r.x, r.br().y}, {r.br().x, r.br().y}, kAxisInk, 1);
  for (const double rate : {edges.front(), 0.0, edges.back()}) {
    const int col = r.x + static_cast<int>(std::lround((rate - edges.front()) /
                                                       (edges.back() - edges.front()) * r.width));
    cv::line(image, {col, r.br().y}, {col, r.br().y + 5}, kAxisInk, 1);
    char label[16];
    std::snprintf(label, sizeof label, "%+.2f", rate);
    if (rate == 0.0) {
      std::snprintf(label, sizeof label, "0");
    }
    put_axis_text(image, label, {col - axis_text_px(label) / 2, r.br().y + 22});
  }
  const std::string title = "turn rate (rad/s)";
  put_axis_text(image, title, {r.x + (r.width - axis_text_px(title)) / 2, r.br().y + 46});
}

// One histogram as bars, as a share of the run's non-zero samples, on a common scale.
cv::Mat draw_histogram(const std::vector<int>& counts, const std::vector<double>& edges,
                       double max_share) {
  cv::Mat image(kHistogramPx, CV_8UC3, cv::Scalar(255, 255, 255));
  int total = 0;
  for (const int c : counts) {
    total += c;
  }
  const cv::Rect& r = kHistogramPlot;
  const double bar = static_cast<double>(r.width) / static_cast<double>(counts.size());
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const double share = total > 0 ? static_cast<double>(counts[k]) / total : 0.0;
    const int top = r.br().y - static_cast<int>(share / max_share * r.height);
    const int x0 = r.x + static_cast<int>(static_cast<double>(k) * bar);
    cv::rectangle(image, {x0 + 1, top}, {static_cast<int>(x0 + bar) - 1, r.br().y},
                  cv::Scalar(180, 110, 40), cv::FILLED);
  }
  draw_share_axis(image, max_share);
  draw_rate_axis(image, edges);
  char label[64];
  std::snprintf(label, sizeof label, "n = %d (|w| >= %.0e)", total, kStillTurnRate);
  put_axis_text(image, label, {r.br().x - axis_text_px(label), r.y - 12});
  return image;
}

}  // namespace

std::vector<servo::SteeringModel> parse_controllers(const std::vector<std::string>& names) {
  std::vector<servo::SteeringModel> models;
  for (const std::string& name : names) {
    const auto model = servo::parse_steering_model(name);
    if (!model) {
      throw base::ConfigError("--controllers " + name, "unknown controller (known ones: " +
                                                           servo::steering_model_names() + ")");
    }
    models.push_back(*model);
  }
  check_controllers(models);
  return models;
}

CompareResult run_compare(const sim_camera::WorldSpec& world, const CompareOptions& options,
                          std::ostream& log) {
  check_controllers(options.controllers);
  std::optional<base::OutputDir> out;
  if (options.write_outputs) {
    out.emplace(options.out_dir);
  }
  CompareResult result;
  result.scenario = world.name;
  double max_turn_rate = 0.0;
  for (const sim_camera::AgentSpec& a : world.agents) {
    max_turn_rate = std::max(max_turn_rate, a.controller.max_turn_rate);
  }
  for (int k = 0; k <= kTurnRateBins; ++k) {
    result.turn_rate_edges.push_back(max_turn_rate * (2.0 * k / kTurnRateBins - 1.0));
  }

  for (const servo::SteeringModel controller : options.controllers) {
    const std::string name(servo::to_string(controller));
    sim_camera::WorldSpec spec = world;
    for (sim_camera::AgentSpec& a : spec.agents) {
      a.controller.model = controller;
    }
    sim::SimOptions sim;
    sim.resolution = options.resolution;
    sim.steps = options.steps;
    sim.write_outputs = options.write_outputs;
    if (out) {
      sim.out_dir = out->staging_path(name);
    }
    log << "flowsteer compare: " << world.name << " with " << name << "\n";
    ControllerRun run{controller, sim::run_simulation(spec, sim, log),
                      std::vector<int>(kTurnRateBins, 0)};
    for (const sim::AgentResult& a : run.result.agents) {
      for (const double w : a.turn_rates) {
        if (std::abs(w) >= kStillTurnRate) {
          const double at = (w + max_turn_rate) / (2.0 * max_turn_rate) * kTurnRateBins;
          ++run.turn_rate_counts[static_cast<std::size_t>(
              std::clamp(static_cast<int>(at), 0, kTurnRateBins - 1))];
        }
      }
    }
    result.runs.push_back(std::move(run));
  }

  if (out) {
    const std::vector<CompareRow> rows = compare_table(result);
    base::CsvTable table({"controller", "collisions", "goals_reached", "agents",
                          "mean_time_to_goal_s", "mean_path_length_m", "min_clearance_m",
                          "path_length_vs_geometric", "min_clearance_vs_geometric_m"});
    for (const CompareRow& r : rows) {
      const sim::RunSummary& s = r.summary;
      table.add({std::string(servo::to_string(r.controller))},
                {static_cast<double>(s.collisions), static_cast<double>(s.goals_reached),
                 static_cast<double>(s.agents), s.mean_time_to_goal_s, s.mean_path_length_m,
                 s.min_clearance_m, r.path_length_vs_reference, r.min_clearance_vs_reference_m});
    }
    table.write(out->staging_path("compare.csv"));

    base::CsvTable agents({"controller", "agent", "reached_goal", "time_to_goal_s", "path_length_m",
                           "min_clearance_m", "collisions"});
    std::vector<std::string> histogram_header = {"omega_low", "omega_high"};
    std::vector<cv::Mat> topviews;
    std::vector<cv::Mat> histograms;
    double max_share = 1e-9;
    for (const ControllerRun& run : result.runs) {
      for (const sim::AgentResult& a : run.result.agents) {
        agents.add({std::string(servo::to_string(run.controller)), a.name},
                   {a.reached_goal ? 1.0 : 0.0, a.reached_goal ? a.time_to_goal_s : kNaN,
                    a.path_length_m, a.min_clearance_m, static_cast<double>(a.collisions)});
      }
      histogram_header.emplace_back(servo::to_string(run.controller));
      topviews.push_back(
          with_title(run.result.topview, std::string(servo::to_string(run.controller))));
      int total = 0;
      for (const int c : run.turn_rate_counts) {
        total += c;
      }
      for (const int c : run.turn_rate_counts) {
        max_share = std::max(max_share, total > 0 ? static_cast<double>(c) / total : 0.0);
      }
    }
    agents.write(out->staging_path("compare_agents.csv"));
    base::CsvTable turn_rates(histogram_header);
    for (int k = 0; k < kTurnRateBins; ++k) {
      std::vector<double> row = {result.turn_rate_edges[static_cast<std::size_t>(k)],
                                 result.turn_rate_edges[static_cast<std::size_t>(k) + 1]};
      for (const ControllerRun& run : result.runs) {
        row.push_back(run.turn_rate_counts[static_cast<std::size_t>(k)]);
      }
      turn_rates.add(row);
    }
    turn_rates.write(out->staging_path("turn_rates.csv"));
    for (const ControllerRun& run : result.runs) {
      histograms.push_back(
          with_title(draw_histogram(run.turn_rate_counts, result.turn_rate_edges, max_share),
                     std::string(servo::to_string(run.controller)) + ": turn rate"));
    }
    sim::write_image(out->staging_path("topviews.png"), side_by_side(topviews));
    sim::write_image(out->staging_path("turn_rates.png"), side_by_side(histograms));
    write_compare_page(result, rows, out->staging_dir());
    out->commit();
  }
  return result;
}

std::vector<CompareRow> compare_table(const CompareResult& result) {
  std::vector<CompareRow> rows;
  for (const ControllerRun& run : result.runs) {
    rows.push_back({run.controller, sim::summarize(run.result), 0.0, 0.0});
  }
  const auto reference = std::find_if(
      rows.begin(), rows.end(), [](const CompareRow& r) { return r.controller == kReference; });
  for (CompareRow& row : rows) {
    row.path_length_vs_reference =
        reference != rows.end()
            ? row.summary.mean_path_length_m / reference->summary.mean_path_length_m - 1.0
            : kNaN;
    row.min_clearance_vs_reference_m =
        reference != rows.end() ? row.summary.min_clearance_m - reference->summary.min_clearance_m
                                : kNaN;
  }
  return rows;
}

void print_compare_table(const std::vector<CompareRow>& rows, std::ostream& out) {
  const std::ios::fmtflags flags = out.flags();
  out << std::left << std::setw(15) << "controller" << std::right << std::setw(11) << "collisions"
      << std::setw(8) << "goals" << std::setw(14) << "time_to_goal" << std::setw(13)
      << "path_length" << std::setw(15) << "min_clearance" << std::setw(16) << "path_vs_geom"
      << std::setw(18) << "clearance_vs_geom"
      << "\n";
  // A number with its unit in `width` characters; "-" where there is none.
  auto cell = [&](double value, const char* unit, int width) {
    std::ostringstream text;
    if (std::isfinite(value)) {
      text << std::fixed << std::setprecision(2) << value << unit;
    } else {
      text << "-";
    }
    out << std::setw(width) << text.str();
  };
  for (const CompareRow& r : rows) {
    const sim::RunSummary& s = r.summary;
    out << std::left << std::setw(15) << servo::to_string(r.controller) << std::right
        << std::setw(11) << s.collisions << std::setw(8)
        << (std::to_string(s.goals_reached) + "/" + std::to_string(s.agents));
    cell(s.mean_time_to_goal_s, " s", 14);
    cell(s.mean_path_length_m, " m", 13);
    cell(s.min_clearance_m, " m", 15);
    cell(100.0 * r.path_length_vs_reference, "%", 16);
    cell(r.min_clearance_vs_reference_m, " m", 18);
    out << "\n";
  }
  out.flags(flags);
}

}  // namespace flowsteer::eval
