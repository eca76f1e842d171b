// The hole brushes (docs/deformation.md, "Holes"): cells whose centre lies within the radius
// become holes (`hole`) or ground again (`fill_hole`), through the same transaction as the
// height brushes (Terrain::commit: bounds, version, change log). Heights are not touched, so
// filling a hole gives back exactly the surface it had.
#include <algorithm>
#include <cmath>
#include <memory>

#include "edit/sample_changes.h"
#include "ridgeline/edit.h"
#include "surface/edit_layer.h"

namespace ridgeline {

EditResult Terrain::edit_holes(const Edit& e, EditResult r) {
  const WorldInfo& hf = surface_.info();
  const double radius = r.radius_used;
  // Cell (a, b)'s centre is at cell units (a + 0.5, b + 0.5): the brush's centre in those units,
  // shifted by half a cell, puts the centres on integers.
  const double cu = (e.x - hf.origin_x) / hf.spacing_x - 0.5;
  const double cv = (e.z - hf.origin_z) / hf.spacing_z - 0.5;
  const double ru = radius / hf.spacing_x, rv = radius / hf.spacing_z;
  const double a0 = std::max(std::ceil(cu - ru), 0.0);
  const double a1 = std::min(std::floor(cu + ru), double(hf.width) - 2.0);
  const double b0 = std::max(std::ceil(cv - rv), 0.0);
  const double b1 = std::min(std::floor(cv + rv), double(hf.height) - 2.0);
  if (!(a0 <= a1 && b0 <= b1)) return r;  // wholly outside: a no-op
  const HoleMask* now = surface_.holes_;
  if (e.brush == Brush::kFillHole && now == nullptr) return r;  // nothing to fill
  auto mask = now != nullptr ? std::make_shared<HoleMask>(*now) : std::make_shared<HoleMask>();
  const bool make = e.brush == Brush::kHole;
  SampleChanges c;
  for (auto b = std::uint32_t(b0); b <= std::uint32_t(b1); ++b) {
    const double dz = (double(b) - cv) * hf.spacing_z;
    for (auto a = std::uint32_t(a0); a <= std::uint32_t(a1); ++a) {
      const double dx = (double(a) - cu) * hf.spacing_x;
      if (dx * dx + dz * dz > radius * radius) continue;
      if (mask->set(a, b, make)) c.add_cell(a, b);
    }
  }
  if (c.empty()) return r;
  surface_.publish_holes(std::move(mask));
  commit(c, r);
  return r;
}

}  // namespace ridgeline
