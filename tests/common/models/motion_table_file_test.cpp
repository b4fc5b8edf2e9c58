// The table file's motion versions: the motion model's table after the paper's counts (the
// layouts in table_file.hpp), saved as version 5 (compact), versions 3 and 4 still read. Version
// 1 stays as it was; table_file_bytes_test.cpp holds the versions to their bytes.

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "circling_robots.hpp"
#include "motion_section_bytes.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "table_bytes.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using namespace ssl_formation::testing;
// The layout of table_file.hpp's motion section.
constexpr std::size_t config_size = 68;
constexpr std::size_t instances_offset = config_size;  // within the motion section
constexpr std::size_t seen_offset = config_size + 8;
constexpr std::size_t row_count_offset = config_size + 16;
constexpr std::size_t rows_length_offset = config_size + 24;  // version 5: the rows' bytes
constexpr std::size_t rows_offset = config_size + 32;
// Versions 3 and 4: fixed-width rows and calibration instances.
constexpr std::size_t row_size = 8 + 8 * MotionRow::size;
constexpr std::size_t held_out_size = 8 + 4 + 4 * motion_instance_values.size() + 4;

using Entries = std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>>;
Entries entries_of(const TransitionTable& table) {
  Entries out;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    out.emplace_back(from, to, count);
  });
  return out;
}

// ---- Streams of opponent robots driving circles, one frame every 1/30 s.

SamplerConfig frame_config(double step_s) {
  SamplerConfig config;
  config.grid = Grid(3, 2);
  config.step_s = step_s;
  config.sampling = Sampling::frame;
  return config;
}

using ssl_formation::testing::circling_stream;

MotionConfig small_calibration_config(double step_s) {
  MotionConfig config;
  config.step_s = step_s;
  config.horizons = 3;
  config.calibration_one_in = 4;     // many held-out blocks in a short stream
  config.calibration_capacity = 40;  // full, so merging has to pick the same instances
  return config;
}

// A table trained on `streams`, each its own stream (as log files are).
std::unique_ptr<Training> train(const std::vector<std::vector<SSL_WrapperPacket>>& streams,
                                const MotionConfig& motion) {
  auto training = std::make_unique<Training>(frame_config(motion.step_s),
                                             TransitionTable(Grid(3, 2)), 0, MotionTable(motion));
  for (const auto& stream : streams) {
    training->start_new_stream();
    for (const auto& packet : stream) training->add(packet);
  }
  return training;
}

// A motion table from instances made up directly: every horizon, held-out times included, an
// instance offered twice (equal calibration neighbours), negative values throughout.
MotionTable synthetic_motion_table(const MotionConfig& config) {
  MotionTable table(config);
  for (int i = 0; i < 600; ++i) {
    MotionInstance instance;
    instance.robot_id = static_cast<std::uint32_t>(i % 19);
    instance.x = -6000 + 37 * i;
    instance.y = 4000 - 23 * i;
    instance.v_x = (i % 7 - 3) * 400;
    instance.v_y = (i % 5 - 2) * 300;
    instance.d_x = -900 + 5 * i;
    instance.d_y = 700 - 3 * i;
    instance.a_x = (i % 11 - 5) * 100;
    instance.a_y = -(i % 13) * 90;
    instance.g_x = (i % 9 - 4) * 70;
    instance.g_y = (i % 4 - 2) * 60;
    instance.s_x = -(i % 6) * 150;
    instance.s_y = (i % 8) * 120;
    instance.t_x = (i % 7 - 3) * 110;
    instance.t_y = -(i % 5) * 95;
    instance.context = static_cast<std::uint32_t>(i % 3);
    const double time_s = 0.37 * i;
    table.add(i % config.horizons, time_s, instance);
    if (i % 50 == 0) table.add(i % config.horizons, time_s, instance);
  }
  return table;
}

