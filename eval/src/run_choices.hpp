#pragma once

// What the evaluations that run a scenario several ways (suite, robustness, compare) share about
// the choices their options give.

#include <algorithm>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "flowsteer/base/config_error.hpp"

namespace flowsteer::eval {

inline constexpr int kMinResolution = 16;  // pixels, either side
inline constexpr int kMaxResolution = 4096;

// Each value given, or one empty value (the case's or scenario's own) when none is.
template <typename T>
std::vector<std::optional<T>> each_or_own(const std::vector<T>& values) {
  std::vector<std::optional<T>> choices(values.begin(), values.end());
  if (choices.empty()) {
    choices.emplace_back();
  }
  return choices;
}

// Throws base::ConfigError "OPTION VALUE: given twice" for the first value given twice; values
// are numbers or have a to_string (the servo enums).
template <typename T>
void refuse_repeats(const std::vector<T>& values, const std::string& option) {
  for (auto it = values.begin(); it != values.end(); ++it) {
    if (std::find(values.begin(), it, *it) != it) {
      std::ostringstream value;
      if constexpr (std::is_arithmetic_v<T>) {
        value << *it;
      } else {
        value << to_string(*it);
      }
      throw base::ConfigError(option + " " + value.str(), "given twice");
    }
  }
}

// Throws base::ConfigError naming --resolution for one out of range or given twice.
inline void check_resolutions(const std::vector<int>& resolutions) {
  for (const int n : resolutions) {
    if (n < kMinResolution || n > kMaxResolution) {
      throw base::ConfigError("--resolution " + std::to_string(n),
                              "must be from " + std::to_string(kMinResolution) + " to " +
                                  std::to_string(kMaxResolution) + " pixels");
    }
  }
  refuse_repeats(resolutions, "--resolution");
}

}  // namespace flowsteer::eval
