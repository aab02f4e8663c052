// A level that is one structured block, coded as a structured piece (PieceInfo::kind 1): the
// structured-piece coder (grid_coder.h) behind the level codec's interface. The encoder gives what
// encodeLevel gives (the header, the vertex and tetrahedron orders) with the whole piece in the
// `connectivity` stream; the decoder emits the mesh stream (mesh/mesh_stream.h) as decodeLevel does.
//
// Decoded order: vertex k is the grid coder's vertex k (the block's nodes that are not aliases, in
// node order, then the exceptions' extra points), which is the source mesh's point k (the block
// starts at point 0 and has no other point); tetrahedra come in the source's order (cell by cell).
// Events: beginLevel; every vertex, in id order; the boundary triangles (outward, the faces that
// computeFaceAdjacency finds in one tetrahedron only, found from the block's outer faces and its
// exceptions); endBoundary; the vertices no tetrahedron uses retired; then each tetrahedron with its
// cell values, each vertex retired right after its last tetrahedron; endLevel.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "codec/grid_coder.h"
#include "codec/level_codec.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Codes `mesh` (a whole level) as the structured piece of `block` (mesh/tet_mesh.h; the structured
// importers set TetMesh::blocks): the block must start at point 0, and the mesh must be that block
// as matchGridLayout finds it (its nodes, aliases and extra points the mesh's points in order, its
// tetrahedra cell by cell, exceptions allowed), with tetrahedra that repeat no vertex, no face in
// three tetrahedra and consistent fields. Otherwise fails with kUnsupported (the caller then codes
// the level with encodeLevel; a mesh encodeLevel refuses is refused here too). The result's
// `connectivity` holds the whole piece; its other streams are empty (one empty vector per field).
StatusOr<EncodedLevel> encodeStructuredPiece(const TetMesh& mesh, const StructuredBlock& block,
                                             const GridEncodeOptions& options = {}, GridEncodeReport* report = nullptr);

// Decodes a piece that encodeStructuredPiece wrote (`bytes`: its `connectivity`) and emits its
// events to `sink` (order above). `header` as encodeStructuredPiece set it: its fields are the
// piece's schema, and its counts (points, tetrahedra, boundary triangles) must be the piece's.
// `fields` (null: all): the fields left out are not decoded, and reach the sink as zero bytes;
// streams_done is called once, before the first event, with the fields left out. Fails with
// kInvalidData naming `what` on corrupt or truncated bytes or counts that disagree, never crashes.
Status decodeStructuredPiece(const LevelHeader& header, std::span<const uint8_t> bytes, MeshSink& sink,
                             const std::string& what, const DecodeFields* fields = nullptr);

// The boundary triangles of the structured piece `layout` (a layout that passes checkGridLayout),
// outward for positively oriented tetrahedra, in an order that depends on the layout alone:
// the faces of the block's outer box and those around and inside its exceptions that belong to one
// tetrahedron only (a rule cell's inner faces, and the faces two rule cells share, belong to two).
// Fails (kInvalidData naming `what`) where a face belongs to three tetrahedra or more.
StatusOr<std::vector<std::array<uint32_t, 3>>> gridBoundary(const GridLayout& layout, const std::string& what);

}  // namespace gtn
