// The command line's processes on glibc: page-sized buffers (a world page's samples, bounds and
// ray pyramid, 100-300 KB each) are made on loader threads and freed on others. With glibc's
// defaults such buffers land in per-thread arenas once its dynamic mmap threshold has risen past
// them, and the arenas fragment: a 10-minute flight over the 65537^2 world held 285-305 MB with a
// 128 MiB page cache. One arena reuses what any thread freed (docs/worlds.md, "Memory"). A fixed
// mmap threshold below a page also bounded the process, but every page buffer was then fresh
// memory from the kernel: page faults made page loads twice as slow and the open 6 ms longer.
// Nothing elsewhere; an engine on its own allocator has no such arenas.
#pragma once

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace ridgeline::cli {

/// Call first in main(), before any thread starts.
inline void keep_page_buffers_in_one_arena() noexcept {
#if defined(__GLIBC__)
  (void)::mallopt(M_ARENA_MAX, 1);
#endif
}

}  // namespace ridgeline::cli
