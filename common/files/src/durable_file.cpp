#include "ssl_formation/files/durable_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <utility>

#include "ssl_formation/files/file_descriptor.hpp"
#include "ssl_formation/files/replacing_file.hpp"

namespace ssl_formation {
inline namespace files {
namespace detail {

void FileWriter::write(const std::uint8_t* data, std::size_t size) {
  if (error_ != 0) return;
  crc_ = crc_update(crc_, data, size);
  while (size > 0) {
    const std::size_t part = std::min(size, buffer_size - buffer_.size());
    buffer_.insert(buffer_.end(), data, data + part);
    data += part;
    size -= part;
    if (buffer_.size() == buffer_size) flush();
  }
}

void FileWriter::write_zero_u32s(std::uint64_t n) {
  static const std::array<std::uint8_t, 4096> zeros{};
  std::uint64_t bytes = n * 4;
  while (bytes > 0 && error_ == 0) {
    const std::size_t part = static_cast<std::size_t>(std::min<std::uint64_t>(bytes, 4096));
    write(zeros.data(), part);
    bytes -= part;
  }
}

void FileWriter::flush() {
  const std::uint8_t* data = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0 && error_ == 0) {
    const ssize_t wrote = ::write(fd_, data, left);
    if (wrote < 0) {
      if (errno != EINTR) error_ = errno;
      continue;
    }
    data += wrote;  // a partial write: the rest goes in the next call
    left -= static_cast<std::size_t>(wrote);
  }
  buffer_.clear();
}

namespace {

// The temporary file of one write: removed on every way out unless it was renamed into place.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~TemporaryFile() {
    fd.close();
    if (!renamed_) ::unlink(path_.c_str());
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const std::filesystem::path& path() const { return path_; }
  void mark_renamed() { renamed_ = true; }

  FileDescriptor fd;

 private:
  std::filesystem::path path_;
  bool renamed_ = false;
};

}  // namespace

Result<DurableFileWritten> write_file_durably(const std::filesystem::path& path,
                                              const WriteContent& write_content,
                                              const DurableFileHooks& hooks) {
  TemporaryFile temp(temporary_beside(path));
  int fd_value = -1;
  do {
    fd_value =
        ::open(temp.path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOCTTY, 0644);
  } while (fd_value < 0 && errno == EINTR);
  if (fd_value < 0) {
    return fail("cannot create temporary file " + temp.path().string() + ": " + errno_text(errno));
  }
  temp.fd.reset(fd_value);

  FileWriter writer(temp.fd.get());
  if (auto problem = write_content(writer)) return fail(std::move(*problem));
  writer.flush();
  if (writer.error() != 0) {
    return fail("cannot write " + temp.path().string() + ": " + errno_text(writer.error()));
  }
  if (::fsync(temp.fd.get()) != 0) {
    return fail("cannot sync " + temp.path().string() + ": " + errno_text(errno));
  }
  if (const int error = temp.fd.close(); error != 0) {
    return fail("cannot close " + temp.path().string() + ": " + errno_text(error));
  }

  if (hooks.before_rename && !hooks.before_rename()) {
    return fail("aborted before the rename; the old file is unchanged");
  }
  if (::rename(temp.path().c_str(), path.c_str()) != 0) {
    return fail("cannot rename " + temp.path().string() + " over it: " + errno_text(errno));
  }
  temp.mark_renamed();

  // The rename lives in the folder; until the folder is synced a crash of the machine may
  // bring the old file back. The new file is in place and whole all the same, so a folder that
  // cannot be synced makes the write less durable, not failed: reporting a failure would make
  // the caller (the trainer exits 1) treat a safe file as lost.
  std::filesystem::path folder = path.parent_path();
  if (folder.empty()) folder = ".";
  const FileDescriptor folder_fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  int sync_error = folder_fd.valid() ? 0 : errno;
  if (sync_error == 0) {
    if (hooks.sync_folder) {
      sync_error = hooks.sync_folder(folder_fd.get());
    } else if (::fsync(folder_fd.get()) != 0) {
      sync_error = errno;
    }
  }
  if (sync_error != 0) {
    return DurableFileWritten{"cannot sync its folder " + folder.string() + ": " +
                              errno_text(sync_error)};
  }
  return DurableFileWritten{};
}

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
