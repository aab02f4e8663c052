// A level as pieces (spec/gtn-format.md, "Pieces"): spatially coherent sets of tetrahedra, each
// coded on its own by the level codec, so that pieces encode and decode in parallel and a reader
// decodes only the pieces it needs. Vertices used by several pieces (seam vertices) are stored once,
// in their seam class (the set of pieces that use them); a piece names them by their index in its
// seam list and codes only its own vertices.
//
// Global vertex ids of a decoded level (what the merge tree's records refer to, and what a MeshSink
// sees): first every seam vertex (classes in class order, each class's vertices in stream order),
// then each piece's own vertices introduced while coding its boundary (piece order), then each
// piece's other own vertices (piece order). With one piece this is the level codec's own order.
// Tetrahedra come piece by piece, each piece's in its decoding order.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "mesh/index.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// The default bound on a piece's tetrahedra (gtn convert --piece-tets), and the smallest allowed.
// The default is chosen by what seams cost (bench-pieces): extra bytes of about 0.4 times the share
// of seam vertices on real unstructured meshes (fire_ug in 4 pieces: 13.8% seam vertices, +6%), but
// 3 to 4.5 times on smooth generated grids (2^18-tetrahedron pieces: +25% to +50%). At 2^20 most
// files are one piece; --piece-tets trades bytes for finer region reads and more parallelism.
inline constexpr uint64_t kDefaultPieceTets = uint64_t{1} << 20;
inline constexpr uint64_t kMinPieceTets = uint64_t{1} << 12;

// Piece kinds (LHDR): the level codec's streams (BNDY CONN GEOM PFLD... CFLD..., one PIEC chunk), or a
// structured piece (GRID, codec/structured_piece.h).
inline constexpr uint8_t kPieceUnstructured = 0;
inline constexpr uint8_t kPieceStructured = 1;

// What the level header records of one piece.
struct PieceInfo {
  uint8_t kind = kPieceUnstructured;
  uint64_t points = 0;               // vertices the piece's streams introduce (own and seam)
  uint64_t own_points = 0;           // of them, those no other piece uses (stored in the piece)
  uint64_t own_boundary_points = 0;  // of the own ones, those introduced while coding the boundary
  uint64_t tets = 0;                 // the piece's tetrahedra
  uint64_t boundary_triangles = 0;   // triangles of the piece's boundary surface (cut faces included)
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};  // of the vertices the piece uses
};

// One seam class: the vertices used by exactly the pieces `pieces` (at least two, increasing).
struct SeamClass {
  std::vector<uint32_t> pieces;
  uint64_t points = 0;
};

// A level coded as pieces.
struct PiecedLevel {
  LevelHeader header;                              // the whole level (counts, bbox, fields)
  std::vector<PieceInfo> pieces;                   // in piece order
  std::vector<EncodedLevel> encoded;               // one per piece (its own header: the piece's counts)
  std::vector<SeamClass> classes;                  // in class order (by piece list, lexicographic)
  std::vector<std::vector<uint8_t>> seam_streams;  // one per class: its vertices' coordinates and values
  // vertex_order[source vertex] = its global id; tet_order[source tetrahedron] = its global position,
  // empty for a grid (isGrid(): its tetrahedra keep the source's order; tetPosition() reads either).
  std::vector<uint32_t> vertex_order;
  std::vector<uint64_t> tet_order;
  uint64_t tetPosition(size_t t) const { return tet_order.empty() ? t : tet_order[t]; }
  // 1: a one-piece level whose streams name the next level's vertices as seam vertices, in that
  // level's vertex numbering, instead of storing their values (LHDR base; spec section 7.7).
  uint8_t base = 0;
  // A grid: the whole level is one structured piece.
  bool isGrid() const { return pieces.size() == 1 && pieces[0].kind == kPieceStructured; }
};

// Cuts `mesh` into pieces of at most `piece_tets` tetrahedra (recursive bisection at the median of
// the tetrahedra's centroids; deterministic, whatever the thread count) and codes each piece, in
// parallel. A mesh of at most `piece_tets` tetrahedra is one piece with no seam, coded exactly as
// encodeLevel codes it. A mesh that is one structured block (options.structured) is one structured
// piece: of at most piece_tets tetrahedra where that takes fewer bytes than the level codec's piece,
// and of more at the default bound (kDefaultPieceTets) without trying the level codec's pieces.
StatusOr<PiecedLevel> encodePieces(const TetMesh& mesh, const EncodeOptions& options, uint64_t piece_tets);

// A level coded by encodeLevel (kPieceUnstructured), or by the structured-piece coder (kPieceStructured),
// as a PiecedLevel of one piece, as encodePieces makes a level of at most piece_tets tetrahedra or a
// structured one.
PiecedLevel onePieceLevel(EncodedLevel encoded, uint8_t kind = kPieceUnstructured);

