// Private: hints to the memory system (cache prefetches).
#pragma once

#include <cstddef>
#include <cstdint>

namespace ridgeline::detail {

/// Asks the caches to fetch the line at p (any address; nothing faults). An asm statement, not
/// __builtin_prefetch: GCC 12 deletes a builtin prefetch (with the loads that compute its
/// address) when it sits under a condition, which is where most of the ROAM core's are.
inline void prefetch(const void* p) noexcept {
#if defined(__x86_64__) || defined(__i386__)
  asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(p)));
#else
  __builtin_prefetch(p);
#endif
}

}  // namespace ridgeline::detail
