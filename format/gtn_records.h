// Payloads of the container's own chunks (spec/gtn-format.md): the file header (GHDR), the level
// header (LHDR) with its piece table, the seam table (SEAM), the directory (DIRC) and the end chunk
// (GEND). The codec's streams (BNDY, CONN, GEOM, PFLD, CFLD, which a piece's PIEC chunk holds, GRID,
// the seam classes' streams) and the merge tree (MTRE) are opaque here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "codec/pieces.h"
#include "format/gtn_chunk.h"
#include "mesh/mesh_stream.h"

namespace gtn {

class ByteReader;
class ByteWriter;

// Bounds a reader enforces on header fields (spec: "Limits").
inline constexpr uint64_t kGtnMaxLevels = 65535;
inline constexpr uint64_t kGtnMaxFields = 65535;
inline constexpr uint64_t kGtnMaxComponents = 4096;           // as the level codec
inline constexpr uint64_t kGtnMaxPieces = uint64_t{1} << 20;  // per level
// Levels in a row that name the next level's vertices (LHDR base 1; spec section 12): a level decodes
// after every level it names, so the run bounds the work of one decode.
inline constexpr uint64_t kGtnMaxNamingRun = 63;
inline constexpr uint64_t kGtnMaxPiecePoints = 0xFFFFFFFEu;  // a piece's vertex ids are 32 bits
// Piece kinds (LHDR): kPieceUnstructured and kPieceStructured, codec/pieces.h.

// GHDR writer flag bits: informational; readers ignore them (and any other "unused" bit).
inline constexpr uint8_t kGhdrHasDirectory = 0x01;

struct GtnFileHeader {
  uint8_t writer_flags = 0;
  uint64_t level_count = 0;
  uint64_t points = 0, tets = 0;       // of level 0
  uint64_t draft = kGtnDraftRevision;  // the draft revision of format 2.0 the file follows
  uint64_t piece_tets = 0;             // the writer's bound on a piece's tetrahedra (informative)
  ScalarType coord_type = ScalarType::kFloat64;
  std::vector<FieldDesc> point_fields, cell_fields;
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};  // of level 0
  std::string tool_version, command_line;                   // provenance
  std::vector<std::pair<std::string, std::string>> metadata;
};

struct GtnLevelRecord {
  uint64_t level = 0;
  uint64_t merges = 0;
  double ratio = 0.0;
  uint64_t points = 0, tets = 0, boundary_triangles = 0;
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  std::vector<PieceInfo> pieces;  // at least one; their tetrahedra sum to `tets`
  // Per piece: the byte sizes of its codec streams in PIEC order (BNDY, CONN, GEOM, each PFLD, each
  // CFLD); empty for a structured piece.
  std::vector<std::vector<uint64_t>> streams;
  // 1: the level names the vertices of the next level (level + 1) instead of storing their values
  // (spec section 7.7); 0: it stores every vertex's values.
  uint8_t base = 0;
};

// The seam table (SEAM payload): the classes and where each class's stream lies in the payload.
struct GtnSeamTable {
  std::vector<SeamClass> classes;
  std::vector<std::pair<uint64_t, uint64_t>> streams;  // per class: offset in the payload, size
};

struct GtnDirectoryEntry {
  ChunkTag tag;
  uint64_t offset = 0, size = 0;  // of the whole chunk (framing included)
  friend bool operator==(const GtnDirectoryEntry&, const GtnDirectoryEntry&) = default;
};
using GtnDirectory = std::vector<std::vector<GtnDirectoryEntry>>;  // per level, its chunks in file order

struct GtnTrailer {
  uint64_t directory_offset = 0, directory_size = 0;  // 0, 0: no directory
};

// Field descriptions as GHDR stores them (name, components, type), also used by other records.
void writeFields(ByteWriter& w, const std::vector<FieldDesc>& fields);
Status readFields(ByteReader& r, std::vector<FieldDesc>* fields, const char* what);

std::vector<uint8_t> encodeFileHeader(const GtnFileHeader& h);
// What an LHDR is coded against: the previous box (GHDR's for level 0, else the previous level's),
// whose equal bounds it does not store, and the number of codec streams of an unstructured piece.
struct LevelRecordContext {
  double prev_min[3] = {0, 0, 0}, prev_max[3] = {0, 0, 0};
  size_t streams = 3;  // 3 + point fields + cell fields
};
LevelRecordContext levelRecordContext(const GtnFileHeader& h);  // level 0's
// Level i + 1's, after level i's record r.
LevelRecordContext nextLevelRecordContext(const LevelRecordContext& c, const GtnLevelRecord& r);

std::vector<uint8_t> encodeLevelRecord(const GtnLevelRecord& r, const LevelRecordContext& c);
// The SEAM payload: the class table, then the class streams concatenated (one per class).
std::vector<uint8_t> encodeSeamTable(const std::vector<SeamClass>& classes,
                                     const std::vector<std::vector<uint8_t>>& streams);
std::vector<uint8_t> encodeDirectory(const GtnDirectory& d);
std::vector<uint8_t> encodeTrailer(const GtnTrailer& t);

// Decoders: `payload` is the chunk's (decompressed) payload, `offset` the file offset of its first byte
// (for messages; for zstd chunks, offsets point into the decompressed payload and say so).
Status decodeFileHeader(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnFileHeader* h);
// Checks the piece table against the level's counts too: kinds known, each piece's counts consistent,
// the pieces' tetrahedra summing to the level's. The one piece of a one-piece level stores only its
// kind and own boundary points; the rest is the level's.
Status decodeLevelRecord(std::span<const uint8_t> payload, uint64_t offset, const std::string& what,
                         const LevelRecordContext& c, GtnLevelRecord* r);
// Checks the table against level `level` (`points` points, piece table `pieces`): classes of 2 or more increasing piece indices below
// the piece count, in increasing lexicographic order, the seam points of each piece matching its
// piece entry, own and seam points summing to the level's, stream sizes summing to the payload.
Status decodeSeamTable(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, uint64_t level,
                       uint64_t points, std::span<const PieceInfo> pieces, GtnSeamTable* t);
Status decodeDirectory(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, uint64_t level_count,
                       GtnDirectory* d);
Status decodeTrailer(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnTrailer* t);

}  // namespace gtn
