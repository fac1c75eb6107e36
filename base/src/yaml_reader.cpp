#include "flowsteer/base/yaml_reader.hpp"

#include <fstream>
#include <sstream>

namespace flowsteer::base {

YAML::Node load_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source_name, e.mark.line + 1, e.mark.column + 1, "", e.msg);
  }
}

YAML::Node load_yaml_map(const std::string& text, const std::string& source_name,
                         const std::string& contents, std::initializer_list<const char*> keys) {
  const YAML::Node root = load_yaml(text, source_name);
  if (!root.IsMap()) {
    throw ConfigError(source_name, 1, 1, "", "expected a mapping with " + contents);
  }
  YamlReader(source_name).only_keys(root, "", keys);
  return root;
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

}  // namespace flowsteer::base
