#pragma once
// Table files as bytes, for the tests that read, patch and reseal them: the layout's header
// offsets (table_file.hpp), little-endian reads and writes, both checksums, and the kind and
// message of a load.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation::testing {

using Bytes = std::vector<std::uint8_t>;
using LoadResult = Result<StoredTable, TableLoadError>;

// The kind and message of a failed load or save. A load that succeeded has no kind and the
// message "(loaded)", so an expected failure that did not happen fails its expectation instead
// of reading an error that is not there.
inline std::optional<TableFileError> kind_of(const LoadResult& result) {
  if (result) return std::nullopt;
  return result.error().kind;
}
inline std::string message_of(const LoadResult& result) {
  return result ? "(loaded)" : result.error().message;
}
inline std::string message_of(const Result<TableSaved>& result) {
  return result ? "(saved)" : result.error().message;
}

// Offsets of the header documented in table_file.hpp; the tests patch fields through them.
inline constexpr std::size_t version_offset = 8;
inline constexpr std::size_t transitions_offset = 56;
inline constexpr std::size_t header_rows_offset = 64;
inline constexpr std::size_t header_checksum_offset = 80;
inline constexpr std::size_t header_size = 84;

inline Bytes read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void write_bytes(const std::filesystem::path& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

inline std::uint32_t get_u32(const Bytes& bytes, std::size_t offset) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= std::uint32_t{bytes[offset + i]} << (8 * i);
  return value;
}
inline std::uint64_t get_u64(const Bytes& bytes, std::size_t offset) {
  std::uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value |= std::uint64_t{bytes[offset + i]} << (8 * i);
  return value;
}
inline void put_u32(Bytes& bytes, std::size_t offset, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}
inline void put_u64(Bytes& bytes, std::size_t offset, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) bytes[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

inline std::uint32_t crc(const Bytes& bytes, std::size_t size) {
  return static_cast<std::uint32_t>(
      ::crc32(::crc32(0L, Z_NULL, 0), bytes.data(), static_cast<uInt>(size)));
}

// Rewrites both checksums, so that a test can plant content a checksum would otherwise catch.
inline void reseal(Bytes& bytes) {
  put_u32(bytes, header_checksum_offset, crc(bytes, header_checksum_offset));
  put_u32(bytes, bytes.size() - 4, crc(bytes, bytes.size() - 4));
}

}  // namespace ssl_formation::testing
