#include "flowsteer/report/page.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "flowsteer/base/atomic_file.hpp"
#include "flowsteer/base/output_files.hpp"
#include "svg.hpp"

namespace flowsteer::report {

namespace {

// A picture larger than this is linked rather than embedded.
constexpr std::uintmax_t kMaxEmbeddedBytes = 8'000'000;

// Sorts a sortable table by the column whose heading was clicked, by its cells' data-sort
// numbers where both cells have one (an empty one is not a number and sorts last), else by text;
// a second click sorts the other way. aria-sort says how it is sorted now.
constexpr const char* kSortScript = R"(
for (const table of document.querySelectorAll("table.sortable")) {
  const headings = Array.from(table.tHead.rows[0].cells);
  headings.forEach((heading, column) => heading.addEventListener("click", () => {
    const ascending = heading.getAttribute("aria-sort") !== "ascending";
    headings.forEach((h) => h.removeAttribute("aria-sort"));
    heading.setAttribute("aria-sort", ascending ? "ascending" : "descending");
    const key = (row) => {
      const cell = row.cells[column];
      if (cell.dataset.sort === undefined) return null;
      return cell.dataset.sort === "" ? Infinity : Number(cell.dataset.sort);
    };
    const body = table.tBodies[0];
    const rows = Array.from(body.rows);
    rows.sort((a, b) => {
      const x = key(a), y = key(b);
      const order = x !== null && y !== null
        ? (x === y ? 0 : x < y ? -1 : 1)
        : a.cells[column].textContent.localeCompare(b.cells[column].textContent);
      return ascending ? order : -order;
    });
    for (const row of rows) body.appendChild(row);
  }));
}
)";

constexpr const char* kStyle = R"(
body { font: 15px/1.4 system-ui, sans-serif; margin: 24px; color: #222; max-width: 1400px; }
h1 { font-size: 22px; margin: 0 0 6px; } h2 { font-size: 17px; margin: 26px 0 8px; }
.facts { color: #555; margin: 0 0 12px; } .problems { border: 2px solid #d00000;
  background: #fff0f0; padding: 8px 14px; } .problems li { color: #a00000; }
table { border-collapse: collapse; } th, td { padding: 3px 10px; border-bottom: 1px solid #ddd;
  text-align: left; } table.sortable th { cursor: pointer; user-select: none; }
th[aria-sort="ascending"]::after { content: " \25b2"; }
th[aria-sort="descending"]::after { content: " \25bc"; }
td { white-space: nowrap; } td.prose { white-space: normal; min-width: 22em; max-width: 44em; }
td.alert { color: #b00000; } .swatch { display: inline-block; width: 12px;
  height: 12px; margin-right: 6px; vertical-align: -1px; }
img { max-width: 100%; border: 1px solid #ccc; }
svg.plot { display: block; margin: 6px 0 14px; } svg.plot .title { font-size: 14px;
  font-weight: 600; } svg.plot .tick { font-size: 11px; fill: #444; }
svg.plot .label { font-size: 12px; fill: #222; } svg.plot .note { font-size: 13px; fill: #777; }
svg.plot .grid { stroke: #e6e6e6; } svg.plot .axis { stroke: #444; }
svg.plot .series { fill: none; stroke-width: 1.5; stroke-linecap: round; } svg.plot line.series { stroke-width: 3; }
svg.plot .mark { stroke: #d00000; stroke-dasharray: 4 3; stroke-width: 1.2; }
)";

std::string base64(const std::string& bytes) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t k = 0; k < bytes.size(); k += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - k);
    std::uint32_t chunk = 0;
    for (std::size_t j = 0; j < 3; ++j) {
      chunk = chunk << 8 | (j < n ? static_cast<unsigned char>(bytes[k + j]) : 0u);
    }
    for (std::size_t j = 0; j < 4; ++j) {
      out += j <= n ? kDigits[chunk >> (18 - 6 * j) & 63] : '=';
    }
  }
  return out;
}

// A relative address with each byte that is not unreserved in a URL's path percent-encoded: a
// case named "a b#2" still links to its folder.
std::string percent_encoded(const std::string& address) {
  std::string out;
  for (const char c : address) {
    if (std::isalnum(static_cast<unsigned char>(c)) != 0 || std::strchr("-._~/", c) != nullptr) {
      out += c;
    } else {
      char code[4];
      std::snprintf(code, sizeof code, "%%%02X", static_cast<unsigned char>(c));
      out += code;
    }
  }
  return out;
}

std::string anchor(const std::string& address, const std::string& text) {
  return "<a href=\"" + escaped(percent_encoded(address)) + "\">" + escaped(text) + "</a>";
}

std::string heading(const std::string& text) {
  return text.empty() ? "" : "<h2>" + escaped(text) + "</h2>\n";
}

std::string cell_html(const Cell& cell) {
  std::string html = "<td";
  if (cell.alert || cell.prose) {
    html += std::string(" class=\"") + (cell.alert ? "alert" : "") +
            (cell.alert && cell.prose ? " " : "") + (cell.prose ? "prose" : "") + "\"";
  }
  if (cell.sort_value) {
    html +=
        " data-sort=\"" +
        (std::isfinite(*cell.sort_value) ? base::json_number(*cell.sort_value, base::Digits::exact)
                                         : "") +
        "\"";
  }
  html += ">";
  if (cell.swatch) {
    html += "<span class=\"swatch\" style=\"background:" + css_color(*cell.swatch) + "\"></span>";
  }
  html += cell.link.empty() ? escaped(cell.text) : anchor(cell.link, cell.text);
  return html + "</td>";
}

std::string html_of(const Table& table, std::vector<std::string>&) {
  std::string html = heading(table.heading) + "<table" +
                     (table.sortable ? " class=\"sortable\"" : "") + "><thead><tr>";
  for (const std::string& column : table.columns) {
    html += "<th>" + escaped(column) + "</th>";
  }
  html += "</tr></thead><tbody>\n";
  for (const std::vector<Cell>& row : table.rows) {
    html += "<tr>";
    for (const Cell& cell : row) {
      html += cell_html(cell);
    }
    html += "</tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string html_of(const Picture& picture, std::vector<std::string>& problems) {
  const std::string name = picture.file.filename().string();
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(picture.file, error);
  if (!error && size > kMaxEmbeddedBytes) {
    // A contact sheet of hundreds of runs: linked, so that the page stays quick to open.
    return heading(picture.heading) + "<p>" + anchor(name, name) + " (" +
           std::to_string(size / 1'000'000) + " MB, not embedded)</p>\n";
  }
  std::ifstream in(picture.file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const char* problem = error                       ? "missing or unreadable"
                        : !in.is_open() || in.bad() ? "unreadable"
                        : bytes.empty()             ? "empty"
                                                    : nullptr;
  if (problem != nullptr) {
    problems.push_back(name + ": " + problem);
    return heading(picture.heading) + "<p class=\"note\">(" + escaped(name) + " " + problem +
           ")</p>\n";
  }
  return heading(picture.heading) + "<img alt=\"" + escaped(picture.heading) +
         "\" src=\"data:image/png;base64," + base64(bytes) + "\">\n";
}

std::string html_of(const Plot& plot, std::vector<std::string>&) {
  return svg_of(plot) + "\n";
}

std::string html_of(const Links& links, std::vector<std::string>&) {
  std::string html = heading(links.heading) + "<ul>";
  for (const auto& [text, address] : links.links) {
    html += "<li>" + anchor(address, text) + "</li>";
  }
  return html + "</ul>\n";
}

std::string html_of(const Text& text, std::vector<std::string>&) {
  std::string html = heading(text.heading);
  for (const std::string& line : text.lines) {
    html += "<p>" + escaped(line) + "</p>";
  }
  return html + "\n";
}

}  // namespace

Cell text_cell(std::string text) {
  Cell cell;
  cell.text = std::move(text);
  return cell;
}

Cell number_cell(double value, int decimals, const std::string& unit) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  Cell cell = text_cell(std::isfinite(value) ? text + unit : "-");
  cell.sort_value = value;
  return cell;
}

Rgb agent_color(std::size_t agent) {
  static constexpr Rgb kPalette[kAgentColors] = {{30, 60, 200},  {40, 160, 40},  {220, 60, 30},
                                                 {180, 40, 180}, {200, 170, 20}, {20, 90, 120},
                                                 {90, 90, 90},   {140, 200, 60}};
  return kPalette[agent % std::size(kPalette)];
}

double tick_step(double at_least) {
  const double decade = std::pow(10.0, std::floor(std::log10(at_least)));
  for (const double mantissa : {1.0, 2.0, 5.0}) {
    if (mantissa * decade >= at_least) {
      return mantissa * decade;
    }
  }
  return 10.0 * decade;
}

std::string render_page(Page& page) {
  std::string body;
  for (const Section& section : page.sections) {
    body += std::visit([&](const auto& s) { return html_of(s, page.problems); }, section);
  }
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
                     escaped(page.title) + "</title><style>" + kStyle + "</style></head><body>\n";
  html += "<h1>" + escaped(page.title) + "</h1>\n";
  for (const std::string& fact : page.facts) {
    html += "<p class=\"facts\">" + escaped(fact) + "</p>\n";
  }
  if (!page.problems.empty()) {
    html += "<div class=\"problems\"><p>Not everything of this folder could be read:</p><ul>";
    for (const std::string& problem : page.problems) {
      html += "<li>" + escaped(problem) + "</li>";
    }
    html += "</ul></div>\n";
  }
  return html + body + "<script>" + kSortScript + "</script>\n</body></html>\n";
}

void write_page(const std::filesystem::path& path, Page& page) {
  base::write_file_atomically(path, render_page(page));
}

}  // namespace flowsteer::report
