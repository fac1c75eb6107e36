#include "suite_files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/sim/outputs.hpp"

namespace flowsteer::eval {

namespace {

const char* const kHeader =
    "run,case,flow,segmentation,depth,controller,law,without,resolution,status,agents,"
    "goals_reached,"
    "agents_with_goal,collisions,obstacle_collisions,min_clearance_m,mean_time_to_goal_s,"
    "mean_path_length_m,mean_path_length_ratio,mean_time_ratio,composite01,turn_flip_ratio,"
    "spinning_s,error";
constexpr std::size_t kLabelColumns = 10;  // run ... status, without camera_noise
constexpr std::size_t kScoreColumns = 13;  // agents ... spinning_s

// A suite that varies the camera noise has a camera_noise column after resolution; one that
// does not writes the file it wrote before the axis existed.
bool has_noise_column(const std::vector<SuiteRun>& runs) {
  return std::any_of(runs.begin(), runs.end(), [](const SuiteRun& run) {
    return run.configuration.camera_noise_levels.has_value();
  });
}

std::string csv_header(bool noise_column) {
  std::string header = kHeader;
  if (noise_column) {
    header.insert(header.find(",status,"), ",camera_noise");
  }
  return header;
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, separator)) {
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == separator) {
    cells.emplace_back();
  }
  return cells;
}

// An error message as one CSV cell that needs no quoting.
std::string as_cell(std::string text) {
  std::replace(text.begin(), text.end(), ',', ';');
  std::replace(text.begin(), text.end(), '"', '\'');
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  return text;
}

const char* status(const SuiteRun& run) {
  return run.failed() ? "failed" : run.clean() ? "clean" : "not_clean";
}

std::string csv_row(const SuiteRun& run, bool noise_column) {
  std::string configuration = to_string(run.configuration);  // flow/segmentation/...
  if (noise_column && !run.configuration.camera_noise_levels) {
    configuration += "/own";
  }
  std::replace(configuration.begin(), configuration.end(), '/', ',');
  std::ostringstream row;
  row << run.index << ',' << run.case_name << ',' << configuration << ',' << status(run) << ','
      << (run.failed() ? std::string(kScoreColumns - 1, ',') : summary_fields(run.summary)) << ','
      << as_cell(run.error);
  return row.str();
}

// A cell of suite.csv back into its value; `what` names it for the error.
template <typename Parse>
auto parse_cell(const std::string& cell, Parse parse, const std::string& what) {
  const auto value = parse(cell);
  if (!value) {
    throw std::runtime_error(what + ": cannot read '" + cell + "'");
  }
  return *value;
}

