// Region reads: the tetrahedra of a mesh that meet an axis-aligned box. A region read decodes the
// pieces of a level whose bounding boxes meet the box (codec/pieces.h) and filters them here.
#pragma once

#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

// Whether tetrahedron (p[0], p[1], p[2], p[3]) and the closed box [lo, hi] share a point: a separating
// axis test (the box's 3 axes, the tetrahedron's 4 face normals, the 18 edge-by-axis cross products)
// in double precision, so a tetrahedron that only touches the box within rounding may go either way.
bool tetMeetsBox(const double* const p[4], const double lo[3], const double hi[3]);

// The tetrahedra of `mesh` that meet the box, in their order, with their cell field values; the
// points they use, in their order, with their point field values; coordinate type and metadata kept.
// `kept_points` / `kept_tets` (optional) receive the indices in `mesh` of the points and tetrahedra kept.
TetMesh cropToBox(const TetMesh& mesh, const double lo[3], const double hi[3],
                  std::vector<size_t>* kept_points = nullptr, std::vector<size_t>* kept_tets = nullptr);

}  // namespace gtn
