#pragma once
// A cache hint shared by the table's row map and the history: both know a moment ahead which
// object they will read.

#include <cstddef>

namespace ssl_formation {
inline namespace motion_model {
namespace detail {

// Fetches every cache line `object` spans into the cache (a hint: nothing waits for it).
template <typename T>
void prefetch_object(const T& object) {
  const char* bytes = reinterpret_cast<const char*>(&object);
  for (std::size_t at = 0; at < sizeof(T); at += 64) __builtin_prefetch(bytes + at);
  __builtin_prefetch(bytes + sizeof(T) - 1);  // an object not aligned to a line spans one more
}

}  // namespace detail
}  // namespace motion_model
}  // namespace ssl_formation