std::optional<double> parse_double(const std::string& cell) {
  if (cell.empty()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  char* end = nullptr;
  const double value = std::strtod(cell.c_str(), &end);
  return end == cell.c_str() + cell.size() ? std::optional(value) : std::nullopt;
}

std::optional<int> parse_int(const std::string& cell) {
  const std::optional<double> value = parse_double(cell);
  return value && *value == std::floor(*value) && std::abs(*value) < 1e9
             ? std::optional(static_cast<int>(*value))
             : std::nullopt;
}

template <typename Method, typename Parse>
std::optional<Method> own_or(const std::string& cell, Parse parse, const std::string& what) {
  if (cell == "own") {
    return std::nullopt;
  }
  return parse_cell(cell, parse, what);
}

SuiteRun parse_csv_row(const std::string& line, bool noise_column, const std::string& where) {
  const std::vector<std::string> cells = split(line, ',');
  const std::size_t labels = kLabelColumns + (noise_column ? 1 : 0);
  if (cells.size() != labels + kScoreColumns + 1) {
    throw std::runtime_error(where + ": expected " + std::to_string(labels + kScoreColumns + 1) +
                             " cells, got " + std::to_string(cells.size()));
  }
  SuiteRun run;
  run.index = static_cast<std::size_t>(parse_cell(cells[0], parse_int, where + ": run"));
  run.case_name = cells[1];
  run.configuration.flow = own_or<servo::FlowMethod>(
      cells[2], [](const std::string& s) { return servo::parse_flow_method(s); }, where);
  run.configuration.segmentation = own_or<servo::SegmentationMethod>(
      cells[3], [](const std::string& s) { return servo::parse_segmentation_method(s); }, where);
  run.configuration.depth = own_or<servo::DepthSource>(
      cells[4], [](const std::string& s) { return servo::parse_depth_source(s); }, where);
  run.configuration.controller = own_or<servo::SteeringModel>(
      cells[5], [](const std::string& s) { return servo::parse_steering_model(s); }, where);
  run.configuration.law = own_or<servo::NavigationLaw>(
      cells[6], [](const std::string& s) { return servo::parse_navigation_law(s); }, where);
  run.configuration.without = own_or<servo::LawMechanism>(
      cells[7], [](const std::string& s) { return servo::parse_law_mechanism(s); }, where);
  run.configuration.resolution = own_or<int>(cells[8], parse_int, where + ": resolution");
  if (noise_column) {
    run.configuration.camera_noise_levels =
        own_or<double>(cells[9], parse_double, where + ": camera_noise");
  }
  run.error = cells.back();
  if (cells[labels - 1] == "failed") {
    run.error = run.error.empty() ? "failed" : run.error;
    return run;
  }
  std::string scores;
  for (std::size_t k = labels; k < labels + kScoreColumns; ++k) {
    if (k > labels) {
      scores += ',';
    }
    scores += cells[k];
  }
  run.summary = parse_summary_fields(scores, where);
  return run;
}

std::string suite_json(const SuiteResult& result) {
  std::ostringstream out;
  out << std::setprecision(6) << "{\n  \"suite_id\": \"" << result.suite_id
      << "\",\n  \"seed\": " << result.seed << ",\n  \"arrival\": \"" << result.arrival
      << "\",\n  \"shard\": " << result.shard.index << ",\n  \"shards\": " << result.shard.count
      << ",\n  \"suite_runs\": " << result.suite_runs << ",\n  \"runs\": " << result.runs.size()
      << ",\n  \"jobs\": " << result.jobs << ",\n  \"wall_s\": " << result.wall_s << "\n}\n";
  return out.str();
}

constexpr int kSheetFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kTilePx = 400;
constexpr int kTileGapPx = 12;
constexpr int kLinePx = 26;      // a caption line under a tile
constexpr int kDetailLines = 2;  // at most, for the configuration and for the verdict each
const cv::Scalar kSheetRed(0, 0, 220);

// A line of a tile's caption and how it is drawn.
struct CaptionLine {
  std::string text;
  double scale = 0.6;
  int thickness = 1;
  cv::Scalar color;
};

int sheet_text_px(const std::string& text, const CaptionLine& style) {
  return cv::getTextSize(text, kSheetFont, style.scale, style.thickness, nullptr).width;
}

// The longest start of `text` that fits width_px with "..." after it.
std::string cut_to_fit(std::string text, const CaptionLine& style, int width_px) {
  while (!text.empty() && sheet_text_px(text + "...", style) > width_px) {
    text.pop_back();
  }
  return text + "...";
}

// The parts of `text` that wrap keeps whole, each ending after a `stop` (a space: words; a
// comma: the items of a list), without the spaces around them.
std::vector<std::string> pieces(const std::string& text, char stop) {
  std::vector<std::string> out(1);
  for (const char c : text) {
    if (c != ' ' || !out.back().empty()) {
      out.back() += c;
    }
    if (c == stop) {
      out.emplace_back();
    }
  }
  for (std::string& piece : out) {
    piece.erase(piece.find_last_not_of(' ') + 1);
  }
  std::erase_if(out, [](const std::string& piece) { return piece.empty(); });
  return out;
}

// `text` in lines of width_px at most, broken after a `stop`; what does not fit in max_lines
// is cut off with "...".
std::vector<std::string> wrap(const std::string& text, char stop, const CaptionLine& style,
                              int width_px, int max_lines) {
  auto px = [&](const std::string& line) { return sheet_text_px(line, style); };
  std::vector<std::string> lines(1);
  for (const std::string& piece : pieces(text, stop)) {
    const std::string longer = lines.back().empty() ? piece : lines.back() + " " + piece;
    if (px(longer) <= width_px || lines.back().empty()) {
      lines.back() = longer;
    } else {
      lines.push_back(piece);
    }
  }
  if (static_cast<int>(lines.size()) > max_lines) {
    lines.resize(static_cast<std::size_t>(max_lines));
    lines.back() = cut_to_fit(lines.back(), style, width_px);
  }
  for (std::string& line : lines) {
    if (px(line) > width_px) {
      line = cut_to_fit(line, style, width_px);
    }
  }
  return lines;
}

std::vector<CaptionLine> tile_caption(const SuiteRun& run) {
  std::vector<CaptionLine> caption = {{run.case_name, 0.7, 2, cv::Scalar(30, 30, 30)}};
  const CaptionLine configuration{"", 0.6, 1, cv::Scalar(90, 90, 90)};
  for (std::string& line :
       wrap(configuration_label(run.configuration), ',', configuration, kTilePx, kDetailLines)) {
    caption.push_back(configuration);
    caption.back().text = std::move(line);
  }
  const CaptionLine verdict{"", 0.6, 2, run.clean() ? cv::Scalar(40, 130, 40) : kSheetRed};
  for (std::string& line : wrap(run_verdict(run), ' ', verdict, kTilePx, kDetailLines)) {
    caption.push_back(verdict);
    caption.back().text = std::move(line);
  }
  return caption;
}

// A run's top view scaled into its tile, or a grey tile saying there is none.
void draw_tile(cv::Mat& sheet, const cv::Rect& tile, const std::filesystem::path& view_path) {
  const cv::Mat view = cv::imread(view_path.string());
  if (view.empty()) {
    sheet(tile).setTo(cv::Scalar(225, 225, 225));
    cv::putText(sheet, "no top view", {tile.x + 12, tile.y + kTilePx / 2}, kSheetFont, 0.7,
                cv::Scalar(90, 90, 90), 2, cv::LINE_AA);
    return;
  }
  const double scale =
      std::min(static_cast<double>(kTilePx) / view.cols, static_cast<double>(kTilePx) / view.rows);
  cv::Mat fitted;
  cv::resize(view, fitted, {}, scale, scale, cv::INTER_AREA);
  fitted.copyTo(sheet(cv::Rect(tile.x + (kTilePx - fitted.cols) / 2,
                               tile.y + (kTilePx - fitted.rows) / 2, fitted.cols, fitted.rows)));
}

}  // namespace

