// CONTRACT for the .gtn container (owned by format/; spec in spec/gtn-format.md). Writing and reading
// whole files; the reader decodes front to back and streams each level to a MeshSink.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "codec/pieces.h"
#include "format/gtn_records.h"
#include "mesh/mesh_stream.h"
#include "mesh/progress.h"
#include "mesh/tet_mesh.h"

namespace gtn {

class RuleGridTets;  // codec/grid_coder.h

// One level to write. For level 0 `merges` is 0; for mip level i it is the number of merge-tree merges
// already applied to obtain `mesh`. `merge_tree` (optional) produces the level's merge-tree chunk
// payload given the level's vertex_order (PiecedLevel::vertex_order: source vertex -> global id, so
// the tree is stored in decoding order).
struct GtnLevelInput {
  const TetMesh* mesh = nullptr;
  uint64_t merges = 0;
  double ratio = 0.0;  // vertices merged away / all vertices of level 0
  std::function<StatusOr<std::vector<uint8_t>>(const std::vector<uint32_t>& vertex_order)> merge_tree;
  // Optional, for a level that may name the next level's vertices (spec section 7.7): per vertex of
  // this level's mesh, its index in the next level's mesh (kNoIndex where it merges away before it),
  // and the level's merge-tree payload holding only the tree's first `merges` merges (those down to
  // the next level), for the level naming the next level's vertices by `next_index`. The writer names
  // the next level's vertices where that takes fewer bytes.
  std::function<StatusOr<std::vector<uint32_t>>()> next_index;
  std::function<StatusOr<std::vector<uint8_t>>(const std::vector<uint32_t>& vertex_order, uint64_t merges,
                                               const std::vector<uint32_t>& next_index)>
      merge_tree_prefix;
  // Optional: `mesh` already encoded by encodePieces with the default options and the write's
  // piece_tets (while the merge tree was ranked, say); the writer then uses it instead of encoding the
  // mesh (it sets the header's level and merges, and verifies it as it would its own). Where the writer
  // holds the only reference, it takes the encoding over (moves from it) instead of copying it, and
  // encodes the mesh again if it needs the level a second time.
  std::shared_ptr<PiecedLevel> encoded;
  // Instead of `mesh`: makes the level's mesh when the writer comes to it (in level order, just before
  // encoding it), so that a level the writer never reaches (past a storage bound) is never made. The
  // mesh must stay valid until writeGtnFile returns; a failure fails the write. `expected_tets` stands
  // for its tetrahedron count in the progress fractions until then.
  std::function<StatusOr<const TetMesh*>()> make_mesh;
  uint64_t expected_tets = 0;
  // Optional, with options.verify: a further check of the level's mesh, run where the writer checks
  // that the level decodes back (before that check; only for the levels it writes, perhaps on another
  // thread while the next level is encoded). A failure fails the write.
  std::function<Status(const TetMesh&)> check_mesh;
  // Optional, with `encoded` (one structured piece): the tetrahedra of `mesh`, made from their indices,
  // where the caller has released the mesh's (validate/write_gtn.h's GtnConvertOptions::
  // release_grid_tets); the writer reads them from here. The caller holds a reference to `encoded`,
  // so that the writer copies it rather than encode `mesh` again. Not for a level that may name the
  // next level's vertices (no next_index).
  const RuleGridTets* grid_tets = nullptr;
};

struct GtnWriteOptions {
  std::string tool_version;  // provenance
  std::string command_line;  // provenance
  bool zstd = true;          // zstd-compress chunks where it helps
  bool directory = true;     // write the directory and trailer for random access
  // The bound on a piece's tetrahedra (encodePieces; at least kMinPieceTets). Recorded in GHDR.
  uint64_t piece_tets = kDefaultPieceTets;
  // > 0: the storage bound of the mip levels. Independent levels (chain_levels off) are kept, finest
  // first, while all kept levels together take at most this multiple of level 0's bytes (every chunk of
  // a level, framing included); the first level that would pass the bound and all coarser ones are left
  // out. With chained levels the unit is level 0 stored alone with its whole tree, the streams and trees
  // are counted, and the coarsest levels are left out while the bound is passed. The last kept level
  // stores the rest of the merge tree, so nothing is lost but the shortcut.
  double level_storage_limit = 0.0;
  // Levels given next_index name the next level's vertices instead of storing their values again
  // where that is smaller (every level is then encoded before the file is written, coarsest first).
  bool chain_levels = true;
  // Decode every level that is written and check that it gives back its mesh exactly
  // (codec/level_check.h) before the file is committed; a level that would not fails the write.
  bool verify = true;
  // Optional: told "encode level I (N levels)" and "verify level I (N levels)" with the fraction of all
  // levels' tetrahedra done (mesh/progress.h).
  ProgressFn progress;
};

// Encodes every level (encodePieces, options.piece_tets), then writes the file atomically
// (format/file_io.h): prefix, GHDR, per level LHDR [SEAM] and per piece PIEC (its streams BNDY CONN
// GEOM PFLD... CFLD...) or GRID, then [MTRE]; then [DIRC] and GEND. Byte-identical whatever the thread count. All levels must
// share level 0's coordinate type and field descriptions. Deterministic: the same meshes and options
// give the same bytes. Fails with kUsage for an empty level list or a level with neither mesh nor
// make_mesh. With
// options.level_storage_limit set, the levels are encoded, finest first, before the first byte is
// written, so that the bound can be applied to the exact bytes; the encoding stops at the first level
// beyond the bound (the coarser ones are neither encoded nor verified).
Status writeGtnFile(const std::string& path, const std::vector<GtnLevelInput>& levels, const GtnWriteOptions& options);

// Zstd level the writer uses for chunks (fixed: part of what makes the output deterministic).
inline constexpr int kGtnZstdLevel = 9;

// Writes the container chunk by chunk to `out` (spec/gtn-format.md). The low-level half of
// writeGtnFile, public so that tools and tests can build files from already encoded levels and add
// chunks of their own (e.g. unknown ones, to test readers).
class GtnStreamWriter {
 public:
  using Output = std::function<Status(std::span<const uint8_t>)>;
  GtnStreamWriter(Output out, GtnWriteOptions options);

