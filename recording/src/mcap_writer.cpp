#include "flowsteer/recording/mcap_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include <lz4frame.h>
#include <zstd.h>

#include "mcap_format.hpp"

namespace flowsteer::recording {

namespace {

// zstd's default: about 3x on a run's messages, fast enough to stream.
constexpr int kZstdLevel = 3;

const char* compression_name(ChunkCompression c) {
  switch (c) {
    case ChunkCompression::zstd:
      return "zstd";
    case ChunkCompression::lz4:
      return "lz4";
    case ChunkCompression::none:
      break;
  }
  return "";
}

}  // namespace

const char* flowsteer_version() {
  return FLOWSTEER_VERSION;
}

std::uint64_t nanoseconds(double t_s) {
  return t_s > 0.0 ? static_cast<std::uint64_t>(std::llround(t_s * 1e9)) : 0;
}

McapWriter::McapWriter(const std::filesystem::path& path, const McapWriterOptions& options)
    : path_(path), partial_path_(path.string() + ".partial"), options_(options) {
  file_.reset(std::fopen(partial_path_.c_str(), "wb"));
  if (file_ == nullptr) {
    throw std::runtime_error("cannot write the recording " + path.string() + ": " +
                             std::strerror(errno));
  }
  try {
    emit(mcap::kMagic);
    mcap::FieldWriter w(record_);
    const std::size_t content = w.begin_record(mcap::Op::header);
    w.string(options_.profile);
    w.string(options_.library);
    w.end_record(content);
    emit_buffer();
  } catch (...) {
    // No destructor runs for a constructor that throws: the partial file goes here.
    file_.reset();
    std::error_code ignored;
    std::filesystem::remove(partial_path_, ignored);
    throw;
  }
}

McapWriter::~McapWriter() {
  file_.reset();
  if (!finished_) {
    std::error_code ignored;
    std::filesystem::remove(partial_path_, ignored);
  }
}

void McapWriter::emit(std::span<const std::uint8_t> bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_.get()) != bytes.size()) {
    throw std::runtime_error("cannot write the recording " + path_.string() + ": " +
                             std::strerror(errno));
  }
  offset_ += bytes.size();
  data_crc_ = mcap::crc(data_crc_, bytes);
  if (in_summary_) {
    summary_crc_ = mcap::crc(summary_crc_, bytes);
  }
}

void McapWriter::emit_buffer() {
  emit(record_);
  record_.clear();
}

std::uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding,
                                     std::string_view data) {
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);  // 0: no schema
  std::vector<std::uint8_t>& record = schema_records_.emplace_back();
  mcap::FieldWriter w(record);
  const std::size_t content = w.begin_record(mcap::Op::schema);
  w.integer(id);
  w.string(name);
  w.string(encoding);
  w.integer(static_cast<std::uint32_t>(data.size()));
  w.bytes({reinterpret_cast<const std::uint8_t*>(data.data()), data.size()});
  w.end_record(content);
  chunk_.insert(chunk_.end(), record.begin(), record.end());
  return id;
}

std::uint16_t McapWriter::add_channel(std::string_view topic, std::string_view message_encoding,
                                      std::uint16_t schema_id) {
  const auto id = static_cast<std::uint16_t>(channel_records_.size());
  std::vector<std::uint8_t>& record = channel_records_.emplace_back();
  mcap::FieldWriter w(record);
  const std::size_t content = w.begin_record(mcap::Op::channel);
  w.integer(id);
  w.integer(schema_id);
  w.string(topic);
  w.string(message_encoding);
  w.integer(std::uint32_t{0});  // metadata: none
  w.end_record(content);
  chunk_.insert(chunk_.end(), record.begin(), record.end());
  chunk_messages_.emplace_back();
  channel_counts_.push_back(0);
  sequences_.push_back(0);
  return id;
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t t_ns,
                       std::span<const std::uint8_t> data) {
  if (channel_id >= channel_records_.size()) {
    throw std::invalid_argument("McapWriter::write: no channel " + std::to_string(channel_id));
  }
  // A chunk's times are its earliest and latest message's: a robot logs a frame at its capture
  // time, after the drive's updates of later times.
  chunk_start_ns_ = chunk_message_count_++ == 0 ? t_ns : std::min(chunk_start_ns_, t_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, t_ns);
  chunk_messages_[channel_id].emplace_back(t_ns, chunk_.size());
  mcap::FieldWriter w(chunk_);
  const std::size_t content = w.begin_record(mcap::Op::message);
  w.integer(channel_id);
  w.integer(sequences_[channel_id]++);
  w.integer(t_ns);  // log time
  w.integer(t_ns);  // publish time
  w.bytes(data);
  w.end_record(content);
  first_ns_ = message_count_ == 0 ? t_ns : std::min(first_ns_, t_ns);
  last_ns_ = std::max(last_ns_, t_ns);
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= options_.chunk_bytes) {
    flush_chunk();
  }
}

