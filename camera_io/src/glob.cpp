#include "flowsteer/camera_io/glob.hpp"

#include <glob.h>

#include <algorithm>
#include <stdexcept>

namespace flowsteer::camera_io {

std::vector<std::filesystem::path> expand_glob(const std::string& pattern) {
  glob_t matches{};
  const int status = ::glob(pattern.c_str(), 0, nullptr, &matches);
  std::vector<std::filesystem::path> paths;
  for (std::size_t i = 0; status == 0 && i < matches.gl_pathc; ++i) {
    paths.emplace_back(matches.gl_pathv[i]);
  }
  ::globfree(&matches);
  if (status != 0 && status != GLOB_NOMATCH) {
    throw std::runtime_error("cannot expand '" + pattern + "' (out of memory)");
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

}  // namespace flowsteer::camera_io
