#include "flowsteer/recording/mcap_reader.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <lz4frame.h>
#include <zstd.h>

#include "flowsteer/recording/recording_error.hpp"
#include "mcap_format.hpp"

namespace flowsteer::recording {

namespace {

void decompress_zstd(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out,
                     const mcap::FieldReader& record) {
  const std::size_t size = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
  if (ZSTD_isError(size)) {
    record.fail(std::string("zstd: ") + ZSTD_getErrorName(size));
  }
  if (size != out.size()) {
    record.fail("zstd gave " + std::to_string(size) + " bytes, the chunk says " +
                std::to_string(out.size()));
  }
}

// MCAP's lz4 is LZ4's frame format.
void decompress_lz4(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out,
                    const mcap::FieldReader& record) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    record.fail("lz4: cannot create a decompression context");
  }
  std::size_t in_done = 0;
  std::size_t out_done = 0;
  std::size_t hint = 1;
  while (hint != 0 && in_done < in.size()) {
    std::size_t in_size = in.size() - in_done;
    std::size_t out_size = out.size() - out_done;
    hint = LZ4F_decompress(context, out.data() + out_done, &out_size, in.data() + in_done, &in_size,
                           nullptr);
    if (LZ4F_isError(hint)) {
      LZ4F_freeDecompressionContext(context);
      record.fail(std::string("lz4: ") + LZ4F_getErrorName(hint));
    }
    in_done += in_size;
    out_done += out_size;
    if (in_size == 0 && out_size == 0) {
      break;  // no progress: the output is full or the frame is cut short
    }
  }
  LZ4F_freeDecompressionContext(context);
  if (hint != 0 || out_done != out.size()) {
    record.fail("lz4 gave " + std::to_string(out_done) + " bytes of a frame " +
                (hint != 0 ? "cut short" : "complete") + ", the chunk says " +
                std::to_string(out.size()));
  }
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& path)
    : file_(path, std::ios::binary),
      in_(file_),
      name_(path.string()),
      max_chunk_bytes_(kMaxChunkBytes) {
  if (!file_) {
    throw RecordingError("cannot open the recording " + name_);
  }
  open();
}

McapReader::McapReader(std::istream& in, std::string name, std::uint64_t max_chunk_bytes)
    : in_(in), name_(std::move(name)), max_chunk_bytes_(max_chunk_bytes) {
  open();
}

void McapReader::open() {
  in_.seekg(0, std::ios::end);
  size_ = static_cast<std::uint64_t>(in_.tellg());
  in_.seekg(0);
  std::array<std::uint8_t, mcap::kMagic.size()> magic{};
  read_bytes(magic, "the magic");
  data_crc_ = mcap::crc(0, magic);
  if (magic != mcap::kMagic) {
    throw RecordingError(name_ + ": not an MCAP file (its first 8 bytes are not MCAP's magic)");
  }
  if (!read_record() || opcode_ != static_cast<std::uint8_t>(mcap::Op::header)) {
    throw RecordingError(name_ + ": the first record is not a Header");
  }
  mcap::FieldReader header(record_, place());
  profile_ = header.string("profile");
  header.string("library");
}

mcap::RecordPlace McapReader::place() const {
  return {name_, opcode_, record_offset_, 0, false};
}

void McapReader::read_bytes(std::span<std::uint8_t> into, const char* what) {
  if (size_ - offset_ < into.size()) {
    throw RecordingError(name_ + ": " + what + " at byte " + std::to_string(offset_) + " needs " +
                         std::to_string(into.size()) + " bytes, the file ends at " +
                         std::to_string(size_));
  }
  in_.read(reinterpret_cast<char*>(into.data()), static_cast<std::streamsize>(into.size()));
  if (!in_) {
    throw RecordingError(name_ + ": cannot read " + what + " at byte " + std::to_string(offset_));
  }
  offset_ += into.size();
}

