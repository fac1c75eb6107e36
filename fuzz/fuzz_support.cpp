#include "fuzz_support.hpp"

#include <stdlib.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace flowsteer::fuzz {

const std::filesystem::path& scratch_dir() {
  // Never destroyed, so that the exit handler that removes the folder can still name it.
  static const auto* const dir = [] {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "flowsteer_fuzz_XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a scratch folder from " + pattern);
    }
    auto* path = new std::filesystem::path(pattern);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratch_dir(), ignored);
    });
    return path;
  }();
  return *dir;
}

void write_scratch_file(const std::string& name, std::string_view text) {
  const std::filesystem::path path = scratch_dir() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!out) {
    throw std::runtime_error("cannot write " + path.string());
  }
}

}  // namespace flowsteer::fuzz
