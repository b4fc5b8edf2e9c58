#pragma once
// Reads a byte range of a file through a fixed buffer, so that loading a table costs memory in
// proportion to the table it builds, never to the file. pread leaves the file offset alone and
// the caller's descriptor is read-only, so nothing here can change the file.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/files/byte_codec.hpp"

namespace ssl_formation {
inline namespace files {
namespace detail {

class ChunkReader {
 public:
  static constexpr std::size_t buffer_size = std::size_t{1} << 16;

  // The bytes [begin, end) of `fd`.
  ChunkReader(int fd, std::uint64_t begin, std::uint64_t end)
      : fd_(fd), next_(begin), end_(end), buffer_(buffer_size) {}

  // Each returns 0 on success, else an errno value; the end of the range or of the file before
  // `size` bytes reports ENODATA.
  int read(std::uint8_t* out, std::size_t size) {
    while (size > 0) {
      if (pos_ == filled_) {
        if (const int error = refill(); error != 0) return error;
      }
      const std::size_t part = std::min(size, filled_ - pos_);
      std::memcpy(out, &buffer_[pos_], part);
      pos_ += part;
      out += part;
      size -= part;
    }
    return 0;
  }
  int read_u32(std::uint32_t& value) {
    if (filled_ - pos_ >= 4) {  // the common case, without the copy
      value = get_u32(&buffer_[pos_]);
      pos_ += 4;
      return 0;
    }
    std::uint8_t bytes[4];
    if (const int error = read(bytes, 4); error != 0) return error;
    value = get_u32(bytes);
    return 0;
  }
  int read_u64(std::uint64_t& value) {
    std::uint8_t bytes[8];
    if (const int error = read(bytes, 8); error != 0) return error;
    value = get_u64(bytes);
    return 0;
  }
  // Continues `crc` over the rest of the range.
  int crc_update_to_end(std::uint32_t& crc);

 private:
  int refill();

  int fd_;
  std::uint64_t next_;
  std::uint64_t end_;
  std::vector<std::uint8_t> buffer_;
  std::size_t pos_ = 0;
  std::size_t filled_ = 0;
};

// Why reading a part of a file failed: a reason for inconsistent content, or an errno value
// for a read that failed (ENODATA: the file ended).
struct ReadProblem {
  std::optional<std::string> content;
  int read_error = 0;
  bool failed() const { return content || read_error != 0; }
};

// The CRC-32 of the bytes [begin, end) of `fd` into `crc`; 0 or an errno value as ChunkReader.
int crc_of_range(int fd, std::uint64_t begin, std::uint64_t end, std::uint32_t& crc);

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