// Levels that name the next level's vertices (spec section 7.7). A mip level's vertices are a subset of
// the finer level's, with the same coordinates and values: the finer level codes the shared ones as
// seam vertices whose values the next level holds, and stores only its own.
//
// The next level's vertices as the seam values of the finer level: coordinates and point values of
// `next` in its decoding order (`next_order[v]` = the id vertex v decodes as).
struct ChainSeams {
  uint32_t count = 0;
  std::vector<double> coords;
  std::vector<uint8_t> values;
  SeamValues view(std::vector<uint32_t>* seam_of_id = nullptr) const;
};
ChainSeams chainSeamsOf(const TetMesh& next, const std::vector<uint32_t>& next_order);

// Codes `mesh` as one piece that names the next level's vertices: next_index[v] is vertex v's index in
// the next level's mesh (kNoIndex for a vertex only this level has), next_order that level's
// vertex_order. The result has base 1. Fails where next_index does not map onto next_order's vertices.
StatusOr<PiecedLevel> encodeChainedLevel(const TetMesh& mesh, const std::vector<uint32_t>& next_index,
                                         const std::vector<uint32_t>& next_order);

// The streams of one piece as read back from a file.
struct PiecePayload {
  LevelHeader header;  // the piece's header (the level's fields; the piece's counts and bbox)
  LevelPayload streams;
};

// Everything the decoder needs of one level coded as pieces.
struct PiecedLevelView {
  const LevelHeader* header = nullptr;                 // the level
  std::span<const PieceInfo> pieces;                   // every piece of the level
  std::span<const SeamClass> classes;                  // every class of the level
  std::vector<std::span<const uint8_t>> seam_streams;  // per class (may be empty for a class no chosen piece needs)
  std::vector<PiecePayload> payloads;                  // per piece (only the chosen pieces' are read)
};

// A decoded level (or part of one): the mesh and its boundary triangles (outward, by vertex index).
struct DecodedPieces {
  TetMesh mesh;
  std::vector<std::array<uint32_t, 3>> boundary;
  // For a subset of pieces: mesh vertex -> the level's global id, and mesh tetrahedron -> the level's
  // global tetrahedron position. Empty when every piece was decoded (the ids are the global ones).
  std::vector<uint32_t> global_vertex;
  std::vector<uint64_t> global_tet;
};

// Decodes the pieces `chosen` (increasing piece indices; empty: all) in parallel, stitched into one
// mesh: shared vertices once, cut faces between two decoded pieces not on the boundary. `what` names
// the source in messages. `fields` as decodeLevel.
StatusOr<DecodedPieces> decodePieces(const PiecedLevelView& view, const std::vector<uint32_t>& chosen,
                                     const std::string& what, const DecodeFields* fields = nullptr);

// The header a piece's streams decode with: the level's fields and metadata, the piece's counts and
// bounding box.
LevelHeader pieceHeader(const LevelHeader& level, const PieceInfo& piece);

// The indices of the pieces whose bounding boxes meet the box [lo, hi] (closed).
std::vector<uint32_t> piecesInBox(std::span<const PieceInfo> pieces, const double lo[3], const double hi[3]);

// The seam vertices each piece uses, in the order its seam indices count them: the classes that
// contain the piece, in class order, each class's vertices in stream order, as global ids.
std::vector<std::vector<uint32_t>> pieceSeamLists(std::span<const SeamClass> classes, size_t pieces);

// Emits a decoded level as a mesh stream (mesh_stream.h order): every vertex a boundary triangle uses
// first with the boundary, then the tetrahedra in order with their other vertices, each vertex retired
// after its last tetrahedron. Vertex ids are the mesh's indices, which must put the boundary's vertices
// first (decodePieces' do).
Status emitDecoded(const LevelHeader& header, const DecodedPieces& decoded, MeshSink& sink);

// ---- A level held in parts --------------------------------------------------------------------------
// A mesh held in parts (the ranks of a distributed dataset) is coded where it is: each part is cut
// into pieces of its own, which it codes, and the parts meet through the level's seam table. A point
// is one point of the level wherever its key occurs (a global point id, or the bits of its
// coordinates): parts hold copies of the points they share. The parts agree on the seams through a
// small exchange that a coordinator (one of the parts) settles:
//   1. each part: planPart, and tells the coordinator its exposed points (PartExposed): those on its
//      boundary surface, those several of its pieces use, and those none uses;
//   2. the coordinator: planSeams over every part's PartExposed (in part order, pieces numbered
//      part after part); each part answers usedKeys for the plan's orphans; settleOrphans;
//   3. each part: encodePart with the classes, its first piece and its exposed points' status;
//   4. the coordinator: assembleParts into the PiecedLevel that the file stores;
//   5. each part: partLosslessMismatch (codec/pieces_check.h) checks its pieces decode back.
// The seam vertices of a class are in the order of their keys; the file is the same whatever the
// number of threads, and for the same parts in the same order.

