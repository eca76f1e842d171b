// A RoamView's output: per-patch vertex and index buffers kept in step with the mesh, slot by
// slot, so that a split or merge rewrites a few slots and an engine re-uploads only those.
//
// Nothing is stored beside what the engine draws but free-slot lists and dirty bits: a
// triangle's corners are its indices (the few over the padding, drawn degenerate, keep theirs in
// a side table), a vertex's lattice position follows from its patch-local x and z.
//
// A patch's buffers never hold many more slots than it has live triangles and vertices: one that
// falls to under half (kSlack) is listed for compaction (compact_pending()), and the view
// renumbers its slots in the order of its trees (compact()), which an engine sees as a resized
// patch to upload whole. Without it a patch kept the slots of its finest moment: on a flyover
// every patch near the path, 6x the live mesh.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "platform/memory_hints.h"
#include "ridgeline/landscape.h"
#include "ridgeline/roam_view.h"
#include "roam/landscape_access.h"

namespace ridgeline::roam {

class PatchOutput {
 public:
  /// Every patch back to its two root triangles over its four corner vertices, read through
  /// `reader` (the view's, kept for later writes: set_reader()).
  void reset(const Landscape& land, const Reader& reader);
  /// The reader of the current update (a vertex's shading and, when not given, its height and
  /// bounds come from its page).
  void set_reader(const Reader& reader) noexcept { reader_ = &reader; }

  /// The data of a new vertex that the caller already has: its height and its diamond's morph
  /// bound and radius.
  struct Known {
    float y, morph, radius;
  };
  /// A vertex slot for finest-lattice vertex (i, j) in `patch`, its data written (looked up).
  std::uint32_t add_vertex(std::uint32_t patch, std::int64_t i, std::int64_t j) {
    return add_vertex_impl(patch, i, j, nullptr);
  }
  /// The same, with the height and bounds given (a split has them in its front entry).
  std::uint32_t add_vertex(std::uint32_t patch, std::int64_t i, std::int64_t j, float y,
                           float morph, float radius) {
    const Known k{y, morph, radius};
    return add_vertex_impl(patch, i, j, &k);
  }
  void remove_vertex(std::uint32_t patch, std::uint32_t slot) {
    Patch& p = patches_[patch];
    --p.live_verts;
    check_slack(patch);
    // No upload: no index refers to it any more. A free slot links to the next free one in its
    // x (read by nothing else), so that taking a free slot touches only the slot.
    MeshVertex& v = p.mesh.vertices[slot];
    v.material = kFreeVertex;
    std::memcpy(&v.x, &p.free_verts, sizeof(std::uint32_t));
    p.free_verts = slot;
  }
  /// Rewrites a live vertex's data from the landscape (after an edit or a tile's arrival).
  void refresh_vertex(std::uint32_t patch, std::uint32_t slot);

  /// A triangle slot with corners (apex, left, right) as vertex slots; drawn unless `padding`.
  std::uint32_t add_triangle(std::uint32_t patch, const std::array<std::uint32_t, 3>& corners,
                             bool padding) {
    Patch& p = patches_[patch];
    std::uint32_t slot;
    if (!p.free_tris.empty()) {
      slot = p.free_tris.back();
      p.free_tris.pop_back();
    } else {
      slot = grow_triangles(p);
    }
    write_triangle(p, slot, corners, padding);
    return slot;
  }
  /// Rewrites the corners of a triangle slot in use.
  void set_triangle(std::uint32_t patch, std::uint32_t slot,
                    const std::array<std::uint32_t, 3>& corners, bool padding) {
    Patch& p = patches_[patch];
    std::uint32_t* ix = &p.mesh.indices[std::size_t(slot) * 3];
    if (ix[0] != ix[1]) {
      --p.mesh.triangles;
    } else {
      p.hidden.erase(slot);
    }
    write_triangle(p, slot, corners, padding);
  }
  void remove_triangle(std::uint32_t patch, std::uint32_t slot) {
    Patch& p = patches_[patch];
    std::uint32_t* ix = &p.mesh.indices[std::size_t(slot) * 3];
    if (ix[0] != ix[1])
      --p.mesh.triangles;
    else
      p.hidden.erase(slot);
    ix[0] = ix[1] = ix[2] = 0;
    p.free_tris.push_back(slot);
    mark(p.tri_bits, slot, 3 * sizeof(std::uint32_t));
    touch(patch);
    check_slack(patch);
  }

