#include "flowsteer/eval/output_files.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

namespace flowsteer::eval {

namespace {

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

// JSON has no NaN or infinity: those become null.
std::string json_number(double value) {
  if (!std::isfinite(value)) {
    return "null";
  }
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

}  // namespace

OutputDir::OutputDir(std::filesystem::path dir) : dir_(std::move(dir)) {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) {
    throw std::runtime_error("cannot create the output folder " + dir_.string() + ": " +
                             error.message());
  }
  std::random_device random;
  staging_ = dir_ / (".staging-" + std::to_string(random()));
  std::filesystem::create_directory(staging_, error);
  if (error) {
    throw std::runtime_error("cannot write into the output folder " + dir_.string() + ": " +
                             error.message());
  }
}

OutputDir::~OutputDir() {
  std::error_code ignored;
  std::filesystem::remove_all(staging_, ignored);
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
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) {
    throw std::runtime_error("cannot write " + path.string());
  }
}

void write_image(const std::filesystem::path& path, const cv::Mat& image) {
  bool written = false;
  try {
    written = cv::imwrite(path.string(), image);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot write " + path.string() + ": " + e.what());
  }
  if (!written) {
    throw std::runtime_error("cannot write " + path.string());
  }
}

std::string format_csv_number(double value) {
  if (!std::isfinite(value)) {
    return "";
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
      out << (k > 0 || !row.labels.empty() ? "," : "") << format_csv_number(row.values[k]);
    }
    out << "\n";
  }
  write_text(path, out.str());
}

void write_summary_json(const std::filesystem::path& path, const SimResult& result) {
  std::ostringstream out;
  out << "{\n  \"scenario\": " << json_string(result.scenario) << ",\n  \"steps\": " << result.steps
      << ",\n  \"duration_s\": " << json_number(result.duration_s) << ",\n  \"agents\": [\n";
  for (std::size_t i = 0; i < result.agents.size(); ++i) {
    const AgentResult& a = result.agents[i];
    out << "    {\"name\": " << json_string(a.name)
        << ", \"reached_goal\": " << (a.reached_goal ? "true" : "false")
        << ", \"time_to_goal_s\": " << (a.reached_goal ? json_number(a.time_to_goal_s) : "null")
        << ", \"path_length_m\": " << json_number(a.path_length_m)
        << ", \"min_clearance_m\": " << json_number(a.min_clearance_m)
        << ", \"collisions\": " << a.collisions;
    if (a.final_distance_to_leader_m >= 0.0) {
      out << ", \"final_distance_to_leader_m\": " << json_number(a.final_distance_to_leader_m);
    }
    out << "}" << (i + 1 < result.agents.size() ? "," : "") << "\n";
  }
  const pipeline::StageTimes& t = result.per_agent_step_ms;
  out << "  ],\n  \"collisions_total\": " << result.collisions.size()
      << ",\n  \"per_agent_step_ms\": {\"render\": " << json_number(t.render)
      << ", \"flow\": " << json_number(t.flow) << ", \"segment\": " << json_number(t.segment)
      << ", \"features\": " << json_number(t.features)
      << ", \"control\": " << json_number(t.control) << ", \"total\": " << json_number(t.total)
      << "},\n  \"threads\": " << result.threads
      << ",\n  \"world_steps_per_s\": " << json_number(result.world_steps_per_s) << "\n}\n";
  write_text(path, out.str());
}

}  // namespace flowsteer::eval
