#include "ssl_formation/files/compressed_input.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <thread>
#include <vector>

#include "fed_pipe.hpp"
#include "gzip_member.hpp"
#include "scratch_dir.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;
using testing::gzip_member;

// The inflaters this build can be asked for by name.
std::vector<Inflater> named_inflaters() {
  if (isal_available()) return {Inflater::zlib, Inflater::isal};
  return {Inflater::zlib};
}

const char* name_of(Inflater inflater) {
  switch (inflater) {
    case Inflater::automatic:
      return "automatic";
    case Inflater::zlib:
      return "zlib";
    case Inflater::isal:
      return "isal";
  }
  return "?";
}

// Bytes that compress a little but not to nothing, so inflating them takes several reads.
std::string sample_bytes(std::size_t size, unsigned seed) {
  std::string out(size, '\0');
  std::uint32_t x = seed;
  for (std::size_t i = 0; i < size; ++i) {
    x = x * 1103515245u + 12345u;
    out[i] = static_cast<char>(i % 7 == 0 ? (x >> 24) : 'a' + (i / 100) % 26);
  }
  return out;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good());
}

struct ReadBack {
  std::string bytes;
  CompressedInput::Fault fault = CompressedInput::Fault::none;
  std::string fault_message;
  Inflater inflater = Inflater::automatic;
  std::uint64_t compressed_offset = 0;
  std::uint64_t compressed_size = 0;
};

// Everything `path` gives, read in pieces of `piece` bytes.
ReadBack read_back(const fs::path& path, Inflater inflater, std::size_t piece = 100'000) {
  ReadBack out;
  Result<CompressedInput> input = CompressedInput::open(path, inflater);
  EXPECT_TRUE(input) << input.error().message;
  if (!input) return out;
  std::vector<char> buffer(piece);
  while (const std::size_t got = input->read(buffer.data(), buffer.size())) {
    out.bytes.append(buffer.data(), got);
  }
  EXPECT_EQ(input->read(buffer.data(), buffer.size()), 0u) << "stays at the end";
  out.fault = input->fault();
  out.fault_message = input->fault_message();
  out.inflater = input->inflater();
  out.compressed_offset = input->compressed_offset();
  out.compressed_size = input->compressed_size();
  return out;
}

class CompressedInputTest : public ::testing::Test {
 protected:
  fs::path path(const std::string& name) const { return dir_.path() / name; }
  testing::ScratchDir dir_{"sslf-compressed-input-test"};
};

