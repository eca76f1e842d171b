// Private: the tessellator's bounds of the stored diamonds, page by page (docs/roam.md, "Error
// bounds"; docs/worlds.md, "Bounds in pages").
//
// Every stored vertex that is not a patch corner is the centre of one diamond (diamond.h) with a
// nested error bound, a nested morph bound and a nested bounding sphere (landscape.h's
// DiamondBound). A diamond of size 2^t lives in the pages of level k = t / 2 (whose stride 4^k
// holds its centre; the coarsest level of the world's pyramid holds every coarser diamond too),
// packed in 4 bytes rounded up (packed::pack): conservative, and nested because every bound is
// computed from its children's packed values.
//
// - Levels >= 1 (t >= 2): the exact nested bounds, computed once from every sample under them
//   (in memory at Landscape::create, or by the bake, which stores them in the world).
// - Level 0 (t = 0, 1): computed from the page alone when the page arrives (records.cpp,
//   level0_block): the descendants of those diamonds lie within 6 samples of their centre, on the
//   page's entries (its cells and six-entry apron), so the page gives their exact nested bounds.
//   Size-1 edge diamonds (t = 0, one odd coordinate; half of all diamonds) are not stored
//   without detail: their bound is the midpoint's offset, read from three heights.
// Every bound is the one a computation over the whole world would give: pages leave no trace.
//
// One definition serves the terrain held in memory and the baked world, so both draw the same
// meshes.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cfloat>
#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "ridgeline/landscape.h"
#include "roam/diamond.h"
#include "surface/hole_mask.h"
#include "world/page.h"

namespace ridgeline {
class DetailField;
}

namespace ridgeline::roam {

/// A bound packed in 32 bits, every part rounded towards +infinity (so conservative, and nested
/// because every bound is computed from its children's packed values):
/// - bits 0-11, the error, and bits 12-23, the radius: 12-bit unsigned floats (6-bit exponent
///   covering 2^-37 .. 2^26 m, 6-bit mantissa: at most 1/64 above the value); 0 stays 0, values
///   past the range (FLT_MAX: over the data's border) become infinity;
/// - bits 24-31, the morph bound over the packed error, 2^(c/64) for c = 0 .. 255 (1 .. 15.8);
///   a larger ratio raises the packed error instead (still a bound).
namespace packed {
inline constexpr int kBias = 38;
inline constexpr std::uint32_t kInfinity = 0xfff;
inline std::uint32_t up12(float v) noexcept {
  if (!(v > 0.0f)) return 0;
  if (!(v < 1.0e30f)) return kInfinity;
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
  std::int32_t e = std::int32_t(bits >> 23) - 127 + kBias;
  std::uint32_t m = ((bits & 0x7fffffu) >> 17) + std::uint32_t((bits & 0x1ffffu) != 0);
  if (m == 64) m = 0, ++e;
  if (e < 1) return 1u << 6;  // the smallest positive value
  const std::uint32_t c = (std::uint32_t(e) << 6) | m;
  return e > 63 || c >= kInfinity ? kInfinity : c;
}
inline float down12(std::uint32_t c) noexcept {
  if (c == 0) return 0.0f;
  if (c >= kInfinity) return std::numeric_limits<float>::infinity();
  return std::bit_cast<float>(((((c >> 6) & 63u) + 127u - kBias) << 23) | ((c & 63u) << 17));
}
inline const std::array<float, 256> kRatio = [] {
  std::array<float, 256> r{};
  for (int c = 0; c < 256; ++c) r[std::size_t(c)] = float(std::exp2(double(c) / 64.0));
  return r;
}();
// floor(64 log2(1 + m / 256)) for the top 8 mantissa bits m: pack()'s first guess of the morph
// code (then corrected against kRatio exactly), instead of a log2 per bound.
inline const std::array<std::uint8_t, 256> kLog2Mantissa = [] {
  std::array<std::uint8_t, 256> r{};
  for (int m = 0; m < 256; ++m) r[std::size_t(m)] = std::uint8_t(std::floor(64.0 * std::log2(1.0 + m / 256.0)));
  return r;
}();
inline DiamondBound unpack(std::uint32_t v) noexcept {
  const float e = down12(v & 0xfffu);
  return {e, e * kRatio[v >> 24], down12((v >> 12) & 0xfffu)};
}
/// The error code `ce` (up12 of the error) with the morph code of a morph bound `morph` (at
/// least the error) in bits 24-31: the error code raised when the ratio would pass kRatio[255].
inline std::uint32_t with_morph(std::uint32_t ce, float morph) noexcept {
  float e = down12(ce);
  std::uint32_t cm = 0;
  if (morph > e) {
    if (!(morph < 1.0e30f)) {
      ce = kInfinity, e = down12(ce);
    } else {
      if (!(e * kRatio[255] >= morph)) ce = up12(morph / kRatio[255] * (1.0f + 0x1p-12f)), e = down12(ce);
      // The smallest c with e 2^(c/64) >= morph: a guess from the ratio's bits within a step or
      // two, then the exact search below (any start gives the same c).
      const std::uint32_t rb = std::bit_cast<std::uint32_t>(morph / e);
      // The guess g is floor(64 log2(morph / e)) or one below, and kRatio's rounding moves the
      // answer by at most one more: it is g - 1 plus how many of the four codes from g - 1 fall
      // short (the test is monotonic in c; four independent comparisons); the loops only confirm.
      const int g = std::clamp((int(rb >> 23) - 127) * 64 + kLog2Mantissa[(rb >> 15) & 0xffu] - 1, 0, 251);
      int c = g;
      for (int k = 0; k < 4; ++k) c += int(e * kRatio[std::size_t(g + k)] < morph);
      while (c > 0 && e * kRatio[std::size_t(c - 1)] >= morph) --c;
      while (c < 255 && e * kRatio[std::size_t(c)] < morph) ++c;
      cm = std::uint32_t(c);
    }
  }
  return ce | (cm << 24);
}
inline std::uint32_t pack(const DiamondBound& b) noexcept {
  return with_morph(up12(b.error), std::max(b.morph, b.error)) | (up12(b.radius) << 12);
}
}  // namespace packed

/// A bound as the records hold it (packed::pack, then unpacked).
inline DiamondBound quantized(const DiamondBound& b) noexcept {
  return packed::unpack(packed::pack(b));
}

/// The level of the pages holding the bounds of a stored diamond of size 2^t in a pyramid of
/// `levels` levels.
inline std::uint32_t record_level(int t, std::uint32_t levels) noexcept {
  return std::min(std::uint32_t(t / 2), levels - 1);
}

/// The bounds of one page's diamonds for one tessellator configuration.
struct RecordBlock {
  std::uint32_t level = 0;
  /// Level 0 with detail: the size-1 edge diamonds are stored too (their children are detail
  /// diamonds, so three heights do not give their bound).
  bool edges = false;
  /// One packed bound (packed::pack) per slot (slot()), held here (blocks made in memory) or,
  /// when empty, read in place from `encoded` (a baked payload the page holds anyway: decode()
  /// copies nothing).
  std::vector<std::uint32_t> values;
  std::shared_ptr<const std::vector<std::uint8_t>> encoded;
  static constexpr std::size_t kHeaderBytes = 8;

