// Reserved address space on POSIX systems: mmap with PROT_NONE, mprotect to commit, a fresh
// PROT_NONE mapping over pages to give them back (virtual_memory.h).
#include "platform/virtual_memory.h"

#include <sys/mman.h>
#include <unistd.h>

namespace ridgeline::platform {

std::size_t page_size() noexcept {
  static const std::size_t p = std::size_t(sysconf(_SC_PAGESIZE));
  return p;
}

void* reserve(std::size_t bytes) noexcept {
  // Address space only: not counted against memory until committed (PROT_NONE, no reserve).
  void* p = mmap(nullptr, bytes, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  return p == MAP_FAILED ? nullptr : p;
}

bool commit(void* at, std::size_t bytes) noexcept {
  return mprotect(at, bytes, PROT_READ | PROT_WRITE) == 0;
}

bool decommit(void* at, std::size_t bytes) noexcept {
  // Fresh zero pages when committed again, and no longer counted as used (MAP_FIXED over the
  // range replaces it atomically: the address space stays ours).
  return mmap(at, bytes, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE | MAP_FIXED, -1,
              0) != MAP_FAILED;
}

void release(void* base, std::size_t bytes) noexcept {
  munmap(base, bytes);
}

}  // namespace ridgeline::platform
