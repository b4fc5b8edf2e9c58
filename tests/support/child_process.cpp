#include "child_process.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace ssl_formation::testing {

namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

ChildProcess::ChildProcess(const std::filesystem::path& program, std::vector<std::string> arguments,
                           const std::filesystem::path& output_dir, const std::string& name,
                           Readiness readiness)
    : stdout_path_(std::filesystem::absolute(output_dir / (name + ".out"))),
      stderr_path_(std::filesystem::absolute(output_dir / (name + ".err"))) {
  arguments = FeedGroups{}.complete(program, std::move(arguments));
  if (readiness == Readiness::ready_file) {
    ready_path_ = std::filesystem::absolute(output_dir / (name + ".ready"));
    std::filesystem::remove(ready_path_);
    arguments.push_back("--ready-file");
    arguments.push_back(ready_path_.string());
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // The test's own folder is the program's working folder: what it writes by default (a table
  // file) stays there, apart from every other test's.
  posix_spawn_file_actions_addchdir_np(&actions, output_dir.c_str());
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path_.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path_.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv_strings{program.string()};
  argv_strings.insert(argv_strings.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  const int error = posix_spawn(&pid_, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error("cannot start " + program.string());
}

ChildProcess::~ChildProcess() {
  if (!reaped_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
  }
}

bool ChildProcess::wait_until_ready(std::chrono::milliseconds timeout) {
  if (ready_path_.empty()) throw std::logic_error("started without Readiness::ready_file");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (std::filesystem::exists(ready_path_)) return true;
    if (!running()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

std::string ChildProcess::ready_fact(const std::string& key) const {
  if (ready_path_.empty()) return {};
  std::istringstream lines(read_file(ready_path_));
  const std::string prefix = key + "=";
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(prefix, 0) == 0) return line.substr(prefix.size());
  }
  return {};
}

void ChildProcess::signal(int signal_number) const {
  if (!reaped_) ::kill(pid_, signal_number);
}

std::optional<int> ChildProcess::wait(std::chrono::milliseconds timeout, int* signalled) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!reaped_) {
    const pid_t done = ::waitpid(pid_, &status_, WNOHANG);
    if (done == pid_) {
      reaped_ = true;
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (WIFSIGNALED(status_)) {
    if (signalled) *signalled = WTERMSIG(status_);
    return std::nullopt;
  }
  return WEXITSTATUS(status_);
}

bool ChildProcess::running() {
  if (reaped_) return false;
  return !wait(std::chrono::milliseconds(0)).has_value() && !reaped_;
}

std::string ChildProcess::stdout_text() const { return read_file(stdout_path_); }
std::string ChildProcess::stderr_text() const { return read_file(stderr_path_); }

bool ChildProcess::wait_for_stderr(const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (stderr_text().find(text) != std::string::npos) return true;
    if (!running()) return stderr_text().find(text) != std::string::npos;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

bool ChildProcess::wait_for_stdout(const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (stdout_text().find(text) != std::string::npos) return true;
    if (!running()) return stdout_text().find(text) != std::string::npos;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

RunResult run_to_end(const std::filesystem::path& program, std::vector<std::string> arguments,
                     const std::filesystem::path& output_dir, const std::string& name,
                     std::chrono::milliseconds timeout) {
  ChildProcess child(program, std::move(arguments), output_dir, name);
  RunResult result;
  const auto code = child.wait(timeout);
  result.exit_code = code ? *code : -1;
  result.out = child.stdout_text();
  result.err = child.stderr_text();
  return result;
}

TempDir::TempDir() {
  std::random_device device;
  path_ = std::filesystem::temp_directory_path() /
          ("sslf-test-" + std::to_string(::getpid()) + "-" + std::to_string(device()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::uint16_t free_udp_port() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof address;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    if (fd >= 0) ::close(fd);
    throw std::runtime_error("cannot find a free UDP port");
  }
  ::close(fd);
  return ntohs(address.sin_port);
}

std::string unique_group(std::uint16_t port) {
  std::random_device device;
  std::uniform_int_distribution<int> octet(1, 254);
  return "239.255." + std::to_string(octet(device)) + "." + std::to_string(octet(device)) + ":" +
         std::to_string(port);
}

}  // namespace ssl_formation::testing
