#pragma once
// A file's bytes as they were before gzip compressed them: a gzip file (one member or several
// concatenated, as `cat a.gz b.gz` makes) is inflated, any other file is read as it is. ISA-L's
// inflate (libisal) is several times faster than zlib's, which bounded reading a `.log.gz`; zlib
// stays for builds without ISA-L and for what is not a regular file (a pipe cannot be peeked at).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "ssl_formation/base/result.hpp"

namespace ssl_formation {
inline namespace files {

// What inflates gzip data. automatic: ISA-L wherever it can, else zlib. The other two are for
// tests and benchmarks that compare them; isal on a build without ISA-L is refused.
enum class Inflater { automatic, zlib, isal };

// Whether this build has ISA-L (the CMake option SSLF_ISAL, on where libisal-dev is installed).
bool isal_available();

class CompressedInput {
 public:
  // Opens `path` for reading; the error names the path and the cause.
  static Result<CompressedInput> open(const std::filesystem::path& path,
                                      Inflater inflater = Inflater::automatic);

  CompressedInput(CompressedInput&&) noexcept;
  CompressedInput& operator=(CompressedInput&&) noexcept;
  ~CompressedInput();

  // Up to `size` uncompressed bytes into `buffer`; 0 only at the end of the data or after a
  // fault. A read of kDirectReadSize or more from a plain file lands straight in `buffer`.
  std::size_t read(char* buffer, std::size_t size);
  static constexpr std::size_t kDirectReadSize = 32 * 1024;

  // Why reading stopped early: cut_off when a gzip stream just stops (a plain file's end is
  // always clean here: only its reader knows where a record was cut), damaged for corrupt gzip
  // data or a failed read. Bytes read before the fault are good as far as the inflater can tell.
  enum class Fault { none, cut_off, damaged };
  Fault fault() const;
  // What the damage is, for example "invalid block type" or "Input/output error"; empty when
  // there is no fault or the stream is only cut off.
  const std::string& fault_message() const;

  // The file on disk: its size (0 when unknown, as for a pipe) and how far into it reading has
  // got, for progress bars.
  std::uint64_t compressed_size() const { return compressed_size_; }
  std::uint64_t compressed_offset() const;
  // What reads the file: isal for a gzip file inflated by ISA-L, zlib for anything else (zlib
  // reads a plain file through as it is).
  Inflater inflater() const;

  // Each way of reading a file, behind read(); defined in compressed_input.cpp.
  class Source;

 private:
  explicit CompressedInput(std::unique_ptr<Source> source);

  std::unique_ptr<Source> source_;
  std::uint64_t compressed_size_ = 0;
};

}  // namespace files
}  // namespace ssl_formation
