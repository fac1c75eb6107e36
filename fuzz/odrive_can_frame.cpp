// ODrive CAN Simple frames as they arrive from the bus: any id, any DLC (SocketCAN hands over
// up to 15 from a raw socket) and any payload go through the decoders without reading past the
// frame or overflowing.
#include <linux/can.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "flowsteer/drivers/odrive_can.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Input: the id (4 bytes, host order), the DLC (1 byte), then the payload (up to 8 bytes).
  can_frame frame{};
  if (size < 5) {
    return 0;
  }
  std::memcpy(&frame.can_id, data, sizeof frame.can_id);
  frame.can_dlc = data[4];
  std::memcpy(frame.data, data + 5, std::min(size - 5, sizeof frame.data));

  namespace odrive = flowsteer::drivers::odrive;
  odrive::node_of(frame.can_id);
  odrive::cmd_of(frame.can_id);
  if (const auto heartbeat = odrive::parse_heartbeat(frame)) {
    odrive::describe_axis_error(heartbeat->axis_error);
  }
  odrive::parse_encoder_estimates(frame);
  return 0;
}
