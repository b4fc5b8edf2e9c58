#include "ssl_formation/app/daemon.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "captured_log.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/app/options.hpp"

namespace ssl_formation::app {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// A fresh folder for each test, removed with everything in it.
class TempDir : public testing::ScratchDir {
 public:
  TempDir() : ScratchDir("sslf-daemon") {}
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

std::vector<std::string> names_in(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// ---- ReadyFile ----

TEST(ReadyFile, NothingIsWrittenWithoutAPath) {
  // Run in an empty folder, so that a file written anywhere relative would show.
  TempDir dir;
  const fs::path before = fs::current_path();
  fs::current_path(dir.path());
  {
    ReadyFile ready("");
    EXPECT_NO_THROW(ready.mark_ready("ssl-test", {{"key", "value"}}));
  }
  fs::current_path(before);
  EXPECT_TRUE(names_in(dir.path()).empty());
}

TEST(ReadyFile, WrittenWithProgramAndPidFirstThenTheFactsAndRemovedAtTheEnd) {
  TempDir dir;
  const fs::path path = dir.path() / "trainer.ready";
  {
    ReadyFile ready(path.string());
    EXPECT_FALSE(fs::exists(path)) << "nothing before mark_ready";
    ready.mark_ready("ssl-trainer",
                     {{"vision", "224.5.23.2:10006"}, {"interface", "127.0.0.1"}, {"table", "/t"}});
    EXPECT_EQ(read_text(path), "program=ssl-trainer\npid=" + std::to_string(::getpid()) +
                                   "\nvision=224.5.23.2:10006\ninterface=127.0.0.1\ntable=/t\n");
    EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"trainer.ready"})
        << "no temporary file is left beside it";
  }
  EXPECT_FALSE(fs::exists(path)) << "the destructor removes the ready file";
  EXPECT_TRUE(names_in(dir.path()).empty());
}

TEST(ReadyFile, ReplacesAnOldFileByRenameNotInPlace) {
  // A reader that has the old file open (here: a second link to it) never sees part of the new
  // one: the new file is renamed over the name, the old inode keeps the old content.
  TempDir dir;
  const fs::path path = dir.path() / "ready";
  write_text(path, "program=old\n");
  fs::create_hard_link(path, dir.path() / "reader");
  ReadyFile ready(path.string());
  ready.mark_ready("ssl-predictor", {});
  EXPECT_EQ(read_text(path), "program=ssl-predictor\npid=" + std::to_string(::getpid()) + "\n");
  EXPECT_EQ(read_text(dir.path() / "reader"), "program=old\n");
}

TEST(ReadyFile, NotMarkedReadyLeavesAFileThereAlone) {
  TempDir dir;
  const fs::path path = dir.path() / "ready";
  write_text(path, "someone else's\n");
  { ReadyFile ready(path.string()); }
  EXPECT_EQ(read_text(path), "someone else's\n");
}

void expect_unwritable(const fs::path& path) {
  ReadyFile ready(path.string());
  try {
    ready.mark_ready("ssl-test", {{"a", "b"}});
    ADD_FAILURE() << "mark_ready wrote " << path;
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(path.string()), std::string::npos) << error.what();
  }
}

TEST(ReadyFile, AnUnwritablePathThrows) {
  TempDir dir;
  write_text(dir.path() / "file", "x");
  expect_unwritable(dir.path() / "file" / "ready");     // its folder is a regular file
  expect_unwritable(dir.path() / "missing" / "ready");  // its folder does not exist
  // A folder in the way of the name: the temporary is written, the rename fails, and the
  // temporary does not stay behind.
  fs::create_directory(dir.path() / "taken");
  write_text(dir.path() / "taken" / "inside", "x");
  expect_unwritable(dir.path() / "taken");
  EXPECT_EQ(names_in(dir.path()), (std::vector<std::string>{"file", "taken"}));
  EXPECT_TRUE(fs::is_directory(dir.path() / "taken")) << "a failed ReadyFile removes nothing";
}

// ---- describe(FieldSize), FieldSizeLog ----

TEST(DescribeField, SaysTheDivision) {
  EXPECT_EQ(describe(FieldSize{12000.0, 9000.0}), "12000 x 9000 mm (Division A)");
  EXPECT_EQ(describe(FieldSize{9000.0, 6000.0}), "9000 x 6000 mm (Division B)");
  EXPECT_EQ(describe(FieldSize{}), "9000 x 6000 mm (Division B)");
  EXPECT_EQ(describe(FieldSize{10400.0, 7400.0}), "10400 x 7400 mm (neither Division A nor B)");
  EXPECT_EQ(describe(FieldSize{9000.0, 12000.0}), "9000 x 12000 mm (neither Division A nor B)");
  EXPECT_EQ(describe(FieldSize{6000.0, 9000.0}), "6000 x 9000 mm (neither Division A nor B)");
  EXPECT_NE(describe(FieldSize{12000.0, 9001.0}).find("neither"), std::string::npos);
}

