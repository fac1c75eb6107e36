#include "csv_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>

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

CsvFile::CsvFile(const std::filesystem::path& path) : path_(path.string()) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error(path_ + ": missing or unreadable");
  }
  std::string line;
  if (!std::getline(in, line) || line.empty()) {
    throw std::runtime_error(path_ + ": empty, no header");
  }
  header_ = split(line);
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    std::vector<std::string> cells = split(line);
    if (cells.size() != header_.size()) {
      throw std::runtime_error(path_ + ":" + std::to_string(line_number) + ": " +
                               std::to_string(cells.size()) + " cells under a header of " +
                               std::to_string(header_.size()));
    }
    cells_.push_back(std::move(cells));
  }
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

double CsvFile::number(std::size_t row, std::size_t column) const {
  const std::string& text = cells_[row][column];
  if (text.empty()) {
    return std::nan("");
  }
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw std::runtime_error(path_ + ":" + std::to_string(row + 2) + ": column '" +
                             header_[column] + "': not a number: '" + text + "'");
  }
  return value;
}

std::vector<double> CsvFile::numbers(const std::string& name) const {
  const std::size_t c = column(name);
  std::vector<double> values(rows());
  for (std::size_t r = 0; r < rows(); ++r) {
    values[r] = number(r, c);
  }
  return values;
}

}  // namespace flowsteer::report