void McapWriter::add_metadata(std::string_view name,
                              const std::vector<std::pair<std::string, std::string>>& entries) {
  const std::uint64_t offset = offset_;
  mcap::FieldWriter w(record_);
  const std::size_t content = w.begin_record(mcap::Op::metadata);
  w.string(name);
  const std::size_t map = w.begin_prefixed();
  for (const auto& [key, value] : entries) {
    w.string(key);
    w.string(value);
  }
  w.end_prefixed(map);
  w.end_record(content);
  emit_buffer();
  metadata_indexes_.push_back({offset, offset_ - offset, std::string(name)});
}

// The open chunk as a Chunk record, then one MessageIndex record per channel it holds.
void McapWriter::flush_chunk() {
  if (chunk_.empty()) {
    return;
  }
  std::span<const std::uint8_t> records = chunk_;
  if (options_.compression == ChunkCompression::zstd) {
    compressed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t size = ZSTD_compress(compressed_.data(), compressed_.size(), chunk_.data(),
                                           chunk_.size(), kZstdLevel);
    if (ZSTD_isError(size)) {
      throw std::runtime_error("cannot write the recording " + path_.string() +
                               ": zstd: " + ZSTD_getErrorName(size));
    }
    records = std::span(compressed_).first(size);
  } else if (options_.compression == ChunkCompression::lz4) {
    compressed_.resize(LZ4F_compressFrameBound(chunk_.size(), nullptr));
    const std::size_t size = LZ4F_compressFrame(compressed_.data(), compressed_.size(),
                                                chunk_.data(), chunk_.size(), nullptr);
    if (LZ4F_isError(size)) {
      throw std::runtime_error("cannot write the recording " + path_.string() +
                               ": lz4: " + LZ4F_getErrorName(size));
    }
    records = std::span(compressed_).first(size);
  }
  ChunkIndex index{chunk_start_ns_, chunk_end_ns_, offset_, 0, {}, 0,
                   records.size(),  chunk_.size()};
  mcap::FieldWriter w(record_);
  const std::size_t content = w.begin_record(mcap::Op::chunk);
  w.integer(chunk_start_ns_);
  w.integer(chunk_end_ns_);
  w.integer(static_cast<std::uint64_t>(chunk_.size()));
  w.integer(mcap::crc(0, chunk_));
  w.string(compression_name(options_.compression));
  w.integer(static_cast<std::uint64_t>(records.size()));
  w.bytes(records);
  w.end_record(content);
  emit_buffer();
  index.length = offset_ - index.offset;
  const std::uint64_t indexes_start = offset_;
  for (std::size_t id = 0; id < chunk_messages_.size(); ++id) {
    auto& messages = chunk_messages_[id];
    if (messages.empty()) {
      continue;
    }
    index.message_index_offsets.emplace_back(static_cast<std::uint16_t>(id), offset_);
    const std::size_t message_index = w.begin_record(mcap::Op::message_index);
    w.integer(static_cast<std::uint16_t>(id));
    const std::size_t entries = w.begin_prefixed();
    for (const auto& [t_ns, offset] : messages) {
      w.integer(t_ns);
      w.integer(offset);
    }
    w.end_prefixed(entries);
    w.end_record(message_index);
    emit_buffer();
    messages.clear();
  }
  index.message_index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  chunk_.clear();
  chunk_message_count_ = 0;
  chunk_start_ns_ = 0;
  chunk_end_ns_ = 0;
}

