// The replay source's image-sequence pattern (`camera.replay.path`, `flowsteer replay`): a glob
// or a printf pattern, resolved to the files it names or refused with std::runtime_error. The
// patterns are taken inside a scratch folder holding two small sequences, one numbered from 0
// and one from 1; absolute patterns and those that could climb out of it (a component starting with
// '.', escaped or not) are skipped, so the fuzzer does not walk the machine's file system.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "flowsteer/camera_io/replay_source.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  for (const char* name :
       {"frames/frame_00000.png", "frames/frame_00001.png", "frames/frame_00002.png",
        "seq/img_1.jpg", "seq/img_2.jpg", "seq/img_3.jpg", "seq/100%/a.png"}) {
    flowsteer::fuzz::write_scratch_file(name, "");
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string pattern = flowsteer::fuzz::as_text(data, size);
  // A component that starts with '.' can match "..", as ".*" does in a shell, and so can one
  // that starts with an escaped '.' ("\.*"): the check reads the pattern without backslashes.
  std::string unescaped = pattern;
  std::erase(unescaped, '\\');
  if (unescaped.starts_with('/') || unescaped.starts_with('.') ||
      unescaped.find("/.") != std::string::npos) {
    return 0;
  }
  const std::string path = (flowsteer::fuzz::scratch_dir() / pattern).string();
  if (!flowsteer::camera_io::is_image_sequence_pattern(path)) {
    return 0;
  }
  try {
    flowsteer::camera_io::image_sequence_files(path);
  } catch (const std::runtime_error&) {
    // The documented refusal of a bad printf pattern (and std::filesystem's errors, which are
    // std::runtime_errors naming the path).
  }
  return 0;
}
