// MCAP recordings (`flowsteer replay FILE.mcap`): the file's records, chunks (zstd, lz4, none)
// and CRCs, then each message's CDR as its schema names it; messages or a
// recording::RecordingError.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "flowsteer/recording/mcap_reader.hpp"
#include "flowsteer/recording/recording_error.hpp"
#include "flowsteer/recording/ros2_messages.hpp"
#include "fuzz_support.hpp"

namespace {

namespace ros2 = flowsteer::recording::ros2;

template <typename Message>
bool decode_as(const flowsteer::recording::McapMessage& m, const std::string& schema) {
  if (schema != ros2::MessageType<Message>::name()) {
    return false;
  }
  ros2::MessageType<Message>::decode(m.data);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(flowsteer::fuzz::as_text(data, size));
  try {
    // A chunk of at most 1 MiB: the harness's memory, not a file's claim, bounds what it holds.
    flowsteer::recording::McapReader reader(in, "fuzz.mcap", 1 << 20);
    while (const auto m = reader.next()) {
      if (m->channel->schema == nullptr) {
        continue;
      }
      const std::string& schema = m->channel->schema->name;
      decode_as<ros2::Twist>(*m, schema) || decode_as<ros2::Odometry>(*m, schema) ||
          decode_as<ros2::TFMessage>(*m, schema) || decode_as<ros2::CompressedImage>(*m, schema) ||
          decode_as<ros2::Image>(*m, schema) || decode_as<ros2::CameraInfo>(*m, schema);
    }
  } catch (const flowsteer::recording::RecordingError&) {
    // The reader's documented refusal; anything else escapes and is a finding.
  }
  return 0;
}
