#pragma once
// Follows the trainer's table file: loads it when it appears and again whenever it is replaced
// (the trainer renames a new file over the old one, which changes its inode and mtime). A file
// that fails to load is reported once and the table in use is kept.

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/models/table_file.hpp"

namespace ssl_formation::predictor {

// How a table file is read: load_table, or a test's stand-in (one that takes its time).
using TableFileLoader =
    std::function<Result<StoredTable, TableLoadError>(const std::filesystem::path&, Grid)>;

class TableWatcher {
 public:
  // `load`: load_table when empty.
  TableWatcher(std::filesystem::path path, Grid expected_grid, TableFileLoader load = {});

  enum class Change { none, loaded, failed };
  // Looks at the file once; loads it if it changed since the last look.
  Change poll();

  // The table in use (nullptr until one loads). Shared, so that a prediction under way keeps
  // the table it started with while a reload replaces it here.
  const std::shared_ptr<const StoredTable>& table() const { return table_; }
  const std::string& last_error() const { return last_error_; }
  std::uint64_t reloads() const { return reloads_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct Identity {
    std::uintmax_t inode = 0;
    std::int64_t mtime_ns = 0;
    std::uintmax_t size = 0;
    friend bool operator==(const Identity&, const Identity&) = default;
  };
  std::optional<Identity> identify() const;

  std::filesystem::path path_;
  Grid expected_grid_;
  TableFileLoader load_;
  std::optional<Identity> seen_;
  std::shared_ptr<const StoredTable> table_;
  std::string last_error_;
  std::uint64_t reloads_ = 0;
};

}  // namespace ssl_formation::predictor
