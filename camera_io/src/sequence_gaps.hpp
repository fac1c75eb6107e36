#pragma once

// Internal to camera_io: dropped-frame counting shared by the camera sources.

#include <cstdint>
#include <optional>

namespace flowsteer::camera_io {

// The frames a camera skipped before the one numbered `sequence`: the gap after `last`, the
// driver's sequence number of the previous frame (none before the first frame, which has no
// gap). Sets `last` to `sequence`.
inline std::uint64_t skipped_frames(std::optional<std::uint32_t>& last, std::uint32_t sequence) {
  const std::uint64_t skipped = last && sequence > *last + 1 ? sequence - *last - 1 : 0;
  last = sequence;
  return skipped;
}

}  // namespace flowsteer::camera_io
