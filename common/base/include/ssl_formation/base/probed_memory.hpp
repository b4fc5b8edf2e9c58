#pragma once
// Memory for arrays a hot path probes at random after sleeping (the motion model's estimate index)
// or fills at random while training (the motion table's rows and their index).

#include <cstddef>

namespace ssl_formation {
inline namespace base {

// Memory for large arrays probed at random: whole 2 MiB pages, with transparent huge pages
// asked for (Linux, where /sys/kernel/mm/transparent_hugepage/enabled allows it), so that one TLB
// entry covers the array where 4 KiB pages would cost a page walk per probe in a process that
// has slept since its last frame, and filling it takes a page fault per 2 MiB rather than per
// 4 KiB. Small arrays are allocated as usual, aligned to 64 bytes.
inline constexpr std::size_t huge_page_bytes = std::size_t{2} << 20;
void* allocate_probed(std::size_t bytes);
void free_probed(void* memory, std::size_t bytes);
template <typename T>
struct ProbedAllocator {
  using value_type = T;
  ProbedAllocator() = default;
  template <typename U>
  ProbedAllocator(const ProbedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_probed(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) { free_probed(p, n * sizeof(T)); }
  friend bool operator==(const ProbedAllocator&, const ProbedAllocator&) { return true; }
};

}  // namespace base
}  // namespace ssl_formation
