// The bytes save_table writes, held to what the code wrote when each format version was made
// (version 1 before table_file.cpp was split by concern, version 5 when it was introduced), and
// the bytes of version 3, which is no longer written but must still load. A table file written
// today must load in every build after it, so any change here is a change of format and needs a
// new version.
//
// The tables are made from explicit counts, rows and held-out instances, never by training, so
// that only the file format decides the bytes.

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/motion_model/motion_model.hpp"
#include "table_bytes.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using namespace ssl_formation::testing;

Bytes bytes_of_hex(const std::string& hex) {
  Bytes out;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
    out.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  }
  return out;
}

std::string hex_of(const Bytes& bytes) {
  std::string out;
  char digits[3];
  for (const std::uint8_t byte : bytes) {
    std::snprintf(digits, sizeof digits, "%02x", byte);
    out += digits;
  }
  return out;
}

// Deterministic pseudo-random numbers, so the tables are the same in every build.
class Lcg {
 public:
  explicit Lcg(std::uint64_t seed) : x_(seed) {}
  std::uint32_t next() {
    x_ = x_ * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::uint32_t>(x_ >> 33);
  }

 private:
  std::uint64_t x_;
};

TableMetadata metadata_of(double step_s) {
  TableMetadata metadata;
  metadata.field = FieldSize{12000.0, 9000.0};
  metadata.step_s = step_s;
  metadata.samples = 4242;
  return metadata;
}

// A tiny table: grid 2x1 (8 states), a handful of counts including the largest.
TransitionTable tiny_table(TableStorage storage) {
  TransitionTable table(Grid(2, 1), storage);
  table.add(0, 0, 1);
  table.add(0, 5, 7);
  table.add(3, 1, 2);
  table.add(3, 2, 300);
  table.add(7, 7, TransitionTable::max_count);
  return table;
}

// A larger table: `transitions` pseudo-random counts over few FROM rows.
TransitionTable larger_table(Grid grid, TableStorage storage, int transitions) {
  TransitionTable table(grid, storage);
  const StateIndex states = table.codec().state_count();
  Lcg random(12345);
  for (int i = 0; i < transitions; ++i) {
    const StateIndex from = random.next() % 64 * (states / 64);
    const StateIndex to = random.next() % states;
    table.add(from, to, 1 + random.next() % 5);
  }
  table.add(states - 1, states - 1, TransitionTable::max_count);
  return table;
}

// A motion table of `rows` rows and `held` held-out instances per horizon, from explicit sums
// and values (negative ones included), with more held-out instances seen than kept.
MotionTable motion_table(double step_s, int horizons, int rows, int held) {
  MotionConfig config;
  config.step_s = step_s;
  config.horizons = horizons;
  config.calibration_one_in = 3;
  config.calibration_capacity = 64;
  MotionTable table(config);
  Lcg random(777);
  const auto signed_value = [&random](std::int64_t range) {
    return static_cast<std::int64_t>(random.next() % (2 * range + 1)) - range;
  };
  for (int i = 0; i < rows; ++i) {
    MotionKeyParts parts;
    parts.horizon_index = i % horizons;
    parts.level = MotionLevel::robot;
    parts.robot_slot = static_cast<int>(random.next() % MotionFeatures::robot_slots);
    parts.cell = static_cast<int>(random.next() % MotionFeatures::cell_count);
    parts.velocity_class = static_cast<int>(random.next() % MotionFeatures::velocity_classes);
    // Running play's contexts: the bytes were fixed before the game's states came in.
    parts.context = random.next() % MotionFeatures::robot_contexts;
    MotionRow row;
    for (std::int64_t& sum : row.sums) sum = signed_value(5'000'000'000LL);
    row.sums[0] = 1 + random.next() % 20;                   // n
    row.sums[3 + 2 * MotionRow::r] = random.next() % 9999;  // dd
    for (int k = 0; k < MotionRow::r; ++k) {
      // xx(k, k), at the place MotionRow::xx reads it (save_table refuses a negative one).
      row.sums[4 + 3 * MotionRow::r + (k * MotionRow::r - k * (k - 1) / 2)] = random.next() % 99999;
    }
    table.add_row(encode_motion_key(parts), row);
  }
  for (int h = 0; h < horizons; ++h) {
    for (int i = 0; i < held; ++i) {
      HeldOutInstance instance;
      const std::uint64_t high = random.next();  // one statement each: the order is fixed
      instance.hash = high << 32 | random.next();
      instance.instance.robot_id = random.next() % 20;
      for (const auto value : motion_instance_values) {
        instance.instance.*value = static_cast<std::int32_t>(signed_value(9000));
      }
      instance.instance.context = random.next() % MotionFeatures::robot_contexts;
      table.add_held_out(h, instance);
    }
  }
  table.restore_held_out_seen(table.held_out() + 5);
  return table;
}

class TableFileBytes : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("sslf-table-bytes-" + std::to_string(::getpid()) + "-" +
                                        info->name() + "-" + std::to_string(counter++));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directory(dir_));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // The bytes of `stored` as save_table writes them; checks that they load back.
  Bytes saved_bytes(const StoredTable& stored) {
    const fs::path path = dir_ / "table.bin";
    const auto saved = save_table(path, stored);
    EXPECT_TRUE(saved) << message_of(saved);
    const LoadResult loaded = load_table(path);
    EXPECT_TRUE(loaded) << message_of(loaded);
    return read_bytes(path);
  }

  fs::path dir_;
};

