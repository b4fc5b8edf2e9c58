#pragma once
// The fixed-width encodings of the table file and its CRC-32: integers little-endian, byte by
// byte so that the host's layout never matters, and doubles as their IEEE-754 bits in a u64.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace ssl_formation::detail {

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

// CRC-32 (zlib's: the polynomial of gzip and PNG). crc_update continues `crc` over `data`, so a
// file's checksum can be kept chunk by chunk; crc_initial() is the CRC of nothing.
std::uint32_t crc_initial();
std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* data, std::size_t size);
std::uint32_t crc_of(const std::uint8_t* data, std::size_t size);

}  // namespace ssl_formation::detail
