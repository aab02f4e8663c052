// Whether an encoded level decodes back to the mesh it was made from. The writer (format/gtn_file.h)
// checks every level it writes this way unless told not to, so that a file is never written that
// would not give its source back; the compression benchmark and the tests use it too.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "codec/grid_coder.h"
#include "codec/level_codec.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Decodes `encoded` and compares what it emits, event by event, with `source` (the mesh given to
// encodeLevel), without building the decoded mesh: the same numbers of points and tetrahedra; each
// source point emitted as vertex encoded.vertex_order[point], with bit-identical coordinates and
// point-field values; each source tetrahedron emitted at encoded.tet_order[tetrahedron], its
// vertices an even permutation of the source's, with bit-identical cell-field values. Returns "" when
// the level decodes back exactly, else the first difference found (or the decoder's error).
// `seams`: the seam values the level names (a piece's seam vertices, or the next level's vertices).
std::string losslessMismatch(const TetMesh& source, const EncodedLevel& encoded, const SeamValues* seams = nullptr);

// The same for a level coded as one structured piece (codec/structured_piece.h): `piece` decoded with
// `header` (the piece's, as a reader derives it), each source point emitted as vertex
// vertex_order[point], the tetrahedra in the source's order. `tets`, where given, are the source's
// tetrahedra where its caller has released them (codec/grid_coder.h's RuleGridTets).
std::string structuredLosslessMismatch(const TetMesh& source, const LevelHeader& header, std::span<const uint8_t> piece,
                                       const std::vector<uint32_t>& vertex_order, const RuleGridTets* tets = nullptr);

}  // namespace gtn
