#pragma once
// The encodings of the table file and its CRC-32: fixed-width integers little-endian, byte by
// byte so that the host's layout never matters, doubles as their IEEE-754 bits in a u64, and the
// compact motion section's varints.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace ssl_formation {
inline namespace files {
namespace detail {

static_assert(std::numeric_limits<double>::is_iec559, "doubles are stored as IEEE-754 bits");

inline void put_u32(std::uint8_t* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
inline void put_u64(std::uint8_t* out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
inline void put_f64(std::uint8_t* out, double value) {
  put_u64(out, std::bit_cast<std::uint64_t>(value));
}

inline std::uint32_t get_u32(const std::uint8_t* in) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= std::uint32_t{in[i]} << (8 * i);
  return value;
}
inline std::uint64_t get_u64(const std::uint8_t* in) {
  std::uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value |= std::uint64_t{in[i]} << (8 * i);
  return value;
}
inline double get_f64(const std::uint8_t* in) { return std::bit_cast<double>(get_u64(in)); }

// The variable-length encodings of the compact motion section (format version 5): an unsigned
// integer in 7-bit groups, least significant first, the high bit set on every byte but the
// last (LEB128); a signed one zigzagged first, so that small magnitudes of either sign are short.
inline std::size_t varint_size(std::uint64_t value) {
  std::size_t size = 1;
  while (value >= 0x80) {
    value >>= 7;
    ++size;
  }
  return size;
}
template <typename Bytes>
void append_varint(Bytes& out, std::uint64_t value) {
  while (value >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(value | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(value));
}
inline std::uint64_t zigzag(std::int64_t value) {
  return (static_cast<std::uint64_t>(value) << 1) ^ static_cast<std::uint64_t>(value >> 63);
}
inline std::int64_t unzigzag(std::uint64_t value) {
  return static_cast<std::int64_t>(value >> 1) ^ -static_cast<std::int64_t>(value & 1);
}
// Reads a varint at `pos`, advancing it; false if it runs past `end` or does not fit in 64
// bits (then `pos` is unspecified).
inline bool read_varint(const std::uint8_t*& pos, const std::uint8_t* end, std::uint64_t& value) {
  value = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (pos == end) return false;
    const std::uint8_t byte = *pos++;
    const std::uint64_t bits = byte & 0x7f;
    // The tenth byte holds the 64th bit alone.
    if (shift == 63 && bits > 1) return false;
    value |= bits << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

// CRC-32 (zlib's: the polynomial of gzip and PNG). crc_update continues `crc` over `data`, so a
// file's checksum can be kept chunk by chunk; crc_initial() is the CRC of nothing.
std::uint32_t crc_initial();
std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* data, std::size_t size);
std::uint32_t crc_of(const std::uint8_t* data, std::size_t size);

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