// Counts each record into the CRC of its section: the data section's up to DataEnd (whose own
// CRC is checked here), the summary's from there through the footer's fields before its CRC.
// Records this reader does not use (indexes, attachments, the summary) are read past in pieces:
// only what it holds counts against max_chunk_bytes.
bool McapReader::read_record() {
  record_offset_ = offset_;
  std::array<std::uint8_t, mcap::kRecordPrefix> prefix{};
  read_bytes(prefix, "a record's opcode and length");
  opcode_ = prefix[0];
  std::uint64_t length;
  std::memcpy(&length, prefix.data() + 1, 8);
  if (length > size_ - offset_) {
    place().fail("its length " + std::to_string(length) + " runs past the file's end at " +
                 std::to_string(size_));
  }
  std::uint32_t& section_crc = summary_start_ ? summary_crc_ : data_crc_;
  const auto op = static_cast<mcap::Op>(opcode_);
  if (op != mcap::Op::data_end) {
    section_crc = mcap::crc(section_crc, prefix);
  }
  if (!used(op)) {
    skip(length, section_crc);
    record_.clear();
    return true;
  }
  // A chunk's compressed records may be a little larger than what they hold.
  if (length > max_chunk_bytes_ + (std::uint64_t{1} << 16)) {
    place().fail("a record of " + std::to_string(length) + " bytes, more than the " +
                 std::to_string(max_chunk_bytes_) + " this reader holds");
  }
  record_.resize(length);
  read_bytes(record_, "a record");
  if (op == mcap::Op::data_end) {
    mcap::FieldReader r(record_, place());
    const auto data_crc = r.integer<std::uint32_t>("data_section_crc");
    if (data_crc != 0 && data_crc != data_crc_) {
      r.fail("the data section's CRC does not match");
    }
    summary_start_ = offset_;
  } else if (op == mcap::Op::footer) {
    summary_crc_ =
        mcap::crc(summary_crc_, std::span(record_).first(std::min<std::size_t>(16, length)));
  } else {
    section_crc = mcap::crc(section_crc, record_);
  }
  return op != mcap::Op::footer;
}

// The records whose content this reader takes: in the data section, those that define channels,
// carry messages or metadata; the DataEnd and the footer for their checks.
bool McapReader::used(mcap::Op op) const {
  switch (op) {
    case mcap::Op::data_end:
    case mcap::Op::footer:
      return true;
    case mcap::Op::header:
    case mcap::Op::schema:
    case mcap::Op::channel:
    case mcap::Op::message:
    case mcap::Op::chunk:
    case mcap::Op::metadata:
      return !summary_start_;
    default:
      return false;
  }
}

void McapReader::skip(std::uint64_t length, std::uint32_t& section_crc) {
  std::array<std::uint8_t, 1 << 16> piece{};
  while (length > 0) {
    const std::span<std::uint8_t> part = std::span(piece).first(
        static_cast<std::size_t>(std::min<std::uint64_t>(length, piece.size())));
    read_bytes(part, "a record");
    section_crc = mcap::crc(section_crc, part);
    length -= part.size();
  }
}

std::optional<McapMessage> McapReader::next() {
  for (;;) {
    while (chunk_position_ < chunk_.size()) {
      mcap::RecordPlace where{name_, 0, chunk_position_, chunk_offset_, true};
      mcap::FieldReader prefix{std::span<const std::uint8_t>(chunk_).subspan(chunk_position_),
                               where};
      where.opcode = prefix.integer<std::uint8_t>("a record's opcode");
      const auto length = prefix.integer<std::uint64_t>("a record's length");
      const std::span<const std::uint8_t> content = prefix.take(length, "a record");
      chunk_position_ += mcap::kRecordPrefix + length;
      switch (static_cast<mcap::Op>(where.opcode)) {
        case mcap::Op::schema:
          add_schema(content, where);
          break;
        case mcap::Op::channel:
          add_channel(content, where);
          break;
        case mcap::Op::message:
          return message(content, where);
        default:
          where.fail("a chunk holds only schemas, channels and messages");
      }
    }
    if (ended_) {
      return std::nullopt;
    }
    if (!read_record()) {
      read_footer(record_, place());
      ended_ = true;
      return std::nullopt;
    }
    const mcap::RecordPlace at = place();
    if (record_.empty() && !used(static_cast<mcap::Op>(opcode_))) {
      continue;  // read past: indexes, attachments, the summary
    }
    switch (static_cast<mcap::Op>(opcode_)) {
      case mcap::Op::header:
        at.fail("a second Header");
      case mcap::Op::schema:
        add_schema(record_, at);
        break;
      case mcap::Op::channel:
        add_channel(record_, at);
        break;
      case mcap::Op::message:
        return message(record_, at);
      case mcap::Op::chunk:
        start_chunk(record_, at);
        break;
      case mcap::Op::metadata:
        add_metadata(record_, at);
        break;
      default:
        break;  // indexes, attachments and records this reader does not know
    }
  }
}

