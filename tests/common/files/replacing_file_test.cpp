// Output files replaced only by a run that succeeded: ReplacingFile for text, LogWriter for logs.
#include "ssl_formation/files/replacing_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "scratch_dir.hpp"
#include "ssl_formation/files/log_file.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Only the files named: no temporary file is left behind.
std::size_t files_in(const fs::path& folder) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(folder), fs::directory_iterator()));
}

TEST(ReplacingFile, ReplacesTheTargetOnlyWhenCommitted) {
  testing::ScratchDir dir;
  const fs::path target = dir.path() / "out.csv";
  write_text(target, "earlier run\n");
  {
    ReplacingFile file(target);
    file.stream() << "half of a new run";
    EXPECT_EQ(read_text(target), "earlier run\n") << "nothing shows before the commit";
    EXPECT_EQ(files_in(dir.path()), 2u);
  }  // never committed: a run that failed
  EXPECT_EQ(read_text(target), "earlier run\n");
  EXPECT_EQ(files_in(dir.path()), 1u);

  ReplacingFile file(target);
  file.stream() << "a whole new run\n";
  file.commit();
  EXPECT_TRUE(file.committed());
  EXPECT_EQ(read_text(target), "a whole new run\n");
  EXPECT_EQ(files_in(dir.path()), 1u);
}

TEST(ReplacingFile, AFolderItCannotWriteInIsNamedAtOnce) {
  testing::ScratchDir dir;
  try {
    ReplacingFile file(dir.path() / "no-such-folder" / "out.csv");
    FAIL() << "opened a file in a missing folder";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("no-such-folder"), std::string::npos) << error.what();
  }
}

TEST(ReplacingFile, ADeviceIsWrittenToAndStaysADevice) {
  ReplacingFile file("/dev/null");
  file.stream() << "discarded";
  file.commit();
  struct stat status {};
  ASSERT_EQ(::stat("/dev/null", &status), 0);
  EXPECT_TRUE(S_ISCHR(status.st_mode)) << "/dev/null was replaced";
}

TEST(ReplacingLog, AWriterThatFailsOrIsNeverClosedLeavesTheEarlierLog) {
  testing::ScratchDir dir;
  for (const std::string name : {"match.log", "match.log.gz"}) {
    SCOPED_TRACE(name);
    const fs::path target = dir.path() / name;
    {
      Result<LogWriter> first = LogWriter::create(target);
      ASSERT_TRUE(first) << first.error().message;
      ASSERT_TRUE(first->write(3, 1, "first"));
      ASSERT_TRUE(first->close());
    }
    const std::string earlier = read_text(target);
    ASSERT_FALSE(earlier.empty());
    {
      Result<LogWriter> second = LogWriter::create(target);
      ASSERT_TRUE(second) << second.error().message;
      ASSERT_TRUE(second->write(3, 2, "second, never closed"));
    }
    EXPECT_EQ(read_text(target), earlier);
    {
      Result<LogWriter> third = LogWriter::create(target);
      ASSERT_TRUE(third) << third.error().message;
      ASSERT_TRUE(third->write(3, 3, "third"));
      ASSERT_TRUE(third->write(3, 4, "and more"));
      ASSERT_TRUE(third->close());
    }
    EXPECT_NE(read_text(target), earlier);
  }
  EXPECT_EQ(files_in(dir.path()), 2u) << "a temporary file was left behind";
}

}  // namespace
}  // namespace ssl_formation
