// Splitting hexahedral cells into tetrahedra. Vertex order is VTK's: 0-3 the bottom quadrilateral
// counter-clockwise, 4-7 the top one above them (for a structured cell (i,j,k): 0=(i,j,k),
// 1=(i+1,j,k), 2=(i+1,j+1,k), 3=(i,j+1,k), then the same at k+1). Output tetrahedra are not yet
// oriented: callers normalise orientation with exact predicates.
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

// Six tetrahedra around the diagonal 0-6. In a structured grid every cell uses the same face
// diagonals as its neighbours, so the split is always conforming.
void splitHexSix(const uint32_t h[8], std::vector<Tet>& out);

// Five tetrahedra: a central one and four corners. Conforming in a structured grid only when
// `odd_parity` alternates between neighbouring cells ((i + j + k) % 2).
void splitHexFive(const uint32_t h[8], bool odd_parity, std::vector<Tet>& out);

}  // namespace gtn