// A file too long to spell out: its size, the CRC-32 of every byte before its file checksum,
// and the file checksum as stored. (A CRC-32 over the whole file would not do: over data followed
// by its own CRC it is the same constant for every file.)
struct Fingerprint {
  std::size_t size = 0;
  std::uint32_t content_crc = 0;
  std::uint32_t stored_crc = 0;
  friend bool operator==(const Fingerprint&, const Fingerprint&) = default;
  friend std::ostream& operator<<(std::ostream& out, const Fingerprint& f) {
    char hex[32];
    std::snprintf(hex, sizeof hex, "0x%08x, 0x%08x", f.content_crc, f.stored_crc);
    return out << "{" << f.size << ", " << hex << "}";
  }
};
Fingerprint fingerprint_of(const Bytes& bytes) {
  if (bytes.size() < 4) return {bytes.size(), 0, 0};
  return {bytes.size(), crc(bytes, bytes.size() - 4), get_u32(bytes, bytes.size() - 4)};
}

TEST_F(TableFileBytes, DenseCountsAreTheBytesTheyWere) {
  const Bytes bytes =
      saved_bytes(StoredTable{tiny_table(TableStorage::dense), metadata_of(0.5), nullptr});
  EXPECT_EQ(hex_of(bytes),
            "53534c465441424c01000000020000000100000000000000000000000070c740000000000094c140"
            "000000000000e03f9210000000000000350100000100000008000000000000004000000000000000"
            "e6a01e54010000000000000000000000000000000000000007000000000000000000000000000000"
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000"
            "000000000000000000000000000000000000000000000000020000002c0100000000000000000000"
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000"
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000"
            "00000000000000000000000000000000000000000000000000000000000000000000000000000000"
            "00000000000000000000000000000000ffffffffa841c5d5");
}

TEST_F(TableFileBytes, SparseCountsAreTheBytesTheyWere) {
  const Bytes bytes =
      saved_bytes(StoredTable{tiny_table(TableStorage::sparse), metadata_of(0.5), nullptr});
  EXPECT_EQ(hex_of(bytes),
            "53534c465441424c01000000020000000100000001000000000000000070c740000000000094c140"
            "000000000000e03f9210000000000000350100000100000003000000000000000500000000000000"
            "5dc96ba5000000000200000000000000010000000500000007000000030000000200000001000000"
            "02000000020000002c010000070000000100000007000000ffffffff5923cf76");
}

