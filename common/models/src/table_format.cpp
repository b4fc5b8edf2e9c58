#include "table_format.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace ssl_formation {
inline namespace models {
namespace detail {

TableHeader header_for(const TransitionTable& table, const TableMetadata& metadata,
                       std::uint32_t version) {
  const bool dense = table.is_dense();
  const std::uint64_t states = table.codec().state_count();
  TableHeader header;
  header.version = version;
  header.length = static_cast<std::uint32_t>(table.grid().length());
  header.width = static_cast<std::uint32_t>(table.grid().width());
  header.encoding = dense ? encoding_dense : encoding_sparse;
  header.metadata = metadata;
  std::uint64_t sparse_rows = 0;
  std::uint64_t nonzero = 0;
  std::optional<StateIndex> last_from;
  table.for_each_nonzero([&](StateIndex from, StateIndex, TransitionTable::Count count) {
    if (!last_from || *last_from != from) ++sparse_rows;
    last_from = from;
    ++nonzero;
    header.transitions += count;
  });
  header.rows = dense ? states : sparse_rows;
  header.entries = dense ? states * states : nonzero;
  return header;
}

std::array<std::uint8_t, header_size> encode_header(const TableHeader& header) {
  std::array<std::uint8_t, header_size> out{};
  std::copy(table_magic.begin(), table_magic.end(), out.begin());
  put_u32(&out[8], header.version);
  put_u32(&out[12], header.length);
  put_u32(&out[16], header.width);
  put_u32(&out[20], header.encoding);
  put_f64(&out[24], header.metadata.field.length_mm);
  put_f64(&out[32], header.metadata.field.width_mm);
  put_f64(&out[40], header.metadata.step_s);
  put_u64(&out[48], header.metadata.samples);
  put_u64(&out[56], header.transitions);
  put_u64(&out[64], header.rows);
  put_u64(&out[72], header.entries);
  put_u32(&out[header_fields_size], crc_of(out.data(), header_fields_size));
  return out;
}

TableHeader decode_header(const std::uint8_t* in) {
  TableHeader header;
  header.version = get_u32(&in[8]);
  header.length = get_u32(&in[12]);
  header.width = get_u32(&in[16]);
  header.encoding = get_u32(&in[20]);
  header.metadata.field.length_mm = get_f64(&in[24]);
  header.metadata.field.width_mm = get_f64(&in[32]);
  header.metadata.step_s = get_f64(&in[40]);
  header.metadata.samples = get_u64(&in[48]);
  header.transitions = get_u64(&in[56]);
  header.rows = get_u64(&in[64]);
  header.entries = get_u64(&in[72]);
  return header;
}

bool valid_step(double step_s) { return std::isfinite(step_s) && step_s > 0.0; }

std::optional<std::string> header_problem(const TableHeader& header) {
  const std::uint32_t max = static_cast<std::uint32_t>(Grid::max_cells);
  if (header.length < 1 || header.width < 1 || header.length > max || header.width > max ||
      header.length * header.width > max) {
    return "invalid grid " + std::to_string(header.length) + "x" + std::to_string(header.width) +
           " in the header";
  }
  if (!header.metadata.field.valid()) return std::string("invalid field size in the header");
  if (!valid_step(header.metadata.step_s)) return std::string("invalid step in the header");
  const std::uint64_t cells = std::uint64_t{header.length} * header.width;
  const std::uint64_t states = cells * cells * cells;
  if (header.encoding == encoding_dense) {
    if (header.rows != states || header.entries != states * states) {
      return std::string("dense row and entry counts do not match the grid");
    }
  } else if (header.encoding == encoding_sparse) {
    // Every row record holds at least one entry and at most S.
    if (header.rows > states || header.entries < header.rows ||
        header.entries > header.rows * states) {
      return std::string("sparse row and entry counts are inconsistent");
    }
  } else {
    return "unknown count encoding " + std::to_string(header.encoding);
  }
  if (header.entries == 0 && header.transitions != 0) {
    return std::string("nonzero transition total with no counts");
  }
  return std::nullopt;
}

std::uint64_t counts_size(const TableHeader& header) {
  return header.encoding == encoding_dense ? header.entries * 4
                                           : header.rows * 8 + header.entries * 8;
}

namespace {

ReadProblem read_dense_counts(ChunkReader& reader, TransitionTable& table, std::uint64_t& sum) {
  const StateIndex states = table.codec().state_count();
  for (StateIndex from = 0; from < states; ++from) {
    for (StateIndex to = 0; to < states; ++to) {
      std::uint32_t count = 0;
      if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
      if (count == 0) continue;
      table.add(from, to, count);
      sum += count;
    }
  }
  return {};
}

ReadProblem read_sparse_counts(ChunkReader& reader, const TableHeader& header,
                               TransitionTable& table, std::uint64_t& sum) {
  const StateIndex states = table.codec().state_count();
  std::uint64_t entries_read = 0;
  std::optional<StateIndex> previous_from;
  for (std::uint64_t row = 0; row < header.rows; ++row) {
    std::uint32_t from = 0;
    std::uint32_t n = 0;
    if (const int error = reader.read_u32(from); error != 0) return {std::nullopt, error};
    if (const int error = reader.read_u32(n); error != 0) return {std::nullopt, error};
    const std::string where =
        "row record " + std::to_string(row) + " (from state " + std::to_string(from) + ")";
    if (from >= states) return {where + ": state index out of range", 0};
    if (previous_from && from <= *previous_from) return {where + ": rows out of order", 0};
    if (n == 0 || n > header.entries - entries_read) {
      return {where + ": entry count " + std::to_string(n) + " is inconsistent", 0};
    }
    previous_from = from;
    std::optional<StateIndex> previous_to;
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint32_t to = 0;
      std::uint32_t count = 0;
      if (const int error = reader.read_u32(to); error != 0) return {std::nullopt, error};
      if (const int error = reader.read_u32(count); error != 0) return {std::nullopt, error};
      if (to >= states) return {where + ": target state index out of range", 0};
      if (previous_to && to <= *previous_to) return {where + ": targets out of order", 0};
      if (count == 0) return {where + ": zero count stored", 0};
      previous_to = to;
      table.add(from, to, count);
      sum += count;
    }
    entries_read += n;
  }
  if (entries_read != header.entries) {
    return {"the rows hold " + std::to_string(entries_read) + " entries, the header says " +
                std::to_string(header.entries),
            0};
  }
  return {};
}

std::optional<std::string> write_dense_counts(FileWriter& writer, const TransitionTable& table) {
  // Fill the zeros between the nonzero counts that for_each_nonzero visits in order. Were that
  // order ever broken, `index - next` would wrap and fill the disk, so it is checked.
  const std::uint64_t states = table.codec().state_count();
  std::uint64_t next = 0;
  bool in_order = true;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    const std::uint64_t index = std::uint64_t{from} * states + to;
    if (!in_order || index < next) {
      in_order = false;
      return;
    }
    writer.write_zero_u32s(index - next);
    writer.write_u32(count);
    next = index + 1;
  });
  writer.write_zero_u32s(states * states - next);
  if (!in_order) return std::string("the table listed its counts out of order");
  return std::nullopt;
}