  /// Slots of a level-0 block: both coordinates odd (128 x 128), both even (129 x 129), then,
  /// with `edges`, odd x (128 x 129) and odd z (129 x 128). Levels >= 1: every entry of the
  /// page's cells and far edges (257 x 257; the apron's diamonds belong to the neighbours).
  static constexpr std::size_t kOdd = 128 * 128, kEven = 129 * 129, kEdge = 128 * 129;
  static constexpr std::int32_t kSide = kPageCells + 1;
  static constexpr std::size_t kCoarse = std::size_t(kSide) * kSide;
  static std::size_t slots(std::uint32_t level, bool edges) noexcept {
    return level > 0 ? kCoarse : kOdd + kEven + (edges ? 2 * kEdge : 0);
  }
  /// Whether entry (a, b) has a slot (a, b in 0 .. 256).
  static bool holds(std::int32_t a, std::int32_t b) noexcept {
    return a >= 0 && b >= 0 && a <= kPageCells && b <= kPageCells;
  }
  /// Slot of entry (a, b), a, b in 0 .. 256 (holds()); at level 0 never a size-1 edge diamond
  /// without `edges`.
  std::size_t slot(std::int32_t a, std::int32_t b) const noexcept { return slot(level, a, b); }
  static std::size_t slot(std::uint32_t level, std::int32_t a, std::int32_t b) noexcept {
    if (level > 0) return std::size_t(a) + std::size_t(b) * std::size_t(kSide);
    const bool oa = (a & 1) != 0, ob = (b & 1) != 0;
    if (oa && ob) return std::size_t(a >> 1) + std::size_t(b >> 1) * 128;
    if (!oa && !ob) return kOdd + std::size_t(a >> 1) + std::size_t(b >> 1) * 129;
    if (oa) return kOdd + kEven + std::size_t(a >> 1) + std::size_t(b >> 1) * 128;
    return kOdd + kEven + kEdge + std::size_t(a >> 1) + std::size_t(b >> 1) * 129;
  }
  DiamondBound get(std::int32_t a, std::int32_t b) const noexcept {
    return at(packed_values(), slot(a, b));
  }
  /// The packed values' bytes (`values`, or the payload read in place): what get() reads, for
  /// readers that look many slots up in one block.
  const std::uint8_t* packed_values() const noexcept {
    return !values.empty() ? reinterpret_cast<const std::uint8_t*>(values.data())
                           : encoded->data() + kHeaderBytes;
  }
  /// The bound in slot `s` of packed values `p` (packed_values()).
  static DiamondBound at(const std::uint8_t* p, std::size_t s) noexcept {
    std::uint32_t v;
    std::memcpy(&v, p + sizeof v * s, sizeof v);
    return packed::unpack(v);
  }
  /// Sets one slot (a block read in place is copied into `values` first).
  void set(std::int32_t a, std::int32_t b, const DiamondBound& d) {
    if (values.empty() && encoded) own();
    values[slot(a, b)] = packed::pack(d);
  }
  /// set() of a bound already packed (packed::pack).
  void set_packed(std::int32_t a, std::int32_t b, std::uint32_t v) {
    if (values.empty() && encoded) own();
    values[slot(a, b)] = v;
  }
  /// Bytes this block holds itself (a block read in place holds none of its payload).
  std::size_t bytes() const noexcept { return sizeof(*this) + values.capacity() * 4; }
  /// The block as bytes (the bake's payload) and back (checked: size and level; null when they
  /// do not fit).
  std::vector<std::uint8_t> encode() const;
  static std::shared_ptr<RecordBlock> decode(std::uint32_t level,
                                             std::shared_ptr<const std::vector<std::uint8_t>> b);
  /// Copies an in-place payload into `values`.
  void own();
};

/// What the bounds depend on besides the heights (a Landscape's configuration).
struct RecordConfig {
  int patch_log2 = 6;             ///< patch exponent of the stored lattice
  double growth = 1.0;            ///< the morph bound's growth per level
  std::int64_t last_i = 0, last_j = 0;  ///< the last stored sample
  std::int64_t pad_i = 0, pad_j = 0;    ///< the padded extent: patches * 2^patch_log2
  double spacing_x = 1, spacing_z = 1;  ///< stored spacing, metres
  /// Procedural detail (L > 0): the stored diamonds' bounds include it (in memory only).
  std::uint32_t L = 0;
  const DetailField* detail = nullptr;
  /// Bound of a detail diamond child of a finest stored diamond, finest-lattice centre: the
  /// landscape's closed form (set with detail).
  std::function<DiamondBound(std::int64_t, std::int64_t)> detail_child;
  /// |detail| bound at a finest-lattice vertex (0 at stored ones; set with detail).
  std::function<float(std::int64_t, std::int64_t)> detail_offset;
  /// The terrain's holes now (a snapshot: null without holes), or null when the configuration
  /// has no terrain (the bake). with_holes() fills `holes` from it.
  std::function<std::shared_ptr<const HoleMask>()> hole_source;
  /// The holes the bounds are computed against: a diamond one of whose triangles covers both a
  /// hole cell and a solid one gets an infinite sphere, as one over the data's border does, so
  /// views split it down to the finest level and the mesh ends exactly on the hole's edge.
  const HoleMask* holes = nullptr;
};

/// `c` with `holes` set from its hole_source (kept alive by `keep`), or `c` itself when the
/// terrain has no holes (the common case: nothing copied).
inline const RecordConfig& with_holes(const RecordConfig& c, RecordConfig& copy,
                                      std::shared_ptr<const HoleMask>& keep) {
  if (!c.hole_source) return c;
  keep = c.hole_source();
  if (keep == nullptr) return c;
  copy = c;
  copy.holes = keep.get();
  return copy;
}

/// Whether a triangle of the stored diamond centred at (i, j) (stored indices; patch exponent
/// `patch_log2`, padded extent pad_i x pad_j) covers both a hole cell and a solid one.
bool straddles_hole(const HoleMask& holes, int patch_log2, std::int64_t pad_i, std::int64_t pad_j,
                    std::int64_t i, std::int64_t j);

/// Local heights of stored samples by global index, clamped into the data (the padding's rule):
/// a dense row-major array (floats, or 16-bit values times `scale`), or a function.
struct Heights {
  const float* f32 = nullptr;
  const std::uint16_t* u16 = nullptr;
  double scale = 1.0;
  std::int64_t stride = 0, last_i = 0, last_j = 0;
  std::function<float(std::int64_t, std::int64_t)> fn;

