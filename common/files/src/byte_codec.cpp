#include "ssl_formation/files/byte_codec.hpp"

#include <zlib.h>

#include <algorithm>

namespace ssl_formation {
inline namespace files {
namespace detail {

std::uint32_t crc_initial() { return static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0)); }

// zlib's crc32 takes a uInt length; our chunks are far below that, but large spans are split
// anyway so the function is correct for any size.
std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* data, std::size_t size) {
  uLong value = crc;
  while (size > 0) {
    const std::size_t part = std::min<std::size_t>(size, std::numeric_limits<uInt>::max());
    value = ::crc32(value, data, static_cast<uInt>(part));
    data += part;
    size -= part;
  }
  return static_cast<std::uint32_t>(value);
}

std::uint32_t crc_of(const std::uint8_t* data, std::size_t size) {
  return crc_update(crc_initial(), data, size);
}

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
