#pragma once
// zlib's gz* error reports in the words of this project's messages, which start with the path.
// Shared by the log writer (log_file.cpp) and zlib's reading (compressed_input.cpp).

#include <cstring>
#include <filesystem>
#include <string>

namespace ssl_formation {
inline namespace files {
namespace detail {

// gzopen and gzclose leave errno at 0 when they fail for want of memory.
inline std::string zlib_errno_text(int err) {
  return err != 0 ? std::strerror(err) : "out of memory";
}

// zlib prefixes its messages with the path it was given; ours already start with it.
inline std::string without_path(std::string message, const std::filesystem::path& path) {
  const std::string prefix = path.string() + ": ";
  if (message.compare(0, prefix.size(), prefix) == 0) message.erase(0, prefix.size());
  return message;
}

}  // namespace detail
}  // namespace files
}  // namespace ssl_formation
