// What the daemons tell their operator: the share of datagrams decoded on the fast path, the
// field size a geometry packet sets with the division it implies, and how a log that ends
// inside its last message is taken (a warning, or an error with --strict).

#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>

#include "child_process.hpp"
#include "pipeline_support.hpp"
#include "status_lines.hpp"

namespace ssl_formation {
namespace {

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::new_group;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;

testing::RunResult write_log(const TempDir& dir, const std::string& name,
                             std::vector<std::string> extra = {}) {
  std::vector<std::string> args{
      "--simulation", "paper", "--referee", "off", "--write-log", (dir / name).string(),
      "--count",      "120",   "--seed",    "3",   "--cameras",   "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  return testing::run_to_end(producer_program, args, dir.path(), "write-" + name, 30s);
}

std::size_t occurrences(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

TEST(DaemonReports, StatusLinesGiveTheFastPathShareAndTheFieldSizeIsLoggedWithItsDivision) {
  TempDir dir;
  ASSERT_EQ(write_log(dir, "a.log", {"--field-length", "12000", "--field-width", "9000"}).exit_code,
            0);
  const std::string vision = new_group();
  for (const std::filesystem::path& program : {trainer_program, predictor_program}) {
    SCOPED_TRACE(program.filename().string());
    std::vector<std::string> args{"--vision-address",  vision, "--table", (dir / "t.bin").string(),
                                  "--status-interval", "0.1"};
    if (program == predictor_program) args.push_back("--quiet");
    ChildProcess daemon(program, args, dir.path(), program.filename().string(),
                        Readiness::ready_file);
    ASSERT_TRUE(daemon.wait_until_ready(10s)) << daemon.stderr_text();
    // At start: the options' field, Division B.
    EXPECT_NE(daemon.stderr_text().find("field: 9000 x 6000 mm (Division B) from the options"),
              std::string::npos)
        << daemon.stderr_text();
    const auto replayed = testing::run_to_end(
        producer_program,
        {"--replay", (dir / "a.log").string(), "--vision-address", vision, "--speed", "0"},
        dir.path(), "replay");
    ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
    // Once per change: the geometry packets of the log say Division A.
    ASSERT_TRUE(
        daemon.wait_for_stderr("field: 12000 x 9000 mm (Division A) from a geometry packet", 10s))
        << daemon.stderr_text();
    EXPECT_EQ(occurrences(daemon.stderr_text(), "(Division A) from a geometry packet"), 1u);
    ASSERT_TRUE(testing::wait_for_status(daemon, "packets", 1, 10s)) << daemon.stderr_text();
    daemon.signal(SIGTERM);
    EXPECT_EQ(daemon.wait(10s), 0) << daemon.stderr_text();
    // Every detection packet of the simulation takes the fast path; geometry goes through
    // protobuf. The share is a detail of the status lines: on the last word at stop, with every
    // figure the periodic lines had no room for.
    const std::string text = daemon.stderr_text();
    const std::string last_word = text.substr(text.rfind("status: "));
    std::smatch share;
    ASSERT_TRUE(std::regex_search(last_word, share, std::regex(R"(fast_path=([\d.]+)%)"))) << text;
    EXPECT_GT(std::stod(share[1]), 50.0);
    EXPECT_LT(std::stod(share[1]), 100.0);  // the geometry packets
  }
}

TEST(DaemonReports, ALogCutOffInsideItsLastMessageIsAWarningUnlessStrict) {
  TempDir dir;
  ASSERT_EQ(write_log(dir, "whole.log").exit_code, 0);
  std::string bytes;
  {
    std::ifstream in(dir / "whole.log", std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    bytes = text.str();
  }
  // A recorder killed mid-write: the file stops 10 bytes into its last message's payload.
  {
    std::ofstream out(dir / "cut.log", std::ios::binary);
    out << bytes.substr(0, bytes.size() - 30);
  }
  const auto trained = testing::run_to_end(
      trainer_program,
      {"--from-log", (dir / "cut.log").string(), "--table", (dir / "cut.bin").string()}, dir.path(),
      "cut");
  EXPECT_EQ(trained.exit_code, 0) << trained.err;
  EXPECT_NE(trained.err.find("ends inside its last message"), std::string::npos) << trained.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "cut.bin"));

  // --strict fails before it writes: a table there before is left as it was.
  std::filesystem::copy_file(dir / "cut.bin", dir / "strict.bin");
  const auto table_before = read_bytes(dir / "strict.bin");
  const auto strict =
      testing::run_to_end(trainer_program,
                          {"--from-log", (dir / "whole.log").string(), (dir / "cut.log").string(),
                           "--table", (dir / "strict.bin").string(), "--strict"},
                          dir.path(), "strict");
  EXPECT_EQ(strict.exit_code, 1) << strict.err;
  EXPECT_EQ(read_bytes(dir / "strict.bin"), table_before) << strict.err;
  EXPECT_NE(strict.err.find("no table written"), std::string::npos) << strict.err;

  // Damage before the end (an absurd message size in the middle) stays an error.
  std::string damaged = bytes;
  const std::size_t middle = 16 + (bytes.size() - 16) / 2;
  // Find a message header near the middle by scanning the headers from the start.
  std::size_t at = 16;
  while (at < middle) {
    const auto size = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + 12]) << 24 |
                                                 static_cast<unsigned char>(bytes[at + 13]) << 16 |
                                                 static_cast<unsigned char>(bytes[at + 14]) << 8 |
                                                 static_cast<unsigned char>(bytes[at + 15]));
    if (at + 16 + size >= middle) break;
    at += 16 + size;
  }
  damaged[at + 12] = '\x7f';  // a size of about 2 GB
  {
    std::ofstream out(dir / "damaged.log", std::ios::binary);
    out << damaged;
  }
  const auto broken = testing::run_to_end(
      trainer_program,
      {"--from-log", (dir / "damaged.log").string(), "--table", (dir / "damaged.bin").string()},
      dir.path(), "damaged");
  EXPECT_EQ(broken.exit_code, 1) << broken.err;
  EXPECT_NE(broken.err.find("absurd message size"), std::string::npos) << broken.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "damaged.bin")) << "a failed run writes no table";
}

}  // namespace
}  // namespace ssl_formation
