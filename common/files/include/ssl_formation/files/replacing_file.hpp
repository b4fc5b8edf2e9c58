#pragma once
// An output file replaced only when the run that writes it succeeds: the text goes to a
// temporary file beside the target (same folder, so the rename stays within one file system)
// and is renamed over the target by commit(). A run that fails or throws before commit() leaves
// the target as it was and removes the temporary file. What the CSVs, reports, prediction files
// and logs of every program are written through. A target that exists and is not a regular file
// (/dev/null, /dev/stdout, a pipe) is written to directly: it is not a file to replace.

#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>

namespace ssl_formation {
inline namespace files {

class ReplacingFile {
 public:
  // Opens the temporary file; throws std::runtime_error naming the target when it cannot.
  explicit ReplacingFile(std::filesystem::path target, bool binary = false);
  ReplacingFile(const ReplacingFile&) = delete;
  ReplacingFile& operator=(const ReplacingFile&) = delete;
  // Removes the temporary file unless committed.
  ~ReplacingFile();

  std::ostream& stream() { return out_; }
  const std::filesystem::path& target() const { return target_; }
  bool good() const { return static_cast<bool>(out_); }
  // Flushes and closes the temporary file and renames it over the target. Throws
  // std::runtime_error naming the target when anything failed (a full disk); the target is then
  // as it was.
  void commit();
  // Gives the run up: the temporary file goes, the target stays as it was.
  void discard();
  bool committed() const { return committed_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::ofstream out_;
  bool in_place_ = false;
  bool committed_ = false;
};

// A temporary name beside `target` that no other process or file of this one uses.
std::filesystem::path temporary_beside(const std::filesystem::path& target);
// Whether `target` is written to directly rather than replaced: it exists and is not a regular
// file (a device, a pipe, a terminal).
bool written_in_place(const std::filesystem::path& target);

}  // namespace files
}  // namespace ssl_formation
