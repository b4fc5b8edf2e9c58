// The fuzz targets' code paths (tests/fuzz/fuzz_paths.hpp) in the normal build: every seed of
// the committed corpus and every input a fuzzer ever crashed on (tests/fuzz/regressions/) runs
// through the same code and invariants as under libFuzzer, so the corpus stays valid input and
// a fixed finding stays fixed.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

#include "../fuzz/fuzz_paths.hpp"

namespace ssl_formation {
namespace {

namespace fs = std::filesystem;

const fs::path fuzz_dir = fs::path(SSLF_TEST_DATA_DIR).parent_path() / "fuzz";
const fs::path corpus_dir = fuzz_dir / "corpus";
const fs::path regressions_dir = fuzz_dir / "regressions";

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string contents(const fs::path& path) { return fuzz::read_bytes(path); }
const std::uint8_t* bytes(const std::string& s) {
  return reinterpret_cast<const std::uint8_t*>(s.data());
}

// A fresh scratch folder per test for the files the readers need.
class FuzzPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("sslf-fuzz-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directories(dir_));
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(FuzzPaths, SamplerSeedsRunCleanAndProduceFormations) {
  const auto files = files_in(corpus_dir / "sampler");
  ASSERT_GE(files.size(), 5u) << corpus_dir;
  std::uint64_t samples = 0;
  std::uint64_t transitions = 0;
  for (const fs::path& file : files) {
    const std::string input = contents(file);
    const fuzz::SamplerOutcome out = fuzz::run_sampler_path(bytes(input), input.size());
    EXPECT_EQ(out.violation, "") << file;
    EXPECT_GT(out.packets, 0u) << file;
    samples += out.samples;
    transitions += out.transitions;
  }
  // The seeds reach the table and the predictor, not just the parser.
  EXPECT_GT(samples, 10u);
  EXPECT_GT(transitions, 10u);
}

TEST_F(FuzzPaths, SamplerStreamFromGrsimSamplesElevenRobots) {
  const std::string input = contents(corpus_dir / "sampler" / "grsim-stream-12x9-0.1s");
  const fuzz::SamplerOutcome out = fuzz::run_sampler_path(bytes(input), input.size());
  EXPECT_EQ(out.violation, "");
  EXPECT_EQ(out.undecodable, 0u);
  EXPECT_GE(out.samples, 3u);
  EXPECT_GT(out.transitions, 0u);
}

TEST_F(FuzzPaths, LogSeedsRunClean) {
  const auto files = files_in(corpus_dir / "log");
  ASSERT_GE(files.size(), 4u) << corpus_dir;
  for (const fs::path& file : files) {
    const std::string input = contents(file);
    const fuzz::LogOutcome out = fuzz::run_log_path(bytes(input), input.size(), dir_);
    EXPECT_EQ(out.violation, "") << file;
    EXPECT_TRUE(out.opened) << file << ": " << out.error;
    if (file.filename() == "truncated.log") {
      EXPECT_NE(out.error.find("truncated message"), std::string::npos) << out.error;
    } else {
      EXPECT_EQ(out.error, "") << file;
    }
  }
}

TEST_F(FuzzPaths, LogSeedsCoverEveryMessageKind) {
  for (const char* name : {"mixed.log", "mixed.log.gz", "mixed-indexed.log"}) {
    const std::string input = contents(corpus_dir / "log" / name);
    const fuzz::LogOutcome out = fuzz::run_log_path(bytes(input), input.size(), dir_);
    EXPECT_EQ(out.violation, "") << name;
    EXPECT_GT(out.vision_packets, 4u) << name;
    EXPECT_EQ(out.counters.parse_errors, 1u) << name;
    EXPECT_EQ(out.counters.legacy_unusable, 1u) << name;
    EXPECT_EQ(out.counters.legacy_vision, 2u) << name;
    EXPECT_EQ(out.counters.referee, 1u) << name;
    EXPECT_EQ(out.counters.blank, 1u) << name;
    EXPECT_EQ(out.counters.tracker, 1u) << name;
    EXPECT_EQ(out.counters.unknown, 1u) << name;
    EXPECT_EQ(out.counters.index, std::string(name) == "mixed-indexed.log" ? 1u : 0u) << name;
  }
}

TEST_F(FuzzPaths, TableSeedsLoadAndRoundTrip) {
  const auto files = files_in(corpus_dir / "table");
  ASSERT_GE(files.size(), 5u) << corpus_dir;
  for (const fs::path& file : files) {
    const std::string input = contents(file);
    const fuzz::TableOutcome out = fuzz::run_table_path(bytes(input), input.size(), dir_);
    EXPECT_EQ(out.violation, "") << file;
    EXPECT_FALSE(out.error.has_value()) << file << ": " << to_string(*out.error);
    EXPECT_FALSE(out.fixed_tried) << file << ": its checksums were not right";
  }
}

// A changed count is refused by the file checksum as given; with the checksums fixed (what the
// fuzz target tries next, to reach the counts) by the header's total, which no longer matches.
TEST_F(FuzzPaths, TableWithAChangedCountIsRefusedWithOrWithoutItsChecksums) {
  std::string input = contents(corpus_dir / "table" / "sparse-3x2.sslft");
  ASSERT_GT(input.size(), 100u);
  // 84-byte header, then the first row record: u32 from, u32 n, then (u32 to, u32 count) pairs.
  input[96] = static_cast<char>(input[96] + 1);
  const fuzz::TableOutcome out = fuzz::run_table_path(bytes(input), input.size(), dir_);
  EXPECT_EQ(out.violation, "");
  EXPECT_EQ(out.error, TableFileError::corrupt);
  EXPECT_TRUE(out.fixed_tried);
  EXPECT_EQ(out.fixed_error, TableFileError::corrupt);
}

// Every input a fuzzer crashed on, through the path of its folder: handled, no broken
// invariant. The specific errors are asserted by the named tests below.
TEST_F(FuzzPaths, EveryRecordedFindingIsHandled) {
  for (const fs::path& file : files_in(regressions_dir / "sampler")) {
    const std::string input = contents(file);
    EXPECT_EQ(fuzz::run_sampler_path(bytes(input), input.size()).violation, "") << file;
  }
  for (const fs::path& file : files_in(regressions_dir / "log")) {
    const std::string input = contents(file);
    EXPECT_EQ(fuzz::run_log_path(bytes(input), input.size(), dir_).violation, "") << file;
  }
  for (const fs::path& file : files_in(regressions_dir / "table")) {
    const std::string input = contents(file);
    EXPECT_EQ(fuzz::run_table_path(bytes(input), input.size(), dir_).violation, "") << file;
  }
  for (const fs::path& file : files_in(regressions_dir / "referee")) {
    const std::string input = contents(file);
    EXPECT_EQ(fuzz::run_referee_path(bytes(input), input.size()).violation, "") << file;
  }
  for (const fs::path& file : files_in(regressions_dir / "tracker")) {
    const std::string input = contents(file);
    EXPECT_EQ(fuzz::run_tracker_path(bytes(input), input.size()).violation, "") << file;
  }
}

// The referee and tracker targets' seeds: valid input that the followers use.
TEST_F(FuzzPaths, RefereeAndTrackerSeedsRunClean) {
  const auto referee_files = files_in(corpus_dir / "referee");
  ASSERT_GE(referee_files.size(), 5u);
  std::uint64_t used = 0;
  for (const fs::path& file : referee_files) {
    const std::string input = contents(file);
    const fuzz::RefereeOutcome out = fuzz::run_referee_path(bytes(input), input.size());
    EXPECT_EQ(out.violation, "") << file;
    used += out.counters.used;
  }
  EXPECT_GT(used, 10u);
  const auto tracker_files = files_in(corpus_dir / "tracker");
  ASSERT_GE(tracker_files.size(), 5u);
  std::uint64_t frames = 0;
  for (const fs::path& file : tracker_files) {
    const std::string input = contents(file);
    const fuzz::TrackerOutcome out = fuzz::run_tracker_path(bytes(input), input.size());
    EXPECT_EQ(out.violation, "") << file;
    frames += out.counters.frames;
  }
  EXPECT_GT(frames, 10u);
}

}  // namespace
}  // namespace ssl_formation
