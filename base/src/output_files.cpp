#include "flowsteer/base/output_files.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace flowsteer::base {

std::string json_string(const std::string& s) {
  std::ostringstream out;
  out << '"';
  for (const char c : s) {
    switch (c) {
      case '"':
        out << "\\\"";
        break;
      case '\\':
        out << "\\\\";
        break;
      case '\n':
        out << "\\n";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          out << "\\u" << std::hex << std::setw(4) << std::setfill('0') << static_cast<int>(c)
              << std::dec;
        } else {
          out << c;
        }
    }
  }
  out << '"';
  return out.str();
}

namespace {

std::string exact_number(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof text, value);
  return {text, end};
}

}  // namespace

std::string json_number(double value, Digits digits) {
  if (!std::isfinite(value)) {
    return "null";
  }
  if (digits == Digits::exact) {
    return exact_number(value);
  }
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

namespace {

constexpr char kStagingPrefix[] = ".staging-";

// A run killed before its commit (SIGKILL, a power cut) leaves its staging folder behind; the
// next run in the same folder removes every one whose process is gone.
void remove_abandoned_staging(const std::filesystem::path& dir) {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(kStagingPrefix)) {
      continue;
    }
    const std::string pid_text = name.substr(std::strlen(kStagingPrefix));
    pid_t pid = 0;
    const auto [end, status] =
        std::from_chars(pid_text.data(), pid_text.data() + pid_text.size(), pid);
    const bool ours = status == std::errc() && end == pid_text.data() + pid_text.size();
    if (ours && pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code ignored;
      std::filesystem::remove_all(entry.path(), ignored);
    }
  }
}

// `dir` and those of its parents that do not exist yet, deepest first: what creating it makes.
std::vector<std::filesystem::path> missing_folders(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> missing;
  std::error_code error;
  for (std::filesystem::path p = std::filesystem::absolute(dir, error);
       !error && !p.empty() && !std::filesystem::exists(p, error); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) {
      break;
    }
  }
  return missing;
}

}  // namespace

OutputDir::OutputDir(std::filesystem::path dir)
    : dir_(std::move(dir)), created_(missing_folders(dir_)) {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) {
    throw std::runtime_error("cannot create the output folder " + dir_.string() + ": " +
                             error.message());
  }
  remove_abandoned_staging(dir_);
  staging_ = dir_ / (std::string(kStagingPrefix) + std::to_string(::getpid()));
  std::filesystem::remove_all(staging_, error);  // a dead run's, under a reused process id
  std::filesystem::create_directory(staging_, error);
  if (error) {
    throw std::runtime_error("cannot write into the output folder " + dir_.string() + ": " +
                             error.message());
  }
}

OutputDir::~OutputDir() {
  std::error_code ignored;
  std::filesystem::remove_all(staging_, ignored);
  if (!committed_) {
    // Only empty folders go: anything another program put there meanwhile stays.
    for (const std::filesystem::path& folder : created_) {
      std::filesystem::remove(folder, ignored);
    }
  }
}

std::filesystem::path OutputDir::staging_path(const std::string& file_name) const {
  return staging_ / file_name;
}

void OutputDir::commit() {
  for (const auto& entry : std::filesystem::directory_iterator(staging_)) {
    std::error_code error;
    const std::filesystem::path target = dir_ / entry.path().filename();
    if (entry.is_directory() && std::filesystem::is_directory(target)) {
      std::filesystem::remove_all(target, error);
    }
    if (!error) {
      std::filesystem::rename(entry.path(), target, error);
    }
    if (error) {
      throw std::runtime_error("cannot move " + entry.path().filename().string() + " into " +
                               dir_.string() + ": " + error.message());
    }
  }
  committed_ = true;
}

void write_bytes(const std::filesystem::path& path, const void* data, std::size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(errno));
  }
  const bool written = std::fwrite(data, 1, size, file) == size && std::fflush(file) == 0;
  const int write_errno = errno;
  if (std::fclose(file) != 0 || !written) {
    throw std::runtime_error("cannot write " + path.string() + ": " +
                             std::strerror(written ? errno : write_errno));
  }
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  write_bytes(path, text.data(), text.size());
}

std::string format_csv_number(double value, Digits digits) {
  if (!std::isfinite(value)) {
    return "";
  }
  if (digits == Digits::exact) {
    return exact_number(value);
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.7g", value);
  return text;
}

void CsvTable::add(std::vector<std::string> labels, std::vector<double> values) {
  if (labels.size() + values.size() != header_.size()) {
    throw std::logic_error("CsvTable: a row of " + std::to_string(labels.size() + values.size()) +
                           " cells under a header of " + std::to_string(header_.size()) +
                           " columns (" + (header_.empty() ? "" : header_.front()) + ", ...)");
  }
  rows_.push_back({std::move(labels), std::move(values)});
}

void CsvTable::write(const std::filesystem::path& path) const {
  std::ostringstream out;
  for (std::size_t k = 0; k < header_.size(); ++k) {
    out << (k > 0 ? "," : "") << header_[k];
  }
  out << "\n";
  for (const Row& row : rows_) {
    for (std::size_t k = 0; k < row.labels.size(); ++k) {
      out << (k > 0 ? "," : "") << row.labels[k];
    }
    for (std::size_t k = 0; k < row.values.size(); ++k) {
      out << (k > 0 || !row.labels.empty() ? "," : "") << format_csv_number(row.values[k], digits_);
    }
    out << "\n";
  }
  write_text(path, out.str());
}

}  // namespace flowsteer::base