// The summary: one group each of schemas, channels, statistics, chunk indexes and metadata
// indexes, then a SummaryOffset per group, which lets a reader find each without the rest.
// Returns where the summary offsets start.
std::uint64_t McapWriter::write_summary() {
  std::vector<std::uint8_t> offsets;
  mcap::FieldWriter offsets_writer(offsets);
  mcap::FieldWriter w(record_);
  auto group = [&](mcap::Op op, auto&& write_records) {
    const std::uint64_t start = offset_;
    write_records();
    if (offset_ == start) {
      return;
    }
    const std::size_t content = offsets_writer.begin_record(mcap::Op::summary_offset);
    offsets_writer.integer(static_cast<std::uint8_t>(op));
    offsets_writer.integer(start);
    offsets_writer.integer(offset_ - start);
    offsets_writer.end_record(content);
  };
  group(mcap::Op::schema, [&] {
    for (const auto& r : schema_records_)
      emit(r);
  });
  group(mcap::Op::channel, [&] {
    for (const auto& r : channel_records_)
      emit(r);
  });
  group(mcap::Op::statistics, [&] {
    const std::size_t content = w.begin_record(mcap::Op::statistics);
    w.integer(message_count_);
    w.integer(static_cast<std::uint16_t>(schema_records_.size()));
    w.integer(static_cast<std::uint32_t>(channel_records_.size()));
    w.integer(std::uint32_t{0});  // attachments
    w.integer(static_cast<std::uint32_t>(metadata_indexes_.size()));
    w.integer(static_cast<std::uint32_t>(chunk_indexes_.size()));
    w.integer(first_ns_);
    w.integer(last_ns_);
    const std::size_t counts = w.begin_prefixed();
    for (std::size_t id = 0; id < channel_counts_.size(); ++id) {
      w.integer(static_cast<std::uint16_t>(id));
      w.integer(channel_counts_[id]);
    }
    w.end_prefixed(counts);
    w.end_record(content);
    emit_buffer();
  });
  group(mcap::Op::chunk_index, [&] {
    for (const ChunkIndex& c : chunk_indexes_) {
      const std::size_t content = w.begin_record(mcap::Op::chunk_index);
      w.integer(c.start_ns);
      w.integer(c.end_ns);
      w.integer(c.offset);
      w.integer(c.length);
      const std::size_t map = w.begin_prefixed();
      for (const auto& [channel, offset] : c.message_index_offsets) {
        w.integer(channel);
        w.integer(offset);
      }
      w.end_prefixed(map);
      w.integer(c.message_index_length);
      w.string(compression_name(options_.compression));
      w.integer(c.compressed_size);
      w.integer(c.uncompressed_size);
      w.end_record(content);
      emit_buffer();
    }
  });
  group(mcap::Op::metadata_index, [&] {
    for (const MetadataIndex& m : metadata_indexes_) {
      const std::size_t content = w.begin_record(mcap::Op::metadata_index);
      w.integer(m.offset);
      w.integer(m.length);
      w.string(m.name);
      w.end_record(content);
      emit_buffer();
    }
  });
  const std::uint64_t offsets_start = offset_;
  emit(offsets);
  return offsets_start;
}

void McapWriter::finish() {
  flush_chunk();
  mcap::FieldWriter w(record_);
  const std::size_t content = w.begin_record(mcap::Op::data_end);
  w.integer(data_crc_);
  w.end_record(content);
  emit_buffer();
  const std::uint64_t summary_start = offset_;
  in_summary_ = true;
  const std::uint64_t summary_offset_start = write_summary();
  // The footer's CRC covers the summary and the footer up to the CRC itself, its length included.
  w.integer(static_cast<std::uint8_t>(mcap::Op::footer));
  w.integer(std::uint64_t{8 + 8 + 4});
  w.integer(summary_start);
  w.integer(summary_offset_start);
  w.integer(mcap::crc(summary_crc_, record_));
  emit_buffer();
  emit(mcap::kMagic);
  if (std::fclose(file_.release()) != 0) {
    throw std::runtime_error("cannot write the recording " + path_.string() + ": " +
                             std::strerror(errno));
  }
  std::filesystem::rename(partial_path_, path_);
  finished_ = true;
}

}  // namespace flowsteer::recording
