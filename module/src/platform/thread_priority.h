// Private: background threads below the engine's own. The page and detail caches' loaders call
// lower_this_thread() as they start, so that streaming never takes a core from the thread that
// updates the view or answers a query (on two cores a loader at the same priority delays the
// frame by whole scheduler slices). Linux: a nice value 10 above the one it inherited from the
// thread that made the cache, for this thread alone. Elsewhere, and with RIDGELINE_PORTABLE,
// nothing (an engine that wants more passes its own executor: WorldCacheDesc::executor,
// DetailCacheDesc::executor).
#pragma once

#if !defined(RIDGELINE_PORTABLE) && defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace ridgeline::detail {

inline void lower_this_thread() noexcept {
#if !defined(RIDGELINE_PORTABLE) && defined(__linux__)
  const id_t tid = id_t(::syscall(SYS_gettid));
  const int now = ::getpriority(PRIO_PROCESS, tid);
  (void)::setpriority(PRIO_PROCESS, tid, now + 10 > 19 ? 19 : now + 10);
#endif
}

}  // namespace ridgeline::detail
