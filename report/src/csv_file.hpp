#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace flowsteer::report {

// A CSV file as the project writes them (base::CsvTable): a header, then rows of cells without
// quotes; an empty cell is a number not given (NaN).
class CsvFile {
 public:
  // Throws std::runtime_error naming the file: missing, empty, or a row whose width differs
  // from the header's (with its line).
  explicit CsvFile(const std::filesystem::path& path);

  const std::string& path() const { return path_; }
  std::size_t rows() const { return cells_.size(); }
  // The column of that name; throws std::runtime_error naming the file and the column.
  std::size_t column(const std::string& name) const;
  bool has_column(const std::string& name) const;
  const std::vector<std::string>& header() const { return header_; }
  const std::string& text(std::size_t row, std::size_t column) const { return cells_[row][column]; }
  // The cell as a number (NaN when empty); throws std::runtime_error naming file, line, column
  // and text for one that is not a number.
  double number(std::size_t row, std::size_t column) const;
  // Every row's number in that column.
  std::vector<double> numbers(const std::string& name) const;

 private:
  std::string path_;
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> cells_;
};

}  // namespace flowsteer::report
