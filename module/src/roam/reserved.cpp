// Reserved address space, committed as it is used (reserved.h). POSIX: mmap and mprotect.
#include "roam/reserved.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <mutex>
#include <new>
#include <vector>

namespace ridgeline::roam {

namespace {
std::size_t page_size() noexcept {
  static const std::size_t p = std::size_t(sysconf(_SC_PAGESIZE));
  return p;
}
std::size_t round_up(std::size_t n, std::size_t step) noexcept {
  return (n + step - 1) / step * step;
}
// Ranges of destroyed reservations, their committed pages kept, for the next reservation of the
// same size: a view created after another was destroyed reuses its pages instead of faulting in
// new ones (~9 us a page on the virtual machine the benchmarks run on; a build of 58k triangles
// commits ~1,100 pages). Heap chunks had that reuse from the allocator. Bounded: at most
// kMaxSpares ranges and kMaxSpareBytes committed; past that a range is unmapped.
struct Spare {
  void* base;
  std::size_t reserved, committed;
};
constexpr std::size_t kMaxSpares = 8, kMaxSpareBytes = std::size_t{64} << 20;
std::mutex spare_mutex;
std::vector<Spare>& spares() {
  static std::vector<Spare>* v = new std::vector<Spare>();  // never destroyed: used at exit
  return *v;
}
}  // namespace

Reservation::~Reservation() {
  if (base_ == nullptr) return;
  {
    std::lock_guard<std::mutex> lock(spare_mutex);
    std::vector<Spare>& v = spares();
    std::size_t held = 0;
    for (const Spare& x : v) held += x.committed;
    if (v.size() < kMaxSpares && held + committed_ <= kMaxSpareBytes) {
      v.push_back({base_, reserved_, committed_});
      return;
    }
  }
  munmap(base_, reserved_);
}

void Reservation::grow_to(std::size_t bytes, std::size_t step, std::size_t max_bytes) {
  if (bytes <= committed_) return;
  const std::size_t range = round_up(max_bytes, page_size());
  if (base_ == nullptr) {
    // A destroyed reservation of the same size, the one with the most pages committed.
    std::lock_guard<std::mutex> lock(spare_mutex);
    std::vector<Spare>& v = spares();
    auto best = v.end();
    for (auto it = v.begin(); it != v.end(); ++it)
      if (it->reserved == range && (best == v.end() || it->committed > best->committed)) best = it;
    if (best != v.end()) {
      base_ = best->base;
      reserved_ = best->reserved;
      committed_ = best->committed;
      v.erase(best);
      if (bytes <= committed_) return;
    }
  }
  if (base_ == nullptr) {
    // Address space only: not counted against memory until committed (PROT_NONE, no reserve).
    // A process limited in address space (ulimit -v) gets a smaller range.
    constexpr std::size_t kFloor = std::size_t{64} << 20;
    for (std::size_t r = range;; r /= 2) {
      void* p = mmap(nullptr, r, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
      if (p != MAP_FAILED) {
        base_ = p;
        reserved_ = r;
        break;
      }
      if (r / 2 < std::min(kFloor, max_bytes)) throw std::bad_alloc();
    }
  }
  const std::size_t want = std::min(round_up(round_up(bytes, step), page_size()), reserved_);
  if (want < bytes) throw std::bad_alloc();  // past the reservation
  if (mprotect(static_cast<char*>(base_) + committed_, want - committed_,
               PROT_READ | PROT_WRITE) != 0)
    throw std::bad_alloc();
  committed_ = want;
}

void Reservation::shrink_to(std::size_t bytes) noexcept {
  const std::size_t keep = round_up(bytes, page_size());
  if (base_ == nullptr || keep >= committed_) return;
  // Fresh zero pages when committed again, and no longer counted as used (MAP_FIXED over the
  // range replaces it atomically: the address space stays ours).
  char* p = static_cast<char*>(base_) + keep;
  if (mmap(p, committed_ - keep, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE | MAP_FIXED,
           -1, 0) == MAP_FAILED)
    return;  // keeps the pages: still correct, just not given back
  committed_ = keep;
}

}  // namespace ridgeline::roam
