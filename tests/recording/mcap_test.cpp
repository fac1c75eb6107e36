#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "flowsteer/recording/mcap_reader.hpp"
#include "flowsteer/recording/mcap_writer.hpp"
#include "flowsteer/recording/recording_error.hpp"

namespace flowsteer::recording {
namespace {

namespace fs = std::filesystem;

class McapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("mcap_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Two channels on one schema, `count` messages each, alternating, at 1 ms steps; chunks of
  // `chunk_bytes`.
  fs::path write(int count, std::size_t chunk_bytes, ChunkCompression compression) {
    const fs::path path = dir_ / "run.mcap";
    McapWriterOptions options;
    options.library = "mcap_test";
    options.chunk_bytes = chunk_bytes;
    options.compression = compression;
    McapWriter writer(path, options);
    const std::uint16_t schema = writer.add_schema("test/Bytes", "text", "uint8[] data\n");
    const std::uint16_t a = writer.add_channel("/a", "raw", schema);
    const std::uint16_t b = writer.add_channel("/b", "raw", schema);
    for (int i = 0; i < count; ++i) {
      const std::vector<std::uint8_t> data(static_cast<std::size_t>(i % 50),
                                           static_cast<std::uint8_t>(i));
      writer.write(i % 2 == 0 ? a : b, static_cast<std::uint64_t>(i) * 1'000'000, data);
    }
    writer.add_metadata("flowsteer", {{"version", "test"}, {"clock", "simulation"}});
    writer.finish();
    return path;
  }

  static std::vector<char> bytes_of(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }

  // Reads every message of `bytes`; throws what the reader throws.
  static int read_all(const std::vector<char>& bytes) {
    std::istringstream in(std::string(bytes.begin(), bytes.end()));
    McapReader reader(in, "memory");
    int n = 0;
    while (reader.next()) {
      ++n;
    }
    return n;
  }

  fs::path dir_;
};

TEST_F(McapTest, WhatIsWrittenReadsBackInOrderAcrossChunks) {
  for (const ChunkCompression compression :
       {ChunkCompression::zstd, ChunkCompression::lz4, ChunkCompression::none}) {
    const fs::path path = write(500, 2000, compression);
    McapReader reader(path);
    EXPECT_EQ(reader.profile(), "ros2");
    int i = 0;
    while (const auto m = reader.next()) {
      EXPECT_EQ(m->channel->topic, i % 2 == 0 ? "/a" : "/b");
      ASSERT_NE(m->channel->schema, nullptr);
      EXPECT_EQ(m->channel->schema->name, "test/Bytes");
      EXPECT_EQ(m->channel->schema->data, "uint8[] data\n");
      EXPECT_EQ(m->index, static_cast<std::uint64_t>(i / 2));
      EXPECT_EQ(m->sequence, static_cast<std::uint32_t>(i / 2));
      EXPECT_EQ(m->log_time_ns, static_cast<std::uint64_t>(i) * 1'000'000);
      ASSERT_EQ(m->data.size(), static_cast<std::size_t>(i % 50));
      for (std::uint8_t byte : m->data) {
        EXPECT_EQ(byte, static_cast<std::uint8_t>(i));
      }
      ++i;
    }
    EXPECT_EQ(i, 500);
    EXPECT_EQ(reader.metadata().at("flowsteer").at("clock"), "simulation");
    EXPECT_EQ(reader.channels().size(), 2u);
  }
}

TEST_F(McapTest, AnUnfinishedWriterLeavesNoFile) {
  const fs::path path = dir_ / "left.mcap";
  {
    McapWriter writer(path, {});
    writer.add_channel("/a", "raw", 0);
  }
  EXPECT_TRUE(fs::is_empty(dir_)) << "neither " << path << " nor its partial file may remain";
}

TEST_F(McapTest, ACorruptChunkIsRefusedByItsCrc) {
  std::vector<char> bytes = bytes_of(write(200, 1 << 20, ChunkCompression::none));
  // A message byte in the one uncompressed chunk, well inside the file.
  bytes[bytes.size() / 2] ^= 0x01;
  try {
    read_all(bytes);
    FAIL() << "a flipped byte was not noticed";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("CRC"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("memory: record 0x06 at byte"), std::string::npos)
        << e.what();
  }
}

TEST_F(McapTest, ATruncatedFileNamesWhereItEnds) {
  const std::vector<char> whole = bytes_of(write(200, 1000, ChunkCompression::zstd));
  EXPECT_EQ(read_all(whole), 200);
  for (const std::size_t cut :
       {std::size_t{4}, std::size_t{20}, whole.size() / 3, whole.size() - 3}) {
    const std::vector<char> bytes(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut));
    EXPECT_THROW(read_all(bytes), RecordingError) << "cut at " << cut;
  }
}

TEST_F(McapTest, AChunkLargerThanTheReaderHoldsIsRefused) {
  const std::vector<char> bytes = bytes_of(write(200, 1 << 20, ChunkCompression::zstd));
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  McapReader reader(in, "memory", 100);
  try {
    while (reader.next()) {
    }
    FAIL() << "a chunk over the limit was read";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("more than the 100 this reader holds"), std::string::npos)
        << e.what();
  }
}

TEST_F(McapTest, NotAnMcapFileIsSaidSo) {
  const std::string text = "t,agent,x\n0,0,1\n";
  try {
    read_all({text.begin(), text.end()});
    FAIL();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("not an MCAP file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowsteer::recording