// Version 5, written since 2026-12-07: the compact rows and calibration instances.
TEST_F(TableFileBytes, MotionRowsAreTheBytesTheyWere) {
  const Bytes bytes =
      saved_bytes(StoredTable{tiny_table(TableStorage::sparse), metadata_of(0.5),
                              std::make_shared<const MotionTable>(motion_table(0.5, 2, 2, 1))});
  EXPECT_EQ(hex_of(bytes),
            "53534c465441424c05000000020000000100000001000000000000000070c740000000000094c140"
            "000000000000e03f9210000000000000350100000100000003000000000000000500000000000000"
            "ce8dd570000000000200000000000000010000000500000007000000030000000200000001000000"
            "02000000020000002c010000070000000100000007000000ffffffff000000000000e03f02000000"
            "9a9999999999b93f9a9999999999a93f000000000000f03f0300000040000000000000000000e03f"
            "00000000000000409a9999999999b93f1d0000000000000007000000000000000200000000000000"
            "42010000000000008a8080f8c09a0c22e5f8e8c31ac7a59bfb24f1c2bae61bc5e6a19218e5fd8efa"
            "1a999aa9fd2483affbf916c3bbecb422e9fddeec17b3dd9ca919e7fed7f420afb282ce1bea3589fe"
            "83841cb1c9b8e11ed3c0b88d1f9be0f2ef17f986c0ed1682f70791a8dbe71983bab5e518cb8c9ce6"
            "20938afbc11fe0b30abbb5f5f0169dc2d2d51a8d84d5ac22caa2079f9cb6d0208bea998a22eccf08"
            "a7c7a5891ad2b4098d8080d0ffa9ac8001189de1d4fb20fdcbb0e81cabffe4961df3ce99ff1cdfcc"
            "cbe81dbdbe95c422818ed9811989b6fc8e248de4b8f815ed8e868e17b9c3b3a11bddbea1ff22fc92"
            "01cb96f8cd1eb5e281cb22c5a7beeb21d9dce2a721c5f9b6ef1e849a0be3ccf59225f5b2d9f7248f"
            "ff82e819819c87bf19d2c501a9feedef218f93fc9f1fa5bd9ede18f8d0019dbe97841acfb0d59e1e"
            "9a559da2e59e19a4d001530000000000000001b49d437d5fb797380c8523955b9a8001c607c21fd9"
            "29d457d16a9e47c46f9b2de08801a52eb483011401bca4d2331c50774003963cd96a8f59a881019b"
            "3eb947ff4d8d59cd6d91688362fa50d58901fb6309000000009c762049");
}

