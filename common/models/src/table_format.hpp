#pragma once
// The table file's header and the paper's counts, dense or sparse (the layout in table_file.hpp):
// encoding, decoding and the checks a header and the counts must pass.

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "ssl_formation/files/chunk_reader.hpp"
#include "ssl_formation/files/durable_file.hpp"
#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation {
inline namespace models {
namespace detail {

// Written with the file codec (files/byte_codec.hpp, chunk_reader.hpp, durable_file.hpp).
using namespace files::detail;

inline constexpr std::array<std::uint8_t, 8> table_magic = {'S', 'S', 'L', 'F', 'T', 'A', 'B', 'L'};
inline constexpr std::uint64_t version_offset = 8;
inline constexpr std::uint64_t header_fields_size = 80;  // everything the header checksum covers
inline constexpr std::uint64_t header_size = header_fields_size + 4;
inline constexpr std::uint64_t checksum_size = 4;  // the file checksum at the end
inline constexpr std::uint32_t encoding_dense = 0;
inline constexpr std::uint32_t encoding_sparse = 1;

// The table's dimensions as the file states them.
struct TableHeader {
  std::uint32_t version = 0;
  std::uint32_t length = 0;
  std::uint32_t width = 0;
  std::uint32_t encoding = 0;
  TableMetadata metadata;
  std::uint64_t transitions = 0;
  std::uint64_t rows = 0;
  std::uint64_t entries = 0;
};

// The header of `table` in a file of `version`, its totals counted from the very entries
// write_counts writes, so that header and counts always agree.
TableHeader header_for(const TransitionTable& table, const TableMetadata& metadata,
                       std::uint32_t version);
// The header's bytes, its checksum included.
std::array<std::uint8_t, header_size> encode_header(const TableHeader& header);
// The fields of a header's bytes (the magic and the checksum are the caller's to check).
TableHeader decode_header(const std::uint8_t* in);

bool valid_step(double step_s);
// Everything a header must satisfy before its sizes are trusted; a reason if it does not.
std::optional<std::string> header_problem(const TableHeader& header);
// The size of the counts a valid header announces.
std::uint64_t counts_size(const TableHeader& header);

// Reads the counts that follow a valid header into `table` (of the header's grid), adding them
// up in `sum`.
ReadProblem read_counts(ChunkReader& reader, const TableHeader& header, TransitionTable& table,
                        std::uint64_t& sum);
// Writes `table`'s counts, dense if the table is, else as sparse rows; a reason if the table
// listed them out of order (its bytes are then not a table).
std::optional<std::string> write_counts(FileWriter& writer, const TransitionTable& table);

}  // namespace detail
}  // namespace models
}  // namespace ssl_formation
