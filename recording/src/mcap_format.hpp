#pragma once

// MCAP's records as bytes (https://mcap.dev/spec): the opcodes, and the little-endian fields the
// writer appends and the reader takes, shared so that both read the same layout.

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <zlib.h>

#include "flowsteer/recording/recording_error.hpp"

namespace flowsteer::recording::mcap {

inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum class Op : std::uint8_t {
  header = 0x01,
  footer = 0x02,
  schema = 0x03,
  channel = 0x04,
  message = 0x05,
  chunk = 0x06,
  message_index = 0x07,
  chunk_index = 0x08,
  attachment = 0x09,
  attachment_index = 0x0A,
  statistics = 0x0B,
  metadata = 0x0C,
  metadata_index = 0x0D,
  summary_offset = 0x0E,
  data_end = 0x0F,
};

// A record's opcode (1 byte) and content length (8 bytes).
inline constexpr std::size_t kRecordPrefix = 9;

// MCAP's CRC-32 (zlib's: the IEEE polynomial), continued from `running` over `bytes`.
inline std::uint32_t crc(std::uint32_t running, std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(crc32(running, bytes.data(), static_cast<uInt>(bytes.size())));
}

// Appends fields to a byte buffer.
class FieldWriter {
 public:
  explicit FieldWriter(std::vector<std::uint8_t>& out) : out_(out) {}
  template <typename Int>
  void integer(Int v) {
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&v);
    out_.insert(out_.end(), bytes, bytes + sizeof v);
  }
  void string(std::string_view s) {
    integer(static_cast<std::uint32_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void bytes(std::span<const std::uint8_t> data) {
    out_.insert(out_.end(), data.begin(), data.end());
  }
  // Starts a record: its opcode and a length patched by end_record.
  std::size_t begin_record(Op op) {
    integer(static_cast<std::uint8_t>(op));
    integer(std::uint64_t{0});
    return out_.size();
  }
  void end_record(std::size_t content_start) {
    const std::uint64_t length = out_.size() - content_start;
    std::memcpy(out_.data() + content_start - 8, &length, 8);
  }
  // Starts a field prefixed by its byte length (a map or an array), patched by end_prefixed.
  std::size_t begin_prefixed() {
    integer(std::uint32_t{0});
    return out_.size();
  }
  void end_prefixed(std::size_t start) {
    const auto length = static_cast<std::uint32_t>(out_.size() - start);
    std::memcpy(out_.data() + start - 4, &length, 4);
  }

 private:
  std::vector<std::uint8_t>& out_;
};

// Where a record is, for the messages of errors: made into text only when one is thrown.
struct RecordPlace {
  std::string_view file;
  std::uint8_t opcode = 0;
  std::uint64_t offset = 0;        // in the file, or in its chunk's records
  std::uint64_t chunk_offset = 0;  // the chunk's record in the file, for a record in a chunk
  bool in_chunk = false;

  std::string text() const {
    char head[96];
    if (in_chunk) {
      std::snprintf(head, sizeof head, ": the chunk at byte %llu, record 0x%02x at its byte %llu",
                    static_cast<unsigned long long>(chunk_offset), opcode,
                    static_cast<unsigned long long>(offset));
    } else {
      std::snprintf(head, sizeof head, ": record 0x%02x at byte %llu", opcode,
                    static_cast<unsigned long long>(offset));
    }
    return std::string(file) + head;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw RecordingError(text() + ": " + what);
  }
};

// Takes fields from a record's content; every field is bounds-checked and a short record throws
// RecordingError naming the record, the field and where the record is.
class FieldReader {
 public:
  FieldReader(std::span<const std::uint8_t> content, const RecordPlace& place)
      : content_(content), place_(place) {}
  template <typename Int>
  Int integer(const char* field) {
    Int v;
    std::memcpy(&v, take(sizeof v, field).data(), sizeof v);
    return v;
  }
  std::string string(const char* field) {
    const auto size = integer<std::uint32_t>(field);
    const std::span<const std::uint8_t> chars = take(size, field);
    return {reinterpret_cast<const char*>(chars.data()), chars.size()};
  }
  std::span<const std::uint8_t> take(std::size_t size, const char* field) {
    if (content_.size() - offset_ < size) {
      fail(std::string(field) + " needs " + std::to_string(size) + " bytes at " +
           std::to_string(offset_) + " of the record's " + std::to_string(content_.size()));
    }
    const std::span<const std::uint8_t> part = content_.subspan(offset_, size);
    offset_ += size;
    return part;
  }
  std::span<const std::uint8_t> rest() { return take(content_.size() - offset_, "the rest"); }
  bool done() const { return offset_ == content_.size(); }
  [[noreturn]] void fail(const std::string& what) const { place_.fail(what); }

 private:
  std::span<const std::uint8_t> content_;
  std::size_t offset_ = 0;
  RecordPlace place_;
};

}  // namespace flowsteer::recording::mcap
