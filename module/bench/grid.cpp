// A terrain's finest lattice as a heightfield (grid.h).
#include "ridgeline/bench/grid.h"

#include <vector>

namespace ridgeline::bench {

Result<Heightfield> finest_lattice(const Terrain& t) {
  const WorldInfo& stored = t.info();
  const SurfaceLattice& at = t.surface().lattice();
  HeightfieldDesc d;
  d.width = static_cast<std::uint32_t>(at.vertices_x);
  d.height = static_cast<std::uint32_t>(at.vertices_z);
  d.spacing_x = stored.spacing_x / double(1u << t.surface().detail_levels());
  d.spacing_z = stored.spacing_z / double(1u << t.surface().detail_levels());
  d.origin_x = stored.origin_x;
  d.origin_z = stored.origin_z;
  d.height_offset = stored.height_offset;
  d.max_samples = std::uint64_t{1} << 31;
  d.name = "finest lattice";
  std::vector<float> v(std::size_t(d.width) * d.height);
  for (std::uint32_t j = 0; j < d.height; ++j)
    for (std::uint32_t i = 0; i < d.width; ++i)
      v[i + std::size_t(j) * d.width] = static_cast<float>(t.surface().vertex_height(i, j));
  return Heightfield::create(d, v);
}

}  // namespace ridgeline::bench
