// RoamMemory: the memory RoamViews keep their bintree nodes and split and merge front in, shared
// by the views created with it, with a cap and the spare ranges an engine can give back.
#pragma once

#include <cstddef>
#include <memory>

namespace ridgeline {

namespace roam {
class RangePool;
}  // namespace roam

/// What a RoamMemory keeps and allows.
struct RoamMemoryDesc {
  /// Bytes of destroyed views' arrays kept committed for the next views created with this
  /// memory (at most 8 arrays): a view that takes one over builds its first mesh without page
  /// faults (~10 us each on a virtual machine, ~1,100 of them for a mesh of 58k triangles).
  /// 0 keeps nothing: a destroyed view's memory goes back to the system at once.
  std::size_t max_spare_bytes = std::size_t{64} << 20;
  /// Cap on the bytes committed by every view using this memory together, spares included
  /// (spares are given back first when a view needs room): 0 = none. A view whose node or front
  /// array would grow past it fails its update with an out-of-memory error (RoamView::update()).
  /// The patch buffers an engine uploads from are not counted (RoamStats::output_bytes).
  std::size_t max_bytes = 0;
};

/// The memory of RoamViews' node arrays and fronts (docs/roam.md, "The node pool"). Each array
/// is a range of reserved address space committed as it grows (or a plain allocation in builds
/// with RIDGELINE_PORTABLE); a view given a RoamMemory hands its ranges, pages and all, to the
/// next view created with the same memory, and counts them against its cap. A view created
/// without one gets a private memory: nothing is kept after it is destroyed.
///
/// Ownership: shared by the views created with it (each holds a reference), so it may be
/// released by the engine before them; the kept ranges go back to the system when the last
/// owner lets go, or at release_spares().
///
/// Threading: every method may run on any thread, also while views created with it update.
class RoamMemory {
 public:
  /// A memory with the given limits (any values are valid).
  static std::shared_ptr<RoamMemory> create(const RoamMemoryDesc& desc = {});
  ~RoamMemory();
  RoamMemory(const RoamMemory&) = delete;
  RoamMemory& operator=(const RoamMemory&) = delete;

  const RoamMemoryDesc& desc() const noexcept { return desc_; }
  /// Bytes committed by the views using this memory and by the ranges kept for later ones.
  std::size_t committed_bytes() const noexcept;
  /// Of which bytes kept in destroyed views' ranges.
  std::size_t spare_bytes() const noexcept;
  /// Gives every kept range back to the system (a level unload, a memory warning); returns the
  /// bytes given back. Views already using this memory are not affected.
  std::size_t release_spares() noexcept;

  /// The pool itself, for the views (private).
  roam::RangePool& pool() noexcept { return *pool_; }

 private:
  explicit RoamMemory(const RoamMemoryDesc& desc);
  RoamMemoryDesc desc_;
  std::unique_ptr<roam::RangePool> pool_;
};

}  // namespace ridgeline
