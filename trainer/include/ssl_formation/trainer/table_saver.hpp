#pragma once
// Saving tables off the thread that reads the feed. Pruning and writing a big table takes a
// good part of a second; on the io thread that is a second of packets left in the socket's
// buffer at every save. The io thread only copies the table (TableSnapshot) and hands it here;
// a thread of its own prunes and writes it. A newer snapshot of a file whose save has not begun
// replaces the older one: only the latest counts.

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "ssl_formation/models/table_budget.hpp"
#include "ssl_formation/trainer/table_store.hpp"

namespace ssl_formation::trainer {

class TableSaver {
 public:
  // `hooks`: save_table's, for tests that hold a save at its end.
  explicit TableSaver(SaveHooks hooks = {});
  // Finishes every save handed in, then stops the thread.
  ~TableSaver();
  TableSaver(const TableSaver&) = delete;
  TableSaver& operator=(const TableSaver&) = delete;

  void submit(const std::filesystem::path& path, TableSnapshot snapshot, const TableBudget& budget);
  // Blocks until every save handed in is done. False if one failed since the last wait.
  bool wait();
  std::uint64_t saved() const;  // saves done, failed or not

 private:
  struct Job {
    TableSnapshot snapshot;
    TableBudget budget;
  };
  void run();

  SaveHooks hooks_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::filesystem::path, Job> pending_;
  bool busy_ = false;
  bool stopping_ = false;
  bool failed_ = false;
  std::uint64_t saved_ = 0;
  std::thread thread_;  // last: it starts once everything above is in place
};

}  // namespace ssl_formation::trainer
