#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace flowsteer::recording {

// ROS 2's serialization: XCDR1, little endian, behind the 4-byte encapsulation header
// (00 01 00 00). Each primitive is aligned to its size (at most 8) from the end of the header;
// strings carry their length with the terminating NUL; sequences their element count.
class CdrWriter {
 public:
  // Starts a new message in `out` (cleared, capacity kept).
  explicit CdrWriter(std::vector<std::uint8_t>& out);

  void u8(std::uint8_t v) { put(&v, 1, 1); }
  void u32(std::uint32_t v) { put(&v, 4, 4); }
  void i32(std::int32_t v) { put(&v, 4, 4); }
  void f64(double v) { put(&v, 8, 8); }
  void string(std::string_view s);
  void bytes(std::span<const std::uint8_t> data);  // uint8[]: count, then the bytes
  void f64_sequence(std::span<const double> values);
  void f64_array(std::span<const double> values);  // a fixed-size array: no count

 private:
  void put(const void* value, std::size_t size, std::size_t alignment);
  std::vector<std::uint8_t>& out_;
};

// Reads what CdrWriter writes, from data that may be anything: every read checks the bounds and
// throws RecordingError naming the field and the offset.
class CdrReader {
 public:
  // Throws RecordingError unless `data` starts with a little-endian XCDR1 header.
  explicit CdrReader(std::span<const std::uint8_t> data);

  std::uint8_t u8(const char* field);
  std::uint32_t u32(const char* field);
  std::int32_t i32(const char* field);
  double f64(const char* field);
  std::string string(const char* field);
  // A uint8[] sequence, viewed in place.
  std::span<const std::uint8_t> bytes(const char* field);
  std::vector<double> f64_sequence(const char* field);
  void f64_array(std::span<double> values, const char* field);
  // The element count of a sequence, checked against what the bytes left could hold.
  std::uint32_t count(const char* field, std::size_t min_element_size);

 private:
  const std::uint8_t* take(std::size_t size, std::size_t alignment, const char* field);
  std::span<const std::uint8_t> data_;
  std::size_t offset_ = 4;
};

}  // namespace flowsteer::recording
