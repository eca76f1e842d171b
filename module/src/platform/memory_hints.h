// Private: hints to the memory system (cache prefetches), on every compiler.
//
// detail::prefetch(p) asks the caches to fetch the line at p (any address; nothing faults):
// - GCC and Clang on x86: an asm statement, not __builtin_prefetch: GCC 12 deletes a builtin
//   prefetch (with the loads that compute its address) when it sits under a condition, which is
//   where most of the ROAM core's are;
// - GCC and Clang elsewhere: __builtin_prefetch;
// - MSVC on x86: _mm_prefetch;
// - anything else, and builds with RIDGELINE_PORTABLE: nothing (a hint only: the results are
//   the same, the changes of an update wait for their memory one at a time).
#pragma once

#if !defined(RIDGELINE_PORTABLE) && defined(_MSC_VER) && \
    (defined(_M_X64) || defined(_M_IX86))
#include <xmmintrin.h>
#endif

namespace ridgeline::detail {

inline void prefetch(const void* p) noexcept {
#if defined(RIDGELINE_PORTABLE)
  (void)p;
#elif (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
  asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(p)));
#elif defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#elif defined(_MSC_VER) && (defined(_M_X64) || defined(_M_IX86))
  _mm_prefetch(static_cast<const char*>(p), _MM_HINT_T0);
#else
  (void)p;
#endif
}

}  // namespace ridgeline::detail
