#pragma once

#include <filesystem>
#include <string>

namespace flowsteer::base {

// Writes `text` to a temporary file next to `path`, flushes it to disk and renames it over
// `path`: readers see the old file or the whole new one, never a part. Throws
// std::runtime_error naming the file; the temporary file is removed on failure.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace flowsteer::base
