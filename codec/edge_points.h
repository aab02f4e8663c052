// Points that no tetrahedron uses but that sit on a tetrahedron's edge: the mid-edge nodes of
// quadratic cells (VTK_QUADRATIC_TETRA and its kin, TetGen's and Gmsh's 10-node tetrahedra), which
// importers keep as unreferenced points when they reduce a cell to its corners. Found by position
// alone, so that they are found whatever the format and its node order: the encoder then codes each
// one when its edge is first decoded, predicted at the edge's midpoint, instead of after the whole
// level from the point before it (spec section 10.5).
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

struct EdgePoint {
  uint32_t point;  // a point no tetrahedron uses
  uint32_t a, b;   // the edge's end points, a < b
};

// For each unused point with finite coordinates that lies within a quarter of an edge's length of
// that edge's midpoint, the edge whose midpoint is nearest relative to its length (the lowest (a, b)
// among equals). Sorted by point. Edges whose search would visit more than a few hundred grid cells
// (far longer than the mesh's typical edge) are not considered, nor are points in a cell of more than
// a few hundred (coincident points).
std::vector<EdgePoint> findEdgePoints(const TetMesh& mesh);

}  // namespace gtn
