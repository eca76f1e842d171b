// The command line's processes on glibc: page-sized buffers (a world page's samples, bounds and
// ray pyramid, 100-300 KB each) are made on loader threads and freed on others. With glibc's
// defaults such buffers land in per-thread arenas once its dynamic mmap threshold has risen past
// them, and the arenas fragment: a 10-minute flight over the 65537^2 world held 285-305 MB with a
// 128 MiB page cache. A fixed threshold below a page keeps them in mmap, given back when freed
// (170 MB for the same flight). Nothing elsewhere; an engine on its own allocator has no such
// arenas (docs/worlds.md, "Memory").
#pragma once

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace ridgeline::cli {

inline void keep_page_buffers_out_of_arenas() noexcept {
#if defined(__GLIBC__)
  (void)::mallopt(M_MMAP_THRESHOLD, 96 * 1024);
#endif
}

}  // namespace ridgeline::cli
