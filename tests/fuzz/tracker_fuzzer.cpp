// libFuzzer target: tracker datagrams (TrackerWrapperPacket), each with its receive time -> one
// TrackedVision -> the frames it hands on through the sampler, as with --vision-source tracked.
// Input format: tests/fuzz/fuzz_paths.hpp.

#include <cstddef>
#include <cstdint>

#include "fuzz_main.hpp"
#include "fuzz_paths.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ssl_formation::fuzz::silence_protobuf();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ssl_formation::fuzz::abort_on(ssl_formation::fuzz::run_tracker_path(data, size).violation);
  return 0;
}