class MotionTableFile : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("sslf-motion-table-file-" + std::to_string(::getpid()) +
                                        "-" + info->name() + "-" + std::to_string(counter++));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directory(dir_));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Writes `bytes` as a table file, loads it and checks that loading left it untouched.
  LoadResult load_bytes(const Bytes& bytes) {
    const fs::path path = dir_ / "damaged.bin";
    write_bytes(path, bytes);
    LoadResult result = load_table(path);
    EXPECT_EQ(read_bytes(path), bytes) << "loading changed the file";
    if (!result) {
      EXPECT_NE(message_of(result).find(path.string()), std::string::npos) << message_of(result);
    }
    return result;
  }

  // A saved file of a small trained table and where its motion section starts.
  struct Saved {
    Bytes bytes;
    std::size_t motion_begin = 0;
    StoredTable stored;
  };
  Saved save_trained(double step_s = 0.5) {
    const auto training = train({circling_stream(10.0, 12.0, 1)}, small_calibration_config(step_s));
    TableMetadata metadata;
    metadata.step_s = step_s;
    metadata.samples = training->samples();
    const fs::path path = dir_ / "v2.bin";
    EXPECT_TRUE(save_table(path, training->stored_table().table, metadata,
                           *training->stored_table().motion));
    const fs::path v1 = dir_ / "v1.bin";
    EXPECT_TRUE(save_table(v1, training->stored_table().table, metadata));
    Saved saved{read_bytes(path), read_bytes(v1).size() - 4, training->stored_table(metadata)};
    return saved;
  }

  fs::path dir_;
};

// The motion section lists the fields of MotionConfig, MotionRow and MotionInstance one by one
// (table_file.cpp). A field added to one of them must be added to the file (and its layout in
// table_file.hpp) too, or tables would lose it on every save: this test fails until then.
TEST(MotionTableFileLayout, CoversEveryFieldOfTheMotionStructs) {
  EXPECT_EQ(sizeof(MotionRow), MotionRow::size * sizeof(std::int64_t))
      << "MotionRow changed: update the motion section of table_file.cpp/.hpp";
  EXPECT_EQ(sizeof(MotionInstance), (2 + motion_instance_values.size()) * sizeof(std::uint32_t))
      << "MotionInstance has a field motion_instance_values leaves out";
  EXPECT_EQ(sizeof(MotionConfig),
            7 * sizeof(double) + sizeof(std::uint64_t) + 2 * sizeof(std::uint32_t))
      << "MotionConfig changed: update the motion section of table_file.cpp/.hpp";
  // The sizes table_file.hpp documents.
  EXPECT_EQ(row_size, 280u) << "update the layout in table_file.hpp";
  EXPECT_EQ(held_out_size, 72u) << "update the layout in table_file.hpp";
}

TEST_F(MotionTableFile, TrainedTableRoundTrips) {
  const MotionConfig config = small_calibration_config(0.5);
  const auto training =
      train({circling_stream(10.0, 20.0, 1), circling_stream(100.0, 15.0, 2)}, config);
  const StoredTable stored = training->stored_table();
  const MotionTable& motion = *stored.motion;
  ASSERT_GT(motion.instances(), 1000u);
  ASSERT_GT(motion.held_out(), 0u);
  for (int h = 0; h < config.horizons; ++h) ASSERT_FALSE(motion.calibration(h).empty()) << h;

  TableMetadata metadata;
  metadata.field = FieldSize{12000.0, 9000.0};
  metadata.step_s = 0.5;
  metadata.samples = training->samples();
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, training->stored_table().table, metadata, motion));
  EXPECT_EQ(get_u32(read_bytes(path), version_offset), table_file_compact_motion_version);

  const LoadResult loaded = load_table(path, Grid(3, 2));
  ASSERT_TRUE(loaded) << message_of(loaded);
  EXPECT_EQ(loaded->metadata, metadata);
  EXPECT_EQ(entries_of(loaded->table), entries_of(training->stored_table().table));
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_TRUE(*loaded->motion == motion);
  EXPECT_EQ(loaded->motion->config(), config);
  EXPECT_EQ(loaded->motion->instances(), motion.instances());
  EXPECT_EQ(loaded->motion->held_out(), motion.held_out());
  EXPECT_EQ(loaded->motion->sorted_rows(), motion.sorted_rows());

  // Saved again as loaded: the same bytes.
  const fs::path again = dir_ / "again.bin";
  ASSERT_TRUE(save_table(again, *loaded));
  EXPECT_EQ(read_bytes(again), read_bytes(path));
}