// A point's identity across parts: {global id, 0, 0}, or the bit patterns of its three coordinates.
using PointKey = std::array<uint64_t, 3>;

// A part cut into pieces (the median bisection of encodePieces, at most piece_tets tetrahedra each),
// and its exposed vertices.
struct PartPlan {
  uint32_t pieces = 0;               // none when the part has no tetrahedra
  std::vector<uint32_t> piece_of;    // per tetrahedron, its piece
  std::vector<uint32_t> exposed;     // the exposed vertices (increasing local indices)
  std::vector<uint32_t> uses_first;  // exposed vertex i is used by pieces uses[uses_first[i] .. uses_first[i + 1])
  std::vector<uint32_t> uses;        // (the part's piece indices, increasing)
};
StatusOr<PartPlan> planPart(const TetMesh& part, uint64_t piece_tets);

// What a part tells the coordinator: its piece count, and per exposed vertex its key and the part's
// pieces that use it (as PartPlan).
struct PartExposed {
  uint32_t pieces = 0;
  std::vector<PointKey> keys;
  std::vector<uint32_t> uses_first, uses;
};

// An exposed vertex's status: a global seam id, or one of these.
inline constexpr uint32_t kPartOwnVertex = kNoIndex;       // the part's own (coded in its piece)
inline constexpr uint32_t kPartDropVertex = kNoIndex - 1;  // another part codes it: left out here

struct SeamPlan {
  std::vector<SeamClass> classes;             // the level's classes, in class order
  std::vector<uint32_t> first_piece;          // per part its first piece's index; last: every piece
  std::vector<std::vector<uint32_t>> status;  // per part, per exposed vertex
  // Per seam id, the copy whose values the class stream stores: (part, exposed index).
  std::vector<std::pair<uint32_t, uint32_t>> seam_source;
  // Keys that parts hold without any of their exposed vertices being used (unused points): the
  // coordinator asks every part whether one of its tetrahedra uses them (usedKeys) and settles them.
  std::vector<PointKey> orphans;
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> orphan_holders;  // per orphan: (part, exposed index)
};

// The seams of the parts' exposed vertices: a key used by pieces of two or more parts, or by two or
// more pieces of one part, is a seam vertex of the class of those pieces; a key used by one piece is
// that piece's own, the other parts' copies dropped; an orphan stays with the first part (with
// pieces) that holds it unless settleOrphans finds it used. Fails when a part exposes one key twice
// (the message shows the key as coordinates when `coordinate_keys`, else as a global id).
StatusOr<SeamPlan> planSeams(const std::vector<PartExposed>& parts, bool coordinate_keys = false);
// used[k]: some part's tetrahedra use orphans[k]; then every holder drops it.
void settleOrphans(SeamPlan& plan, const std::vector<char>& used);
// Per key of `keys`: whether a tetrahedron of `part` uses a vertex with that key (`part_keys`: per
// vertex of the part).
std::vector<char> usedKeys(const TetMesh& part, std::span<const PointKey> part_keys, std::span<const PointKey> keys);

// A part's pieces, coded.
struct EncodedPart {
  std::vector<PieceInfo> pieces;
  std::vector<EncodedLevel> encoded;
  // Every piece's boundary faces whose corners are all seam vertices, as sorted global seam ids (a
  // face between two pieces appears twice over all parts).
  std::vector<std::array<uint32_t, 3>> seam_faces;
  // The part's own record: per piece its vertices (increasing local indices) and tetrahedra; per
  // vertex its seam id (kNoIndex: none).
  std::vector<std::vector<uint32_t>> piece_vertices, piece_tets;
  std::vector<uint32_t> seam_id;
};

// Codes the pieces of `part` (as `plan` cuts it; in parallel) against the level's `classes`, its
// pieces being the level's pieces first_piece, first_piece + 1, ...; `status` per exposed vertex
// (SeamPlan::status). Unused own points go with a piece that uses the edge they lie on, else with the
// part's last piece.
StatusOr<EncodedPart> encodePart(const TetMesh& part, const PartPlan& plan, std::span<const SeamClass> classes,
                                 uint32_t first_piece, std::span<const uint32_t> status,
                                 const EncodeOptions& options = {});

// The level from every part's pieces (`parts` in part order: their pieces, encodings and seam faces;
// their own record is not needed) and `seams`, a mesh of the seam vertices alone in seam id order
// with the level's coordinate type and point fields (the values of SeamPlan::seam_source). The
// PiecedLevel's vertex_order and tet_order stay empty: the parts hold the sources.
StatusOr<PiecedLevel> assembleParts(std::vector<EncodedPart>&& parts, const SeamPlan& plan, const TetMesh& seams);

}  // namespace gtn
