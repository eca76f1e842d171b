// Private: hints to the operating system about large, long-lived arrays.
#pragma once

#include <cstddef>
#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

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

/// Asks for transparent huge pages (2 MiB) under the whole 2 MiB-aligned pages inside
/// [p, p + bytes): randomly accessed arrays of many megabytes (the landscape's bound records,
/// a view's node chunks) otherwise miss the TLB on almost every access. Already touched pages are
/// collapsed in place where the kernel can (Linux 6.1+); elsewhere, or when the system refuses,
/// nothing changes. Never fails.
inline void advise_huge_pages(const void* p, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (end <= begin) return;
  void* a = reinterpret_cast<void*>(begin);
  (void)madvise(a, end - begin, MADV_HUGEPAGE);
#ifndef MADV_COLLAPSE
#define MADV_COLLAPSE 25
#endif
  (void)madvise(a, end - begin, MADV_COLLAPSE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace ridgeline::detail
