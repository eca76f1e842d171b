// The 4-8 hierarchy of diamonds over the finest lattice, in O(1) integer arithmetic.
//
// Every lattice vertex that is not a patch corner is the centre of exactly one diamond: the pair
// of bintree triangles whose shared hypotenuse has the vertex as its midpoint (one triangle on
// the landscape border). Splitting a diamond adds its centre vertex; its parents are the
// diamonds whose splits made its triangles (the apexes of those triangles), its children the
// four diamonds centred at the midpoints of its outer edges. This is the hierarchy of Lindstrom &
// Pascucci's SOAR and of Duchaineau's ROAM diamonds; the bintree of a patch (landscape.h) is the
// same hierarchy seen triangle by triangle.
//
// A vertex (i, j) with t = min(ctz i, ctz j) below the patch level K (patches of 2^K finest
// cells) is
// - a square diamond ("A") when i >> t and j >> t are both odd: the square of half side s = 2^t
//   around it, split along one diagonal; its children are the four vertices (i +- s, j),
//   (i, j +- s); its parents the two corners on the other diagonal. The diagonal is the one
//   whose corners' coordinates / 2s sum to an even number (that is the diagonal rule of the
//   surface); at t = K - 1 it is a patch centre, whose diagonal is the patch's main diagonal
//   (the two roots) and which has no parents.
// - an edge diamond ("B") when exactly one of i >> t, j >> t is odd: the square of half diagonal
//   s = 2^t turned by 45 degrees, split along the lattice edge through it (horizontal when i >> t
//   is odd); its parents are the square diamonds at the two other corners, its children the
//   four vertices (i +- s/2, j +- s/2) (none at t = 0: its children are half-cell triangles).
// Depth counts diamonds from the patch centre: 2 (K - 1 - t) for A, one more for B; the
// triangles of a diamond at depth d are bintree nodes of level d.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>

#include "ridgeline/landscape.h"

namespace ridgeline::roam {

/// Trailing zero bits of x, 64 for 0.
inline int ctz64(std::int64_t x) noexcept {
  return std::countr_zero(static_cast<std::uint64_t>(x));
}

struct Diamond {
  std::int64_t i = 0, j = 0;  ///< centre, finest-lattice indices
  std::int64_t s = 0;         ///< half side (A) or half diagonal (B), lattice cells; 2^t
  int t = 0;                  ///< log2 s
  bool square = false;        ///< kind A (axis-aligned square) rather than B (edge diamond)
  bool top = false;           ///< a patch centre: the two roots, no parents
  bool corner = false;        ///< a patch corner: not a diamond at all

  /// Bintree level of the diamond's triangles (0 for the roots), for patches of 2^patch_log2
  /// finest cells.
  int depth(int patch_log2) const noexcept { return 2 * (patch_log2 - 1 - t) + (square ? 0 : 1); }

  /// The two ends of the shared hypotenuse.
  void hypotenuse(std::int64_t& ax, std::int64_t& az, std::int64_t& bx,
                  std::int64_t& bz) const noexcept {
    if (square) {
      // Main diagonal when (i - s)/2s + (j - s)/2s is even (and for patch centres).
      const bool main = top || ((((i - s) >> (t + 1)) + ((j - s) >> (t + 1))) & 1) == 0;
      ax = i - s, bx = i + s;
      az = main ? j - s : j + s;
      bz = main ? j + s : j - s;
    } else if (((i >> t) & 1) != 0) {
      ax = i - s, az = j, bx = i + s, bz = j;  // horizontal hypotenuse
    } else {
      ax = i, az = j - s, bx = i, bz = j + s;  // vertical
    }
  }

  /// The two apexes of the diamond's triangles (its parents' centres, or patch corners for a
  /// patch centre), in either order.
  void apexes(std::int64_t& ax, std::int64_t& az, std::int64_t& bx,
              std::int64_t& bz) const noexcept {
    std::int64_t hx0, hz0, hx1, hz1;
    hypotenuse(hx0, hz0, hx1, hz1);
    // Turn the half hypotenuse by 90 degrees about the centre.
    const std::int64_t dx = hx1 - i, dz = hz1 - j;
    ax = i - dz, az = j + dx;
    bx = i + dz, bz = j - dx;
  }

