#include "flowsteer/recording/cdr.hpp"

#include <array>
#include <bit>
#include <cstring>

#include "flowsteer/recording/recording_error.hpp"

namespace flowsteer::recording {

static_assert(std::endian::native == std::endian::little, "the CDR code writes little endian");

namespace {

constexpr std::array<std::uint8_t, 4> kLittleEndianHeader = {0x00, 0x01, 0x00, 0x00};
constexpr std::size_t kHeaderSize = kLittleEndianHeader.size();

// Padding that aligns `offset` (counted from the end of the header) to `alignment`.
std::size_t padding(std::size_t offset, std::size_t alignment) {
  return (alignment - offset % alignment) % alignment;
}

}  // namespace

CdrWriter::CdrWriter(std::vector<std::uint8_t>& out) : out_(out) {
  out_.assign(kLittleEndianHeader.begin(), kLittleEndianHeader.end());
}

void CdrWriter::put(const void* value, std::size_t size, std::size_t alignment) {
  out_.resize(out_.size() + padding(out_.size() - kHeaderSize, alignment), 0);
  const auto* bytes = static_cast<const std::uint8_t*>(value);
  out_.insert(out_.end(), bytes, bytes + size);
}

void CdrWriter::string(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size() + 1));
  out_.insert(out_.end(), s.begin(), s.end());
  out_.push_back(0);
}

void CdrWriter::bytes(std::span<const std::uint8_t> data) {
  u32(static_cast<std::uint32_t>(data.size()));
  out_.insert(out_.end(), data.begin(), data.end());
}

void CdrWriter::f64_sequence(std::span<const double> values) {
  u32(static_cast<std::uint32_t>(values.size()));
  f64_array(values);
}

void CdrWriter::f64_array(std::span<const double> values) {
  for (double v : values) {
    f64(v);
  }
}

CdrReader::CdrReader(std::span<const std::uint8_t> data) : data_(data) {
  if (data.size() < kHeaderSize || data[0] != 0x00 || data[1] != 0x01) {
    throw RecordingError("not a little-endian CDR message (its first bytes are not 00 01)");
  }
}

const std::uint8_t* CdrReader::take(std::size_t size, std::size_t alignment, const char* field) {
  const std::size_t start = offset_ + padding(offset_ - kHeaderSize, alignment);
  if (start > data_.size() || data_.size() - start < size) {
    throw RecordingError(std::string("CDR field ") + field + " at byte " + std::to_string(offset_) +
                         ": the message ends at byte " + std::to_string(data_.size()));
  }
  offset_ = start + size;
  return data_.data() + start;
}

std::uint8_t CdrReader::u8(const char* field) {
  return *take(1, 1, field);
}

std::uint32_t CdrReader::u32(const char* field) {
  std::uint32_t v;
  std::memcpy(&v, take(4, 4, field), 4);
  return v;
}

std::int32_t CdrReader::i32(const char* field) {
  std::int32_t v;
  std::memcpy(&v, take(4, 4, field), 4);
  return v;
}

double CdrReader::f64(const char* field) {
  double v;
  std::memcpy(&v, take(8, 8, field), 8);
  return v;
}

std::uint32_t CdrReader::count(const char* field, std::size_t min_element_size) {
  const std::uint32_t n = u32(field);
  if (min_element_size > 0 && n > (data_.size() - offset_) / min_element_size) {
    throw RecordingError(std::string("CDR field ") + field + " at byte " +
                         std::to_string(offset_ - 4) + ": " + std::to_string(n) +
                         " elements, more than the message's remaining " +
                         std::to_string(data_.size() - offset_) + " bytes hold");
  }
  return n;
}

std::string CdrReader::string(const char* field) {
  const std::uint32_t size = count(field, 1);
  if (size == 0) {  // some writers send an empty string as length 0
    return {};
  }
  const auto* chars = reinterpret_cast<const char*>(take(size, 1, field));
  if (chars[size - 1] != '\0') {
    throw RecordingError(std::string("CDR field ") + field + ": the string is not NUL-terminated");
  }
  return std::string(chars, size - 1);
}

std::span<const std::uint8_t> CdrReader::bytes(const char* field) {
  const std::uint32_t size = count(field, 1);
  return {take(size, 1, field), size};
}

std::vector<double> CdrReader::f64_sequence(const char* field) {
  std::vector<double> values(count(field, 8));
  f64_array(values, field);
  return values;
}

void CdrReader::f64_array(std::span<double> values, const char* field) {
  for (double& v : values) {
    v = f64(field);
  }
}

}  // namespace flowsteer::recording
