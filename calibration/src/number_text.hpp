#pragma once

// Internal to calibration: how the files and messages it writes spell a number.

#include <charconv>
#include <string>

namespace flowsteer::calibration {

// The shortest text that reads back as the same double (std::to_chars): 0.0254001 stays
// 0.0254001, 0.1 is 0.1.
inline std::string number_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

}  // namespace flowsteer::calibration