void write_sparse_counts(FileWriter& writer, const TransitionTable& table) {
  // One row is buffered because its record starts with its entry count.
  std::vector<std::pair<StateIndex, TransitionTable::Count>> row;
  std::optional<StateIndex> row_from;
  const auto write_row = [&] {
    if (!row_from) return;
    writer.write_u32(*row_from);
    writer.write_u32(static_cast<std::uint32_t>(row.size()));
    for (const auto& [to, count] : row) {
      writer.write_u32(to);
      writer.write_u32(count);
    }
    row.clear();
  };
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    if (row_from != from) {
      write_row();
      row_from = from;
    }
    row.emplace_back(to, count);
  });
  write_row();
}

}  // namespace

ReadProblem read_counts(ChunkReader& reader, const TableHeader& header, TransitionTable& table,
                        std::uint64_t& sum) {
  return header.encoding == encoding_dense ? read_dense_counts(reader, table, sum)
                                           : read_sparse_counts(reader, header, table, sum);
}

std::optional<std::string> write_counts(FileWriter& writer, const TransitionTable& table) {
  if (table.is_dense()) return write_dense_counts(writer, table);
  write_sparse_counts(writer, table);
  return std::nullopt;
}

}  // namespace detail
}  // namespace models
}  // namespace ssl_formation