  /// Patches listed for compaction since the last take_compact_pending(): their slots
  /// outnumbered their live triangles or vertices more than kSlack to 1 (plus kSlackFloor) when
  /// listed. The caller compacts those still oversized (oversized()), calls unlist_compact() for
  /// each it takes off the list, and may leave some listed.
  std::vector<std::uint32_t>& compact_pending() { return pending_; }
  bool oversized(std::uint32_t patch) const {
    const Patch& p = patches_[patch];
    return p.mesh.indices.size() / 3 > kSlack * live_triangles(patch) + kSlackFloor ||
           p.mesh.vertices.size() > kSlack * p.live_verts + kSlackFloor;
  }
  std::size_t live_triangles(std::uint32_t patch) const {
    const Patch& p = patches_[patch];
    return p.mesh.indices.size() / 3 - p.free_tris.size();
  }
  /// Called for each patch taken from compact_pending(), compacted or not.
  void unlist_compact(std::uint32_t patch) { patches_[patch].pending = false; }
  /// Renumbers a patch's slots: `order` holds every live triangle slot once, in the new order
  /// (triangle k takes slot k); vertices take slots in the order the triangles first use them
  /// (the four corners keep 0-3). Buffers shrink to fit and the patch counts as resized (upload
  /// it whole). `vmap` receives each old vertex slot's new slot (kNoSlot for free ones), for the
  /// interior nodes that name their midpoint's slot.
  void compact(std::uint32_t patch, const std::vector<std::uint32_t>& order,
               std::vector<std::uint32_t>& vmap);
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;

  /// The corners (apex, left, right) of a triangle slot in use.
  std::array<std::uint32_t, 3> corners(std::uint32_t patch, std::uint32_t slot) const {
    const Patch& p = patches_[patch];
    const std::uint32_t* ix = &p.mesh.indices[std::size_t(slot) * 3];
    if (ix[0] != ix[1]) return {ix[0], ix[1], ix[2]};
    return p.hidden.at(slot);
  }
  /// Whether a triangle slot in use is hidden (degenerate: over the padding or a hole).
  bool hidden(std::uint32_t patch, std::uint32_t slot) const {
    const std::uint32_t* ix = &patches_[patch].mesh.indices[std::size_t(slot) * 3];
    return ix[0] == ix[1];
  }
  /// Finest-lattice position of a vertex slot (from its patch-local x and z).
  std::array<std::int64_t, 2> coord(std::uint32_t patch, std::uint32_t slot) const {
    const MeshVertex& v = patches_[patch].mesh.vertices[slot];
    const std::int64_t P = land_->patch_cells();
    return {std::int64_t(patch % land_->patches_x()) * P +
                std::llround(double(v.x) / LandscapeAccess::spacing_x(*land_)),
            std::int64_t(patch / land_->patches_x()) * P +
                std::llround(double(v.z) / LandscapeAccess::spacing_z(*land_))};
  }
  std::uint32_t vertex_slots(std::uint32_t patch) const {
    return std::uint32_t(patches_[patch].mesh.vertices.size());
  }
  bool vertex_live(std::uint32_t patch, std::uint32_t slot) const {
    return patches_[patch].mesh.vertices[slot].material != kFreeVertex;
  }

  const PatchMesh& mesh(std::uint32_t patch) const { return patches_[patch].mesh; }
  std::uint32_t patch_count() const { return std::uint32_t(patches_.size()); }

  /// Patches changed since the last call, ascending, with their dirty ranges filled in.
  std::vector<std::uint32_t> take_dirty();
  /// Bytes changed since the last call to this function (dirty slots, whole resized buffers).
  std::uint64_t take_upload_bytes();
  std::uint32_t dirty_patch_count() const { return std::uint32_t(dirty_list_.size()); }
  /// Bytes held by the buffers and their bookkeeping (capacity). Kept up to date per patch:
  /// only patches changed since the last call are counted again.
  std::size_t memory_bytes();