std::string configuration_label(const SuiteConfiguration& c) {
  std::vector<std::string> parts;
  auto add = [&](const char* what, const auto& value) {
    if (value) {
      parts.push_back(std::string(what) + " " + std::string(servo::to_string(*value)));
    }
  };
  add("flow", c.flow);
  add("segmentation", c.segmentation);
  add("depth", c.depth);
  add("controller", c.controller);
  add("law", c.law);
  add("without", c.without);
  if (c.resolution) {
    parts.push_back(std::to_string(*c.resolution) + " px");
  }
  if (c.camera_noise_levels) {
    parts.push_back("noise " + base::format_csv_number(*c.camera_noise_levels));
  }
  if (parts.empty()) {
    return "the case's own settings";
  }
  std::string label = parts.front();
  for (std::size_t k = 1; k < parts.size(); ++k) {
    label += ", " + parts[k];
  }
  return label;
}

std::string run_verdict(const SuiteRun& run) {
  if (run.failed()) {
    return "failed: " + run.error;
  }
  if (run.clean()) {
    return "clean";
  }
  const sim::RunSummary& s = run.summary;
  std::vector<std::string> parts;
  if (s.collisions > 0) {
    parts.push_back(std::to_string(s.collisions) +
                    (s.collisions == 1 ? " collision" : " collisions"));
    if (s.obstacle_collisions > 0) {
      parts.back() += " (" + std::to_string(s.obstacle_collisions) + " with obstacles)";
    }
  }
  if (s.goals_reached < s.agents_with_goal()) {
    parts.push_back("goals " + std::to_string(s.goals_reached) + "/" +
                    std::to_string(s.agents_with_goal()));
  }
  if (parts.empty()) {
    // Not clean by a count no part names: more goals than agents with goals (a follower that
    // also had goals reached them).
    return "goals " + std::to_string(s.goals_reached) + "/" + std::to_string(s.agents_with_goal());
  }
  return parts.size() == 1 ? parts.front() : parts.front() + ", " + parts.back();
}

cv::Mat contact_sheet(const std::vector<SuiteRun>& runs, const std::filesystem::path& topviews) {
  std::vector<std::vector<CaptionLine>> captions;
  std::size_t caption_lines = 1;
  for (const SuiteRun& run : runs) {
    captions.push_back(tile_caption(run));
    caption_lines = std::max(caption_lines, captions.back().size());
  }
  const int caption_px = static_cast<int>(caption_lines) * kLinePx + 8;
  const int n = std::max<int>(1, static_cast<int>(runs.size()));
  const int columns = std::min(8, static_cast<int>(std::ceil(std::sqrt(n))));
  const int rows = (n + columns - 1) / columns;
  cv::Mat sheet(rows * (kTilePx + caption_px + kTileGapPx) + kTileGapPx,
                columns * (kTilePx + kTileGapPx) + kTileGapPx, CV_8UC3, cv::Scalar(255, 255, 255));
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const cv::Rect tile(
        kTileGapPx + static_cast<int>(k) % columns * (kTilePx + kTileGapPx),
        kTileGapPx + static_cast<int>(k) / columns * (kTilePx + caption_px + kTileGapPx), kTilePx,
        kTilePx);
    draw_tile(sheet, tile, topviews / (runs[k].folder_name() + ".png"));
    if (!runs[k].clean()) {
      cv::rectangle(sheet, tile, kSheetRed, 6);
    }
    int baseline = tile.br().y + kLinePx - 4;
    for (const CaptionLine& line : captions[k]) {
      cv::putText(sheet, line.text, {tile.x, baseline}, kSheetFont, line.scale, line.color,
                  line.thickness, cv::LINE_AA);
      baseline += kLinePx;
    }
  }
  return sheet;
}

