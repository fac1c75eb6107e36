#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::config {

// A scenario file's text under its name, as a benchmark suite lists its cases.
struct CaseFile {
  std::string name;  // the file name without its extension
  std::string path;  // for messages; the file's extension says its format
  std::string text;
};

// The scenario files the paths name: a file, or every .xml, .yaml and .yml file of a folder (not
// of its subfolders) in name order. Throws base::ConfigError naming a path that does not exist
// or cannot be read, a file of another kind, or a folder without a case.
std::vector<CaseFile> read_case_files(const std::vector<std::filesystem::path>& paths);

// The project's own suite: config/suite/, compiled in so that it runs from any folder.
std::vector<CaseFile> builtin_suite();

// The case's world, read by its extension: .xml as a SteerSuite test case, .yaml or .yml as a
// scenario file. seed: as load_steersuite.
LoadedCase parse_case(const CaseFile& file, std::uint32_t seed);

}  // namespace flowsteer::config
