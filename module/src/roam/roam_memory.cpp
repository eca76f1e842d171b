// RoamMemory (roam_memory.h): a RangePool (roam/reserved.h) an engine owns.
#include "ridgeline/roam_memory.h"

#include "roam/reserved.h"

namespace ridgeline {

RoamMemory::RoamMemory(const RoamMemoryDesc& desc)
    : desc_(desc), pool_(std::make_unique<roam::RangePool>(desc.max_spare_bytes, desc.max_bytes)) {}

RoamMemory::~RoamMemory() = default;

std::shared_ptr<RoamMemory> RoamMemory::create(const RoamMemoryDesc& desc) {
  return std::shared_ptr<RoamMemory>(new RoamMemory(desc));
}

std::size_t RoamMemory::committed_bytes() const noexcept {
  return pool_->bytes();
}

std::size_t RoamMemory::spare_bytes() const noexcept {
  return pool_->spare_bytes();
}

std::size_t RoamMemory::release_spares() noexcept {
  return pool_->release_spares();
}

}  // namespace ridgeline
