// Camera mount files (`perception.mount` of a launch file): a mount or a base::ConfigError.
#include <cstddef>
#include <cstdint>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    flowsteer::calibration::parse_camera_mount(flowsteer::fuzz::as_text(data, size), "fuzz.yaml");
  } catch (const flowsteer::base::ConfigError&) {
    // The reader's documented refusal; anything else escapes and is a finding.
  }
  return 0;
}
