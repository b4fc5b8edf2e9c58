#pragma once
// One writer per table: two ssl-trainers saving the same file would each overwrite the other's
// counts at every save, without a word. A writer holds an exclusive flock(2) on a lock file
// beside its table ("TABLE.lock", or ".ssl-trainer.lock" in a --table-dir) for as long as it
// runs; a second writer is refused at start, told which process holds it. A writer that stops
// removes the file, still holding the lock, so a clean stop leaves nothing in the user's folder;
// a writer that starts meanwhile and finds its locked file gone from the path takes the lock
// again on the path's new file. The kernel releases the lock however the holder ends, so a
// killed one's file stays, unlocked, and is taken over by the next writer: no stale lock ever
// blocks a start.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace ssl_formation {
inline namespace files {

class TableLockError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class TableWriterLock {
 public:
  // The lock for the table file `table`, or for every table in the folder `table_dir`.
  static std::filesystem::path lock_path_for_table(const std::filesystem::path& table);
  static std::filesystem::path lock_path_for_folder(const std::filesystem::path& table_dir);

  // Takes the lock at `lock_path` for `what` (the table or folder, as the user named it), and
  // writes this process's id into it. Throws TableLockError when another process holds it
  // ("... is written by another process (pid 1234) ...") or the file cannot be opened.
  TableWriterLock(const std::filesystem::path& lock_path, const std::string& what);
  // Removes the lock file and releases the lock.
  ~TableWriterLock();
  TableWriterLock(const TableWriterLock&) = delete;
  TableWriterLock& operator=(const TableWriterLock&) = delete;
  TableWriterLock(TableWriterLock&& other) noexcept;
  TableWriterLock& operator=(TableWriterLock&&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace files
}  // namespace ssl_formation
