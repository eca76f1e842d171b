// Private: a point located on a Terrain's finest lattice (terrain_detail.cpp).
#pragma once

#include <cstdint>

#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

struct Terrain::FineLocated {
  std::int64_t i = 0, j = 0;  // finest-lattice cell
  CellTriangle tri;
  double h[3] = {0, 0, 0};  // local heights of the triangle's corners
};

}  // namespace ridgeline
