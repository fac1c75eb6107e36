// Demo scenes (`flowsteer demo --scene FILE`): a scene whose every number is within its bound,
// or a base::ConfigError.
#include <cstddef>
#include <cstdint>

#include "bounds_check.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/demo_scene.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    flowsteer::fuzz::check_bounds(
        flowsteer::config::parse_demo_scene(flowsteer::fuzz::as_text(data, size), "fuzz.yaml"));
  } catch (const flowsteer::base::ConfigError&) {
    // The reader's documented refusal; anything else escapes and is a finding.
  }
  return 0;
}
