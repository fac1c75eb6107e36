#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace flowsteer::base {

// An output folder that is written all at once: files go to a staging folder inside it
// (.staging-PID) and move into place on commit(), each by one rename, so no file in the folder
// is ever half-written. Without a commit (an error on the way) the staging folder is removed
// and the folder keeps what it had; the folders this object created are removed too, so a run
// that fails leaves nothing on disk it did not find. A staging folder left by a killed run is
// removed by the next run there.
class OutputDir {
 public:
  // Creates the folder; throws std::runtime_error naming it when that fails.
  explicit OutputDir(std::filesystem::path dir);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  std::filesystem::path staging_path(const std::string& file_name) const;
  // The staging folder itself, for what reads the files staged there before the commit.
  const std::filesystem::path& staging_dir() const { return staging_; }
  // Moves every file and folder of the staging folder into place; a folder replaces the one of
  // the same name.
  void commit();

 private:
  std::filesystem::path dir_;
  std::filesystem::path staging_;
  std::vector<std::filesystem::path> created_;  // the folders made for dir_, deepest first
  bool committed_ = false;
};

// How numbers are written: rounded to the few significant digits a person reads (6 in JSON, 7 in
// CSV), or exactly (the shortest text that reads back as the same double), for what other tools
// compare to bit for bit.
enum class Digits { rounded, exact };

// A string as a JSON string literal, quotes included.
std::string json_string(const std::string& s);
// A number as JSON holds it, rounded or exact (Digits); JSON has no NaN or infinity: those
// become null.
std::string json_number(double value, Digits digits = Digits::rounded);

// A number as CSV cells hold it: 7 significant digits, or exactly; NaN and infinities as an empty
// cell.
std::string format_csv_number(double value, Digits digits = Digits::rounded);

// A table of numbers written as CSV (NaN as an empty cell); a row may start with text cells
// (names without commas or quotes).
class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> header, Digits digits = Digits::rounded)
      : header_(std::move(header)), digits_(digits) {}
  // Each row has one cell per header column; a row of another width is a programming error
  // (std::logic_error), caught before a column shifts under its header.
  void add(std::vector<double> row) { add({}, std::move(row)); }
  void add(std::vector<std::string> labels, std::vector<double> values);
  // Throws std::runtime_error naming the file when it cannot be written.
  void write(const std::filesystem::path& path) const;

 private:
  std::vector<std::string> header_;
  Digits digits_;
  struct Row {
    std::vector<std::string> labels;
    std::vector<double> values;
  };
  std::vector<Row> rows_;
};

// Writes `size` bytes to `path`, or throws std::runtime_error naming the file and the reason
// (a full disk shows at the write or at the close, as ENOSPC).
void write_bytes(const std::filesystem::path& path, const void* data, std::size_t size);
// Writes `text` to `path`, or throws std::runtime_error naming the file.
void write_text(const std::filesystem::path& path, const std::string& text);

}  // namespace flowsteer::base
