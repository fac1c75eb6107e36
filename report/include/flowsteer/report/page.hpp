#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace flowsteer::report {

// A report page: one self-contained HTML file that a browser shows without a network. Pictures
// are embedded as data URIs, plots are inline SVG, and a sortable table sorts by a small inline
// script, so the file can be mailed or archived alone.

struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
};
// The colour agent i has in every picture of a run: the top view, its legend, the plots, the 3D
// scene of a recording; the palette repeats after kAgentColors agents.
inline constexpr std::size_t kAgentColors = 8;
Rgb agent_color(std::size_t agent);

// The smallest of 1, 2 or 5 times a power of ten that is at least `at_least` (> 0): the step
// between an axis' ticks.
double tick_step(double at_least);

// One agent's values over time in a plot; NaN leaves a gap (an agent that has left, no value).
struct Series {
  std::string name;
  Rgb color;
  std::vector<double> t_s;
  std::vector<double> values;
};

// Values over time, one line per series, with moments marked (contacts) as vertical lines.
struct Plot {
  std::string title;
  std::string y_label;  // with its unit
  std::vector<Series> series;
  std::vector<double> marks_t_s;
  std::string marks_label;  // what a mark is, in the legend ("contact")
  // Values above are drawn at this height (a time to contact of minutes says nothing).
  std::optional<double> y_max;
  std::string empty_note;  // shown in place of lines when no series has a value
};

struct Cell {
  std::string text;
  // What the column sorts by; none: the text. NaN sorts as a number above every other (last
  // when ascending, first when descending).
  std::optional<double> sort_value;
  std::string link;           // a relative address, or none
  bool alert = false;         // drawn as a problem (red)
  bool prose = false;         // words that wrap in a wide column (a reason), not a value
  std::optional<Rgb> swatch;  // a colour square before the text (an agent's colour)
};

// A cell of text; a cell of a number with `decimals` decimals and its unit, sorted by the number
// ("-" for NaN).
Cell text_cell(std::string text);
Cell number_cell(double value, int decimals, const std::string& unit = "");

struct Table {
  std::string heading;
  std::vector<std::string> columns;
  std::vector<std::vector<Cell>> rows;
  bool sortable = false;  // a click on a column's heading sorts by it, again the other way
};

struct Picture {
  std::string heading;
  // A PNG beside the page: embedded, or linked where it is over 8 MB (a contact sheet of
  // hundreds of runs); one that cannot be read is a problem.
  std::filesystem::path file;
};

struct Links {
  std::string heading;
  std::vector<std::pair<std::string, std::string>> links;  // text, relative address
};

struct Text {
  std::string heading;
  std::vector<std::string> lines;
};

using Section = std::variant<Text, Table, Picture, Plot, Links>;

struct Page {
  std::string title;
  std::vector<std::string> facts;     // lines under the title
  std::vector<std::string> problems;  // what could not be read, shown before anything else
  std::vector<Section> sections;
};

// The page as HTML. A picture that cannot be read is added to page.problems, which the page
// shows.
std::string render_page(Page& page);

// Writes render_page(page) to path (atomically); throws std::runtime_error naming the file.
void write_page(const std::filesystem::path& path, Page& page);

}  // namespace flowsteer::report
