// The one clock of Ridgeline's benchmark programs, tools and sample game: wall milliseconds from
// the steady clock, the calling thread's CPU milliseconds, its minor page faults, and the
// benchmark hygiene every timed frame loop shares (memory kept in the process, the rest of a
// game's frame evicting the caches). Part of Ridgeline::bench, not of the core library.
//
// Threading: every function may be called from any thread; OtherWork is used by one thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <vector>

namespace ridgeline::bench {

using Clock = std::chrono::steady_clock;

/// Wall milliseconds from `a` to `b` (negative when `b` is earlier).
inline double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}
/// Wall milliseconds from `t0` to now (steady clock).
inline double ms_since(Clock::time_point t0) { return ms_between(t0, Clock::now()); }

/// CPU milliseconds of the calling thread so far (CLOCK_THREAD_CPUTIME_ID): unlike wall time it
/// does not count the time the thread waits for a core, which on a shared machine can dominate.
double thread_cpu_ms();
/// CPU milliseconds of the whole process so far (every thread; CLOCK_PROCESS_CPUTIME_ID).
double process_cpu_ms();
/// Minor page faults of the calling thread so far (getrusage): a fresh page costs its first write
/// ~10 us on this project's virtual machines, so a first update's time is mostly its faults.
long thread_minor_faults();

/// Wall and thread-CPU milliseconds and minor page faults of one piece of work.
struct Timing {
  double wall_ms = 0, cpu_ms = 0;
  long faults = 0;
};

/// Runs `work()` and returns what it cost the calling thread.
template <class Work>
Timing timed(Work&& work) {
  const long f0 = thread_minor_faults();
  const double c0 = thread_cpu_ms();
  const auto t0 = Clock::now();
  work();
  const double wall = ms_since(t0);
  return {wall, thread_cpu_ms() - c0, thread_minor_faults() - f0};
}

/// For programs that time one piece of work per frame and measure it between frames: keeps the
/// memory the measurement frees inside the process (glibc: no unmapping, no trimming). Otherwise
/// a measurement that frees a large buffer unmaps it, which flushes the TLB, and the next timed
/// frame pays for refilling it (~0.5 ms for a 50k-triangle view): a cost of the benchmark, not of
/// the work timed. Applies to every technique alike.
void keep_freed_memory();

/// The rest of a game's frame: touch() reads and writes one byte in every cache line of `mib`
/// MiB of other memory, so that the next timed frame finds the caches holding that memory
/// instead of the terrain's. The frame loop calls it before every technique's update (0 MiB:
/// nothing).
class OtherWork {
 public:
  explicit OtherWork(double mib) : bytes_(std::size_t(mib * 1048576.0), 1) {}
  void touch() noexcept;

 private:
  std::vector<unsigned char> bytes_;
  unsigned sink_ = 0;
};

}  // namespace ridgeline::bench
