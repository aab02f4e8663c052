// Writing a mesh as .gtn the way `gtn convert` does: level 0, its mip levels and merge trees as the
// options ask, every level decoded back and checked before the atomic rename (GtnWriteOptions::verify).
// The CLI and the Python package both write through here, so that their files are the same.
#pragma once

#include <string>
#include <vector>

#include "codec/pieces.h"
#include "format/gtn_file.h"
#include "mesh/tet_mesh.h"
#include "simplify/ranking.h"

namespace gtn {

// Automatic levels beside a level 0 stored as a structured piece: a mip level is stored only when it
// and the coarser levels (which it may name, and which a reader then decodes first) hold at most
// 1/kStructuredLevelShare of level 0's tetrahedra. A structured piece decodes at memory speed and on-
// the-fly simplification streams it at a small fraction of the level codec's cost per tetrahedron, so
// a larger mip level would read slower than level 0 simplified to its ratio, and take more bytes.
inline constexpr uint64_t kStructuredLevelShare = 12;

struct GtnConvertOptions {
  int levels = -1;             // mip levels beyond level 0; -1 = automatic (down to a small mesh), 0 = none
  bool merge_tree = true;      // store the merge trees (on-the-fly simplification); false: level 0 alone
  double level_storage = 2.0;  // automatic levels: all levels within this multiple of level 0's bytes (0 = no bound)
  RankingOptions ranking;
  // A mesh with errors of its own that `gtn validate` reports on the file (overlapping tetrahedra, a
  // boundary whose faces disagree in orientation): refused, nothing written, unless this is set (then
  // written with a warning). Checked where the writer verifies (GtnWriteOptions::verify).
  bool keep_invalid = false;
  // Where the caller lets the writer change the mesh while it works (the overload of
  // writeGtnWithLevels that takes a pointer), a grid of rule cells of this many tetrahedra or more
  // (a structured block with no alias and no exception, as level 0's structured piece codes it) has
  // its tetrahedra released from the ranking until the file is written, each one made from its index
  // where it is read (RankingOptions::grid_tets, GtnLevelInput::grid_tets), and made again before
  // writeGtnWithLevels returns: 16 bytes a tetrahedron less at a large convert's peak of memory.
  // Level 0 is then encoded and checked before the ranking rather than beside its tail, and a level 0
  // that may name the next level's vertices (levels asked for) gets them back before the file is
  // written. The file is the same.
  uint64_t release_grid_tets = uint64_t{1} << 22;
};

// Writes `mesh` (orientation normalised, e.g. by an importer) to `path`. `source` names the mesh in
// messages (the input file). The encoder's refusals become "<source>: cannot be encoded: <reason>"; a
// mesh with errors of its own is refused with kInvalidData naming them (GtnConvertOptions::keep_invalid).
// `warnings` (optional) receives what the user should hear about, e.g. fewer levels than asked for
// because the merge tree stops early.
// The merge tree a .gtn stores for `mesh` ranked as `ranked` (rankMerges), level 0 being `level0`
// (encodePieces), and the form level 0's payload codes it in: batched (batchMerges) by the keys its
// payloads order batches by, which are level 0's decoding ids where level 0 is one structured piece
// (whose tree codes its parents as grid places, or as deltas where the block has aliases, and so
// decodes without the level), and the positions elsewhere (parents as candidates); in the ranking's
// rounds of parts where it had them (RankingStats::rounds, from `ranking` where given), which the
// batches follow.
struct StoredMergeTree {
  MergeTree tree;
  MergeTreeForm level0_form;
};
StatusOr<StoredMergeTree> storedMergeTree(const TetMesh& mesh, const MergeTree& ranked, const PiecedLevel& level0,
                                          const RankingStats* ranking = nullptr,
                                          const RuleGridTets* grid_tets = nullptr);

Status writeGtnWithLevels(const std::string& path, const TetMesh& mesh, const GtnConvertOptions& options,
                          const GtnWriteOptions& write_options, const std::string& source,
                          std::vector<std::string>* warnings = nullptr);
// The same for a mesh the writer may change while it works (GtnConvertOptions::release_grid_tets):
// `mesh` is as it was given when this returns, on an error too.
Status writeGtnWithLevels(const std::string& path, TetMesh* mesh, const GtnConvertOptions& options,
                          const GtnWriteOptions& write_options, const std::string& source,
                          std::vector<std::string>* warnings = nullptr);

}  // namespace gtn
