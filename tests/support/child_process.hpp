#pragma once
// Runs one of our programs as a real process for end-to-end tests: its stdout and stderr go to
// files the test can read and wait on; the destructor kills whatever is still running, so a
// failing test leaves no process behind. A daemon joins and sends only on groups of its test's
// own, never on the default ones (feed_groups.hpp).

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "feed_groups.hpp"

namespace ssl_formation::testing {

// Whether the program is one of our daemons, started with `--ready-file OUTPUT_DIR/NAME.ready`
// so the test can wait for it to be ready (sockets joined, table loaded) instead of reading logs.
enum class Readiness { none, ready_file };

class ChildProcess {
 public:
  // Starts `program` with `arguments`, completed with groups of its own for every feed the
  // arguments leave out (FeedGroups::complete), in `output_dir` as its working folder.
  ChildProcess(const std::filesystem::path& program, std::vector<std::string> arguments,
               const std::filesystem::path& output_dir, const std::string& name,
               Readiness readiness = Readiness::none);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int signal_number) const;
  // Waits for the process to end; its exit code, or nullopt on time-out (or if killed by a
  // signal: then `signalled` is set).
  std::optional<int> wait(std::chrono::milliseconds timeout, int* signalled = nullptr);
  bool running();

  std::string stdout_text() const;
  std::string stderr_text() const;
  // Waits until stderr (or stdout) contains `text`; false on time-out or if the process ended.
  bool wait_for_stderr(const std::string& text, std::chrono::milliseconds timeout);
  bool wait_for_stdout(const std::string& text, std::chrono::milliseconds timeout);
  // Waits until the daemon has written its ready file (Readiness::ready_file); false on
  // time-out or if the process ended first.
  bool wait_until_ready(std::chrono::milliseconds timeout);
  // What the ready file says, key by key ("pid", "table_loaded", ...); empty before it exists.
  std::string ready_fact(const std::string& key) const;

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = 0;
  std::filesystem::path stdout_path_;
  std::filesystem::path stderr_path_;
  std::filesystem::path ready_path_;  // empty without Readiness::ready_file
};

// Runs a program to completion (bounded by `timeout`), returning its exit code and output.
struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
RunResult run_to_end(const std::filesystem::path& program, std::vector<std::string> arguments,
                     const std::filesystem::path& output_dir, const std::string& name,
                     std::chrono::milliseconds timeout = std::chrono::seconds(60));

// A fresh folder for one test, removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace ssl_formation::testing
