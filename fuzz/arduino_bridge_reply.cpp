// ros_arduino_bridge's reply to `e` (a line of up to 64 bytes from the serial port): two
// counts or std::nullopt, never a read past the line.
#include <cstddef>
#include <cstdint>
#include <string>

#include "flowsteer/drivers/serial_drives.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A copy of exactly the input's size, so that AddressSanitizer sees a read past its end.
  const std::string reply = flowsteer::fuzz::as_text(data, size);
  flowsteer::drivers::arduino_bridge::parse_encoder_reply(reply);
  return 0;
}
