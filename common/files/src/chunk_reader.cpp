#include "ssl_formation/files/chunk_reader.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace ssl_formation {
inline namespace files {
namespace detail {

int ChunkReader::crc_update_to_end(std::uint32_t& crc) {
  while (true) {
    if (pos_ == filled_) {
      if (next_ == end_) return 0;
      if (const int error = refill(); error != 0) return error;
    }
    crc = crc_update(crc, &buffer_[pos_], filled_ - pos_);
    pos_ = filled_;
  }
}

int ChunkReader::refill() {
  if (next_ >= end_) return ENODATA;
  const std::size_t want =
      static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size(), end_ - next_));
  ssize_t got = 0;
  do {
    got = ::pread(fd_, buffer_.data(), want, static_cast<off_t>(next_));
  } while (got < 0 && errno == EINTR);
  if (got < 0) return errno;
  if (got == 0) return ENODATA;  // the file shrank under us
  next_ += static_cast<std::uint64_t>(got);
  pos_ = 0;
  filled_ = static_cast<std::size_t>(got);
  return 0;
}

int crc_of_range(int fd, std::uint64_t begin, std::uint64_t end, std::uint32_t& crc) {
  crc = crc_initial();
  ChunkReader reader(fd, begin, end);
  return reader.crc_update_to_end(crc);
}

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
