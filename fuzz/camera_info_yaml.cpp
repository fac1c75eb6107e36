// camera_info files (`camera.calibration` of a launch file, `calibrate mount --intrinsics`): a
// camera model or a base::ConfigError.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> warnings;
  try {
    flowsteer::calibration::parse_camera_info(flowsteer::fuzz::as_text(data, size), "fuzz.yaml",
                                              warnings);
  } catch (const flowsteer::base::ConfigError&) {
    // The reader's documented refusal; anything else escapes and is a finding.
  }
  return 0;
}
