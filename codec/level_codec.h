// CONTRACT between codec/ (the lossless level codec) and format/ (the .gtn container), simplify/ and
// render/. One "level" is one tetrahedral mesh (level 0 = the lossless source, level i = mip level i),
// coded as independent byte streams that format/ stores as chunks. Owned by the codec; changes to this
// header must stay compatible with its users.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

struct EncodeOptions {
  // Reserved: keep the source's vertex and tetrahedron order (costs ~18-21 bits per tetrahedron).
  bool keep_order = false;
  // Code the unused points that lie on an edge with that edge (spec section 10.5), not after the
  // level: the mid-edge nodes of quadratic cells. Off only to measure what it saves.
  bool edge_points = true;
  // Keep a value stream's packed form (spec section 10.2.1) where it is smaller than the predicted
  // stream. Off only to measure the predictions alone.
  bool packed_streams = true;
  // A piece's seam vertices (codec/pieces.h), stored outside the level: seam[v] = vertex v's index in
  // the piece's seam list (0 .. seam_count - 1), kNoIndex for a vertex coded here; empty: none. Every
  // index must name exactly one vertex, and every seam vertex must be used by a tetrahedron.
  std::vector<uint32_t> seam;
  uint32_t seam_count = 0;
  // encodePieces: a level that is one structured block (TetMesh::blocks) may be coded as a
  // structured piece (codec/structured_piece.h) where that is smaller. Off only to measure.
  bool structured = true;
};

// The coded streams of one level. `header` carries counts, field descriptions, bounding box and
// metadata; format/ serialises it in the level's header chunk.
struct EncodedLevel {
  LevelHeader header;
  std::vector<uint8_t> boundary;                   // the boundary surface (a triangle mesh), coded compactly
  std::vector<uint8_t> connectivity;               // the surface-peeling code of every tetrahedron
  std::vector<uint8_t> geometry;                   // coordinates, predicted in decoding order
  std::vector<std::vector<uint8_t>> point_fields;  // one stream per header.point_fields entry
  std::vector<std::vector<uint8_t>> cell_fields;   // one stream per header.cell_fields entry
  // vertex_order[source vertex index] = the id the decoder gives that vertex (its emission order);
  // tet_order[source tetrahedron index] = the tetrahedron's position in the decoded stream; empty
  // where that is the source's order (a structured piece, whose 8 bytes a tetrahedron of identity
  // stayed in memory through a large convert): tetPosition() reads either.
  // Callers use these to store per-vertex data (the merge tree) in decoding order.
  std::vector<uint32_t> vertex_order;
  std::vector<uint64_t> tet_order;
  uint64_t tetPosition(size_t t) const { return tet_order.empty() ? t : tet_order[t]; }
  // Vertices introduced while coding the boundary: the decoder's ids 0 .. boundary_points - 1.
  uint64_t boundary_points = 0;
};

// The header encodeLevel gives `mesh`: its counts (boundary_triangles left 0), coordinate type,
// fields, metadata and bounding box.
LevelHeader levelHeaderOf(const TetMesh& mesh);

// Encodes a mesh whose tetrahedra are positively oriented (zero-volume ones allowed).
StatusOr<EncodedLevel> encodeLevel(const TetMesh& mesh, const EncodeOptions& options);

// Which fields a decode delivers; empty vectors select every field. A consumer that needs only some
// (the renderer needs one point field and no cell field) leaves the others out, and their values are
// not decoded (spec section 10): a field's values depend on its own stream, CONN and GEOM alone, and on
// the streams of the components it repeats, which are decoded with it. The values of a field left out
// reach the sink unspecified (zero bytes unless a kept field repeats one of its components), and a
// corrupt stream left out goes unnoticed beyond its chunk checksum: validators decode everything.
struct DecodeFields {
  std::vector<bool> point, cell;  // point[f]: decode header.point_fields[f]; likewise cell
  // Called once, when every stream's declarations have been read, with the fields whose streams the
  // decode reads no further (point_out[f], cell_out[f]: left out, after the repeats a kept field
  // needs), so that their bytes may be freed while the decode goes on. May be empty.
  std::function<void(const std::vector<char>& point_out, const std::vector<char>& cell_out)> streams_done;
};

// Views of the coded streams of one level as read back from a file.
struct LevelPayload {
  std::span<const uint8_t> boundary, connectivity, geometry;
  std::vector<std::span<const uint8_t>> point_fields, cell_fields;
};

// A piece's seam vertices, given to its decoder (codec/pieces.h): their coordinates (3 per vertex, as
// stored) and point-field values (the header's point fields' items concatenated, per vertex). The
// decoder reports, through `seam_of_id` (when not null), each emitted vertex's seam index or kNoIndex,
// set before the sink's vertex() call for it. A decode fails unless the streams name every seam vertex
// exactly once.
struct SeamValues {
  uint32_t count = 0;
  const double* coords = nullptr;
  const uint8_t* values = nullptr;
  std::vector<uint32_t>* seam_of_id = nullptr;
};

struct DecodeStats {
  uint64_t peak_live_vertices = 0;  // largest number of vertices emitted and not yet retired
};

// Views of the streams of an encoding held in memory (to decode it without a container).
LevelPayload payloadOf(const EncodedLevel& encoded);

// Decodes one level and emits its events (mesh_stream.h order) to `sink`. Fails with kInvalidData,
// never crashes, on any corrupt payload; `what` names the source in messages (file and level).
// `fields`: which fields to decode (null: all).
Status decodeLevel(const LevelHeader& header, const LevelPayload& payload, MeshSink& sink, DecodeStats* stats,
                   const std::string& what, const DecodeFields* fields = nullptr, const SeamValues* seams = nullptr);

}  // namespace gtn
