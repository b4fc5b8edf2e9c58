#include "ssl_formation/files/table_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace ssl_formation {
inline namespace files {

namespace {

// Takes in a row that find the file they locked gone from the path: only other writers starting
// and stopping at that very moment, over and over, could make this many.
constexpr int kMaxTakes = 100;

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

// Whether `path` still names the file open as `fd`: not when a holder removed it on its way out
// (or someone else did), whether or not a new file has been made there since.
bool names_open_file(const std::filesystem::path& path, int fd) {
  struct stat opened {};
  struct stat named {};
  if (::fstat(fd, &opened) != 0 || ::stat(path.c_str(), &named) != 0) return false;
  return opened.st_dev == named.st_dev && opened.st_ino == named.st_ino;
}

}  // namespace

std::filesystem::path TableWriterLock::lock_path_for_table(const std::filesystem::path& table) {
  std::filesystem::path lock = table;
  lock += ".lock";
  return lock;
}

std::filesystem::path TableWriterLock::lock_path_for_folder(
    const std::filesystem::path& table_dir) {
  return table_dir / ".ssl-trainer.lock";
}

TableWriterLock::TableWriterLock(const std::filesystem::path& lock_path, const std::string& what)
    : path_(lock_path) {
  // A holder removes the file as it stops, still holding the lock. Whoever opened the file before
  // that holds, once it gets the lock, a lock on a file no longer at the path, which the next
  // writer does not see: such a lock counts for nothing, and the take starts again on the file
  // the path names now (made anew if need be).
  bool writable = false;
  for (int take = 0; fd_ < 0; ++take) {
    if (take == kMaxTakes) {
      throw TableLockError("cannot lock " + lock_path.string() + " for " + what +
                           ": other writers kept removing it");
    }
    fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    writable = fd_ >= 0;
    // A lock file left by another user (a run with sudo) can still be locked, read only.
    if (fd_ < 0 && errno == EACCES) fd_ = ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) {
      throw TableLockError("cannot open the lock file " + lock_path.string() + " for " + what +
                           ": " + std::strerror(errno));
    }
    const bool locked = ::flock(fd_, LOCK_EX | LOCK_NB) == 0;
    const int error = errno;
    if (names_open_file(lock_path, fd_)) {
      if (locked) break;
      const std::string holder = holder_of(fd_);
      ::close(fd_);
      fd_ = -1;
      if (error == EWOULDBLOCK) {
        throw TableLockError(
            what + " is written by another process" +
            (holder.empty() ? "" : " (pid " + holder + ")") +
            ", an ssl-trainer most likely: two writers would overwrite each other's counts. "
            "Stop it, or give this one another table (the lock is " +
            lock_path.string() + ")");
      }
      throw TableLockError("cannot lock " + lock_path.string() + " for " + what + ": " +
                           std::strerror(error));
    }
    // Locked or not, a file its holder already removed: that holder is stopping.
    ::close(fd_);
    fd_ = -1;
  }
  // Who holds it, for the message a second writer gets. Best effort: the lock is what counts.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (writable && ::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd_, pid.data(), pid.size(), 0);
  }
}

TableWriterLock::~TableWriterLock() {
  if (fd_ < 0) return;
  // Removed before it is released, so that no other writer can hold it meanwhile; and only if
  // the path still names this file, not one another writer made after someone removed this one.
  // Best effort: a file that stays (a folder this user cannot write) is taken over all the same.
  if (names_open_file(path_, fd_)) ::unlink(path_.c_str());
  ::close(fd_);  // releases the lock
}

TableWriterLock::TableWriterLock(TableWriterLock&& other) noexcept
    : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)) {}

}  // namespace files
}  // namespace ssl_formation
