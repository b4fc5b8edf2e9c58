#pragma once
// A POSIX file descriptor closed on every way out, and errno's text, for the table file's
// reading (table_file.cpp) and durable writing (durable_file.cpp).

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

namespace ssl_formation {
inline namespace files {
namespace detail {

inline std::string errno_text(int error) { return std::strerror(error); }

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd = -1) : fd_(fd) {}
  ~FileDescriptor() { close(); }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset(int fd) noexcept {
    close();
    fd_ = fd;
  }
  // Closes now and reports the error (0 or an errno value), because close can be the first to
  // report a failed write. noexcept: destructors call it.
  int close() noexcept {
    const int fd = std::exchange(fd_, -1);
    return fd >= 0 && ::close(fd) != 0 ? errno : 0;
  }

 private:
  int fd_;
};

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
