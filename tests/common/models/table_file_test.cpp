#include "ssl_formation/models/table_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "table_bytes.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using namespace ssl_formation::testing;
// The header's row count, as the tests call it.
constexpr std::size_t rows_offset = header_rows_offset;

// Deterministic pseudo-random transitions, so failures reproduce.
TransitionTable make_table(Grid grid, int transitions, TableStorage storage,
                           std::uint64_t seed = 12345) {
  TransitionTable table(grid, storage);
  const StateIndex states = table.codec().state_count();
  std::uint64_t x = seed;
  const auto next = [&x] {
    x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::uint32_t>(x >> 33);
  };
  for (int i = 0; i < transitions; ++i) {
    // Few distinct FROM states so rows hold several entries, as a trained table does.
    const StateIndex from = next() % 64 * (states / 64);
    const StateIndex to = next() % states;
    table.add(from, to, 1 + next() % 5);
  }
  table.add(states - 1, states - 1, TransitionTable::max_count);  // the largest state and count
  return table;
}

TableMetadata make_metadata() {
  TableMetadata metadata;
  metadata.field = FieldSize{12000.0, 9000.0};
  metadata.step_s = 0.5;
  metadata.samples = 987654321;
  return metadata;
}

std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>> entries_of(
    const TransitionTable& table) {
  std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>> entries;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    entries.emplace_back(from, to, count);
  });
  return entries;
}

void expect_same_table(const TransitionTable& loaded, const TransitionTable& original) {
  ASSERT_EQ(loaded.grid(), original.grid());
  EXPECT_EQ(loaded.transitions(), original.transitions());
  EXPECT_EQ(loaded.nonzero_entries(), original.nonzero_entries());
  EXPECT_EQ(loaded.rows_seen(), original.rows_seen());
  const auto entries = entries_of(original);
  EXPECT_EQ(entries_of(loaded), entries);
  for (const auto& [from, to, count] : entries) {
    EXPECT_EQ(loaded.count(from, to), count);
    EXPECT_EQ(loaded.row_total(from), original.row_total(from)) << "row " << from;
  }
  const StateIndex cells = original.codec().cell_count();
  for (StateIndex t = 0; t < cells; ++t) {
    EXPECT_EQ(loaded.centroid_total(t), original.centroid_total(t)) << "centroid " << t;
    for (StateIndex c = 0; c < cells; ++c) {
      ASSERT_EQ(loaded.centroid_count(t, c), original.centroid_count(t, c))
          << "centroid block " << t << "," << c;
    }
  }
}

class TableFile : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("sslf-table-file-" + std::to_string(::getpid()) + "-" +
                                        info->name() + "-" + std::to_string(counter++));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directory(dir_));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  std::vector<std::string> files_in_dir() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  // Writes `bytes` as a table file, loads it and checks that loading left it untouched.
  LoadResult load_bytes(const Bytes& bytes, std::optional<Grid> expected = std::nullopt) {
    const fs::path path = dir_ / "damaged.bin";
    write_bytes(path, bytes);
    LoadResult result = load_table(path, expected);
    EXPECT_EQ(read_bytes(path), bytes) << "loading changed the file";
    if (!result) {
      EXPECT_NE(message_of(result).find(path.string()), std::string::npos) << message_of(result);
    }
    return result;
  }

  fs::path dir_;
};

TEST_F(TableFile, RoundTripDense3x2) {
  const Grid grid(3, 2);
  const TransitionTable table = make_table(grid, 500, TableStorage::automatic);
  ASSERT_TRUE(table.is_dense());
  const TableMetadata metadata = make_metadata();
  const fs::path path = dir_ / "table.bin";

  const auto saved = save_table(path, table, metadata);
  ASSERT_TRUE(saved) << message_of(saved);
  EXPECT_TRUE(saved->durable);
  EXPECT_TRUE(saved->warning.empty());
  const std::uint64_t states = table.codec().state_count();
  EXPECT_EQ(fs::file_size(path), header_size + states * states * 4 + 4);  // dense encoding

  const LoadResult loaded = load_table(path, grid);
  ASSERT_TRUE(loaded) << message_of(loaded);
  EXPECT_TRUE(loaded->table.is_dense());
  EXPECT_EQ(loaded->metadata, metadata);
  expect_same_table(loaded->table, table);
  EXPECT_EQ(files_in_dir(), std::vector<std::string>{"table.bin"});
}

