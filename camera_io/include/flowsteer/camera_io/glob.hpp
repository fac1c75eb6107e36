#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace flowsteer::camera_io {

// The files a shell-style pattern names (POSIX glob: *, ? and [...]), sorted; empty when none
// does (folders that do not exist or cannot be read match nothing, as in a shell). The caller
// says what an empty match means. Throws std::runtime_error only when glob itself fails (out of
// memory).
std::vector<std::filesystem::path> expand_glob(const std::string& pattern);

}  // namespace flowsteer::camera_io
