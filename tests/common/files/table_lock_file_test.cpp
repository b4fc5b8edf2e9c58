// The one-writer lock of a table, in-process: a released lock leaves no file beside the table,
// and writers that take and release it at the same moment never hold it together, though each
// holder removes the file it locked on its way out. Locks on one file conflict between two open
// descriptions even in one process, so threads stand in for trainers.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "scratch_dir.hpp"
#include "ssl_formation/files/table_lock.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

ino_t inode_of(const fs::path& path) {
  struct stat status {};
  return ::stat(path.c_str(), &status) == 0 ? status.st_ino : 0;
}

TEST(TableLockFile, AReleasedLockLeavesNoFileAndAKilledHoldersFileIsTakenOver) {
  const testing::ScratchDir dir;
  const fs::path path = TableWriterLock::lock_path_for_table(dir.path() / "table.bin");
  {
    const TableWriterLock lock(path, "the table table.bin");
    EXPECT_EQ(read_text(path), std::to_string(::getpid()) + "\n");
  }
  EXPECT_FALSE(fs::exists(path));

  // What a killed writer leaves: the file with its pid, locked by nobody.
  { std::ofstream(path) << "999999\n"; }
  {
    const TableWriterLock lock(path, "the table table.bin");
    EXPECT_EQ(read_text(path), std::to_string(::getpid()) + "\n");
  }
  EXPECT_FALSE(fs::exists(path));

  // The folder's lock the same.
  {
    const TableWriterLock lock(TableWriterLock::lock_path_for_folder(dir.path()), "the folder");
    EXPECT_TRUE(fs::exists(dir.path() / ".ssl-trainer.lock"));
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(TableLockFile, AWriterStoppingDoesNotRefuseTheNextOne) {
  const testing::ScratchDir dir;
  const fs::path path = dir.path() / "table.bin.lock";
  // A holder on its way out: it has removed its file and not yet closed it.
  const int stopping = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  ASSERT_GE(stopping, 0);
  ASSERT_EQ(::flock(stopping, LOCK_EX | LOCK_NB), 0);
  ASSERT_EQ(::unlink(path.c_str()), 0);
  {
    const TableWriterLock next(path, "the table table.bin");
    EXPECT_TRUE(fs::exists(path));
    // And the new holder's lock counts.
    EXPECT_THROW(TableWriterLock(path, "the table table.bin"), TableLockError);
  }
  ::close(stopping);
  EXPECT_FALSE(fs::exists(path));
}

TEST(TableLockFile, AHolderLeavesAFileItDidNotLock) {
  const testing::ScratchDir dir;
  const fs::path path = dir.path() / "table.bin.lock";
  std::optional<TableWriterLock> first(std::in_place, path, "the table table.bin");
  // Removed by hand while held: a second writer makes a new one and holds that.
  fs::remove(path);
  const TableWriterLock second(path, "the table table.bin");
  const ino_t seconds_file = inode_of(path);
  ASSERT_NE(seconds_file, 0u);
  first.reset();
  EXPECT_EQ(inode_of(path), seconds_file) << "the first writer removed the second's lock file";
}

TEST(TableLockFile, WritersTakingAndReleasingAtOnceNeverHoldItTogether) {
  const testing::ScratchDir dir;
  const fs::path path = dir.path() / "table.bin.lock";
  constexpr int kWriters = 4;
  constexpr int kTriesEach = 2000;
  std::atomic<int> holding{0};
  std::atomic<int> most_holding{0};
  std::atomic<int> taken{0};
  std::atomic<int> refused{0};
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w) {
    writers.emplace_back([&] {
      for (int i = 0; i < kTriesEach; ++i) {
        try {
          const TableWriterLock lock(path, "the table table.bin");
          const int now = ++holding;
          int most = most_holding.load();
          while (now > most && !most_holding.compare_exchange_weak(most, now)) {
          }
          // Long enough for the others to open the file, and some to wait on it as it goes.
          std::this_thread::yield();
          --holding;
          ++taken;
        } catch (const TableLockError&) {
          ++refused;
        }
      }
    });
  }
  for (std::thread& writer : writers) writer.join();
  EXPECT_EQ(most_holding.load(), 1) << "two writers held the lock at once";
  EXPECT_GT(taken.load(), 0);
  EXPECT_EQ(taken.load() + refused.load(), kWriters * kTriesEach);
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace ssl_formation
