// A log written by ssl-producer --output (--write-log) or ssl-record replaces the file at its path
// only when the run succeeds: a run whose writes fail partway (here the disk "fills": the process
// may write no file beyond 64 KiB) exits non-zero with a line that says so, leaves the earlier
// file there byte for byte, and leaves no temporary file beside it.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "child_process.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path record_program = SSLF_RECORD_PATH;

// No file a child writes may grow past this: its log fails at the first buffer it writes out
// beyond it (the writer's buffer is 128 KiB), its standard error and ready file stay far below.
constexpr rlim_t kChildFileSizeLimit = 64 * 1024;

// While it lives, the processes this test starts may write no file beyond `bytes`, and a write
// past that fails with EFBIG instead of killing them with SIGXFSZ: a disk that fills partway,
// reliably, for root in a container too. posix_spawn sets no limits of its own, so a child
// inherits the test's: the test lowers its own soft limit only while it starts the child.
class ChildFileSizeLimit {
 public:
  explicit ChildFileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_limit_);
    rlimit lowered = saved_limit_;
    lowered.rlim_cur = bytes;
    saved_handler_ = ::signal(SIGXFSZ, SIG_IGN);  // an ignored signal stays ignored across exec
    EXPECT_EQ(::setrlimit(RLIMIT_FSIZE, &lowered), 0);
  }
  ~ChildFileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_limit_);
    ::signal(SIGXFSZ, saved_handler_);
  }
  ChildFileSizeLimit(const ChildFileSizeLimit&) = delete;
  ChildFileSizeLimit& operator=(const ChildFileSizeLimit&) = delete;

 private:
  rlimit saved_limit_{};
  sighandler_t saved_handler_ = SIG_DFL;
};

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The files in `folder` that a write left behind: "*.tmp-*".
std::vector<std::string> temporary_files_in(const std::filesystem::path& folder) {
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) {
      left.push_back(entry.path().filename().string());
    }
  }
  return left;
}

// An earlier log at `path`: a short simulated match, written by a run that succeeds.
std::string write_earlier_log(const std::filesystem::path& path, const TempDir& dir) {
  const auto written = testing::run_to_end(
      producer_program,
      {"--output", path.string(), "--overwrite", "--duration", "1", "--seed", "4"}, dir.path(),
      "earlier", 60s);
  EXPECT_EQ(written.exit_code, 0) << written.err;
  const std::string bytes = read_bytes(path);
  EXPECT_GT(bytes.size(), 0u);
  return bytes;
}

TEST(FailedLogWrites, AProducerLogThatFailsPartwayLeavesTheEarlierLog) {
  TempDir dir;
  const auto path = dir / "out.log";
  const std::string earlier = write_earlier_log(path, dir);
  ASSERT_FALSE(earlier.empty());

  // A minute of the match (several megabytes): the writes fail long before its end.
  std::optional<ChildProcess> producer;
  {
    const ChildFileSizeLimit limit(kChildFileSizeLimit);
    producer.emplace(producer_program,
                     std::vector<std::string>{"--output", path.string(), "--overwrite",
                                              "--duration", "60", "--seed", "5"},
                     dir.path(), "failing");
  }
  int signalled = 0;
  const auto code = producer->wait(60s, &signalled);
  ASSERT_TRUE(code.has_value()) << "signal " << signalled << ": " << producer->stderr_text();
  EXPECT_EQ(*code, 1) << producer->stderr_text();
  const std::string err = producer->stderr_text();
  EXPECT_NE(err.find(path.string() + ": cannot write at byte "), std::string::npos) << err;
  EXPECT_NE(err.find("File too large"), std::string::npos) << err;
  EXPECT_NE(err.find("as it was"), std::string::npos) << err;
  EXPECT_EQ(read_bytes(path), earlier) << "the earlier log was changed";
  EXPECT_EQ(temporary_files_in(dir.path()), std::vector<std::string>{});
}

TEST(FailedLogWrites, ARecordingThatFailsPartwayLeavesTheEarlierRecording) {
  TempDir dir;
  const auto path = dir / "match.log";
  const std::string earlier = write_earlier_log(path, dir);
  ASSERT_FALSE(earlier.empty());

  const std::string vision = new_group();
  std::optional<ChildProcess> recorder;
  {
    const ChildFileSizeLimit limit(kChildFileSizeLimit);
    recorder.emplace(record_program,
                     std::vector<std::string>{"--vision-address", vision, "--output", path.string(),
                                              "--overwrite"},
                     dir.path(), "record", Readiness::ready_file);
  }
  ASSERT_TRUE(recorder->wait_until_ready(10s)) << recorder->stderr_text();
  // The paper's formations, a thousand a second, until the recorder gives up (or the test kills
  // the producer with its end): well past the limit within a second or two.
  ChildProcess producer(producer_program,
                        {"--simulation", "paper", "--vision-address", vision, "--period", "0.001",
                         "--status-interval", "100"},
                        dir.path(), "producer");
  int signalled = 0;
  const auto code = recorder->wait(60s, &signalled);
  ASSERT_TRUE(code.has_value()) << "signal " << signalled << ": " << recorder->stderr_text();
  EXPECT_EQ(*code, 1) << recorder->stderr_text();
  const std::string err = recorder->stderr_text();
  EXPECT_NE(err.find(path.string() + ": cannot write at byte "), std::string::npos) << err;
  EXPECT_NE(err.find("File too large"), std::string::npos) << err;
  EXPECT_NE(err.find("as it was"), std::string::npos) << err;
  EXPECT_EQ(read_bytes(path), earlier) << "the earlier recording was changed";
  EXPECT_EQ(temporary_files_in(dir.path()), std::vector<std::string>{});
}

}  // namespace
}  // namespace ssl_formation
