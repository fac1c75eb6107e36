#include "csv_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string_view>

namespace flowsteer::report {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t from = 0;
  for (std::size_t comma = line.find(','); comma != std::string::npos;
       comma = line.find(',', from)) {
    cells.push_back(line.substr(from, comma - from));
    from = comma + 1;
  }
  cells.push_back(line.substr(from));
  return cells;
}

}  // namespace

CsvFile::CsvFile(const std::filesystem::path& path, const std::vector<std::string>& text_columns)
    : path_(path.string()) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error(path_ + ": missing or unreadable");
  }
  std::string line;
  if (!std::getline(in, line) || line.empty()) {
    throw std::runtime_error(path_ + ": empty, no header");
  }
  header_ = split(line);
  for (const std::string& name : header_) {
    is_text_.push_back(std::find(text_columns.begin(), text_columns.end(), name) !=
                       text_columns.end());
  }
  numbers_.resize(header_.size());
  texts_.resize(header_.size());
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    const auto cells = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
    if (cells != header_.size()) {
      throw std::runtime_error(path_ + ":" + std::to_string(line_number) + ": " +
                               std::to_string(cells) + " cells under a header of " +
                               std::to_string(header_.size()));
    }
    std::size_t from = 0;
    for (std::size_t c = 0; c < header_.size(); ++c) {
      const std::size_t end = std::min(line.find(',', from), line.size());
      const std::string_view cell(line.data() + from, end - from);
      from = end + 1;
      if (is_text_[c]) {
        texts_[c].emplace_back(cell);
      } else {
        numbers_[c].push_back(number(cell, line_number, c));
      }
    }
    ++rows_;
  }
}

double CsvFile::number(std::string_view cell, int line_number, std::size_t column) const {
  double value = std::nan("");
  if (cell.empty()) {
    return value;
  }
  const auto [stop, error] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (error != std::errc() || stop != cell.data() + cell.size()) {
    throw std::runtime_error(path_ + ":" + std::to_string(line_number) + ": column '" +
                             header_[column] + "': not a number: '" + std::string(cell) + "'");
  }
  return value;
}

bool CsvFile::has_column(const std::string& name) const {
  return std::find(header_.begin(), header_.end(), name) != header_.end();
}

std::size_t CsvFile::column(const std::string& name) const {
  const auto found = std::find(header_.begin(), header_.end(), name);
  if (found == header_.end()) {
    throw std::runtime_error(path_ + ": no column '" + name + "' in its header");
  }
  return static_cast<std::size_t>(found - header_.begin());
}

const std::vector<double>& CsvFile::numbers(const std::string& name) const {
  const std::size_t c = column(name);
  if (is_text_[c]) {
    throw std::runtime_error(path_ + ": column '" + name + "' is text, not numbers");
  }
  return numbers_[c];
}

const std::vector<std::string>& CsvFile::texts(const std::string& name) const {
  const std::size_t c = column(name);
  if (!is_text_[c]) {
    throw std::runtime_error(path_ + ": column '" + name + "' holds numbers, not text");
  }
  return texts_[c];
}

}  // namespace flowsteer::report
