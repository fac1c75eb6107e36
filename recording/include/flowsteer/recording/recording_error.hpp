#pragma once

#include <stdexcept>

namespace flowsteer::recording {

// A recording that cannot be read as what it claims to be: a truncated or corrupt MCAP file, a
// message whose bytes do not hold its type. The message names where (file, byte offset, topic,
// message index, field).
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace flowsteer::recording
