#pragma once

#include <stdexcept>
#include <string>

namespace flowsteer::base {

// A problem in a file the user wrote: the message starts with "file:line:column: field:" so
// that editors and terminals can jump to it.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, int line, int column, const std::string& field,
              const std::string& message)
      : std::runtime_error(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                           (field.empty() ? "" : field + ": ") + message) {}
  // For a file that cannot be read at all.
  ConfigError(const std::string& file, const std::string& message)
      : std::runtime_error(file + ": " + message) {}
};

}  // namespace flowsteer::base
