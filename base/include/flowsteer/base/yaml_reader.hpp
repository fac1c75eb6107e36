#pragma once

#include <cmath>
#include <initializer_list>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "flowsteer/base/bounds.hpp"
#include "flowsteer/base/config_error.hpp"

namespace flowsteer::base {

// Reads typed fields out of YAML nodes and reports problems at the node's position, under a
// dotted field path such as "objects[2].radius_m". The bounded readers take each field's bound
// from the reader's table (base::FieldBound), one row per field of the file's format.
class YamlReader {
 public:
  explicit YamlReader(std::string source, std::span<const FieldBound> bounds = {})
      : source_(std::move(source)), bounds_(bounds) {}

  // A node that is not there (a missing key) or the null document of an empty file has no
  // position: the error then points at line 1.
  [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                         const std::string& message) const {
    const YAML::Mark mark = node.IsDefined() && node.Mark().line >= 0 ? node.Mark() : YAML::Mark();
    throw ConfigError(source_, mark.line + 1, mark.column + 1, field, message);
  }

  // Fails on any key of `map` that is not in `allowed`, so that typos do not pass silently.
  void only_keys(const YAML::Node& map, const std::string& field,
                 std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) {
      fail(map, field, "expected a mapping");
    }
    const std::set<std::string> names(allowed.begin(), allowed.end());
    for (const auto& entry : map) {
      const std::string key = key_text(entry.first, field);
      if (!names.contains(key)) {
        std::string list;
        for (const char* name : allowed) {
          list += list.empty() ? name : std::string(", ") + name;
        }
        fail(entry.first, join(field, key), "unknown key (expected one of: " + list + ")");
      }
    }
  }

  // The text of a mapping's key. YAML also allows a sequence, a mapping or nothing as a key
  // ("? [a, b]: 1"), which no file of the project has: an error at the key.
  std::string key_text(const YAML::Node& key, const std::string& field) const {
    if (!key.IsScalar()) {
      fail(key, field, "expected a text key, got " + describe(key));
    }
    return key.Scalar();
  }

  double number(const YAML::Node& map, const std::string& field, const char* key,
                double fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    return number(node, join(field, key));
  }