using testing::CapturedLog;

TEST(FieldSizeLog, LogsAtStartAndOncePerChange) {
  CapturedLog log;
  FieldSizeLog field_log(FieldSize{9000.0, 6000.0}, true);
  ASSERT_EQ(log.lines().size(), 1u);
  EXPECT_NE(log.lines()[0].find("9000 x 6000 mm (Division B)"), std::string::npos)
      << log.lines()[0];
  field_log.update(FieldSize{9000.0, 6000.0});  // the same: nothing
  EXPECT_EQ(log.lines().size(), 1u);
  field_log.update(FieldSize{12000.0, 9000.0});
  ASSERT_EQ(log.lines().size(), 2u);
  EXPECT_NE(log.lines()[1].find("12000 x 9000 mm (Division A)"), std::string::npos)
      << log.lines()[1];
  EXPECT_NE(log.lines()[1].find("was 9000 x 6000"), std::string::npos) << log.lines()[1];
  field_log.update(FieldSize{12000.0, 9000.0});
  field_log.update(FieldSize{12000.0, 9000.0});
  EXPECT_EQ(log.lines().size(), 2u);
}

TEST(FieldSizeLog, NeverThrows) {
  CapturedLog log;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (bool geometry : {true, false}) {
    EXPECT_NO_THROW({
      FieldSizeLog field_log(FieldSize{10400.0, 7400.0}, geometry);
      field_log.update(FieldSize{0.0, 0.0});
      field_log.update(FieldSize{-1.0, 1e300});
      field_log.update(FieldSize{nan, inf});
      field_log.update(FieldSize{12000.0, 9000.0});
    });
  }
  const std::vector<std::string> lines = log.lines();
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines[0].find("until a geometry packet"), std::string::npos) << lines[0];
}

// ---- StopSignals, in forked children ----

// A child process that is killed and reaped, whatever happens to the test.
class Child {
 public:
  explicit Child(pid_t pid) : pid_(pid) {}
  ~Child() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  pid_t pid() const { return pid_; }

  // The wait status once the child has ended, or nullopt if it is still running at the deadline.
  std::optional<int> wait_for_exit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      int status = 0;
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        pid_ = -1;  // reaped: nothing left to kill
        return status;
      }
      if (done < 0 && errno != EINTR) return std::nullopt;
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(10ms);
    }
  }
  bool running() {
    int status = 0;
    return ::waitpid(pid_, &status, WNOHANG) == 0;
  }

 private:
  pid_t pid_;
};

// Both ends of a pipe, closed at the end.
struct Pipe {
  int read_end = -1;
  int write_end = -1;
  Pipe() {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
    read_end = fds[0];
    write_end = fds[1];
  }
  ~Pipe() {
    if (read_end >= 0) ::close(read_end);
    if (write_end >= 0) ::close(write_end);
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
};

// Reads up to `size` bytes that arrive before the deadline.
std::string read_for(int fd, std::size_t size, std::chrono::milliseconds timeout) {
  std::string out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (out.size() < size) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) break;
    char buffer[64];
    const ssize_t n = ::read(fd, buffer, std::min(sizeof buffer, size - out.size()));
    if (n <= 0) break;  // the child closed its end (it ended)
    out.append(buffer, static_cast<std::size_t>(n));
  }
  return out;
}

void write_all(int fd, const std::string& text) {
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

// Runs `body` in a forked child that never returns into the test framework.
template <typename Body>
pid_t fork_child(Pipe& pipe, Body body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(pipe.read_end);
    int code = 0;
    try {
      code = body(pipe.write_end);
    } catch (...) {
      code = 99;
    }
    ::_exit(code);
  }
  if (pid < 0) throw std::runtime_error("fork failed");
  ::close(pipe.write_end);
  pipe.write_end = -1;
  return pid;
}

// "S<n>;" : on_stop was called with signal n.
std::string stopped_with(int signal) { return "S" + std::to_string(signal) + ";"; }

