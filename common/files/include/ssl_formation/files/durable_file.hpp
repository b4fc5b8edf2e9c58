#pragma once
// Replacing a file so that a reader or a crash never sees half of it (docs/models.md): the
// new content goes to a temporary file beside the target (`path` + ".tmp-<pid>-<n>", in the same
// folder so that the rename stays within one file system), is written whole, fsynced and
// closed, then renamed over the target, and the folder is fsynced. The one place that knows
// about partial writes, EINTR and fsync.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/base/result.hpp"
#include "ssl_formation/files/byte_codec.hpp"

namespace ssl_formation {
inline namespace files {
namespace detail {

// Writes through a fixed buffer, keeping the CRC-32 of everything written and the first error,
// so that callers inside a visitor (which cannot stop early) just keep going until the end.
class FileWriter {
 public:
  static constexpr std::size_t buffer_size = std::size_t{1} << 16;

  explicit FileWriter(int fd) : fd_(fd) { buffer_.reserve(buffer_size); }

  void write(const std::uint8_t* data, std::size_t size);
  void write_u32(std::uint32_t value) {
    std::uint8_t bytes[4];
    put_u32(bytes, value);
    write(bytes, 4);
  }
  void write_u64(std::uint64_t value) {
    std::uint8_t bytes[8];
    put_u64(bytes, value);
    write(bytes, 8);
  }
  void write_f64(double value) {
    std::uint8_t bytes[8];
    put_f64(bytes, value);
    write(bytes, 8);
  }
  void write_zero_u32s(std::uint64_t n);
  // Hands the buffer to the kernel, however many write calls that takes.
  void flush();
  std::uint32_t crc() const { return crc_; }
  int error() const { return error_; }  // the first errno of a failed write, or 0

 private:
  int fd_;
  std::vector<std::uint8_t> buffer_;
  std::uint32_t crc_ = crc_initial();
  int error_ = 0;
};

// Test hooks (SaveHooks in table_file.hpp says what they are for).
struct DurableFileHooks {
  // Called once the temporary file is written, fsynced and closed; false gives up before the
  // rename, as a crash would, except that the temporary file is removed.
  std::function<bool()> before_rename;
  // Replaces the fsync of the folder after the rename: 0 or an errno value.
  std::function<int(int folder_fd)> sync_folder;
};

struct DurableFileWritten {
  // Empty when the folder was synced after the rename. Otherwise why not ("cannot sync its
  // folder F: E"): the new file is in place, but a crash of the machine before the kernel writes
  // the folder back may bring the old one back.
  std::string folder_not_synced;
};

// Writes the content of the file; a reason to give up the write, or nothing.
using WriteContent = std::function<std::optional<std::string>(FileWriter&)>;

// Replaces `path` by what `write_content` writes. On failure (a reason that names the temporary
// file and the cause, or the reason `write_content` gave) the temporary file is removed and
// `path` is left as it was. Once the rename has succeeded the write succeeds.
Result<DurableFileWritten> write_file_durably(const std::filesystem::path& path,
                                              const WriteContent& write_content,
                                              const DurableFileHooks& hooks = {});

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