// Version 3, written until 2026-12-07 and still read: the same table as fixed-width rows.
TEST_F(TableFileBytes, VersionThreeBytesStillLoad) {
  const Bytes version_three = bytes_of_hex(
      "53534c465441424c03000000020000000100000001000000000000000070c740000000000094c140"
      "000000000000e03f9210000000000000350100000100000003000000000000000500000000000000"
      "34680c22000000000200000000000000010000000500000007000000030000000200000001000000"
      "02000000020000002c010000070000000100000007000000ffffffff000000000000e03f02000000"
      "9a9999999999b93f9a9999999999a93f000000000000f03f0300000040000000000000000000e03f"
      "00000000000000409a9999999999b93f1d0000000000000007000000000000000200000000000000"
      "0a00000fd43000001100000000000000cde1c22bffffffff9c964cd8feffffff47af9821ffffffff"
      "5dc6db3effffffff8d205e28ffffffff73d92ad8feffffff3e946048ffffffff1e71b2ecfeffffff"
      "8b203441ffffffffa6686c35ffffffff4c00b5f8feffffff68b31f23ffffffff750d000000000000"
      "7b80bf1fffffffffa7ede809ffffffffd6ef2807fffffffff2a70141ffffffff43fe2749ffffffff"
      "c1fd000000000000f7958431ffffffff7e51a939ffffffffda7c9cf9feffffff769de003ffffffff"
      "f04c010000000000a252f148ffffffff71afa52afffffffff95e35edfeffffffa5e8000000000000"
      "f038f9fafeffffff7ac55ceffefffffff6130100000000002c4e6b2fffffffff292d010000000000"
      "1700000924e200010c00000000000000b16745f8feffffff01ed7919ffffffff2a609316ffffffff"
      "46cc0c18ffffffffd08c7611ffffffff6150bdebfeffffff7fdce437ffffffff7b7210dffeffffff"
      "f9e67850ffffffff493c1f47ffffffff238fe925ffffffff51d00be8feffffffbe24000000000000"
      "5afa200bffffffff65c74febfeffffff1d3648f1feffffffd3a883f5feffffff9d210909ffffffff"
      "8266010000000000ce4cd1d6feffffff45d384d8feffffff38a07f31ffffffffff180f34ffffffff"
      "69310000000000006b4002f1feffffff387b0006ffffffffad301c3affffffff3c34000000000000"
      "7110bd2fffffffffd853150effffffff4d1500000000000071571336ffffffff1234000000000000"
      "01000000b49d437d5fb797380c0000003df7ffff35e9ffff0d200000e3010000e107000093f5ffff"
      "ea15000057e5ffffcf110000e21b0000b2f4ffff302200006df4ffffda2000001400000001000000"
      "bca4d2331c507740030000000b0f000053e5ffffb8e9ffff5420000072f0ffff23eeffff80ecffff"
      "b9e9ffff99e4fffff7e5ffff7ee7ffff3d14000095ddffff02e7ffff09000000f736c75f");
  const fs::path path = dir_ / "version3.bin";
  write_bytes(path, version_three);
  const LoadResult loaded = load_table(path, std::nullopt, TableStorage::sparse);
  ASSERT_TRUE(loaded) << message_of(loaded);
  EXPECT_EQ(loaded->format_version, table_file_motion_version);
  ASSERT_TRUE(loaded->motion != nullptr);
  EXPECT_TRUE(*loaded->motion == motion_table(0.5, 2, 2, 1));
  EXPECT_EQ(
      saved_bytes(*loaded),
      saved_bytes(StoredTable{tiny_table(TableStorage::sparse), metadata_of(0.5),
                              std::make_shared<const MotionTable>(motion_table(0.5, 2, 2, 1))}));
}

TEST_F(TableFileBytes, LargerTablesAreTheBytesTheyWere) {
  const StoredTable dense{larger_table(Grid(3, 2), TableStorage::automatic, 500), metadata_of(2.0)};
  ASSERT_TRUE(dense.table.is_dense());
  EXPECT_EQ(fingerprint_of(saved_bytes(dense)), (Fingerprint{186712, 0x50d61bb1, 0x50d61bb1}));

  const StoredTable sparse{larger_table(Grid(12, 9), TableStorage::automatic, 3000),
                           metadata_of(2.0)};
  ASSERT_FALSE(sparse.table.is_dense());
  EXPECT_EQ(fingerprint_of(saved_bytes(sparse)), (Fingerprint{24616, 0xea90437c, 0xea90437c}));

  const StoredTable sparse_motion{
      larger_table(Grid(6, 4), TableStorage::automatic, 2000), metadata_of(1.0),
      std::make_shared<const MotionTable>(motion_table(1.0, 3, 300, 40))};
  ASSERT_FALSE(sparse_motion.table.is_dense());
  EXPECT_EQ(fingerprint_of(saved_bytes(sparse_motion)),
            (Fingerprint{69046, 0x3e48a2be, 0x3e48a2be}));

  // Every horizon a file can hold.
  const StoredTable dense_motion{
      larger_table(Grid(3, 2), TableStorage::dense, 500), metadata_of(1.0),
      std::make_shared<const MotionTable>(motion_table(1.0, MotionConfig::max_horizons, 100, 3))};
  EXPECT_EQ(fingerprint_of(saved_bytes(dense_motion)),
            (Fingerprint{204692, 0x2f0dd7f0, 0x2f0dd7f0}));
}

}  // namespace
}  // namespace ssl_formation
