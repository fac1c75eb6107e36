// RoboClaw's reply to Read Encoders (command 78): counts, or std::nullopt with a reason for a
// reply of another length or a CRC mismatch.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

#include "flowsteer/drivers/serial_drives.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Input: the board's address (1 byte), then the reply.
  if (size < 1) {
    return 0;
  }
  const std::vector<std::uint8_t> reply(data + 1, data + size);
  std::string why;
  const auto counts = flowsteer::drivers::roboclaw::parse_encoder_reply(data[0], reply, why);
  if (!counts && why.empty()) {
    std::abort();  // a refused reply must say why
  }
  return 0;
}