TEST(StopSignals, ASecondSigintEndsTheProcessDuringASlowStop) {
  Pipe pipe;
  Child child(fork_child(pipe, [](int out) {
    boost::asio::io_context io;
    StopSignals signals(io, [out](int signal) {
      write_all(out, stopped_with(signal));
      std::this_thread::sleep_for(10s);  // a slow save
      write_all(out, "saved;");
    });
    write_all(out, "R");
    io.run();
    return 3;  // stopped cleanly: the second signal did not end the process
  }));
  ASSERT_EQ(read_for(pipe.read_end, 1, 5000ms), "R") << "the child did not start";

  ASSERT_EQ(::kill(child.pid(), SIGINT), 0);
  const std::string stop = stopped_with(SIGINT);
  ASSERT_EQ(read_for(pipe.read_end, stop.size(), 3000ms), stop)
      << "the first SIGINT must call on_stop with SIGINT";
  ASSERT_EQ(child.wait_for_exit(300ms), std::nullopt)
      << "the first signal must not end the process";

  ASSERT_EQ(::kill(child.pid(), SIGINT), 0);
  const std::optional<int> status = child.wait_for_exit(3000ms);
  ASSERT_TRUE(status.has_value()) << "the second SIGINT did not end the process within 3 s";
  ASSERT_TRUE(WIFSIGNALED(*status)) << "exited with " << WEXITSTATUS(*status);
  EXPECT_EQ(WTERMSIG(*status), SIGINT);
  EXPECT_EQ(read_for(pipe.read_end, 16, 100ms), "") << "the slow save must not have finished";
}

TEST(StopSignals, AFirstSigtermCallsOnStopOnceWithItsNumber) {
  Pipe pipe;
  Child child(fork_child(pipe, [](int out) {
    boost::asio::io_context io;
    int calls = 0;
    int last_signal = 0;
    StopSignals signals(io, [&](int signal) {
      ++calls;
      last_signal = signal;
    });
    write_all(out, "R");
    io.run();  // returns once nothing is left to wait for
    write_all(out,
              "calls=" + std::to_string(calls) + " signal=" + std::to_string(last_signal) + ";");
    return 0;
  }));
  ASSERT_EQ(read_for(pipe.read_end, 1, 5000ms), "R") << "the child did not start";
  ASSERT_EQ(::kill(child.pid(), SIGTERM), 0);
  const std::string expected = "calls=1 signal=" + std::to_string(SIGTERM) + ";";
  EXPECT_EQ(read_for(pipe.read_end, expected.size(), 3000ms), expected);
  const std::optional<int> status = child.wait_for_exit(3000ms);
  ASSERT_TRUE(status.has_value()) << "the child did not end after on_stop";
  ASSERT_TRUE(WIFEXITED(*status)) << "the first SIGTERM must be handled, not end the process";
  EXPECT_EQ(WEXITSTATUS(*status), 0);
}

// ---- RepeatingTimer, seconds_option ----

TEST(RepeatingTimer, TicksUntilCancelled) {
  boost::asio::io_context io;
  int ticks = 0;
  std::unique_ptr<RepeatingTimer> timer;
  timer = std::make_unique<RepeatingTimer>(io, 5ms, [&] {
    // The daemons cancel from another handler (the stop signal's): one runs right after this.
    if (++ticks == 3) boost::asio::post(io, [&] { timer->cancel(); });
  });
  const auto start = std::chrono::steady_clock::now();
  io.run_for(5s);  // returns early once the cancelled timer leaves no work
  EXPECT_EQ(ticks, 3);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 4s) << "the timer was not cancelled";
}

// A cancel() made inside the tick has no wait to cancel: the timer must not arm again.
TEST(RepeatingTimer, CancelInsideTheTickStopsIt) {
  boost::asio::io_context io;
  int ticks = 0;
  std::unique_ptr<RepeatingTimer> timer;
  timer = std::make_unique<RepeatingTimer>(io, 5ms, [&] {
    if (++ticks == 3) timer->cancel();
  });
  io.run_for(500ms);
  EXPECT_EQ(ticks, 3);
}

TEST(SecondsOption, AcceptsPositiveSecondsAndNamesTheOptionOtherwise) {
  EXPECT_EQ(seconds_option("flush-interval", 1.5), std::chrono::milliseconds(1500));
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity(), 2e6}) {
    try {
      (void)seconds_option("flush-interval", bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const UsageError& error) {
      EXPECT_NE(std::string(error.what()).find("--flush-interval"), std::string::npos)
          << error.what();
    }
  }
}

TEST(RecalibrationOption, ZeroIsOffAndABadHalfLifeNamesTheOption) {
  EXPECT_FALSE(recalibration_settings(0.0).has_value());
  const auto settings = recalibration_settings(30.0);
  ASSERT_TRUE(settings.has_value());
  EXPECT_EQ(settings->half_life_s, 30.0);
  EXPECT_EQ(settings->prior_weight, OnlineCalibrationSettings{}.prior_weight);
  for (double bad :
       {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    try {
      (void)recalibration_settings(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const UsageError& error) {
      EXPECT_NE(std::string(error.what()).find("--recalibration-half-life"), std::string::npos)
          << error.what();
    }
  }
}

}  // namespace
}  // namespace ssl_formation::app