TEST_F(MotionTableFile, SparseGridAndSyntheticInstancesRoundTrip) {
  MotionConfig config;
  config.step_s = 1.0;
  config.horizons = MotionConfig::max_horizons;
  config.calibration_one_in = 3;
  config.calibration_capacity = 7;
  // Every other setting away from its default, so that each is seen to be saved.
  config.velocity_window_s = 0.2;
  config.settle_window_s = 0.7;
  config.long_settle_window_s = 3.0;
  config.learn_interval_s = 0.25;
  config.tolerance_s = 0.04;
  config.calibration_block_s = 2.0;
  const MotionTable motion = synthetic_motion_table(config);
  ASSERT_GT(motion.held_out(), 7u) << "some calibration instances must have been dropped";

  TransitionTable table(Grid(12, 9));
  table.add(5, 77, 3);
  table.add(123456, 9, 1);
  TableMetadata metadata;
  metadata.step_s = 1.0;
  metadata.samples = 42;
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, table, metadata, motion));
  const LoadResult loaded = load_table(path);
  ASSERT_TRUE(loaded) << message_of(loaded);
  EXPECT_FALSE(loaded->table.is_dense());
  EXPECT_EQ(entries_of(loaded->table), entries_of(table));
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_EQ(loaded->motion->config(), config);
  EXPECT_TRUE(*loaded->motion == motion);
}

TEST_F(MotionTableFile, EmptyMotionTableRoundTrips) {
  MotionConfig config;
  config.step_s = 2.0;
  const MotionTable motion(config);
  const fs::path path = dir_ / "table.bin";
  ASSERT_TRUE(save_table(path, TransitionTable(Grid(3, 2)), TableMetadata{}, motion));
  const LoadResult loaded = load_table(path);
  ASSERT_TRUE(loaded) << message_of(loaded);
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_TRUE(*loaded->motion == motion);
  EXPECT_EQ(loaded->motion->instances(), 0u);
}

// A kick-off made up directly: robot 2 runs along y after NORMAL_START, the others stand.
SetPlayEpisode made_up_kickoff(std::int32_t shift_mm) {
  SetPlayEpisode episode;
  for (int i = 0; i < 40; ++i) {
    SetPlaySnapshot s;
    s.offset_ms = 100 * i;
    s.stage = i < 10   ? SetPlayStage::preparation
              : i < 30 ? SetPlayStage::taken
                       : SetPlayStage::over;
    s.since_command_ms = i < 10 ? 100 * i : 100 * (i - 10);
    for (std::uint32_t id = 0; id < 6; ++id) {
      s.seen |= 1U << id;
      s.position[id] = {-600 * static_cast<std::int32_t>(id) + shift_mm, id == 2 ? 50 * i : -300};
    }
    episode.snapshots.push_back(s);
  }
  return episode;
}

TEST_F(MotionTableFile, VersionFiveIsVersionOneWithTheMotionSectionAppended) {
  const Saved saved = save_trained();
  const Bytes v1 = read_bytes(dir_ / "v1.bin");
  EXPECT_EQ(get_u32(v1, version_offset), table_file_version);
  EXPECT_EQ(get_u32(saved.bytes, version_offset), table_file_compact_motion_version);
  // Everything but the version, the header checksum and the file checksum is v1's, in place.
  ASSERT_GT(saved.bytes.size(), v1.size());
  EXPECT_TRUE(
      std::equal(v1.begin() + 12, v1.begin() + header_checksum_offset, saved.bytes.begin() + 12));
  EXPECT_TRUE(
      std::equal(v1.begin() + header_size, v1.end() - 4, saved.bytes.begin() + header_size));
  // The motion section is the layout table_file.hpp documents, field by field.
  const std::size_t m = saved.motion_begin;
  const MotionTable& motion = *saved.stored.motion;
  EXPECT_EQ(get_u64(saved.bytes, m + instances_offset), motion.instances());
  EXPECT_EQ(get_u64(saved.bytes, m + seen_offset), motion.held_out());
  EXPECT_EQ(get_u64(saved.bytes, m + row_count_offset), motion.rows());
  const Bytes section(saved.bytes.begin() + static_cast<std::ptrdiff_t>(m), saved.bytes.end() - 4);
  EXPECT_EQ(section, compact_motion_section(MotionSectionContent::of(motion)));
  // Compact: the rows take a fraction of their fixed width.
  EXPECT_LT(get_u64(saved.bytes, m + rows_length_offset), motion.rows() * row_size / 2);

  // save_table of a StoredTable without motion is the version-1 save.
  StoredTable paper = saved.stored;
  paper.motion.reset();
  ASSERT_TRUE(save_table(dir_ / "paper.bin", paper));
  EXPECT_EQ(read_bytes(dir_ / "paper.bin"), v1);
}