  // Writes the prefix and the GHDR. `level0` gives counts, coordinate type, fields, bounding box and
  // metadata; `level_count` how many levels will follow.
  Status begin(const LevelHeader& level0, uint64_t level_count);
  // Writes one level's chunks: LHDR with the piece table, SEAM when there are several pieces, each
  // piece's chunk (PIEC: its streams; GRID), MTRE (`merge_tree`, when given). `level.header.level` must be the next index, its
  // fields those of level 0, every piece's stream counts match its field counts, and the pieces'
  // tetrahedra sum to the level's.
  Status addLevel(const PiecedLevel& level, double ratio, const std::optional<std::vector<uint8_t>>& merge_tree);
  // A level coded by encodeLevel, written as one piece (tests and tools that hand-make streams).
  Status addLevel(const EncodedLevel& encoded, double ratio, const std::optional<std::vector<uint8_t>>& merge_tree);
  // Writes an arbitrary chunk here (part of the current level in the directory, if one has begun).
  Status addChunk(ChunkTag tag, std::span<const uint8_t> payload, bool ancillary);
  // Writes the directory (if enabled) and the end chunk. Fails if fewer levels than declared were added.
  Status finish();

  uint64_t offset() const { return offset_; }

 private:
  Status emit(ChunkTag tag, std::span<const uint8_t> payload, bool ancillary, bool try_zstd);

  Output out_;
  GtnWriteOptions options_;
  LevelHeader level0_;
  LevelRecordContext record_context_;  // what the next LHDR is coded against
  uint64_t level_count_ = 0;
  uint64_t levels_written_ = 0;
  uint64_t offset_ = 0;
  bool begun_ = false, finished_ = false;
  std::vector<std::vector<GtnDirectoryEntry>> directory_;
  std::vector<uint8_t> scratch_;
};

// The output of a GtnStreamWriter that writes to the open file `f`. Its failures ("write failed: No
// space left on device") name no file: the writer's caller names it once, with namedByOutput.
GtnStreamWriter::Output fileOutput(std::FILE* f);
// `st` with the output `path` before its message ("-": standard output), where it failed: for the
// failures of a GtnStreamWriter and its output, which name no file.
Status namedByOutput(const std::string& path, Status st);

// Assembles a whole file in memory from encoded levels, one piece each (tests, tools). `merge_trees` is empty or has
// one optional payload per level; `ratios` likewise (missing entries: 0).
StatusOr<std::vector<uint8_t>> assembleGtn(const std::vector<const EncodedLevel*>& levels,
                                           const GtnWriteOptions& options, const std::vector<double>& ratios = {},
                                           const std::vector<std::optional<std::vector<uint8_t>>>& merge_trees = {});

}  // namespace gtn
