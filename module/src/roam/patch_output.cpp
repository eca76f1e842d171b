// Per-patch buffers kept in step with the mesh, and the dirty slots an engine re-uploads.
#include "roam/patch_output.h"

#include <algorithm>
#include <bit>
#include <cfloat>
#include <glm/geometric.hpp>

#include "ridgeline/log.h"
#include "ridgeline/surface.h"
#include "roam/diamond.h"
#include "roam/landscape_access.h"
#include "ridgeline/terrain.h"

namespace ridgeline::roam {

void PatchOutput::reset(const Landscape& land, const Reader& reader) {
  land_ = &land;
  reader_ = &reader;
  const std::uint32_t np = land.patch_count();
  if (patches_.size() != np) patches_.assign(np, Patch{});
  dirty_list_.clear();
  stale_.clear();
  pending_.clear();
  bytes_ = 0;
  const std::int64_t P = land.patch_cells();
  for (std::uint32_t p = 0; p < np; ++p) {
    Patch& pt = patches_[p];
    const std::int64_t i0 = std::int64_t(p % land.patches_x()) * P;
    const std::int64_t j0 = std::int64_t(p / land.patches_x()) * P;
    pt.mesh.origin_x = LandscapeAccess::world_x(land, i0);
    pt.mesh.origin_z = LandscapeAccess::world_z(land, j0);
    pt.mesh.origin_y = land.terrain().info().height_offset;
    pt.mesh.vertices.clear();
    pt.mesh.indices.clear();
    pt.mesh.dirty_vertices.clear();
    pt.mesh.dirty_triangles.clear();
    pt.mesh.triangles = 0;
    ++pt.mesh.version;
    pt.free_tris.clear();
    pt.free_verts = kNoSlot;
    pt.live_verts = 0;
    pt.pending = false;
    pt.tri_bits.clear();
    pt.vert_bits.clear();
    pt.hidden.clear();
    pt.listed = false;
    pt.grew = true;
    pt.counted = false;
    pt.bytes = 0;
    pt.stale = true;
    stale_.push_back(p);
    // Corners: slots 0 (0, 0), 1 (P, 0), 2 (0, P), 3 (P, P), never freed.
    for (int c = 0; c < 4; ++c) add_vertex(p, i0 + (c & 1) * P, j0 + (c >> 1) * P);
    // Root 0: apex (P, 0), left (0, 0), right (P, P); root 1: apex (0, P), left (P, P),
    // right (0, 0) (landscape.h). Their slots are 0 and 1. A root over the padding is hidden.
    // So is one wholly over holes.
    const bool pad = i0 >= LandscapeAccess::last_i(land) || j0 >= LandscapeAccess::last_j(land);
    const HoleMask* holes = reader.holes();
    const int L = int(land.detail_levels());
    add_triangle(p, {1, 0, 3},
                 pad || (holes && holes->all_holes(i0 + P, j0, i0, j0, i0 + P, j0 + P, L)));
    add_triangle(p, {2, 3, 0},
                 pad || (holes && holes->all_holes(i0, j0 + P, i0 + P, j0 + P, i0, j0, L)));
  }
}

void PatchOutput::write_vertex(std::uint32_t patch, std::uint32_t slot, std::int64_t i,
                               std::int64_t j, const Known* known) {
  const Landscape& l = *land_;
  Patch& p = patches_[patch];
  const std::int64_t P = l.patch_cells();
  const std::int64_t i0 = std::int64_t(patch % l.patches_x()) * P;
  const std::int64_t j0 = std::int64_t(patch / l.patches_x()) * P;
  MeshVertex v;
  v.x = static_cast<float>(double(i - i0) * LandscapeAccess::spacing_x(l));
  v.z = static_cast<float>(double(j - j0) * LandscapeAccess::spacing_z(l));
  const int L = int(l.detail_levels());
  const std::int64_t mask = (std::int64_t{1} << L) - 1;
  const Diamond d = diamond_at(i, j, l.patch_log2());
  VertexShading sh;
  if ((i & mask) != 0 || (j & mask) != 0) {
    // Below the stored resolution: the detail lattice's.
    sh = LandscapeAccess::detail_shading(l, i, j);
    if (known == nullptr) {
      const DiamondBound b = LandscapeAccess::compute_detail(l, i, j);
      v.y = static_cast<float>(l.terrain().surface().vertex_height(i, j));
      v.morph_bound = b.morph;
      v.morph_radius = b.radius;
    }
  } else {
    const std::int64_t si = i >> L, sj = j >> L;
    const Diamond sd = diamond_at(si, sj, int(l.patch_exponent()));
    // Patch corners take the coarsest level holding them (always resident): stored_shading().
    const int t = sd.corner ? int(l.patch_exponent()) : sd.t;
    float corner_y = 0;
    const bool ok = reader_->stored_shading(si, sj, sd, t, sh, &corner_y);
    RIDGELINE_ASSERT(ok);
    (void)ok;
    if (known == nullptr) {
      DiamondBound b;
      float y = 0;
      if (d.corner) {
        y = corner_y;
        b = {FLT_MAX, FLT_MAX, 0.0f};
      } else if (reader_->stored(i, j, b, y) != Reader::Vertex::kResident) {
        y = static_cast<float>(l.terrain().surface().stored_height(si, sj));
        b = l.diamond(i, j);
      }
      v.y = y;
      v.morph_bound = b.morph;
      v.morph_radius = b.radius >= FLT_MAX ? FLT_MAX : b.radius;
    }
  }
  if (known != nullptr) {
    v.y = known->y;
    v.morph_bound = known->morph;
    v.morph_radius = known->radius >= FLT_MAX ? FLT_MAX : known->radius;
  }
  if (d.corner) {
    v.morph_bound = FLT_MAX;
    v.morph_radius = 0.0f;
  }
  v.nx = sh.normal.x, v.ny = sh.normal.y, v.nz = sh.normal.z;
  v.morph_dy = sh.morph_dy;
  v.material = sh.material;
  p.mesh.vertices[slot] = v;
  mark(p.vert_bits, slot, sizeof(MeshVertex));
}

std::uint32_t PatchOutput::grow_vertices(Patch& p) {
  const auto slot = std::uint32_t(p.mesh.vertices.size());
  if (p.mesh.vertices.size() == p.mesh.vertices.capacity()) p.grew = true;
  p.mesh.vertices.emplace_back();
  if ((slot >> 6) >= p.vert_bits.size()) p.vert_bits.push_back(0);
  return slot;
}

std::uint32_t PatchOutput::grow_triangles(Patch& p) {
  const auto slot = std::uint32_t(p.mesh.indices.size() / 3);
  if (p.mesh.indices.size() + 3 > p.mesh.indices.capacity()) p.grew = true;
  p.mesh.indices.insert(p.mesh.indices.end(), 3, 0u);
  if ((slot >> 6) >= p.tri_bits.size()) p.tri_bits.push_back(0);
  return slot;
}

void PatchOutput::compact(std::uint32_t patch, const std::vector<std::uint32_t>& order,
                          std::vector<std::uint32_t>& vmap) {
  Patch& p = patches_[patch];
  std::vector<MeshVertex> verts;
  verts.reserve(p.live_verts);
  vmap.assign(p.mesh.vertices.size(), kNoSlot);
  for (std::uint32_t c = 0; c < 4; ++c) {  // the corners, never freed
    vmap[c] = c;
    verts.push_back(p.mesh.vertices[c]);
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(order.size() * 3);
  std::unordered_map<std::uint32_t, std::array<std::uint32_t, 3>> hidden;
  for (std::uint32_t old : order) {
    std::array<std::uint32_t, 3> k = corners(patch, old);
    for (std::uint32_t& v : k) {
      if (vmap[v] == kNoSlot) {
        vmap[v] = std::uint32_t(verts.size());
        verts.push_back(p.mesh.vertices[v]);
      }
      v = vmap[v];
    }
    const std::uint32_t* ix = &p.mesh.indices[std::size_t(old) * 3];
    if (ix[0] == ix[1]) {  // over the padding: degenerate, its corners aside
      hidden.emplace(std::uint32_t(indices.size() / 3), k);
      indices.insert(indices.end(), 3, 0u);
    } else {
      indices.insert(indices.end(), k.begin(), k.end());
    }
  }
  // Every live vertex is a corner of a live triangle of its patch (a patch corner, or the
  // midpoint of an ancestor's hypotenuse), so none is lost.
  RIDGELINE_ASSERT(verts.size() == p.live_verts);
  p.mesh.vertices = std::move(verts);
  p.mesh.indices = std::move(indices);
  p.hidden = std::move(hidden);
  p.free_verts = kNoSlot;
  std::vector<std::uint32_t>().swap(p.free_tris);
  p.vert_bits.assign((p.mesh.vertices.size() + 63) / 64, 0);
  p.vert_bits.shrink_to_fit();
  p.tri_bits.assign((p.mesh.indices.size() / 3 + 63) / 64, 0);
  p.tri_bits.shrink_to_fit();
  p.grew = true;  // resized: uploaded whole
  p.stale = true;
  stale_.push_back(patch);
  touch(patch);
}

void PatchOutput::refresh_vertex(std::uint32_t patch, std::uint32_t slot) {
  const auto c = coord(patch, slot);
  write_vertex(patch, slot, c[0], c[1], nullptr);
  touch(patch);
}

namespace {

// Sorted, disjoint runs of the set bits (cleared as they are read).
void to_ranges(std::vector<std::uint64_t>& bits, std::vector<MeshRange>& out) {
  out.clear();
  for (std::size_t w = 0; w < bits.size(); ++w) {
    std::uint64_t b = bits[w];
    bits[w] = 0;
    while (b != 0) {
      const auto s = std::uint32_t(w * 64 + std::size_t(std::countr_zero(b)));
      b &= b - 1;
      if (!out.empty() && out.back().first + out.back().count == s)
        ++out.back().count;
      else
        out.push_back({s, 1});
    }
  }
}

}  // namespace

std::vector<std::uint32_t> PatchOutput::take_dirty() {
  std::vector<std::uint32_t> out(dirty_list_);  // the list keeps its capacity
  dirty_list_.clear();
  std::sort(out.begin(), out.end());
  for (std::uint32_t pi : out) {
    Patch& p = patches_[pi];
    p.listed = false;
    p.mesh.resized = p.grew;
    to_ranges(p.vert_bits, p.mesh.dirty_vertices);
    to_ranges(p.tri_bits, p.mesh.dirty_triangles);
    if (p.grew) {
      p.mesh.dirty_vertices.assign(1, {0, std::uint32_t(p.mesh.vertices.size())});
      p.mesh.dirty_triangles.assign(1, {0, std::uint32_t(p.mesh.indices.size() / 3)});
    }
    p.grew = false;
    p.counted = false;
    p.stale = true;  // its dirty ranges' capacity may have changed
    stale_.push_back(pi);
  }
  return out;
}

std::uint64_t PatchOutput::take_upload_bytes() {
  // A patch whose buffers grew is uploaded whole.
  for (std::uint32_t pi : dirty_list_) {
    Patch& p = patches_[pi];
    if (p.grew && !p.counted) {
      upload_bytes_ += p.mesh.vertices.size() * sizeof(MeshVertex) +
                       p.mesh.indices.size() * sizeof(std::uint32_t);
      p.counted = true;
    }
  }
  const std::uint64_t b = upload_bytes_;
  upload_bytes_ = 0;
  return b;
}

std::size_t PatchOutput::memory_bytes() {
  auto count = [&](std::uint32_t pi) {
    Patch& p = patches_[pi];
    bytes_ -= p.bytes;
    p.bytes =
        p.mesh.vertices.capacity() * sizeof(MeshVertex) +
        p.mesh.indices.capacity() * sizeof(std::uint32_t) +
        (p.mesh.dirty_vertices.capacity() + p.mesh.dirty_triangles.capacity()) * sizeof(MeshRange) +
        p.free_tris.capacity() * 4 + (p.tri_bits.capacity() + p.vert_bits.capacity()) * 8 +
        p.hidden.size() * (sizeof(std::uint32_t) + 12 + 16) + p.hidden.bucket_count() * 8;
    bytes_ += p.bytes;
    p.stale = false;
  };
  // Only the patches changed since the last count (a full count walks every patch's vectors:
  // cache misses on patches nobody touched).
  for (std::uint32_t pi : dirty_list_) count(pi);
  for (std::uint32_t pi : stale_)
    if (patches_[pi].stale) count(pi);
  stale_.clear();
  return patches_.capacity() * sizeof(Patch) + (dirty_list_.capacity() + stale_.capacity()) * 4 +
         bytes_;
}

}  // namespace ridgeline::roam