  float operator()(std::int64_t i, std::int64_t j) const {
    i = i < 0 ? 0 : (i > last_i ? last_i : i);
    j = j < 0 ? 0 : (j > last_j ? last_j : j);
    if (f32) return f32[std::size_t(i) + std::size_t(j) * std::size_t(stride)];
    if (u16)
      return static_cast<float>(scale * double(u16[std::size_t(i) + std::size_t(j) * std::size_t(stride)]));
    return fn(i, j);
  }
};

/// The patch exponent a Landscape takes when asked for the world's (LandscapeDesc 0) and the
/// bake's default: 6 (65 x 65 samples), raised until there are at most 64 patches per side (at
/// most 10).
inline std::uint32_t default_patch_exponent(std::uint32_t width, std::uint32_t height) noexcept {
  std::uint32_t exponent = 6;
  while (exponent < 10 && ((std::int64_t(width - 1) + (std::int64_t{1} << exponent) - 1) >> exponent > 64 ||
                    (std::int64_t(height - 1) + (std::int64_t{1} << exponent) - 1) >> exponent > 64))
    ++exponent;
  return exponent;
}

/// v rounded up to a float (never below the double).
inline float round_up(double v) noexcept {
  float f = static_cast<float>(v);
  if (double(f) < v) {  // the next float up (std::nextafter's answer, without the library call)
    if (f == 0.0f) return std::numeric_limits<float>::denorm_min();
    const std::uint32_t b = std::bit_cast<std::uint32_t>(f);
    f = std::bit_cast<float>(f > 0.0f ? b + 1 : b - 1);
  }
  return f;
}

/// The bound of a size-1 edge diamond (t = 0, one odd coordinate) without detail, from the
/// heights of its centre and the two ends of its hypotenuse (horizontal when i is odd): its
/// triangles hold no other vertex, so the bound is the centre's offset from the hypotenuse's
/// midpoint; no descendants, so a zero sphere unless it straddles the data's border. Exactly what
/// diamond_bound() gives.
inline DiamondBound edge_bound_of(const RecordConfig& c, float hc, float hl, float hr,
                                  std::int64_t i, std::int64_t j, bool horizontal) noexcept {
  const std::int64_t along = horizontal ? i : j, across = horizontal ? j : i;
  const std::int64_t last_along = horizontal ? c.last_i : c.last_j;
  const std::int64_t last_across = horizontal ? c.last_j : c.last_i;
  const std::int64_t pad_across = horizontal ? c.pad_j : c.pad_i;
  bool any = false, straddles = false;
  for (const std::int64_t ac : {across - 1, across + 1}) {
    if (ac < 0 || ac > pad_across) continue;
    straddles |= along == last_along;
    if (along - 1 >= last_along || std::min(across, ac) >= last_across) continue;
    any = true;
  }
  const float err = any ? round_up(std::abs(double(hc) - 0.5 * (double(hl) + double(hr)))) : 0.0f;
  return quantized({err, err, straddles ? FLT_MAX : 0.0f});
}

/// The exact nested bound of the stored diamond centred at (i, j) from the heights and its
/// children's (quantised) bounds: the largest |surface - plane| of its triangles over every
/// sample under them, nested over the children, with its sphere (FLT_MAX when it straddles the
/// data's border).
DiamondBound diamond_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j,
                           const std::function<DiamondBound(std::int64_t, std::int64_t)>& child);