TEST_F(TableFile, RoundTripSparse12x9WithoutAllocatingSSquared) {
  const Grid grid(12, 9);
  const TransitionTable table = make_table(grid, 5000, TableStorage::automatic);
  ASSERT_FALSE(table.is_dense());
  const TableMetadata metadata = make_metadata();
  const fs::path path = dir_ / "table.bin";

  const auto saved = save_table(path, table, metadata);
  ASSERT_TRUE(saved) << message_of(saved);
  EXPECT_EQ(fs::file_size(path),
            header_size + (table.rows_seen() + table.nonzero_entries()) * 8 + 4);  // sparse rows

  const LoadResult loaded = load_table(path, grid);
  ASSERT_TRUE(loaded) << message_of(loaded);
  EXPECT_FALSE(loaded->table.is_dense());
  // S*S counts would be terabytes; the loaded table costs what it learned.
  EXPECT_LT(loaded->table.memory_bytes(), std::size_t{64} << 20);
  EXPECT_EQ(loaded->metadata, metadata);
  expect_same_table(loaded->table, table);
}

TEST_F(TableFile, SparseFileOfASmallGridLoadsIntoEitherStorage) {
  const Grid grid(3, 2);
  const TransitionTable table = make_table(grid, 300, TableStorage::sparse);
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, table, make_metadata()));
  EXPECT_LT(fs::file_size(path), 216u * 216u * 4u);  // written as rows, not densely

  const LoadResult as_dense = load_table(path, grid, TableStorage::dense);
  ASSERT_TRUE(as_dense) << message_of(as_dense);
  EXPECT_TRUE(as_dense->table.is_dense());
  expect_same_table(as_dense->table, table);
  const LoadResult as_sparse = load_table(path, grid, TableStorage::sparse);
  ASSERT_TRUE(as_sparse) << message_of(as_sparse);
  EXPECT_FALSE(as_sparse->table.is_dense());
  expect_same_table(as_sparse->table, table);
}

TEST_F(TableFile, EmptyTablesRoundTrip) {
  for (const TableStorage storage : {TableStorage::dense, TableStorage::sparse}) {
    const TransitionTable table(Grid(3, 2), storage);
    const fs::path path = dir_ / "empty.bin";
    ASSERT_TRUE(save_table(path, table, TableMetadata{}));
    const LoadResult loaded = load_table(path, Grid(3, 2));
    ASSERT_TRUE(loaded) << message_of(loaded);
    EXPECT_EQ(loaded->table.transitions(), 0u);
    EXPECT_EQ(loaded->table.nonzero_entries(), 0u);
    EXPECT_EQ(loaded->metadata, TableMetadata{});
  }
}

TEST_F(TableFile, FlippedByteIsDetectedAndTheFileIsLeftAlone) {
  for (const Grid grid : {Grid(3, 2), Grid(12, 9)}) {
    SCOPED_TRACE(grid.to_string());
    const fs::path path = dir_ / "table.bin";
    ASSERT_TRUE(save_table(path, make_table(grid, 400, TableStorage::automatic), make_metadata()));
    const Bytes original = read_bytes(path);
    const std::size_t size = original.size();
    // Each header field, including grid and size fields whose flip would still look valid
    // (3x2 -> 19x2, 12x9 -> 28x9; entries +-16) were it not for the header checksum.
    const std::vector<std::size_t> offsets = {0,        5,           version_offset,
                                              12,       13,          16,
                                              22,       30,          47,
                                              50,       60,          64,
                                              66,       72,          77,
                                              81,       header_size, header_size + 5,
                                              size / 2, size - 5,    size - 2};
    for (const std::size_t offset : offsets) {
      SCOPED_TRACE("offset " + std::to_string(offset));
      Bytes damaged = original;
      damaged[offset] ^= 0x10;
      const LoadResult result = load_bytes(damaged, grid);
      ASSERT_FALSE(result);  // neither a table nor an error without a kind
      EXPECT_FALSE(result.error().message.empty());
      if (offset < 8) {
        EXPECT_EQ(kind_of(result), TableFileError::not_a_table) << message_of(result);
      } else if (offset < 12) {
        EXPECT_EQ(kind_of(result), TableFileError::wrong_version) << message_of(result);
      } else {
        // The header checksum catches a flipped header field (grid and sizes included) before
        // it can pose as another grid or a truncation; the file checksum catches the rest.
        EXPECT_EQ(kind_of(result), TableFileError::corrupt) << message_of(result);
      }
      if (offset >= header_size) {
        EXPECT_NE(message_of(result).find("checksum mismatch: the file is corrupt"),
                  std::string::npos)
            << message_of(result);
      }
    }
  }
}

