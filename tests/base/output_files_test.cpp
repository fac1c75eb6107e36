// base::OutputDir shows a folder's files only once they are all written; CsvTable and the JSON
// helpers write numbers as the run files promise (NaN as an empty cell, or null).
#include "flowsteer/base/output_files.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace flowsteer::base {
namespace {

namespace fs = std::filesystem;

class OutputFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("output_files_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string read(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  fs::path dir_;
};

TEST_F(OutputFiles, FilesAppearOnlyOnCommit) {
  OutputDir out(dir_);
  write_text(out.staging_path("a.txt"), "first\n");
  fs::create_directory(out.staging_path("runs"));
  write_text(out.staging_path("runs") / "b.txt", "second\n");
  EXPECT_FALSE(fs::exists(dir_ / "a.txt"));
  out.commit();
  EXPECT_EQ(read(dir_ / "a.txt"), "first\n");
  EXPECT_EQ(read(dir_ / "runs" / "b.txt"), "second\n");
}

TEST_F(OutputFiles, WithoutCommitTheFolderKeepsWhatItHad) {
  fs::create_directories(dir_);
  write_text(dir_ / "a.txt", "old\n");
  {
    OutputDir out(dir_);
    write_text(out.staging_path("a.txt"), "new\n");
  }
  EXPECT_EQ(read(dir_ / "a.txt"), "old\n");
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename(), "a.txt") << "left behind: " << entry.path();
  }
}

// A run that fails before its commit (a bad_alloc in the renderer, say) leaves no folder that was
// not there before, parents included; one that did exist stays, as the test above shows.
TEST_F(OutputFiles, WithoutCommitTheFoldersItCreatedAreGone) {
  {
    OutputDir out(dir_ / "a" / "b");
    write_text(out.staging_path("a.txt"), "new\n");
    EXPECT_TRUE(fs::is_directory(dir_ / "a" / "b"));
  }
  EXPECT_FALSE(fs::exists(dir_));
}

TEST_F(OutputFiles, CommittedFolderReplacesTheOldOne) {
  fs::create_directories(dir_ / "runs");
  write_text(dir_ / "runs" / "stale.txt", "stale\n");
  OutputDir out(dir_);
  fs::create_directory(out.staging_path("runs"));
  write_text(out.staging_path("runs") / "fresh.txt", "fresh\n");
  out.commit();
  EXPECT_FALSE(fs::exists(dir_ / "runs" / "stale.txt"));
  EXPECT_TRUE(fs::exists(dir_ / "runs" / "fresh.txt"));
}

TEST_F(OutputFiles, UnwritablePathIsNamed) {
  const fs::path path = dir_ / "no_such_folder" / "a.txt";
  try {
    write_text(path, "x");
    FAIL() << "wrote into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

TEST_F(OutputFiles, CsvCellsAndJsonNumbers) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  OutputDir out(dir_);
  CsvTable table({"name", "x", "y"});
  table.add({"a"}, {1.5, nan});
  table.add({"b"}, {1.0 / 3.0, -2.0});
  table.write(out.staging_path("t.csv"));
  out.commit();
  EXPECT_EQ(read(dir_ / "t.csv"), "name,x,y\na,1.5,\nb,0.3333333,-2\n");
  EXPECT_EQ(json_number(nan), "null");
  EXPECT_EQ(json_number(INFINITY), "null");
  EXPECT_EQ(json_number(0.25), "0.25");
  EXPECT_EQ(json_string("say \"hi\"\n"), "\"say \\\"hi\\\"\\n\"");
}

TEST_F(OutputFiles, CsvRowOfAnotherWidthIsAProgrammingError) {
  CsvTable table({"x", "y"});
  EXPECT_THROW(table.add(std::vector<double>{1.0}), std::logic_error);
}

}  // namespace
}  // namespace flowsteer::base