// Tables saved before version 5 load as they were; saved again, they are version 5.
TEST_F(MotionTableFile, OlderVersionsLoadAndAreSavedAsVersionFive) {
  const Saved saved = save_trained();
  MotionTable motion = *saved.stored.motion;
  const Bytes v1 = read_bytes(dir_ / "v1.bin");
  for (const bool kickoffs : {false, true}) {
    if (kickoffs) motion.set_plays().add(made_up_kickoff(0));
    const std::uint32_t version =
        kickoffs ? table_file_set_play_version : table_file_motion_version;
    const Bytes old_bytes = with_motion_section(
        v1, version, fixed_motion_section(MotionSectionContent::of(motion), kickoffs));
    const LoadResult loaded = load_bytes(old_bytes);
    ASSERT_TRUE(loaded) << version << ": " << message_of(loaded);
    EXPECT_EQ(loaded->format_version, version);
    ASSERT_TRUE(loaded->motion != nullptr);
    EXPECT_TRUE(*loaded->motion == motion) << version;
    EXPECT_EQ(entries_of(loaded->table), entries_of(saved.stored.table));

    const fs::path again = dir_ / "again.bin";
    ASSERT_TRUE(save_table(again, *loaded));
    const Bytes new_bytes = read_bytes(again);
    EXPECT_EQ(get_u32(new_bytes, version_offset), table_file_compact_motion_version);
    EXPECT_LT(new_bytes.size(), old_bytes.size());
    const LoadResult reloaded = load_table(again);
    ASSERT_TRUE(reloaded) << message_of(reloaded);
    EXPECT_EQ(reloaded->format_version, table_file_compact_motion_version);
    EXPECT_TRUE(*reloaded->motion == motion) << version;
  }
}

TEST_F(MotionTableFile, VersionOneFilesLoadWithoutMotion) {
  const Saved saved = save_trained();
  const LoadResult v1 = load_table(dir_ / "v1.bin");
  ASSERT_TRUE(v1) << message_of(v1);
  EXPECT_FALSE(v1->motion != nullptr);
  EXPECT_EQ(entries_of(v1->table), entries_of(saved.stored.table));

  // A version-1 file written before motion tables existed.
  const LoadResult golden = load_table(fs::path(SSLF_TEST_DATA_DIR) / "step-golden-6x4.bin");
  ASSERT_TRUE(golden) << message_of(golden);
  EXPECT_FALSE(golden->motion != nullptr);
  EXPECT_GT(golden->table.transitions(), 0u);
}

TEST_F(MotionTableFile, TruncatedMotionSectionIsTruncated) {
  const Saved saved = save_trained();
  const std::size_t size = saved.bytes.size();
  ASSERT_GT(size, saved.motion_begin + 1000);
  std::vector<std::size_t> cuts;
  for (std::size_t n = saved.motion_begin - 8; n < saved.motion_begin + 200; ++n) cuts.push_back(n);
  // Past the section's start, about 300 cuts spread over the rest (the file is large).
  const std::size_t stride = std::max<std::size_t>(53, (size - saved.motion_begin) / 300 | 1);
  for (std::size_t n = saved.motion_begin + 200; n < size; n += stride) cuts.push_back(n);
  for (std::size_t n = size - 8; n < size; ++n) cuts.push_back(n);
  for (const std::size_t n : cuts) {
    const Bytes cut(saved.bytes.begin(), saved.bytes.begin() + static_cast<std::ptrdiff_t>(n));
    const LoadResult result = load_bytes(cut);
    ASSERT_EQ(kind_of(result), TableFileError::truncated)
        << n << " of " << size << " bytes: " << message_of(result);
    EXPECT_NE(message_of(result).find("truncated"), std::string::npos) << message_of(result);
  }
  // Cut inside the counts: the header's size is a lower bound for version 3.
  const Bytes in_counts(saved.bytes.begin(), saved.bytes.begin() + header_size + 10);
  const LoadResult result = load_bytes(in_counts);
  EXPECT_EQ(kind_of(result), TableFileError::truncated) << message_of(result);
  EXPECT_NE(message_of(result).find("at least"), std::string::npos) << message_of(result);
}

