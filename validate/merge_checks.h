// The merge-tree and levels layers of the validator: the forest of ranked merges of level 0 is replayed
// in rank order on an incremental copy of level 0 (vertex -> tetrahedra incidence; each merge checks
// only the tetrahedra and boundary triangles around the merged vertex), and every stored mip level is
// compared, up to renumbering, with the replay at its number of merges.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "codec/merge_tree_coder.h"
#include "mesh/index.h"
#include "mesh/tet_mesh.h"
#include "validate/report.h"

namespace gtn {

inline constexpr uint32_t kMergeRoot = kNoIndex;

// One merge per non-root vertex v: v merges into parent[v] (or into whatever parent[v] has merged
// into by then) as the rank[v]-th merge. Roots have parent kMergeRoot and rank 0. Indices are level 0's
// vertex ids (decoding order).
struct MergeForest {
  std::vector<uint32_t> parent;
  std::vector<uint64_t> rank;
  // Optional annotations a file stores per vertex (empty when absent): 1 when v's merge is a boundary
  // merge, and the number of tetrahedra v's merge removes. Checked against the replay.
  std::vector<uint8_t> boundary;
  std::vector<uint32_t> removed;
};

// The forest of a decoded merge tree, with its annotations.
MergeForest forestFromTree(const MergeTree& tree);

// A stored mip level to compare with the replay.
struct StoredLevel {
  uint32_t level = 0;
  uint64_t merges = 0;
  double ratio = -1.0;  // declared ratio; negative when the file declares none
  const TetMesh* mesh = nullptr;
};

struct MergeReplayStats {
  uint64_t merges = 0;           // M
  uint64_t roots = 0;            // independent vertices
  uint64_t boundary_merges = 0;  // merges of a boundary vertex
  uint64_t tets_checked = 0;     // orientation tests made during the replay
  uint64_t max_depth = 0;        // longest root path in the forest
};

// Checks the forest (MERGE_TREE_*), replays it (MERGE_*) and compares the stored levels
// (LEVEL_*). `level0` must have passed checkMesh (indices in range); tetrahedra with non-finite points
// make the geometric checks skip. Levels are identified in paths as /levels/<level>.
void checkMergeTree(const TetMesh& level0, const MergeForest& forest, const std::vector<StoredLevel>& levels,
                    ValidationReport& report, MergeReplayStats* stats = nullptr);

}  // namespace gtn