TEST_F(CompressedInputTest, EveryKindOfFileGivesItsUncompressedBytes) {
  const std::string first = sample_bytes(700'000, 1);
  const std::string second = sample_bytes(300'000, 2);
  struct Case {
    const char* name;
    std::string on_disk;
    std::string expected;
    bool gzip;
  };
  const std::vector<Case> cases = {
      {"plain", first, first, false},
      {"one member", gzip_member(first), first, true},
      {"stored, not compressed", gzip_member(first, 0), first, true},
      {"best compression, named in the header", gzip_member(first, 9, "match.log"), first, true},
      // `cat a.gz b.gz`: zlib reads the members one after the other, ignoring what follows the
      // last one (here the zeros some tools pad a file with).
      {"two members and padding", gzip_member(first) + gzip_member(second) + std::string(7, '\0'),
       first + second, true},
      {"an empty member between two", gzip_member(first) + gzip_member("") + gzip_member(second),
       first + second, true},
  };
  for (const Case& c : cases) {
    const fs::path file = path("input.bin");
    write_bytes(file, c.on_disk);
    for (const Inflater inflater : named_inflaters()) {
      SCOPED_TRACE(std::string(c.name) + ", " + name_of(inflater));
      const ReadBack got = read_back(file, inflater);
      EXPECT_TRUE(got.bytes == c.expected) << got.bytes.size() << " bytes of " << c.expected.size();
      EXPECT_EQ(got.fault, CompressedInput::Fault::none) << got.fault_message;
      EXPECT_EQ(got.fault_message, "");
      EXPECT_EQ(got.inflater, c.gzip ? inflater : Inflater::zlib);
      EXPECT_EQ(got.compressed_size, c.on_disk.size());
      EXPECT_EQ(got.compressed_offset, c.on_disk.size());
    }
  }
}

TEST_F(CompressedInputTest, SmallReadsGiveTheSameBytes) {
  const std::string data = sample_bytes(200'000, 3);
  const fs::path file = path("small-reads.gz");
  write_bytes(file, gzip_member(data.substr(0, 77'777)) + gzip_member(data.substr(77'777)));
  for (const Inflater inflater : named_inflaters()) {
    SCOPED_TRACE(name_of(inflater));
    for (const std::size_t piece : {1u, 7u, 4096u}) {
      EXPECT_TRUE(read_back(file, inflater, piece).bytes == data) << "pieces of " << piece;
    }
  }
}

TEST_F(CompressedInputTest, AutomaticTakesIsalForGzipFilesAndZlibForTheRest) {
  const fs::path gzip = path("a.gz");
  const fs::path plain = path("a.log");
  write_bytes(gzip, gzip_member("gzip"));
  write_bytes(plain, "plain");
  EXPECT_EQ(CompressedInput::open(gzip).value().inflater(),
            isal_available() ? Inflater::isal : Inflater::zlib);
  EXPECT_EQ(CompressedInput::open(plain).value().inflater(), Inflater::zlib);
  EXPECT_EQ(CompressedInput::open(gzip, Inflater::zlib).value().inflater(), Inflater::zlib);
}

// A pipe cannot be peeked at, so zlib reads it whatever was asked for; nothing is lost.
TEST_F(CompressedInputTest, APipeGoesThroughZlib) {
  const std::string data = sample_bytes(300'000, 4);
  const std::string bytes = gzip_member(data);
  for (const Inflater inflater : named_inflaters()) {
    SCOPED_TRACE(name_of(inflater));
    ReadBack got;
    {
      const testing::FedPipe pipe(bytes);
      got = read_back(pipe.path(), inflater);
    }
    EXPECT_EQ(got.inflater, Inflater::zlib);
    EXPECT_TRUE(got.bytes == data) << got.bytes.size() << " bytes";
    EXPECT_EQ(got.compressed_size, 0u) << "a pipe has no size";
  }
}

TEST_F(CompressedInputTest, ACutOffStreamIsCutOffAfterEverythingBeforeTheCut) {
  const std::string data = sample_bytes(500'000, 5);
  const std::string whole =
      gzip_member(data.substr(0, 200'000)) + gzip_member(data.substr(200'000));
  const std::size_t first_member = gzip_member(data.substr(0, 200'000)).size();
  // In the first header, the first deflate data, the first trailer, the second member's header,
  // the middle of the second member, and one byte short of the end.
  for (const std::size_t cut : {std::size_t{5}, std::size_t{40}, first_member - 3, first_member + 4,
                                whole.size() / 2, whole.size() - 1}) {
    const fs::path file = path("cut.gz");
    write_bytes(file, whole.substr(0, cut));
    std::string by_zlib;
    for (const Inflater inflater : named_inflaters()) {
      SCOPED_TRACE(std::string(name_of(inflater)) + ", cut at " + std::to_string(cut));
      const ReadBack got = read_back(file, inflater);
      EXPECT_EQ(got.fault, CompressedInput::Fault::cut_off) << got.fault_message;
      EXPECT_EQ(got.fault_message, "");
      ASSERT_LE(got.bytes.size(), data.size());
      EXPECT_TRUE(data.compare(0, got.bytes.size(), got.bytes) == 0) << "a prefix of the data";
      if (inflater == Inflater::zlib) {
        by_zlib = got.bytes;
      } else {
        EXPECT_EQ(got.bytes.size(), by_zlib.size()) << "as much as zlib gives";
      }
    }
  }
}

TEST_F(CompressedInputTest, CorruptDataIsDamagedAndNamed) {
  const std::string data = sample_bytes(400'000, 6);
  const std::string member = gzip_member(data);
  struct Case {
    const char* name;
    std::size_t at;
    unsigned char flip;
  };
  // The trailer holds the CRC-32 of the data, then its length; flipping a bit in the middle of
  // the deflate data may still decode, to other bytes, so the CRC-32 is what catches it.
  for (const Case& c :
       {Case{"deflate data", member.size() / 2, 0x10}, Case{"CRC-32", member.size() - 8, 0x01},
        Case{"length", member.size() - 4, 0x01}}) {
    std::string bytes = member;
    bytes[c.at] = static_cast<char>(bytes[c.at] ^ c.flip);
    const fs::path file = path("corrupt.gz");
    write_bytes(file, bytes);
    for (const Inflater inflater : named_inflaters()) {
      SCOPED_TRACE(std::string(c.name) + ", " + name_of(inflater));
      const ReadBack got = read_back(file, inflater);
      EXPECT_EQ(got.fault, CompressedInput::Fault::damaged);
      EXPECT_NE(got.fault_message, "");
    }
  }
}

TEST_F(CompressedInputTest, MissingFileNamesThePathAndTheCause) {
  for (const Inflater inflater : named_inflaters()) {
    const auto opened = CompressedInput::open(path("nope.gz"), inflater);
    ASSERT_FALSE(opened);
    EXPECT_EQ(opened.error().message,
              path("nope.gz").string() + ": cannot open: No such file or directory");
  }
}

TEST_F(CompressedInputTest, IsalIsRefusedByABuildWithoutIt) {
  if (isal_available()) GTEST_SKIP() << "this build has ISA-L";
  const fs::path file = path("a.gz");
  write_bytes(file, gzip_member("gzip"));
  const auto opened = CompressedInput::open(file, Inflater::isal);
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error().message.find("ISA-L"), std::string::npos) << opened.error().message;
}

}  // namespace
}  // namespace ssl_formation
