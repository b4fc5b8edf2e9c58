#include "ssl_formation/base/probed_memory.hpp"

#include <sys/mman.h>

#include <cstdint>
#include <new>

namespace ssl_formation {
inline namespace base {

namespace {
// Below this an array is allocated as usual: a huge page would be mostly empty.
constexpr std::size_t probed_min_bytes = std::size_t{128} << 10;
// Small arrays are aligned to a cache line (the index's slots are one line each).
constexpr std::align_val_t probed_alignment{64};
std::size_t huge_pages_of(std::size_t bytes) {
  return (bytes + huge_page_bytes - 1) / huge_page_bytes * huge_page_bytes;
}
}  // namespace

// Large arrays are mapped from the kernel and unmapped when freed, not taken from malloc: glibc
// raises its mapping threshold each time a mapped block is freed, after which blocks this large
// come from the heap, whose holes it never gives back. A table pruned while it learns frees its
// old rows once a while; through malloc the process's memory stayed at its largest table's.
void* allocate_probed(std::size_t bytes) {
  if (bytes < probed_min_bytes) return ::operator new(bytes, probed_alignment);
  const std::size_t size = huge_pages_of(bytes);
  // A huge page more than needed, and the ends cut off, so that the array starts on one.
  const std::size_t mapped = size + huge_page_bytes;
  void* map = ::mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (map == MAP_FAILED) throw std::bad_alloc();
  const auto start = reinterpret_cast<std::uintptr_t>(map);
  const std::uintptr_t aligned = (start + huge_page_bytes - 1) / huge_page_bytes * huge_page_bytes;
  if (aligned > start) ::munmap(map, aligned - start);
  const std::size_t tail = start + mapped - (aligned + size);
  if (tail > 0) ::munmap(reinterpret_cast<void*>(aligned + size), tail);
  void* memory = reinterpret_cast<void*>(aligned);
#ifdef MADV_HUGEPAGE
  ::madvise(memory, size, MADV_HUGEPAGE);  // advice only: without it, 4 KiB pages
#endif
  return memory;
}

void free_probed(void* memory, std::size_t bytes) {
  if (bytes < probed_min_bytes) {
    ::operator delete(memory, probed_alignment);
  } else {
    ::munmap(memory, huge_pages_of(bytes));
  }
}

}  // namespace base
}  // namespace ssl_formation