std::string summary_fields(const sim::RunSummary& s) {
  const double values[kScoreColumns] = {static_cast<double>(s.agents),
                                        static_cast<double>(s.goals_reached),
                                        static_cast<double>(s.agents_with_goal()),
                                        static_cast<double>(s.collisions),
                                        static_cast<double>(s.obstacle_collisions),
                                        s.min_clearance_m,
                                        s.mean_time_to_goal_s,
                                        s.mean_path_length_m,
                                        s.mean_path_length_ratio,
                                        s.mean_time_ratio,
                                        s.composite01,
                                        s.turn_flip_ratio,
                                        s.spinning_s};
  std::string fields;
  for (std::size_t k = 0; k < kScoreColumns; ++k) {
    if (k > 0) {
      fields += ',';
    }
    fields += base::format_csv_number(values[k]);
  }
  return fields;
}

sim::RunSummary parse_summary_fields(const std::string& text, const std::string& source) {
  const std::vector<std::string> cells = split(text, ',');
  if (cells.size() != kScoreColumns) {
    throw std::runtime_error(source + ": expected " + std::to_string(kScoreColumns) +
                             " scores, got '" + text + "'");
  }
  auto integer = [&](std::size_t k) { return parse_cell(cells[k], parse_int, source); };
  auto real = [&](std::size_t k) { return parse_cell(cells[k], parse_double, source); };
  sim::RunSummary s;
  s.agents = integer(0);
  s.goals_reached = integer(1);
  s.followers = s.agents - integer(2);
  s.collisions = integer(3);
  s.obstacle_collisions = integer(4);
  s.min_clearance_m = real(5);
  s.mean_time_to_goal_s = real(6);
  s.mean_path_length_m = real(7);
  s.mean_path_length_ratio = real(8);
  s.mean_time_ratio = real(9);
  s.composite01 = real(10);
  s.turn_flip_ratio = real(11);
  s.spinning_s = real(12);
  return s;
}

void write_suite_files(const SuiteResult& result, base::OutputDir& out) {
  const bool noise_column = has_noise_column(result.runs);
  std::string csv = csv_header(noise_column) + "\n";
  for (const SuiteRun& run : result.runs) {
    csv += csv_row(run, noise_column) + "\n";
  }
  base::write_text(out.staging_path("suite.csv"), csv);
  std::ostringstream table;
  print_suite_table(result.runs, table);
  base::write_text(out.staging_path("suite.txt"), table.str());
  base::write_text(out.staging_path("suite.json"), suite_json(result));
  sim::write_image(out.staging_path("contact_sheet.png"),
                   contact_sheet(result.runs, out.staging_path("topviews")));
}

SuiteResult read_suite_files(const std::filesystem::path& dir) {
  const std::string json_path = (dir / "suite.json").string();
  if (!std::filesystem::exists(json_path)) {
    throw base::ConfigError(dir.string(), "not a suite's output folder: it has no suite.json");
  }
  YAML::Node json;
  try {
    json = YAML::LoadFile(json_path);
  } catch (const YAML::Exception& e) {
    throw base::ConfigError(json_path, e.mark.line + 1, e.mark.column + 1, "", e.msg);
  }
  const base::YamlReader reader(json_path);
  SuiteResult result;
  result.suite_id = reader.text(json, "", "suite_id", "");
  result.seed = static_cast<std::uint32_t>(reader.non_negative(json, "", "seed", 1));
  result.arrival = reader.word(json, "", "arrival", {"own", "stay", "leave"}, "own");
  result.shard = {static_cast<int>(reader.non_negative(json, "", "shard", 0)),
                  static_cast<int>(reader.positive(json, "", "shards", 1))};
  result.suite_runs = static_cast<std::size_t>(reader.non_negative(json, "", "suite_runs", 0));
  result.jobs = static_cast<int>(reader.positive(json, "", "jobs", 1));
  result.wall_s = reader.non_negative(json, "", "wall_s", 0);

  const std::string csv_path = (dir / "suite.csv").string();
  std::ifstream csv(csv_path);
  std::string line;
  if (!std::getline(csv, line) || (line != csv_header(false) && line != csv_header(true))) {
    throw base::ConfigError(csv_path, 1, 1, "",
                            "not a suite.csv: expected the header " + csv_header(false) +
                                " (with camera_noise after resolution where the suite varies it)");
  }
  const bool noise_column = line == csv_header(true);
  for (int line_number = 2; std::getline(csv, line); ++line_number) {
    try {
      result.runs.push_back(
          parse_csv_row(line, noise_column, csv_path + ":" + std::to_string(line_number)));
    } catch (const std::runtime_error& e) {
      throw base::ConfigError(csv_path, e.what());
    }
  }
  return result;
}

}  // namespace flowsteer::eval