TEST_F(MotionTableFile, KickOffsRoundTripExactly) {
  Saved saved = save_trained();
  MotionTable motion = *saved.stored.motion;
  motion.set_plays().add(made_up_kickoff(0));
  motion.set_plays().add(made_up_kickoff(-70));
  ASSERT_EQ(motion.set_plays().episodes().size(), 2u);
  const fs::path path = dir_ / "kickoffs.bin";
  ASSERT_TRUE(save_table(path, saved.stored.table, saved.stored.metadata, motion));
  const Bytes bytes = read_bytes(path);
  EXPECT_EQ(get_u32(bytes, version_offset), table_file_compact_motion_version);
  // The file without kick-offs held their count (0); now 2 x (4 + 40 x 144) bytes more.
  EXPECT_EQ(bytes.size(), saved.bytes.size() + 2 * (4 + 40 * 144));
  const LoadResult loaded = load_table(path);
  ASSERT_TRUE(loaded) << message_of(loaded);
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_TRUE(*loaded->motion == motion);
  EXPECT_EQ(loaded->motion->set_plays(), motion.set_plays());
  const fs::path again = dir_ / "again.bin";
  ASSERT_TRUE(save_table(again, *loaded));
  EXPECT_EQ(read_bytes(again), bytes);

  // Cut anywhere in the kick-offs: truncated; a byte flipped there: corrupt.
  for (std::size_t n = saved.bytes.size() - 8; n < bytes.size(); n += 97) {
    const LoadResult cut =
        load_bytes(Bytes(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n)));
    ASSERT_EQ(kind_of(cut), TableFileError::truncated) << n << ": " << message_of(cut);
  }
  for (std::size_t at = saved.bytes.size() - 4; at < bytes.size() - 4; at += 131) {
    Bytes flipped = bytes;
    flipped[at] ^= 0x10;
    const LoadResult result = load_bytes(flipped);
    ASSERT_FALSE(result) << at;
    EXPECT_NE(kind_of(result), TableFileError::wrong_version) << at;
  }
  // Resealed content that breaks the rules: snapshots out of order.
  Bytes unordered = bytes;
  // The count at the old file's last 8 bytes, then the first kick-off's snapshot count.
  const std::size_t first_snapshot = saved.bytes.size() - 8 + 4 + 4;
  put_u32(unordered, first_snapshot + 144, 5000);  // the second snapshot's offset_ms
  reseal(unordered);
  const LoadResult result = load_bytes(unordered);
  EXPECT_EQ(kind_of(result), TableFileError::corrupt) << message_of(result);
  EXPECT_NE(message_of(result).find("kick-off 0"), std::string::npos) << message_of(result);
}

