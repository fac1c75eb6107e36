#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace flowsteer::report {

// A CSV file as the project writes them (base::CsvTable): a header, then rows of cells without
// quotes. Every cell is read as a number (an empty one is a number not given, NaN) but those of
// the text columns named; a run's tables of a million rows take 8 bytes a number cell.
class CsvFile {
 public:
  // Throws std::runtime_error naming the file: missing, empty, a row whose width differs from
  // the header's, or a cell that is not a number (with its line and column).
  explicit CsvFile(const std::filesystem::path& path,
                   const std::vector<std::string>& text_columns = {});

  const std::string& path() const { return path_; }
  std::size_t rows() const { return rows_; }
  const std::vector<std::string>& header() const { return header_; }
  bool has_column(const std::string& name) const;
  // Every row's number in that column; throws std::runtime_error naming the file and the
  // column when it has none of that name or it is a text column.
  const std::vector<double>& numbers(const std::string& name) const;
  // Every row's text in a text column; throws as numbers() does.
  const std::vector<std::string>& texts(const std::string& name) const;

 private:
  std::size_t column(const std::string& name) const;
  double number(std::string_view cell, int line_number, std::size_t column) const;
  std::string path_;
  std::vector<std::string> header_;
  std::vector<bool> is_text_;
  std::size_t rows_ = 0;
  std::vector<std::vector<double>> numbers_;     // by column; empty for a text column
  std::vector<std::vector<std::string>> texts_;  // by column; empty for a number column
};

}  // namespace flowsteer::report
