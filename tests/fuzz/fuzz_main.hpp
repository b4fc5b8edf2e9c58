#pragma once
// What the libFuzzer targets share: a scratch folder per process under /tmp for the
// files the readers need, protobuf's per-packet error log silenced, and the abort that turns
// a broken invariant into a finding.

#include <google/protobuf/stubs/logging.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace ssl_formation::fuzz {

// Created on first use, removed when the process exits normally.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& target)
      : path_(std::filesystem::temp_directory_path() /
              ("sslf-fuzz-" + target + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// ParseFromArray logs every packet that lacks a required field; thousands per second of fuzzing.
inline void silence_protobuf() {
  google::protobuf::SetLogHandler(
      [](google::protobuf::LogLevel level, const char*, int, const std::string& message) {
        if (level >= google::protobuf::LOGLEVEL_FATAL)
          std::fprintf(stderr, "%s\n", message.c_str());
      });
}

inline void abort_on(const std::string& violation) {
  if (violation.empty()) return;
  std::fprintf(stderr, "INVARIANT BROKEN: %s\n", violation.c_str());
  std::abort();
}

}  // namespace ssl_formation::fuzz