  double number(const YAML::Node& node, const std::string& field) const {
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
      fail(node, field, "expected a finite number, got '" + describe(node) + "'");
    }
    return value;
  }

  // A number within the table's bound for `field`.`key`; `fallback` when the key is absent.
  // The row is looked up either way, so that a field its table forgot fails at once.
  double bounded(const YAML::Node& map, const std::string& field, const char* key,
                 double fallback) const {
    const std::string path = join(field, key);
    const Bound& bound = bound_of(bounds_, path);
    const YAML::Node node = map[key];
    return node ? within(node, path, bound) : fallback;
  }
  // A whole number within the table's bound for `field`.
  int bounded_integer(const YAML::Node& node, const std::string& field) const {
    return within_integer(node, field, bound_of(bounds_, field));
  }
  int within_integer(const YAML::Node& node, const std::string& field, const Bound& bound) const {
    int value = 0;
    if (!node.IsScalar() || !YAML::convert<int>::decode(node, value)) {
      fail(node, field, "expected a whole number, got '" + describe(node) + "'");
    }
    if (!bound.contains(value)) {
      fail(node, field, bound.refusal(value));
    }
    return value;
  }
  // A pair [x, y] whose components are within the table's bound for `field`.`key`.
  Eigen::Vector2d bounded_pair(const YAML::Node& map, const std::string& field, const char* key,
                               const Eigen::Vector2d& fallback) const {
    const std::string path = join(field, key);
    const Bound& bound = bound_of(bounds_, path);
    const YAML::Node node = map[key];
    return node ? bounded_pair(node, path, bound) : fallback;
  }
  Eigen::Vector2d bounded_pair(const YAML::Node& node, const std::string& field,
                               const Bound& bound) const {
    if (!node.IsSequence() || node.size() != 2) {
      fail(node, field, "expected a pair [x, y]");
    }
    return {within(node[0], field + "[0]", bound), within(node[1], field + "[1]", bound)};
  }
  // A number within `bound`, for a field whose row the caller found.
  double within(const YAML::Node& node, const std::string& field, const Bound& bound) const {
    const double value = number(node, field);
    if (!bound.contains(value)) {
      fail(node, field, bound.refusal(value));
    }
    return value;
  }
  std::span<const FieldBound> bounds() const { return bounds_; }

  double positive(const YAML::Node& map, const std::string& field, const char* key,
                  double fallback) const {
    const double value = number(map, field, key, fallback);
    if (!(value > 0.0)) {
      fail(map[key] ? map[key] : map, join(field, key), "must be positive, got " + format(value));
    }
    return value;
  }

  double non_negative(const YAML::Node& map, const std::string& field, const char* key,
                      double fallback) const {
    const double value = number(map, field, key, fallback);
    if (value < 0.0) {
      fail(map[key], join(field, key), "must be >= 0, got " + format(value));
    }
    return value;
  }

  int integer(const YAML::Node& node, const std::string& field, int min_value) const {
    int value = 0;
    if (!node.IsScalar() || !YAML::convert<int>::decode(node, value)) {
      fail(node, field, "expected an integer, got '" + describe(node) + "'");
    }
    if (value < min_value) {
      fail(node, field,
           "must be at least " + std::to_string(min_value) + ", got " + std::to_string(value));
    }
    return value;
  }

  std::string word(const YAML::Node& map, const std::string& field, const char* key,
                   std::initializer_list<const char*> allowed, const char* fallback) const {
    return word(map, field, key, std::span<const char* const>(allowed.begin(), allowed.size()),
                fallback);
  }
  std::string word(const YAML::Node& map, const std::string& field, const char* key,
                   std::span<const char* const> allowed, const char* fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    const std::string value = node.IsScalar() ? node.as<std::string>() : "";
    for (const char* a : allowed) {
      if (value == a) {
        return value;
      }
    }
    std::string list;
    for (const char* a : allowed) {
      list += list.empty() ? a : std::string(", ") + a;
    }
    fail(node, join(field, key), "expected one of: " + list + "; got '" + describe(node) + "'");
  }

  // A text value: a scalar, else a ConfigError at the node. `non_empty` also refuses "".
  std::string text(const YAML::Node& map, const std::string& field, const char* key,
                   const std::string& fallback, bool non_empty = false) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    if (!node.IsScalar() || (non_empty && node.Scalar().empty())) {
      fail(node, join(field, key), non_empty ? "expected a non-empty text" : "expected a text");
    }
    return node.Scalar();
  }

  bool boolean(const YAML::Node& map, const std::string& field, const char* key,
               bool fallback) const {
    const YAML::Node node = map[key];
    if (!node) {
      return fallback;
    }
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
      fail(node, join(field, key), "expected true or false, got '" + describe(node) + "'");
    }
    return value;
  }

  static std::string join(const std::string& field, const std::string& key) {
    return field.empty() ? key : field + "." + key;
  }

 private:
  static std::string describe(const YAML::Node& node) {
    if (node.IsScalar()) {
      return node.Scalar();
    }
    return node.IsSequence() ? "a sequence" : node.IsMap() ? "a mapping" : "nothing";
  }
  static std::string format(double value) { return format_number(value); }

  std::string source_;
  std::span<const FieldBound> bounds_;
};

// Parses YAML text, turning a syntax error into a ConfigError at its line and column.
YAML::Node load_yaml(const std::string& text, const std::string& source_name);

// load_yaml for a file whose top level is a mapping with the given keys only: ConfigError
// "expected a mapping with <contents>" at line 1 otherwise, and at an unknown key.
YAML::Node load_yaml_map(const std::string& text, const std::string& source_name,
                         const std::string& contents, std::initializer_list<const char*> keys);

// Reads a whole file; ConfigError when it cannot be opened or read.
std::string read_text_file(const std::string& path, const char* what);

}  // namespace flowsteer::base
