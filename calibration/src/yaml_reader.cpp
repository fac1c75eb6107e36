#include "flowsteer/calibration/yaml_reader.hpp"

#include <fstream>

namespace flowsteer::calibration {

YAML::Node load_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source_name, e.mark.line + 1, e.mark.column + 1, "", e.msg);
  }
}

std::string read_text_file(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) {
    throw ConfigError(path, std::string("cannot open the ") + what);
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw ConfigError(path, std::string("cannot read the ") + what);
  }
  return text.str();
}

}  // namespace flowsteer::calibration
