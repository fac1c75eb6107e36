#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace flowsteer::fuzz {

// The fuzzer's bytes as text, as a reader gets a file's contents.
inline std::string as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A folder of this process's own under the system's temporary folder, made once and removed at
// exit: harnesses whose reader opens files by name find them there, and parallel fuzzing jobs
// do not share one.
const std::filesystem::path& scratch_dir();

// Writes `text` to `name` in scratch_dir(), creating the folders on the way.
void write_scratch_file(const std::string& name, std::string_view text);

}  // namespace flowsteer::fuzz