/// The bound of a size-1 edge diamond (t = 0, one odd coordinate) without detail: its
/// midpoint's offset (what diamond_bound() gives, from three heights).
DiamondBound edge_bound(const RecordConfig& c, const Heights& h, std::int64_t i, std::int64_t j);

/// The level-0 block of `page`, computed from the page alone.
std::shared_ptr<RecordBlock> level0_block(const RecordConfig& c, const world::Page& page);

/// Every block of a world held whole (in memory, or by the bake): level-1 and coarser blocks
/// from the exact nested bounds, then (with `level0`) the level-0 blocks. `h`: the heights;
/// `page(key)`: the level-0 pages (for their blocks). Calls `out(key, block)` for every page of
/// every level (from several threads at once, `threads` of them).
void build_all(const RecordConfig& c, const world::PageGrid& grid, const Heights& h,
               const std::function<const world::Page*(const PageKey&)>& page,
               const std::function<void(const PageKey&, std::shared_ptr<RecordBlock>)>& out,
               unsigned threads, bool level0 = true);

/// After the stored samples [i0, i1] x [j0, j1] changed: the new blocks of every page whose
/// bounds may have changed (coarse levels from the exact nested bounds, level 0 from the page).
/// `block(key)` gives the current block of a page, `page(key)` the page (with its new samples).
std::vector<std::pair<PageKey, std::shared_ptr<const RecordBlock>>> remake(
    const RecordConfig& c, const world::PageGrid& grid, const Heights& h,
    const std::function<const world::Page*(const PageKey&)>& page,
    const std::function<const RecordBlock*(const PageKey&)>& block, std::int64_t i0,
    std::int64_t j0, std::int64_t i1, std::int64_t j1);

}  // namespace ridgeline::roam
