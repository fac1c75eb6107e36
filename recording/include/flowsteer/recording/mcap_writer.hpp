#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace flowsteer::recording {

enum class ChunkCompression { none, zstd, lz4 };

// flowsteer's version (the project's, from CMake), as recordings state it.
const char* flowsteer_version();

// A time in seconds (the simulation's, a clock's) as a recording's nanoseconds; times before 0
// are 0.
std::uint64_t nanoseconds(double t_s);

struct McapWriterOptions {
  std::string profile = "ros2";  // MCAP's profile: the ROS 2 conventions for its channels
  std::string library = std::string("flowsteer ") + flowsteer_version();  // the Header's writer
  std::size_t chunk_bytes = 1 << 20;  // uncompressed bytes a chunk collects before it is written
  ChunkCompression compression = ChunkCompression::zstd;
};

// Writes an MCAP file (https://mcap.dev/spec): messages in chunks, each compressed, followed by
// its message indexes; then the summary (schemas, channels, statistics, chunk and metadata
// indexes, summary offsets) and the footer. Every CRC the format has is filled in. The file is
// written under a temporary name beside `path` and takes its name only in finish(): a run that
// fails leaves no half-written recording.
class McapWriter {
 public:
  // Throws std::runtime_error naming the file when it cannot be created.
  McapWriter(const std::filesystem::path& path, const McapWriterOptions& options);
  // Removes the temporary file when finish() was not reached.
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Ids for a schema and for a channel using it; the records go into the current chunk, before
  // the channel's first message.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  std::uint16_t add_channel(std::string_view topic, std::string_view message_encoding,
                            std::uint16_t schema_id);
  // One message, published and logged at t_ns.
  void write(std::uint16_t channel_id, std::uint64_t t_ns, std::span<const std::uint8_t> data);
  void add_metadata(std::string_view name,
                    const std::vector<std::pair<std::string, std::string>>& entries);
  // Writes the last chunk, the summary and the footer, and gives the file its name. Throws
  // std::runtime_error naming the file on a write error.
  void finish();

 private:
  struct ChunkIndex {
    std::uint64_t start_ns, end_ns, offset, length;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets;
    std::uint64_t message_index_length, compressed_size, uncompressed_size;
  };
  struct MetadataIndex {
    std::uint64_t offset;
    std::uint64_t length;
    std::string name;
  };
  void flush_chunk();
  std::uint64_t write_summary();
  // Appends to the file, counting the offset and the running CRCs.
  void emit(std::span<const std::uint8_t> bytes);
  void emit_buffer();  // emits record_ and clears it

  std::filesystem::path path_;
  std::filesystem::path partial_path_;
  McapWriterOptions options_;
  struct Closer {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  std::unique_ptr<std::FILE, Closer> file_;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;     // of every byte written so far
  std::uint32_t summary_crc_ = 0;  // from the summary's start
  bool in_summary_ = false;
  bool finished_ = false;
  std::vector<std::uint8_t> record_;  // the record being written outside chunks
  std::vector<std::uint8_t> chunk_;   // the open chunk's records, uncompressed
  std::vector<std::uint8_t> compressed_;
  std::uint64_t chunk_start_ns_ = 0;
  std::uint64_t chunk_end_ns_ = 0;
  std::size_t chunk_message_count_ = 0;
  // Per channel: (log time, offset in the open chunk) of its messages there.
  std::vector<std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_messages_;
  std::vector<std::vector<std::uint8_t>> schema_records_;
  std::vector<std::vector<std::uint8_t>> channel_records_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<MetadataIndex> metadata_indexes_;
  std::vector<std::uint64_t> channel_counts_;
  std::vector<std::uint32_t> sequences_;
  std::uint64_t message_count_ = 0;
  std::uint64_t first_ns_ = 0;
  std::uint64_t last_ns_ = 0;
};

}  // namespace flowsteer::recording
