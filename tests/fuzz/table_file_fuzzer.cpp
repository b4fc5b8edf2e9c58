// libFuzzer target: bytes as a table file -> load_table (as given and with its checksums
// fixed), the file left byte-identical, and save/load round trips of whatever loads.

#include <cstddef>
#include <cstdint>

#include "fuzz_main.hpp"
#include "fuzz_paths.hpp"

namespace {
const ssl_formation::fuzz::ScratchDir& scratch() {
  static const ssl_formation::fuzz::ScratchDir dir("table");
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
      ssl_formation::fuzz::run_table_path(data, size, scratch().path()).violation);
  return 0;
}
