// Whether a level coded as pieces decodes back to the mesh it was made from: what
// codec/level_check.h checks of one piece, for a PiecedLevel (the writer checks every level it writes
// this way unless told not to).
#pragma once

#include <string>

#include "codec/grid_coder.h"
#include "codec/pieces.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Views of every stream of a PiecedLevel held in memory (to decode it without a container). The view
// points into `level`, which must outlive it.
PiecedLevelView piecedViewOf(const PiecedLevel& level);

// Decodes every piece of `level` (decodePieces) and compares the stitched mesh with `source`: the same
// numbers of points and tetrahedra; each source point at global id level.vertex_order[point] with
// bit-identical coordinates and point-field values; each source tetrahedron at
// level.tet_order[tetrahedron], its vertices an even permutation of the source's, with bit-identical
// cell-field values. One piece is checked as losslessMismatch checks it. Returns "" when the level
// decodes back exactly, else the first difference found (or the decoder's error). `tets`, where given,
// are the source's tetrahedra where its caller has released them (codec/grid_coder.h's RuleGridTets;
// for a level of one structured piece).
std::string piecedLosslessMismatch(const TetMesh& source, const PiecedLevel& level, const RuleGridTets* tets = nullptr);

// Whether the pieces of a part (codec/pieces.h, "A level held in parts"), decoded from the level as
// the file holds it, give back the part exactly: `view` holds every piece's info, every class and seam
// stream, and the payloads of the part's pieces (first_piece, first_piece + 1, ...); the other
// payloads are not read. Each vertex of the part's pieces and each of its tetrahedra is compared as
// piecedLosslessMismatch compares them. Returns "" when they decode back exactly.
std::string partLosslessMismatch(const TetMesh& part, const EncodedPart& encoded, uint32_t first_piece,
                                 const PiecedLevelView& view);

}  // namespace gtn
