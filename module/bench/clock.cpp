// The benchmark clock (ridgeline/bench/clock.h).
#include "ridgeline/bench/clock.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <sys/resource.h>

#include <ctime>

namespace ridgeline::bench {

namespace {
double cpu_clock_ms(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}
}  // namespace

double thread_cpu_ms() { return cpu_clock_ms(CLOCK_THREAD_CPUTIME_ID); }

double process_cpu_ms() { return cpu_clock_ms(CLOCK_PROCESS_CPUTIME_ID); }

long thread_minor_faults() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u.ru_minflt;
}

void keep_freed_memory() {
#if defined(__GLIBC__)
  (void)mallopt(M_MMAP_THRESHOLD, 1 << 30);
  (void)mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

void OtherWork::touch() noexcept {
  unsigned s = 0;
  for (std::size_t k = 0; k < bytes_.size(); k += 64) s += bytes_[k]++;
  // Kept, so that the loop is not optimised away.
  sink_ += s;
  asm volatile("" : : "r"(sink_) : "memory");
}

}  // namespace ridgeline::bench
