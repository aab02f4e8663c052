// Applying a prefix of the merge tree in memory: the reference result that the on-the-fly stream
// filter (stream_simplifier.h) and the stored mip levels (levels.h) must reproduce exactly.
#pragma once

#include <cstdint>
#include <vector>

#include "codec/grid_coder.h"
#include "codec/merge_tree_coder.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// ancestor[v] after the merges of rank <= n (paper section 4.2: a top-down traversal of the merge
// tree, parents before children because ranks increase towards the roots). The tree must satisfy
// MergeTree::check; n is clamped to tree.merges.
std::vector<uint32_t> computeAncestors(const MergeTree& tree, uint64_t n);

// The mesh after the first n merges (rank order): every vertex replaced by its ancestor,
// tetrahedra with two equal vertices dropped, surviving vertices compacted in their original order,
// tetrahedra and cell fields kept in their original order. new_index (optional) receives, per source
// vertex, its index in the result or MergeTree::kRoot when it was merged away.
// `grid_tets`, where given, are the mesh's tetrahedra where its caller has released them (mesh.tets
// empty; simplify/ranking.h's RankingOptions::grid_tets).
StatusOr<TetMesh> applyMerges(const TetMesh& mesh, const MergeTree& tree, uint64_t n,
                              std::vector<uint32_t>* new_index = nullptr, const RuleGridTets* grid_tets = nullptr);

// The rest of the tree after the first n merges, in the numbering new_index gives (applyMerges):
// ranks shifted down by n, merged-away vertices dropped.
MergeTree remainingTree(const MergeTree& tree, uint64_t n, const std::vector<uint32_t>& new_index);

}  // namespace gtn

namespace gtn {

// Shape of a merge tree, as `gtn info --merge-tree` reports it, over the vertices tetrahedra use (the
// first merges, of points no tetrahedron uses, are left out: codec/merge_tree_coder.h's leadingFreeMerges).
struct MergeTreeStats {
  uint64_t points = 0, merges = 0, roots = 0, boundary_merges = 0, tets_removed = 0;
  uint64_t depth_max = 0;   // merges on the longest path from a vertex to its root
  double depth_mean = 0;    // over all vertices (roots have depth 0)
  uint64_t fanout_max = 0;  // children of one vertex
  double fanout_mean = 0;   // over the vertices that have children
};
MergeTreeStats computeMergeTreeStats(const MergeTree& tree);

}  // namespace gtn