TEST_F(TableFile, TruncatedFileIsDetectedAndTheFileIsLeftAlone) {
  for (const Grid grid : {Grid(3, 2), Grid(12, 9)}) {
    SCOPED_TRACE(grid.to_string());
    const fs::path path = dir_ / "table.bin";
    ASSERT_TRUE(save_table(path, make_table(grid, 400, TableStorage::automatic), make_metadata()));
    const Bytes original = read_bytes(path);
    const std::size_t size = original.size();
    // Empty, mid-magic, mid-version, mid-header, header only, mid-counts, no checksum, part of it.
    const std::vector<std::size_t> lengths = {0,           3,        10,       40,
                                              header_size, size / 2, size - 4, size - 1};
    for (const std::size_t length : lengths) {
      SCOPED_TRACE("length " + std::to_string(length));
      const Bytes cut(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(length));
      const LoadResult result = load_bytes(cut, grid);
      EXPECT_EQ(kind_of(result), TableFileError::truncated) << message_of(result);
      EXPECT_NE(message_of(result).find("truncated: " + std::to_string(length) + " bytes"),
                std::string::npos)
          << message_of(result);
    }
  }
}

TEST_F(TableFile, ShortOrForeignFileIsNotATable) {
  const Bytes foreign = {'S', 'S', 'X'};
  EXPECT_EQ(kind_of(load_bytes(foreign)), TableFileError::not_a_table);
  const std::string text =
      "grid 3x2\nthis is a text file, not a table, but long enough for a header"
      " and then some more bytes\n";
  const LoadResult result = load_bytes(Bytes(text.begin(), text.end()));
  EXPECT_EQ(kind_of(result), TableFileError::not_a_table);
  EXPECT_NE(message_of(result).find("not a table file"), std::string::npos) << message_of(result);
}

TEST_F(TableFile, TrailingBytesAreCorrupt) {
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, make_table(Grid(3, 2), 50, TableStorage::automatic), {}));
  Bytes bytes = read_bytes(path);
  bytes.push_back(0);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::corrupt);
  EXPECT_NE(message_of(result).find("1 trailing bytes"), std::string::npos) << message_of(result);
}

TEST_F(TableFile, WrongGridNamesBothGrids) {
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, make_table(Grid(6, 4), 50, TableStorage::automatic), {}));
  const Bytes before = read_bytes(path);

  const LoadResult result = load_table(path, Grid(3, 2));
  EXPECT_FALSE(result);
  EXPECT_EQ(kind_of(result), TableFileError::wrong_grid);
  EXPECT_EQ(message_of(result),
            path.string() + " holds a 6x4 grid, expected 3x2 (give --grid 6x4 to use it)");
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_TRUE(load_table(path, Grid(6, 4)));
  EXPECT_TRUE(load_table(path));  // no expectation: any grid
}

TEST_F(TableFile, WrongVersionNamesBothVersions) {
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, make_table(Grid(3, 2), 50, TableStorage::automatic), {}));
  Bytes bytes = read_bytes(path);
  ASSERT_EQ(get_u32(bytes, version_offset), table_file_version);
  // The checksums are left stale on purpose: load_table checks the version before any checksum,
  // since another version may lay out or checksum its header differently.
  // Versions 3 to 5 are the motion model's and 2 its retired one
  // (motion_table_file_test.cpp); 6 is from a newer program.
  put_u32(bytes, version_offset, 6);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::wrong_version) << message_of(result);
  EXPECT_NE(message_of(result).find("version 6"), std::string::npos) << message_of(result);
  EXPECT_NE(message_of(result).find("version 1, 3, 4 or 5"), std::string::npos)
      << message_of(result);
}

