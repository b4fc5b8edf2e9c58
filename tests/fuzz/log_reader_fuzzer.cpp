// libFuzzer target: bytes as an official SSL log file (plain or gzip) -> LogReader, and the
// vision packets it yields through the sampler, as a replay does.

#include <cstddef>
#include <cstdint>

#include "fuzz_main.hpp"
#include "fuzz_paths.hpp"

namespace {
const ssl_formation::fuzz::ScratchDir& scratch() {
  static const ssl_formation::fuzz::ScratchDir dir("log");
  return dir;
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ssl_formation::fuzz::silence_protobuf();
  scratch();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ssl_formation::fuzz::abort_on(
      ssl_formation::fuzz::run_log_path(data, size, scratch().path()).violation);
  return 0;
}
