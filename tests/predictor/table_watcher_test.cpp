#include "ssl_formation/predictor/table_watcher.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include "scratch_dir.hpp"
#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation::predictor {
namespace {

namespace fs = std::filesystem;

// A fresh folder for each test, removed with everything in it.
class TempDir : public testing::ScratchDir {
 public:
  TempDir() : ScratchDir("sslf-table-watcher") {}
};

// A table with `n` transitions, so that each version of the file is told apart by its total.
TransitionTable table_with(Grid grid, std::uint32_t n) {
  TransitionTable table(grid);
  const StateIndex states = table.codec().state_count();
  for (std::uint32_t i = 0; i < n; ++i) table.add(i % states, (7 * i + 3) % states);
  return table;
}

// Saves as the trainer does: a temporary file renamed over `path`.
void save(const fs::path& path, Grid grid, std::uint32_t transitions, std::uint64_t samples = 5) {
  TableMetadata metadata;
  metadata.samples = samples;
  const auto saved = save_table(path, table_with(grid, transitions), metadata);
  ASSERT_TRUE(saved) << saved.error().message;
}

// Replaces `path` by renaming a file with these bytes over it.
void replace_with_bytes(const fs::path& path, const std::string& bytes) {
  const fs::path temporary = path.string() + ".new";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << bytes;
  }
  fs::rename(temporary, path);
}

TEST(TableWatcher, NoFileIsNoChange) {
  TempDir dir;
  TableWatcher watcher(dir.path() / "table.sslf", Grid(3, 2));
  EXPECT_EQ(watcher.path(), dir.path() / "table.sslf");
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  EXPECT_EQ(watcher.table(), nullptr);
  EXPECT_EQ(watcher.reloads(), 0u);
  EXPECT_TRUE(watcher.last_error().empty());
}

TEST(TableWatcher, LoadsTheFileWhenItAppearsAndOnlyThen) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  TableWatcher watcher(path, Grid(3, 2));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::none);

  save(path, Grid(3, 2), 40, 17);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  ASSERT_NE(watcher.table(), nullptr);
  EXPECT_EQ(watcher.table()->table.transitions(), 40u);
  EXPECT_EQ(watcher.table()->metadata.samples, 17u);
  EXPECT_EQ(watcher.reloads(), 1u);
  EXPECT_TRUE(watcher.last_error().empty());

  // Unchanged: nothing to do, the same table.
  const StoredTable* first = watcher.table().get();
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  EXPECT_EQ(watcher.table().get(), first);
  EXPECT_EQ(watcher.reloads(), 1u);
}

TEST(TableWatcher, ReloadsAFileReplacedByRenameAndAHolderKeepsTheOldTable) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save(path, Grid(3, 2), 40);
  TableWatcher watcher(path, Grid(3, 2));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);

  // A prediction under way holds the table it started with.
  std::shared_ptr<const StoredTable> held = watcher.table();
  save(path, Grid(3, 2), 55);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  EXPECT_EQ(watcher.reloads(), 2u);
  EXPECT_EQ(watcher.table()->table.transitions(), 55u);
  EXPECT_NE(watcher.table(), held);
  EXPECT_EQ(held->table.transitions(), 40u) << "the holder's table is intact";
  EXPECT_EQ(held.use_count(), 1) << "the watcher let go of the old table";
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);

  // A replacement of exactly the same size (dense tables always are) is still a new file.
  save(path, Grid(3, 2), 56);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  EXPECT_EQ(watcher.table()->table.transitions(), 56u);
  EXPECT_EQ(watcher.reloads(), 3u);
}

TEST(TableWatcher, ReloadsAFileRewrittenInPlace) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  const fs::path other = dir.path() / "other.sslf";
  save(path, Grid(2, 1), 3);
  TableWatcher watcher(path, Grid(2, 1));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  // Another table's bytes copied into the same inode (cp does this): size and time change.
  save(other, Grid(2, 1), 9);
  fs::copy_file(other, path, fs::copy_options::overwrite_existing);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  EXPECT_EQ(watcher.table()->table.transitions(), 9u);
}

TEST(TableWatcher, ACorruptReplacementFailsOnceAndKeepsTheTable) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save(path, Grid(3, 2), 40);
  TableWatcher watcher(path, Grid(3, 2));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  const std::shared_ptr<const StoredTable> good = watcher.table();

  replace_with_bytes(path, "SSLFTABL but nothing a table needs after it");
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::failed);
  EXPECT_EQ(watcher.table(), good) << "the table in use stays";
  EXPECT_EQ(watcher.reloads(), 1u);
  EXPECT_NE(watcher.last_error().find(path.string()), std::string::npos) << watcher.last_error();

  // Reported once: the same bad file is not loaded again and again.
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  EXPECT_EQ(watcher.table(), good);

  // The next good file is loaded, and the error is over.
  save(path, Grid(3, 2), 77);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  EXPECT_EQ(watcher.table()->table.transitions(), 77u);
  EXPECT_TRUE(watcher.last_error().empty()) << watcher.last_error();
  EXPECT_EQ(watcher.reloads(), 2u);
}

TEST(TableWatcher, ATruncatedReplacementFails) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save(path, Grid(3, 2), 40);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  TableWatcher watcher(path, Grid(3, 2));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  replace_with_bytes(path, bytes.substr(0, bytes.size() / 2));
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::failed);
  EXPECT_EQ(watcher.table()->table.transitions(), 40u);
  EXPECT_NE(watcher.last_error().find("truncated"), std::string::npos) << watcher.last_error();
}

TEST(TableWatcher, ATableOfAnotherGridFails) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  TableWatcher watcher(path, Grid(3, 2));
  // Never a table of the right grid yet: failed, and still no table.
  save(path, Grid(4, 3), 10);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::failed);
  EXPECT_EQ(watcher.table(), nullptr);
  EXPECT_EQ(watcher.reloads(), 0u);
  EXPECT_NE(watcher.last_error().find(path.string()), std::string::npos) << watcher.last_error();
  EXPECT_NE(watcher.last_error().find("4x3"), std::string::npos) << watcher.last_error();
  EXPECT_NE(watcher.last_error().find("3x2"), std::string::npos) << watcher.last_error();

  save(path, Grid(3, 2), 12);
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  // Then a trainer restarted with another grid replaces it: the 3x2 table stays in use.
  save(path, Grid(4, 3), 10);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::failed);
  ASSERT_NE(watcher.table(), nullptr);
  EXPECT_EQ(watcher.table()->table.grid(), Grid(3, 2));
  EXPECT_EQ(watcher.table()->table.transitions(), 12u);
}

TEST(TableWatcher, ARemovedFileKeepsTheTable) {
  TempDir dir;
  const fs::path path = dir.path() / "table.sslf";
  save(path, Grid(3, 2), 40);
  TableWatcher watcher(path, Grid(3, 2));
  ASSERT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  fs::remove(path);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::none);
  ASSERT_NE(watcher.table(), nullptr);
  EXPECT_EQ(watcher.table()->table.transitions(), 40u);
  // And a new file there is loaded.
  save(path, Grid(3, 2), 41);
  EXPECT_EQ(watcher.poll(), TableWatcher::Change::loaded);
  EXPECT_EQ(watcher.table()->table.transitions(), 41u);
}

}  // namespace
}  // namespace ssl_formation::predictor
