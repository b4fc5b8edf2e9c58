// One writer per table: a second ssl-trainer on the same --table or --table-dir is refused at
// start, naming the first; a killed trainer leaves no lock behind that blocks the next one, and
// a trainer that stops cleanly (a signal, the end of its logs, a merge) leaves no lock file at
// all.

#include "ssl_formation/files/table_lock.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "feed_groups.hpp"

namespace ssl_formation {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::Readiness;
using testing::TempDir;

const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;

std::vector<std::string> live_trainer(const std::string& table_option, const std::string& where) {
  return {"--vision-address",  testing::new_group(),
          "--referee-address", testing::new_group(),
          table_option,        where,
          "--status-interval", "60",
          "--model",           "paper"};
}

TEST(TableLock, ASecondTrainerOnTheSameTableIsRefusedAndAKilledOneLeavesNoLock) {
  TempDir dir;
  const std::string table = (dir / "table.bin").string();
  ChildProcess first(trainer_program, live_trainer("--table", table), dir.path(), "first",
                     Readiness::ready_file);
  ASSERT_TRUE(first.wait_until_ready(10s)) << first.stderr_text();

  const auto second = testing::run_to_end(trainer_program, live_trainer("--table", table),
                                          dir.path(), "second", 10s);
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_NE(second.err.find("the table " + table + " is written by another process (pid " +
                            std::to_string(first.pid()) + ")"),
            std::string::npos)
      << second.err;
  EXPECT_NE(second.err.find("another table"), std::string::npos) << second.err;
  // The first runs on.
  EXPECT_FALSE(first.wait(200ms).has_value());

  // Killed without a chance to clean up: the next trainer starts all the same.
  first.signal(SIGKILL);
  int signalled = 0;
  first.wait(5s, &signalled);
  ASSERT_EQ(signalled, SIGKILL);
  ChildProcess third(trainer_program, live_trainer("--table", table), dir.path(), "third",
                     Readiness::ready_file);
  ASSERT_TRUE(third.wait_until_ready(10s)) << third.stderr_text();
  third.signal(SIGTERM);
  EXPECT_EQ(third.wait(5s), 0) << third.stderr_text();
}

TEST(TableLock, ATableFolderHasOneWriterLiveOrFromLogs) {
  TempDir dir;
  const std::string tables = (dir / "tables").string();
  ChildProcess live(trainer_program, live_trainer("--table-dir", tables), dir.path(), "live",
                    Readiness::ready_file);
  ASSERT_TRUE(live.wait_until_ready(10s)) << live.stderr_text();
  // A second live trainer, and an offline one adding logs to the same folder.
  const auto second = testing::run_to_end(trainer_program, live_trainer("--table-dir", tables),
                                          dir.path(), "second", 10s);
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_NE(second.err.find("the table folder " + tables + " is written by another process"),
            std::string::npos)
      << second.err;
  const auto offline = testing::run_to_end(
      trainer_program,
      {"--from-log", std::string(SSLF_TEST_DATA_DIR) + "/grsim-4cam-11v11-idle.log.gz",
       "--table-dir", tables, "--opponent-team", "all", "--model", "paper"},
      dir.path(), "offline", 30s);
  EXPECT_EQ(offline.exit_code, 1) << offline.err;
  EXPECT_NE(offline.err.find("is written by another process"), std::string::npos) << offline.err;
  live.signal(SIGTERM);
  EXPECT_EQ(live.wait(5s), 0) << live.stderr_text();
}

TEST(TableLock, ATrainerStoppedBySignalLeavesNoLockFile) {
  TempDir dir;
  const auto table = dir / "table.bin";
  const auto lock = TableWriterLock::lock_path_for_table(table);
  ChildProcess by_interrupt(trainer_program, live_trainer("--table", table.string()), dir.path(),
                            "interrupted", Readiness::ready_file);
  ASSERT_TRUE(by_interrupt.wait_until_ready(10s)) << by_interrupt.stderr_text();
  EXPECT_TRUE(std::filesystem::exists(lock));
  by_interrupt.signal(SIGINT);
  EXPECT_EQ(by_interrupt.wait(5s), 0) << by_interrupt.stderr_text();
  EXPECT_FALSE(std::filesystem::exists(lock));

  const auto tables = dir / "tables";
  ChildProcess by_terminate(trainer_program, live_trainer("--table-dir", tables.string()),
                            dir.path(), "terminated", Readiness::ready_file);
  ASSERT_TRUE(by_terminate.wait_until_ready(10s)) << by_terminate.stderr_text();
  EXPECT_TRUE(std::filesystem::exists(TableWriterLock::lock_path_for_folder(tables)));
  by_terminate.signal(SIGTERM);
  EXPECT_EQ(by_terminate.wait(5s), 0) << by_terminate.stderr_text();
  EXPECT_FALSE(std::filesystem::exists(TableWriterLock::lock_path_for_folder(tables)));
}

TEST(TableLock, TrainingFromLogsAndMergingLeaveNoLockFile) {
  TempDir dir;
  const std::string log = std::string(SSLF_TEST_DATA_DIR) + "/step-golden.log.gz";
  for (const char* table : {"a.bin", "b.bin"}) {
    const auto trained = testing::run_to_end(
        trainer_program, {"--from-log", log, "--table", (dir / table).string(), "--model", "paper"},
        dir.path(), table, 30s);
    ASSERT_EQ(trained.exit_code, 0) << trained.err;
    EXPECT_FALSE(std::filesystem::exists(TableWriterLock::lock_path_for_table(dir / table)));
  }
  const auto merged =
      testing::run_to_end(trainer_program,
                          {"merge", (dir / "a.bin").string(), (dir / "b.bin").string(), "-o",
                           (dir / "ab.bin").string()},
                          dir.path(), "merge", 30s);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "ab.bin"));
  EXPECT_FALSE(std::filesystem::exists(TableWriterLock::lock_path_for_table(dir / "ab.bin")));

  const auto tables = dir / "tables";
  const auto into_folder = testing::run_to_end(
      trainer_program,
      {"--from-log", std::string(SSLF_TEST_DATA_DIR) + "/grsim-4cam-11v11-idle.log.gz",
       "--table-dir", tables.string(), "--opponent-team", "all", "--model", "paper"},
      dir.path(), "into-folder", 30s);
  ASSERT_EQ(into_folder.exit_code, 0) << into_folder.err;
  EXPECT_FALSE(std::filesystem::exists(TableWriterLock::lock_path_for_folder(tables)));
}

TEST(TableLock, TwoLocksOnOneFileConflictEvenInOneProcessAndTheFileNamesItsHolder) {
  TempDir dir;
  const auto path = TableWriterLock::lock_path_for_table(dir / "t.bin");
  EXPECT_EQ(path, dir / "t.bin.lock");
  {
    const TableWriterLock held(path, "the table t.bin");
    try {
      const TableWriterLock again(path, "the table t.bin");
      FAIL() << "a second lock was given";
    } catch (const TableLockError& error) {
      EXPECT_NE(std::string(error.what()).find("(pid " + std::to_string(::getpid()) + ")"),
                std::string::npos)
          << error.what();
    }
  }
  // Released with its holder.
  EXPECT_NO_THROW(TableWriterLock(path, "the table t.bin"));
  EXPECT_THROW(TableWriterLock(dir / "no-such-folder" / "x.lock", "x"), TableLockError);
}

}  // namespace
}  // namespace ssl_formation