TEST_F(MotionTableFile, FlippedByteInTheMotionSectionIsDetected) {
  const Saved saved = save_trained();
  const std::size_t m = saved.motion_begin;
  const std::size_t size = saved.bytes.size();
  // The positions of the section's sizes: a flip there may also read as truncated (see
  // table_file.hpp); anywhere else it is corrupt.
  std::vector<std::size_t> sizes;
  for (std::size_t i = 0; i < 4; ++i) sizes.push_back(m + 8 + i);  // horizons
  for (std::size_t i = 0; i < 8; ++i) sizes.push_back(m + rows_length_offset + i);
  const std::size_t calibration_length_at =
      m + rows_offset + get_u64(saved.bytes, m + rows_length_offset);
  for (std::size_t i = 0; i < 8; ++i) sizes.push_back(calibration_length_at + i);
  for (std::size_t i = 0; i < 4; ++i) sizes.push_back(size - 8 + i);  // the kick-off count
  // Every byte of the section's start, then about 300 flips spread over the rest (an odd
  // stride, so they fall on every byte of a field somewhere).
  const std::size_t stride = std::max<std::size_t>(41, (size - m) / 300 | 1);
  for (std::size_t offset = m; offset < size; offset += (offset < m + 200 ? 1 : stride)) {
    for (const std::uint8_t mask : {0x01, 0x80}) {
      Bytes bytes = saved.bytes;
      bytes[offset] ^= mask;
      const LoadResult result = load_bytes(bytes);
      ASSERT_FALSE(result) << "a flip at " << offset << " went unnoticed";
      const bool size_field = std::find(sizes.begin(), sizes.end(), offset) != sizes.end();
      if (!size_field) {
        EXPECT_EQ(kind_of(result), TableFileError::corrupt)
            << "flip at " << offset << ": " << message_of(result);
      } else {
        EXPECT_TRUE(kind_of(result) == TableFileError::corrupt ||
                    kind_of(result) == TableFileError::truncated)
            << message_of(result);
      }
    }
  }
}

TEST_F(MotionTableFile, TrailingBytesAreCorrupt) {
  Saved saved = save_trained();
  Bytes bytes = saved.bytes;
  bytes.insert(bytes.end() - 4, {1, 2, 3, 4});
  reseal(bytes);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::corrupt) << message_of(result);
  EXPECT_NE(message_of(result).find("trailing"), std::string::npos) << message_of(result);
}

TEST_F(MotionTableFile, WrongVersionWithAMotionSection) {
  Saved saved = save_trained();
  Bytes bytes = saved.bytes;
  put_u32(bytes, version_offset, 6);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::wrong_version) << message_of(result);
  EXPECT_NE(message_of(result).find("version 6"), std::string::npos) << message_of(result);
}

// Version 2 had version 3's layout, but its rows were keyed by the earlier features: read as
// version 3 they would load and mean something else.
TEST_F(MotionTableFile, VersionTwoMotionTablesAreRefusedWithTheReason) {
  Saved saved = save_trained();
  Bytes bytes = saved.bytes;
  put_u32(bytes, version_offset, table_file_retired_motion_version);
  reseal(bytes);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::wrong_version) << message_of(result);
  EXPECT_NE(message_of(result).find("version 2"), std::string::npos) << message_of(result);
  EXPECT_NE(message_of(result).find("train it again"), std::string::npos) << message_of(result);
}

TEST_F(MotionTableFile, VersionOneBytesMarkedVersionThreeAreRejected) {
  (void)save_trained();
  Bytes bytes = read_bytes(dir_ / "v1.bin");
  put_u32(bytes, version_offset, table_file_motion_version);
  reseal(bytes);
  const LoadResult result = load_bytes(bytes);
  EXPECT_EQ(kind_of(result), TableFileError::truncated) << message_of(result);
}

