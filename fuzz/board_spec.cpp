// Calibration board specs (`--board chessboard:9x6:0.025`): a spec or std::invalid_argument,
// and a spec that parses must build its detector (or be refused with std::invalid_argument)
// and read back from its own text unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>

#include "flowsteer/calibration/board.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using flowsteer::calibration::BoardSpec;
  BoardSpec spec;
  try {
    spec = BoardSpec::parse(flowsteer::fuzz::as_text(data, size));
  } catch (const std::invalid_argument&) {
    return 0;  // the parser's documented refusal
  }
  spec.warnings();
  spec.corner_count();
  const BoardSpec again = BoardSpec::parse(spec.text());
  if (again.text() != spec.text() || again.cols != spec.cols || again.rows != spec.rows ||
      again.square_m != spec.square_m || again.marker_m != spec.marker_m) {
    std::abort();  // text() must be a spec parse() reads back exactly
  }
  try {
    flowsteer::calibration::BoardDetector detector(spec);
  } catch (const std::invalid_argument&) {
    // A dictionary too small for the board: documented.
  }
  return 0;
}