TEST_F(TableFile, InconsistentContentUnderValidChecksumsIsCorrupt) {
  const fs::path path = dir_ / "table.bin";
  const TransitionTable table = make_table(Grid(12, 9), 50, TableStorage::automatic);
  ASSERT_TRUE(save_table(path, table, {}));
  const Bytes original = read_bytes(path);
  const std::size_t first_row = header_size;  // u32 from, u32 n, then (u32 to, u32 count) pairs
  const std::uint32_t states = table.codec().state_count();
  ASSERT_EQ(original.size(), header_size + (table.rows_seen() + table.nonzero_entries()) * 8 + 4);

  const auto expect_corrupt = [&](Bytes bytes, const std::string& reason) {
    SCOPED_TRACE(reason);
    reseal(bytes);
    const LoadResult result = load_bytes(bytes);
    EXPECT_EQ(kind_of(result), TableFileError::corrupt) << message_of(result);
    EXPECT_NE(message_of(result).find(reason), std::string::npos) << message_of(result);
  };
  {
    Bytes bytes = original;
    bytes[transitions_offset] ^= 1;
    expect_corrupt(bytes, "the header says");
  }
  {
    Bytes bytes = original;
    put_u32(bytes, first_row + 12, 0);  // the first count
    expect_corrupt(bytes, "zero count");
  }
  {
    Bytes bytes = original;
    put_u32(bytes, first_row + 8, states);  // the first target
    expect_corrupt(bytes, "out of range");
  }
  {
    Bytes bytes = original;
    put_u32(bytes, first_row, states);  // the first row's FROM state
    expect_corrupt(bytes, "out of range");
  }
  {
    Bytes bytes = original;
    put_u32(bytes, first_row + 4, 0);  // the first row's entry count
    expect_corrupt(bytes, "entry count");
  }
  {
    Bytes bytes = original;  // an unknown encoding in an otherwise valid header
    put_u32(bytes, 20, 7);
    expect_corrupt(bytes, "encoding");
  }
  {
    // A dense file whose row count disagrees with its grid, though its length still fits.
    const fs::path dense_path = dir_ / "dense.bin";
    ASSERT_TRUE(save_table(dense_path, make_table(Grid(3, 2), 50, TableStorage::dense), {}));
    Bytes bytes = read_bytes(dense_path);
    bytes[rows_offset] ^= 1;
    expect_corrupt(bytes, "dense row and entry counts");
  }
  // The untouched file, resealed the same way, still loads: the cases above fail for their reason.
  Bytes resealed = original;
  reseal(resealed);
  EXPECT_EQ(resealed, original);
  EXPECT_TRUE(load_bytes(resealed));
}

TEST_F(TableFile, MissingFileCannotBeOpened) {
  const fs::path path = dir_ / "nothing-here.bin";
  const LoadResult result = load_table(path);
  EXPECT_EQ(kind_of(result), TableFileError::cannot_open);
  EXPECT_NE(message_of(result).find(path.string()), std::string::npos) << message_of(result);
  EXPECT_NE(message_of(result).find(std::strerror(ENOENT)), std::string::npos)
      << message_of(result);
  EXPECT_FALSE(fs::exists(path));

  const LoadResult folder = load_table(dir_);
  EXPECT_EQ(kind_of(folder), TableFileError::cannot_open) << message_of(folder);
}

TEST_F(TableFile, SaveInterruptedBeforeRenameLeavesTheOldFile) {
  const Grid grid(3, 2);
  const fs::path path = dir_ / "table.bin";
  const TransitionTable old_table = make_table(grid, 100, TableStorage::automatic, 1);
  const TransitionTable new_table = make_table(grid, 200, TableStorage::automatic, 2);
  ASSERT_NE(entries_of(old_table), entries_of(new_table));
  ASSERT_TRUE(save_table(path, old_table, make_metadata()));
  const Bytes before = read_bytes(path);

  bool hook_ran = false;
  SaveHooks hooks;
  hooks.before_rename = [&] {
    hook_ran = true;
    // At this moment the new table sits complete in a temporary file beside the target.
    const auto names = files_in_dir();
    EXPECT_EQ(names.size(), 2u);
    for (const auto& name : names) {
      if (name == "table.bin") continue;
      EXPECT_EQ(name.rfind("table.bin.tmp-", 0), 0u) << name;
      const LoadResult temp = load_table(dir_ / name, grid);
      EXPECT_TRUE(temp) << message_of(temp);
      if (temp) expect_same_table(temp->table, new_table);
    }
    return false;
  };
  const auto aborted = save_table(path, new_table, make_metadata(), hooks);
  EXPECT_TRUE(hook_ran);
  EXPECT_FALSE(aborted);
  EXPECT_NE(message_of(aborted).find(path.string()), std::string::npos) << message_of(aborted);
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_EQ(files_in_dir(), std::vector<std::string>{"table.bin"});

  // The same save without the interruption replaces the file.
  ASSERT_TRUE(save_table(path, new_table, make_metadata()));
  const LoadResult loaded = load_table(path, grid);
  ASSERT_TRUE(loaded) << message_of(loaded);
  expect_same_table(loaded->table, new_table);
  EXPECT_EQ(files_in_dir(), std::vector<std::string>{"table.bin"});
}