// Content a writer could get wrong, planted under valid checksums: always corrupt, with a
// message that says what.
TEST_F(MotionTableFile, InconsistentMotionSectionUnderValidChecksumsIsCorrupt) {
  const Saved saved = save_trained();
  const std::size_t m = saved.motion_begin;
  const MotionTable& motion = *saved.stored.motion;
  ASSERT_GE(motion.rows(), 2u);
  ASSERT_GE(motion.calibration(0).size(), 2u);

  const auto expect_corrupt = [&](Bytes bytes, const std::string& words) {
    reseal(bytes);
    const LoadResult result = load_bytes(bytes);
    EXPECT_EQ(kind_of(result), TableFileError::corrupt) << words << ": " << message_of(result);
    EXPECT_NE(message_of(result).find(words), std::string::npos) << message_of(result);
  };
  {
    Bytes bytes = saved.bytes;  // horizons 0: the section's extent is unknown
    put_u32(bytes, m + 8, 0);
    expect_corrupt(bytes, "invalid motion model configuration");
  }
  {
    Bytes bytes = saved.bytes;
    put_u32(bytes, m + 36, 1);  // calibration_one_in 1
    expect_corrupt(bytes, "invalid motion model configuration");
  }
  {
    Bytes bytes = saved.bytes;
    put_u64(bytes, m + 60, std::bit_cast<std::uint64_t>(-1.0));  // learn_interval_s
    expect_corrupt(bytes, "invalid motion model configuration");
  }
  {
    Bytes bytes = saved.bytes;
    put_u64(bytes, m + 44, std::bit_cast<std::uint64_t>(-1.0));  // settle_window_s
    expect_corrupt(bytes, "invalid motion model configuration");
  }
  {
    Bytes bytes = saved.bytes;
    put_u64(bytes, m, std::bit_cast<std::uint64_t>(0.25));  // the step
    expect_corrupt(bytes, "differs from the header");
  }
  {
    Bytes bytes = saved.bytes;
    put_u64(bytes, m + instances_offset, motion.instances() + 1);
    expect_corrupt(bytes, "instances");
  }
  {
    Bytes bytes = saved.bytes;
    put_u64(bytes, m + seen_offset, 1);
    expect_corrupt(bytes, "held out");
  }
  // The rows and the calibration sample planted as a writer with a bug would encode them.
  const Bytes v1 = read_bytes(dir_ / "v1.bin");
  const MotionSectionContent content = MotionSectionContent::of(motion);
  const auto planted = [&](const MotionSectionContent& c) {
    return with_motion_section(v1, table_file_compact_motion_version, compact_motion_section(c));
  };
  ASSERT_EQ(planted(content), saved.bytes) << "the test's encoder differs from the writer's";
  {
    MotionSectionContent c = content;  // the first two rows swapped
    std::swap(c.rows[0], c.rows[1]);
    expect_corrupt(planted(c), "rows out of order");
  }
  {
    MotionSectionContent c = content;  // two rows of the same key
    c.rows[1].first = c.rows[0].first;
    expect_corrupt(planted(c), "motion row 1: rows out of order");
  }
  {
    MotionSectionContent c = content;  // the first row's key at no level there is
    c.rows[0].first |= MotionKey{0xf} << 52;
    c.rows.resize(1);
    c.row_count = 1;
    c.instances = static_cast<std::uint64_t>(c.rows[0].second.n());
    expect_corrupt(planted(c), "motion row 0: not a motion key");
  }
  {
    MotionSectionContent c = content;  // a zone's key with a robot's slot left in it
    MotionKeyParts parts = decode_motion_key(c.rows.back().first);
    parts.level = MotionLevel::zone;
    parts.robot_slot = 0;
    c.rows.back().first = encode_motion_key(parts) | (MotionKey{1} << 44);
    if (c.rows.back().first <= c.rows[c.rows.size() - 2].first) GTEST_SKIP() << "key order";
    expect_corrupt(planted(c), "not a motion key");
  }
  {
    MotionSectionContent c = content;  // the last row's context beyond every context there is
                                       // (the key grows, so the rows stay in order)
    MotionKeyParts parts = decode_motion_key(c.rows.back().first);
    parts.context = MotionFeatures::context_count;
    c.rows.back().first = encode_motion_key(parts);
    expect_corrupt(planted(c),
                   "motion row " + std::to_string(c.rows.size() - 1) + ": feature out of range");
  }
  {
    MotionSectionContent c = content;  // a row with a count of 0
    c.instances -= static_cast<std::uint64_t>(c.rows[0].second.n());
    c.rows[0].second.sums[0] = 0;
    expect_corrupt(planted(c), "count 0");
  }
  {
    Bytes bytes = saved.bytes;  // more calibration instances than its capacity
    put_u32(bytes, m + 40, 1);
    expect_corrupt(bytes, "capacity");
  }
  {
    MotionSectionContent c = content;  // the first calibration instance's context beyond any
    c.samples[0][0].instance.context = MotionFeatures::context_count;
    expect_corrupt(planted(c), "instance 0: context " +
                                   std::to_string(MotionFeatures::context_count) + " out of range");
  }
  {
    MotionSectionContent c = content;  // the first two calibration instances swapped
    std::swap(c.samples[0][0], c.samples[0][1]);
    if (motion.calibration(0)[0] == motion.calibration(0)[1]) GTEST_SKIP() << "equal instances";
    expect_corrupt(planted(c), "out of order");
  }
  {
    MotionSectionContent c = content;  // more rows stated than there are: the bytes run out
    c.row_count += 1000;
    expect_corrupt(planted(c), "motion row " + std::to_string(motion.rows()) + ": cut off");
  }
  {
    MotionSectionContent c = content;  // fewer rows stated than there are
    c.row_count -= 1;
    expect_corrupt(planted(c), "bytes after the last motion row");
  }
  {
    Bytes bytes = saved.bytes;  // a rows' length that runs past the end of the file
    put_u64(bytes, m + rows_length_offset, get_u64(bytes, m + rows_length_offset) + 100000);
    expect_corrupt(bytes, "past the end");
  }
  {
    Bytes bytes = saved.bytes;  // a rows' length short of the rows
    put_u64(bytes, m + rows_length_offset, get_u64(bytes, m + rows_length_offset) - 1);
    reseal(bytes);
    const LoadResult result = load_bytes(bytes);
    EXPECT_EQ(kind_of(result), TableFileError::corrupt) << message_of(result);
  }
}

