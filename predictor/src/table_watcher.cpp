#include "ssl_formation/predictor/table_watcher.hpp"

#include <sys/stat.h>

namespace ssl_formation::predictor {

TableWatcher::TableWatcher(std::filesystem::path path, Grid expected_grid, TableFileLoader load)
    : path_(std::move(path)), expected_grid_(expected_grid), load_(std::move(load)) {}

std::optional<TableWatcher::Identity> TableWatcher::identify() const {
  struct stat info {};
  if (::stat(path_.c_str(), &info) != 0) return std::nullopt;
  return Identity{
      static_cast<std::uintmax_t>(info.st_ino),
      static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1000000000 + info.st_mtim.tv_nsec,
      static_cast<std::uintmax_t>(info.st_size)};
}

TableWatcher::Change TableWatcher::poll() {
  const std::optional<Identity> now = identify();
  if (!now || (seen_ && *now == *seen_)) return Change::none;
  seen_ = now;
  auto loaded = load_ ? load_(path_, expected_grid_) : load_table(path_, expected_grid_);
  if (!loaded) {
    last_error_ = std::move(loaded).error().message;
    return Change::failed;
  }
  table_ = std::make_shared<const StoredTable>(std::move(*loaded));
  last_error_.clear();
  ++reloads_;
  return Change::loaded;
}

}  // namespace ssl_formation::predictor
