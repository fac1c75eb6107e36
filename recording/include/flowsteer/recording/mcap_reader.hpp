#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace flowsteer::recording {

namespace mcap {
enum class Op : std::uint8_t;
struct RecordPlace;
}  // namespace mcap

struct McapSchema {
  std::uint16_t id = 0;
  std::string name;
  std::string encoding;
  std::string data;
};

struct McapChannel {
  std::uint16_t id = 0;
  std::string topic;
  std::string message_encoding;
  const McapSchema* schema = nullptr;  // none for a schemaless channel
  std::uint64_t messages_read = 0;     // so far: the next message's index on this channel
};

// A message as read: its bytes stay valid until the next call to McapReader::next.
struct McapMessage {
  const McapChannel* channel = nullptr;
  std::uint64_t index = 0;  // among its channel's messages, from 0
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0;
  std::uint64_t publish_time_ns = 0;
  std::span<const std::uint8_t> data;
};

// Reads an MCAP file front to back, one record at a time, holding one chunk in memory: the
// messages in the order the file has them, chunks decompressed (zstd, lz4 or none) and checked
// against their CRC, the data section's and the summary's CRCs checked where the writer gave
// them, the closing magic required. Anything that is not such a file (truncated, a length past
// the end, a message on a channel never defined, a chunk larger than max_chunk_bytes) throws
// RecordingError naming the file, the record's byte offset and what is wrong.
class McapReader {
 public:
  static constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

  explicit McapReader(const std::filesystem::path& path);
  // `name` for messages; `in` must outlive the reader.
  McapReader(std::istream& in, std::string name, std::uint64_t max_chunk_bytes = kMaxChunkBytes);

  // The next message, or none once the file has ended as an MCAP file must.
  std::optional<McapMessage> next();

  const std::string& profile() const { return profile_; }
  const std::string& name() const { return name_; }
  // The channels and metadata met so far (all of them once next() returned none).
  const std::map<std::uint16_t, McapChannel>& channels() const { return channels_; }
  const std::map<std::string, std::map<std::string, std::string>>& metadata() const {
    return metadata_;
  }

 private:
  void open();
  // Reads the next top-level record into record_; false at the footer.
  bool read_record();
  void read_bytes(std::span<std::uint8_t> into, const char* what);
  bool used(mcap::Op op) const;
  void skip(std::uint64_t length, std::uint32_t& section_crc);
  void start_chunk(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  void add_schema(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  void add_channel(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  McapMessage message(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  void add_metadata(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  void read_footer(std::span<const std::uint8_t> content, const mcap::RecordPlace& where);
  mcap::RecordPlace place() const;  // of the record read last

  std::ifstream file_;
  std::istream& in_;
  std::string name_;
  std::uint64_t max_chunk_bytes_;
  std::uint64_t size_ = 0;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;     // of every byte before the DataEnd record
  std::uint32_t summary_crc_ = 0;  // from the first byte after DataEnd
  std::optional<std::uint64_t> summary_start_;
  bool ended_ = false;
  std::string profile_;
  std::vector<std::uint8_t> record_;
  std::uint8_t opcode_ = 0;
  std::uint64_t record_offset_ = 0;
  std::vector<std::uint8_t> chunk_;  // the open chunk's records, decompressed
  std::uint64_t chunk_offset_ = 0;   // where the open chunk's record starts in the file
  std::size_t chunk_position_ = 0;   // the next record within chunk_
  std::map<std::uint16_t, McapSchema> schemas_;
  std::map<std::uint16_t, McapChannel> channels_;
  std::map<std::string, std::map<std::string, std::string>> metadata_;
};

}  // namespace flowsteer::recording
