// No reserved address space (RIDGELINE_PORTABLE, or a platform without one): reserve() refuses,
// so callers use plain allocations (virtual_memory.h, roam/reserved.h).
#include "platform/virtual_memory.h"

namespace ridgeline::platform {

std::size_t page_size() noexcept {
  return 4096;
}
void* reserve(std::size_t) noexcept {
  return nullptr;
}
bool commit(void*, std::size_t) noexcept {
  return false;
}
bool decommit(void*, std::size_t) noexcept {
  return false;
}
void release(void*, std::size_t) noexcept {}

}  // namespace ridgeline::platform