 private:
  static constexpr std::uint32_t kFreeVertex = 0xffffffffu;  // MeshVertex::material of a free slot
  // A patch is compacted when its slots exceed kSlack x its live triangles (or vertices) plus
  // kSlackFloor (docs/roam.md, "Output for an engine"; 4 instead of 2 measured 3 % more memory
  // and 8 % less upload on the noise flyover: the tighter bound on the drawn array won).
  static constexpr std::size_t kSlack = 2, kSlackFloor = 64;
  struct Patch {
    PatchMesh mesh;
    std::vector<std::uint32_t> free_tris;
    std::uint32_t free_verts = kNoSlot;  // the last freed vertex slot (a list through x)
    std::uint32_t live_verts = 0;        // vertex slots in use
    std::vector<std::uint64_t> tri_bits, vert_bits;  // slots changed since the last take
    // Corners of the triangles over the padding (their indices are degenerate).
    std::unordered_map<std::uint32_t, std::array<std::uint32_t, 3>> hidden;
    bool listed = false, grew = false, counted = false, stale = true;
    bool pending = false;   // in pending_
    std::size_t bytes = 0;  // this patch's share of memory_bytes(), when not stale
  };
  void touch(std::uint32_t patch) {
    Patch& p = patches_[patch];
    ++p.mesh.version;
    if (!p.listed) {
      p.listed = true;
      dirty_list_.push_back(patch);
    }
  }
  void check_slack(std::uint32_t patch) {
    Patch& p = patches_[patch];
    if (!p.pending && oversized(patch)) {
      p.pending = true;
      pending_.push_back(patch);
    }
  }
  void mark(std::vector<std::uint64_t>& bits, std::uint32_t slot, std::uint32_t bytes) {
    std::uint64_t& w = bits[slot >> 6];
    const std::uint64_t b = std::uint64_t{1} << (slot & 63);
    if (!(w & b)) upload_bytes_ += bytes;
    w |= b;
  }
  void write_triangle(Patch& p, std::uint32_t slot, const std::array<std::uint32_t, 3>& corners,
                      bool padding) {
    std::uint32_t* ix = &p.mesh.indices[std::size_t(slot) * 3];
    if (padding) {
      ix[0] = ix[1] = ix[2] = 0;
      p.hidden[slot] = corners;
    } else {
      ix[0] = corners[0], ix[1] = corners[1], ix[2] = corners[2];
      ++p.mesh.triangles;
    }
    mark(p.tri_bits, slot, 3 * sizeof(std::uint32_t));
    touch(std::uint32_t(&p - patches_.data()));
  }
  std::uint32_t add_vertex_impl(std::uint32_t patch, std::int64_t i, std::int64_t j,
                                const Known* known) {
    Patch& p = patches_[patch];
    std::uint32_t slot;
    if (p.free_verts != kNoSlot) {
      slot = p.free_verts;
      std::memcpy(&p.free_verts, &p.mesh.vertices[slot].x, sizeof(std::uint32_t));
      // The next allocation in this patch reads the next free slot.
      detail::prefetch(p.mesh.vertices.data() + (p.free_verts != kNoSlot ? p.free_verts : slot));
    } else {
      slot = grow_vertices(p);
    }
    ++p.live_verts;
    write_vertex(patch, slot, i, j, known);
    touch(patch);
    return slot;
  }
  void write_vertex(std::uint32_t patch, std::uint32_t slot, std::int64_t i, std::int64_t j,
                    const Known* known);
  std::uint32_t grow_vertices(Patch& p);
  std::uint32_t grow_triangles(Patch& p);

  const Landscape* land_ = nullptr;
  const Reader* reader_ = nullptr;
  std::vector<Patch> patches_;
  std::vector<std::uint32_t> dirty_list_;
  std::vector<std::uint32_t> pending_;  // patches listed for compaction
  std::vector<std::uint32_t> stale_;    // patches whose bytes changed outside the dirty list
  std::size_t bytes_ = 0;               // sum of the patches' bytes (stale ones as last counted)
  std::uint64_t upload_bytes_ = 0;
};

}  // namespace ridgeline::roam
