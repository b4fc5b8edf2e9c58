#include "ssl_formation/files/replacing_file.hpp"

#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <system_error>

namespace ssl_formation {
inline namespace files {

std::filesystem::path temporary_beside(const std::filesystem::path& target) {
  // The pid keeps processes apart, the counter keeps concurrent writes of one process apart.
  static std::atomic<unsigned> next{0};
  std::filesystem::path temporary = target;
  temporary += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(next++);
  return temporary;
}

bool written_in_place(const std::filesystem::path& target) {
  std::error_code error;
  const auto status = std::filesystem::status(target, error);
  return !error && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status);
}

ReplacingFile::ReplacingFile(std::filesystem::path target, bool binary)
    : target_(std::move(target)), in_place_(written_in_place(target_)) {
  temporary_ = in_place_ ? target_ : temporary_beside(target_);
  out_.open(temporary_, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
  if (!out_) {
    throw std::runtime_error("cannot write " + target_.string() + ": cannot create a file in " +
                             (target_.has_parent_path() ? target_.parent_path().string() : "."));
  }
}

ReplacingFile::~ReplacingFile() {
  if (!committed_) discard();
}

void ReplacingFile::commit() {
  if (committed_) return;
  out_.flush();
  const bool written = static_cast<bool>(out_);
  out_.close();
  if (!written || out_.fail()) {
    discard();
    throw std::runtime_error("cannot write " + target_.string() + " (left as it was)");
  }
  std::error_code error;
  if (!in_place_) std::filesystem::rename(temporary_, target_, error);
  if (error) {
    discard();
    throw std::runtime_error("cannot replace " + target_.string() + ": " + error.message());
  }
  committed_ = true;
}

void ReplacingFile::discard() {
  if (out_.is_open()) out_.close();
  if (in_place_) return;
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

}  // namespace files
}  // namespace ssl_formation