void McapReader::start_chunk(std::span<const std::uint8_t> content,
                             const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  r.integer<std::uint64_t>("message_start_time");
  r.integer<std::uint64_t>("message_end_time");
  const auto uncompressed_size = r.integer<std::uint64_t>("uncompressed_size");
  const auto uncompressed_crc = r.integer<std::uint32_t>("uncompressed_crc");
  const std::string compression = r.string("compression");
  const auto records_size = r.integer<std::uint64_t>("records' length");
  const std::span<const std::uint8_t> records = r.take(records_size, "records");
  if (uncompressed_size > max_chunk_bytes_) {
    r.fail("a chunk of " + std::to_string(uncompressed_size) + " bytes, more than the " +
           std::to_string(max_chunk_bytes_) + " this reader holds");
  }
  chunk_.resize(uncompressed_size);
  if (compression.empty()) {
    if (records.size() != uncompressed_size) {
      r.fail("an uncompressed chunk of " + std::to_string(records.size()) + " bytes says " +
             std::to_string(uncompressed_size));
    }
    std::copy(records.begin(), records.end(), chunk_.begin());
  } else if (compression == "zstd") {
    decompress_zstd(records, chunk_, r);
  } else if (compression == "lz4") {
    decompress_lz4(records, chunk_, r);
  } else {
    r.fail("compression '" + compression + "' (this reader knows zstd, lz4 and none)");
  }
  if (uncompressed_crc != 0 && mcap::crc(0, chunk_) != uncompressed_crc) {
    r.fail("the chunk's CRC does not match its records");
  }
  chunk_offset_ = record_offset_;
  chunk_position_ = 0;
}

void McapReader::add_schema(std::span<const std::uint8_t> content, const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  McapSchema schema;
  schema.id = r.integer<std::uint16_t>("schema id");
  schema.name = r.string("schema name");
  schema.encoding = r.string("schema encoding");
  schema.data = r.string("schema data");
  if (schema.id == 0) {
    r.fail("schema id 0 (0 means a channel has no schema)");
  }
  schemas_.try_emplace(schema.id, std::move(schema));
}

void McapReader::add_channel(std::span<const std::uint8_t> content,
                             const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  McapChannel channel;
  channel.id = r.integer<std::uint16_t>("channel id");
  const auto schema_id = r.integer<std::uint16_t>("schema id");
  channel.topic = r.string("topic");
  channel.message_encoding = r.string("message encoding");
  if (schema_id != 0) {
    const auto schema = schemas_.find(schema_id);
    if (schema == schemas_.end()) {
      r.fail("channel " + channel.topic + " names schema " + std::to_string(schema_id) +
             ", which no earlier record defines");
    }
    channel.schema = &schema->second;
  }
  channels_.try_emplace(channel.id, std::move(channel));
}

McapMessage McapReader::message(std::span<const std::uint8_t> content,
                                const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  const auto channel_id = r.integer<std::uint16_t>("channel id");
  const auto channel = channels_.find(channel_id);
  if (channel == channels_.end()) {
    r.fail("a message on channel " + std::to_string(channel_id) +
           ", which no earlier record defines");
  }
  McapMessage m;
  m.channel = &channel->second;
  m.index = channel->second.messages_read++;
  m.sequence = r.integer<std::uint32_t>("sequence");
  m.log_time_ns = r.integer<std::uint64_t>("log_time");
  m.publish_time_ns = r.integer<std::uint64_t>("publish_time");
  m.data = r.rest();
  return m;
}

void McapReader::add_metadata(std::span<const std::uint8_t> content,
                              const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  const std::string name = r.string("metadata name");
  const auto map_size = r.integer<std::uint32_t>("metadata map's length");
  mcap::FieldReader map(r.take(map_size, "metadata map"), where);
  std::map<std::string, std::string>& entries = metadata_[name];
  while (!map.done()) {
    std::string key = map.string("metadata key");
    entries[std::move(key)] = map.string("metadata value");
  }
}

void McapReader::read_footer(std::span<const std::uint8_t> content,
                             const mcap::RecordPlace& where) {
  mcap::FieldReader r(content, where);
  const auto summary_start = r.integer<std::uint64_t>("summary_start");
  r.integer<std::uint64_t>("summary_offset_start");
  const auto summary_crc = r.integer<std::uint32_t>("summary_crc");
  if (summary_start != 0 && summary_crc != 0) {
    if (!summary_start_ || summary_start != *summary_start_) {
      r.fail("the footer's summary start " + std::to_string(summary_start) +
             " is not where the data section ends");
    }
    if (summary_crc_ != summary_crc) {
      r.fail("the summary's CRC does not match");
    }
  }
  std::array<std::uint8_t, mcap::kMagic.size()> magic{};
  read_bytes(magic, "the closing magic");
  if (magic != mcap::kMagic) {
    throw RecordingError(name_ + ": the file does not end with MCAP's magic");
  }
}

}  // namespace flowsteer::recording
