// A ROAM view's leaves as a drawn mesh (roam_view.h's leaves_mesh): what RoamView::measure_error
// hands to the MeshErrorMeter. Part of the view (it reads the view's bintree), kept out of
// mesh_error.cpp so that the measurement depends on no tessellator and the view on the
// measurement, not both ways. Its home is roam/mesh_walk.cpp, beside measure_error, once the
// view's current rework there has landed.
#include <glm/vec3.hpp>

#include "ridgeline/mesh_error.h"
#include "ridgeline/roam_view.h"
#include "surface/lattice.h"

namespace ridgeline {

DrawnMesh leaves_mesh(const RoamView& view) {
  const Landscape& l = view.landscape();
  DrawnMesh out;
  out.corners.reserve(std::size_t(view.triangle_count()) * 3);
  const Surface& s = l.terrain().surface();
  const double offset = l.terrain().info().height_offset;
  auto corner = [&](std::int64_t i, std::int64_t j) {
    return glm::dvec3(double(i), offset + double(float(s.vertex_height(i, j))), double(j));
  };
  // The leaves over holes are not drawn (the view hides them): left out.
  const HoleMask* holes = detail::SurfaceAccess::holes(s);
  const int L = int(l.detail_levels());
  view.for_each_leaf([&](std::uint32_t, std::uint64_t, const LatticeTriangle& t) {
    if (holes != nullptr && holes->all_holes(t.ax, t.az, t.lx, t.lz, t.rx, t.rz, L)) return;
    out.add(corner(t.ax, t.az), corner(t.lx, t.lz), corner(t.rx, t.rz));
  });
  return out;
}

}  // namespace ridgeline