  /// Centres of the four children (valid only when has_children()).
  bool has_children() const noexcept { return square || t > 0; }
  void child(int k, std::int64_t& ci, std::int64_t& cj) const noexcept {
    if (square) {
      static constexpr int kDx[4] = {1, -1, 0, 0}, kDz[4] = {0, 0, 1, -1};
      ci = i + kDx[k] * s, cj = j + kDz[k] * s;
    } else {
      const std::int64_t h = s / 2;
      ci = i + ((k & 1) ? h : -h), cj = j + ((k & 2) ? h : -h);
    }
  }

  /// Half width (lattice cells, along x and z) of the square around the centre that holds every
  /// descendant's triangles: 3 s for A (children at s plus their reach of 2 s), 2 s for B
  /// (s/2 + s/2 + s/4 + s/4 + ... < 2 s).
  std::int64_t reach() const noexcept { return square ? 3 * s : 2 * s; }
};

/// Which of a diamond's two apexes a triangle's apex (ax, az) is, seen from the centre (i, j):
/// 1 when it lies at larger x, or at equal x and larger z. The two apexes are symmetric about the
/// centre, so exactly one of them has side 1.
inline std::uint32_t apex_side(std::int64_t ax, std::int64_t az, std::int64_t i,
                               std::int64_t j) noexcept {
  return (ax > i || (ax == i && az > j)) ? 1u : 0u;
}

/// Classifies lattice vertex (i, j) for patches of 2^patch_log2 finest cells (K above).
inline Diamond diamond_at(std::int64_t i, std::int64_t j, int patch_log2) noexcept {
  Diamond d;
  d.i = i, d.j = j;
  const int t = std::min(ctz64(i), ctz64(j));
  if (t >= patch_log2) {
    d.corner = true;
    return d;
  }
  d.t = t;
  d.s = std::int64_t{1} << t;
  const bool oi = ((i >> t) & 1) != 0, oj = ((j >> t) & 1) != 0;
  d.square = oi && oj;
  d.top = d.square && t == patch_log2 - 1;
  return d;
}

}  // namespace ridgeline::roam

namespace ridgeline::roam {

/// A diamond's half hypotenuse (hu, hw) in its canonical orientation: the vector from the centre
/// to one end of the shared hypotenuse, chosen so that its turn by 90 degrees, p = (-hw, hu),
/// points at the apex of side 1 (apex_side()). Then the triangle of side s is, with sigma = +1
/// for side 1 and -1 for side 0,
///   apex A = c + sigma p,  left L = c + sigma h,  right R = c - sigma h
/// (counter-clockwise seen from above, (apex, left, right) as in landscape.h), and its children
/// are (M, A, L) and (M, R, A) with M = c.
inline void canonical_half(std::int64_t& hu, std::int64_t& hw) noexcept {
  if (hw > 0 || (hw == 0 && hu < 0)) hu = -hu, hw = -hw;
}

/// The canonical half hypotenuse of the diamond centred at (i, j) (not a patch corner).
inline void half_hypotenuse(std::int64_t i, std::int64_t j, int patch_log2, std::int64_t& hu,
                            std::int64_t& hw) noexcept {
  const Diamond d = diamond_at(i, j, patch_log2);
  std::int64_t x0, z0, x1, z1;
  d.hypotenuse(x0, z0, x1, z1);
  hu = x1 - i, hw = z1 - j;
  canonical_half(hu, hw);
}

/// The triangle of side `side` (apex_side()) of the diamond centred at (i, j) with canonical
/// half hypotenuse (hu, hw) (canonical_half()): apex c + sigma p, left c + sigma h, right
/// c - sigma h, with sigma = +1 for side 1 and -1 for side 0 and p = (-hw, hu).
/// (Inline: called per split, merge and built diamond from several files; out of line, the
/// returned triangle went through memory and its 16-byte reloads missed store forwarding.)
inline LatticeTriangle triangle_of_diamond(std::int64_t i, std::int64_t j, std::int64_t hu,
                                           std::int64_t hw, std::uint32_t side) noexcept {
  const std::int64_t su = side ? hu : -hu, sw = side ? hw : -hw;
  return {i - sw, j + su, i + su, j + sw, i - su, j - sw};
}

}  // namespace ridgeline::roam
