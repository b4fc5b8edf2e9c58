#pragma once
// A fresh folder under the system's temporary folder for one in-process test, removed with
// everything in it. Header-only, so the programs' unit tests share it without linking the
// process-test support (child_process.cpp has its own TempDir for the process tests).

#include <stdlib.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace ssl_formation::testing {

class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix = "sslf-test") {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace ssl_formation::testing