TEST_F(MotionTableFile, SaveRefusesAMotionTableOfAnotherStep) {
  MotionConfig config;
  config.step_s = 1.0;
  TableMetadata metadata;
  metadata.step_s = 2.0;
  const fs::path path = dir_ / "table.bin";
  const auto saved = save_table(path, TransitionTable(Grid(3, 2)), metadata, MotionTable(config));
  ASSERT_FALSE(saved);
  EXPECT_NE(saved.error().message.find("step"), std::string::npos) << saved.error().message;
  EXPECT_FALSE(fs::exists(path));
}

// Tables add up: two tables trained from two streams, saved, loaded and merged, equal the table
// trained on both streams in one Training, bit for bit, calibration samples included (their
// capacity is full, so the merge has to keep exactly the instances one training keeps).
TEST_F(MotionTableFile, MergedFilesEqualTrainingOnBothStreams) {
  const MotionConfig config = small_calibration_config(0.5);
  const auto a = circling_stream(10.0, 20.0, 1);
  const auto b = circling_stream(300.0, 25.0, 2);
  const auto trained_a = train({a}, config);
  const auto trained_b = train({b}, config);
  const auto together = train({a, b}, config);
  ASSERT_GT(trained_a->stored_table().motion->instances(), 0u);
  ASSERT_GT(trained_b->stored_table().motion->instances(), 0u);
  ASSERT_GT(together->stored_table().motion->held_out(), 3u * config.calibration_capacity);

  const auto save = [&](const Training& training, const fs::path& path) {
    TableMetadata metadata;
    metadata.step_s = config.step_s;
    metadata.samples = training.samples();
    ASSERT_TRUE(
        save_table(path, training.stored_table().table, metadata, *training.stored_table().motion));
  };
  save(*trained_a, dir_ / "a.bin");
  save(*trained_b, dir_ / "b.bin");
  LoadResult merged = load_table(dir_ / "a.bin");
  const LoadResult other = load_table(dir_ / "b.bin");
  ASSERT_TRUE(merged && other);
  merged->table.merge(other->table);
  auto motion_sum = std::make_shared<MotionTable>(*merged->motion);
  motion_sum->merge(*other->motion);
  merged->motion = motion_sum;

  EXPECT_EQ(entries_of(merged->table), entries_of(together->stored_table().table));
  EXPECT_TRUE(*merged->motion == *together->stored_table().motion);
  EXPECT_EQ(merged->motion->instances(), together->stored_table().motion->instances());
  EXPECT_EQ(merged->motion->held_out(), together->stored_table().motion->held_out());
  for (int h = 0; h < config.horizons; ++h) {
    EXPECT_EQ(merged->motion->calibration(h), together->stored_table().motion->calibration(h)) << h;
  }
}

}  // namespace
}  // namespace ssl_formation
