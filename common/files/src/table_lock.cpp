#include "ssl_formation/files/table_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace ssl_formation {

namespace {

// The process id the holder wrote, or "" when the file says none.
std::string holder_of(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  if (n <= 0) return {};
  std::string pid(text, static_cast<std::size_t>(n));
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  for (const char c : pid) {
    if (c < '0' || c > '9') return {};
  }
  return pid;
}

}  // namespace

std::filesystem::path TableWriterLock::lock_path_for_table(const std::filesystem::path& table) {
  std::filesystem::path lock = table;
  lock += ".lock";
  return lock;
}

std::filesystem::path TableWriterLock::lock_path_for_folder(const std::filesystem::path& table_dir) {
  return table_dir / ".ssl-trainer.lock";
}

TableWriterLock::TableWriterLock(const std::filesystem::path& lock_path, const std::string& what)
    : path_(lock_path) {
  fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  bool writable = fd_ >= 0;
  // A lock file left by another user (a run with sudo) can still be locked, read only.
  if (fd_ < 0 && errno == EACCES) fd_ = ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    throw TableLockError("cannot open the lock file " + lock_path.string() + " for " + what +
                         ": " + std::strerror(errno));
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    const std::string holder = holder_of(fd_);
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      throw TableLockError(
          what + " is written by another process" + (holder.empty() ? "" : " (pid " + holder + ")") +
          ", an ssl-trainer most likely: two writers would overwrite each other's counts. Stop "
          "it, or give this one another table (the lock is " +
          lock_path.string() + ")");
    }
    throw TableLockError("cannot lock " + lock_path.string() + " for " + what + ": " +
                         std::strerror(error));
  }
  // Who holds it, for the message a second writer gets. Best effort: the lock is what counts.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (writable && ::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd_, pid.data(), pid.size(), 0);
  }
}

TableWriterLock::~TableWriterLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

TableWriterLock::TableWriterLock(TableWriterLock&& other) noexcept
    : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)) {}

}  // namespace ssl_formation