TEST_F(TableFile, FolderThatCannotBeSyncedAfterTheRenameIsASaveWithAWarning) {
  const Grid grid(3, 2);
  const fs::path path = dir_ / "table.bin";
  const TransitionTable old_table = make_table(grid, 100, TableStorage::automatic, 1);
  const TransitionTable new_table = make_table(grid, 200, TableStorage::automatic, 2);
  ASSERT_NE(entries_of(old_table), entries_of(new_table));
  ASSERT_TRUE(save_table(path, old_table, make_metadata()));

  int synced_fd = -1;
  SaveHooks hooks;
  hooks.sync_folder = [&](int folder_fd) {
    synced_fd = folder_fd;
    // By now the new table has been renamed over the old one.
    const LoadResult renamed = load_table(path, grid);
    EXPECT_TRUE(renamed) << message_of(renamed);
    if (renamed) expect_same_table(renamed->table, new_table);
    return EIO;
  };
  const auto saved = save_table(path, new_table, make_metadata(), hooks);
  EXPECT_GE(synced_fd, 0);
  // The rename succeeded, so the table is safe: a success, not a failure the trainer exits on.
  ASSERT_TRUE(saved) << message_of(saved);
  EXPECT_FALSE(saved->durable);
  EXPECT_NE(saved->warning.find(path.string()), std::string::npos) << saved->warning;
  EXPECT_NE(saved->warning.find(std::strerror(EIO)), std::string::npos) << saved->warning;
  EXPECT_NE(saved->warning.find("cannot sync its folder"), std::string::npos) << saved->warning;

  const LoadResult loaded = load_table(path, grid);
  ASSERT_TRUE(loaded) << message_of(loaded);
  expect_same_table(loaded->table, new_table);
  EXPECT_EQ(files_in_dir(), std::vector<std::string>{"table.bin"});

  // A folder that syncs makes the save durable again, without a warning.
  hooks.sync_folder = [](int) { return 0; };
  const auto durable = save_table(path, old_table, make_metadata(), hooks);
  ASSERT_TRUE(durable) << message_of(durable);
  EXPECT_TRUE(durable->durable);
  EXPECT_TRUE(durable->warning.empty()) << durable->warning;
}

TEST_F(TableFile, SaveIntoMissingFolderFailsCleanly) {
  const fs::path path = dir_ / "missing" / "table.bin";
  const auto result =
      save_table(path, make_table(Grid(3, 2), 10, TableStorage::automatic), make_metadata());
  EXPECT_FALSE(result);
  EXPECT_NE(message_of(result).find(path.string()), std::string::npos) << message_of(result);
  EXPECT_NE(message_of(result).find(std::strerror(ENOENT)), std::string::npos)
      << message_of(result);
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
  EXPECT_TRUE(files_in_dir().empty());
}

TEST_F(TableFile, SaveRefusesMetadataThatCouldNotBeLoaded) {
  const fs::path path = dir_ / "table.bin";
  const TransitionTable table(Grid(3, 2));
  TableMetadata no_step;
  no_step.step_s = 0.0;
  TableMetadata no_field;
  no_field.field.width_mm = -1.0;
  for (const TableMetadata& metadata : {no_step, no_field}) {
    const auto result = save_table(path, table, metadata);
    EXPECT_FALSE(result);
    EXPECT_NE(message_of(result).find(path.string()), std::string::npos) << message_of(result);
  }
  EXPECT_TRUE(files_in_dir().empty());
}

}  // namespace
}  // namespace ssl_formation
