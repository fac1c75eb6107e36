#include "flowsteer/config/case_files.hpp"

#include <algorithm>

#include "builtin_suite.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/base/yaml_reader.hpp"

namespace flowsteer::config {

namespace {

bool is_case_file(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  return extension == ".xml" || extension == ".yaml" || extension == ".yml";
}

CaseFile read_case_file(const std::filesystem::path& path) {
  if (!is_case_file(path)) {
    throw base::ConfigError(path.string(),
                            "not a case: expected a SteerSuite test case (.xml) or a scenario "
                            "file (.yaml, .yml)");
  }
  return {path.stem().string(), path.string(), base::read_text_file(path.string(), "case")};
}

std::vector<std::filesystem::path> cases_in_folder(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file() && is_case_file(entry.path())) {
      files.push_back(entry.path());
    }
  }
  if (files.empty()) {
    throw base::ConfigError(folder.string(), "a folder without a case (.xml, .yaml, .yml)");
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

std::vector<CaseFile> read_case_files(const std::vector<std::filesystem::path>& paths) {
  std::vector<CaseFile> files;
  for (const std::filesystem::path& path : paths) {
    if (!std::filesystem::exists(path)) {
      throw base::ConfigError(path.string(), "no such file or folder");
    }
    if (std::filesystem::is_directory(path)) {
      for (const std::filesystem::path& file : cases_in_folder(path)) {
        files.push_back(read_case_file(file));
      }
    } else {
      files.push_back(read_case_file(path));
    }
  }
  return files;
}

std::vector<CaseFile> builtin_suite() {
  std::vector<CaseFile> files;
  for (const auto& [name, text] : builtin::kSuite) {
    files.push_back(
        {std::filesystem::path(name).stem().string(), std::string("config/suite/") + name, text});
  }
  return files;
}

LoadedCase parse_case(const CaseFile& file, std::uint32_t seed) {
  if (std::filesystem::path(file.path).extension() == ".xml") {
    return parse_steersuite(file.text, file.path, seed);
  }
  return {parse_scenario(file.text, file.path), {}};
}

}  // namespace flowsteer::config
