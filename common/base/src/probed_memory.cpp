#include "ssl_formation/base/probed_memory.hpp"

#include <sys/mman.h>

#include <cstdlib>
#include <new>

namespace ssl_formation {

namespace {
// Below this an array is allocated as usual: a huge page would be mostly empty.
constexpr std::size_t probed_min_bytes = std::size_t{128} << 10;
// Small arrays are aligned to a cache line (the index's slots are one line each).
constexpr std::align_val_t probed_alignment{64};
std::size_t huge_pages_of(std::size_t bytes) {
  return (bytes + huge_page_bytes - 1) / huge_page_bytes * huge_page_bytes;
}
}  // namespace

void* allocate_probed(std::size_t bytes) {
  if (bytes < probed_min_bytes) return ::operator new(bytes, probed_alignment);
  const std::size_t size = huge_pages_of(bytes);
  void* memory = std::aligned_alloc(huge_page_bytes, size);
  if (!memory) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  ::madvise(memory, size, MADV_HUGEPAGE);  // advice only: without it, 4 KiB pages
#endif
  return memory;
}

void free_probed(void* memory, std::size_t bytes) {
  if (bytes < probed_min_bytes) {
    ::operator delete(memory, probed_alignment);
  } else {
    std::free(memory);
  }
}

}  // namespace ssl_formation
