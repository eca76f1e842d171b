// Private: address space reserved once and committed page by page, where the platform has it.
//
// Two implementations, chosen at build time: virtual_memory_posix.cpp (mmap, mprotect, munmap)
// and, with RIDGELINE_PORTABLE or on a platform other than POSIX,
// virtual_memory_none.cpp, whose reserve() always refuses. Callers fall back to plain
// allocations then (roam/reserved.h), which move when they grow.
#pragma once

#include <cstddef>

namespace ridgeline::platform {

/// Bytes per page (what commit() and decommit() round to); 4096 where there is no virtual memory.
std::size_t page_size() noexcept;
/// Reserves `bytes` of address space (a page multiple) that uses no memory until committed;
/// nullptr when the system refuses or has no such thing.
void* reserve(std::size_t bytes) noexcept;
/// Makes [at, at + bytes) of a reserved range usable (page multiples); false when refused.
/// Committed pages read zero the first time.
bool commit(void* at, std::size_t bytes) noexcept;
/// Gives the committed pages [at, at + bytes) back to the system; the range stays reserved and
/// reads zero when committed again. False when it could not (the pages then stay usable).
bool decommit(void* at, std::size_t bytes) noexcept;
/// Gives a whole reserved range back (pages and address space).
void release(void* base, std::size_t bytes) noexcept;

}  // namespace ridgeline::platform
