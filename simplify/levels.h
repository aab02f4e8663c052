// Mip levels (paper section 5): level i is the mesh after the first N_i merges of the merge tree,
// N_i = U + round((1 - 1/2^i) * (points - U)) capped at the tree's merge count (U: leadingFreeMerges,
// the merges of the points no tetrahedron uses, which come first), compacted, with the rest of the
// merge tree (ranks shifted down by N_i) in that level's own numbering, so that any level can be
// refined further on the fly. The writer (format/gtn_file.h) stores a level either whole, with that
// tree, or naming the next level's vertices, with the tree's merges down to the next level only
// (spec section 7.7; wholeMergeTree below puts a level's tree back together).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "codec/grid_coder.h"
#include "codec/merge_tree_coder.h"
#include "format/gtn_file.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

struct LevelOptions {
  int levels = -1;            // mip levels beyond level 0; -1 = down to a small mesh
  uint64_t min_points = 256;  // automatic levels stop before a level would have fewer points
  bool merge_tree = true;     // store each level's merge tree
  // Automatic levels also stop before a level would have fewer tetrahedra than the smallest piece
  // (codec/pieces.h, kMinPieceTets): below that a level's own costs (its connectivity, its sparse
  // vertices' values, each stream's models learning from nothing) come to 19-25 bits a tetrahedron
  // against 15-18 for level 0. A coarser view is read on the fly from the coarsest stored level
  // instead: the bunny's at ratio 0.95 in 18-23 ms rather than 5-6 ms from its own level.
  uint64_t min_tets = kMinPieceTets;
};

// N_i for level i of a mesh with `points` vertices and a tree of `merges` merges.
uint64_t levelMerges(int level, uint64_t points, uint64_t merges);

// U = leadingFreeMerges(tree) (codec/merge_tree_coder.h): the merges of the points no tetrahedron uses,
// which come first. The merges of a level, a ratio or a target count on from there: N_i = U +
// levelMerges(i, points - U, merges - U), and a ratio is (merges - U) / (points - U), over the
// vertices tetrahedra use.

struct MipLevels {
  // meshes[0] is empty: level 0 is the source mesh, which the caller keeps.
  std::vector<TetMesh> meshes;
  std::vector<std::shared_ptr<const MergeTree>> trees;  // per level, in the level's numbering
  std::vector<uint64_t> merges;                         // N_i
  std::vector<double> ratios;                           // N_i / points of level 0
  std::vector<std::vector<uint32_t>> next_index;        // per level but the last: vertex -> next level's

  // The inputs for writeGtnFile; `source` is level 0 and must outlive the result, as must *this. The
  // merge trees are MTRE version 4, level 0's in `level0_form` (validate/write_gtn.h's storedMergeTree
  // says which the writer chooses), the others with their parents as candidates.
  std::vector<GtnLevelInput> inputs(const TetMesh& source, const MergeTreeForm& level0_form = {}) const;
  // Every level's mesh, `source` (level 0) first.
  std::vector<const TetMesh*> levelMeshes(const TetMesh& source) const;
};

// Builds the levels of `source` from its merge tree (level 0 included, with the whole tree).
StatusOr<MipLevels> buildMipLevels(const TetMesh& source, const MergeTree& tree, const LevelOptions& options);

// The levels of buildMipLevels, built on demand: how many there are, and each one's merges and ratio,
// are known from the start (they depend on counts only); level i's mesh and tree are made when it is
// first asked for, from level i - 1's, so that a writer that stops early (a storage bound) builds no
// level it does not store. `source` and `tree` must outlive the builder. Not thread-safe; the meshes
// and trees it returns stay valid (and unchanged) while it lives, whatever is built after them.
class MipLevelBuilder {
 public:
  // `source_tets`, where given, are the source's tetrahedra where its caller has released them
  // (applyMerges); they must outlive the builder.
  static StatusOr<MipLevelBuilder> create(const TetMesh& source, const MergeTree& tree, const LevelOptions& options,
                                          const RuleGridTets* source_tets = nullptr);

  size_t count() const { return merges_.size(); }                  // levels, level 0 included
  const std::vector<uint64_t>& merges() const { return merges_; }  // N_i
  const std::vector<double>& ratios() const { return ratios_; }    // N_i / points of level 0
  size_t built() const { return meshes_.size(); }                  // levels made so far, level 0 included
  // Level i's mesh (level 0: the source), building the levels up to it first.
  StatusOr<const TetMesh*> level(size_t i);
  // Level i's tetrahedra, from the tree's counts: nothing is built.
  uint64_t tetsOf(size_t i) const;
  // The levels from 1 to first - 1 will never be asked for (a writer stores level 0 and levels first
  // on): level first is then made from the source in one pass, and the levels between are never made.
  // Before any level is built; first >= 1.
  void skipTo(size_t first) { skip_to_ = first; }
  // Level i's merge tree in its numbering, once level i is built; null where options.merge_tree is off
  // and for the levels skipTo leaves out.
  std::shared_ptr<const MergeTree> tree(size_t i) const { return i < trees_.size() ? trees_[i] : nullptr; }
  // Per vertex of level i, its index in level i + 1 (MergeTree::kRoot where it merges away), once level
  // i + 1 is built; empty before, and for the levels skipTo leaves out.
  const std::vector<uint32_t>& nextIndex(size_t i) const {
    static const std::vector<uint32_t> none;
    return i < next_index_.size() ? next_index_[i] : none;
  }

 private:
  friend StatusOr<MipLevels> buildMipLevels(const TetMesh&, const MergeTree&, const LevelOptions&);
  MipLevelBuilder(const TetMesh& source, const MergeTree& tree, bool keep_trees);

  const TetMesh* source_;
  const RuleGridTets* source_tets_ = nullptr;
  uint64_t source_tet_count_ = 0;
  const MergeTree* tree_;
  bool keep_trees_;
  size_t skip_to_ = 1;
  std::vector<uint64_t> merges_;
  std::vector<double> ratios_;
  std::vector<std::unique_ptr<TetMesh>> meshes_;         // meshes_[0] is null: the source
  std::vector<std::shared_ptr<const MergeTree>> trees_;  // kept where keep_trees_
  std::shared_ptr<const MergeTree> finest_tree_;         // the newest level's tree, to build the next
  std::vector<std::vector<uint32_t>> next_index_;        // per built level but the newest: to the next
};

// The finest stored level to start from for a target of `target_merges` merges: the index of the
// largest level_merges[i] <= target_merges (level_merges ascending, level_merges[0] = 0).
size_t chooseLevel(const std::vector<uint64_t>& level_merges, uint64_t target_merges);

}  // namespace gtn

namespace gtn {

class GtnReader;

// Where a reader starts for a target of `target_merges` merges (counted on level 0's tree): the
// finest stored level with no more merges than the target, and the merges still to apply on the fly.
struct SimplifyPlan {
  size_t level = 0;
  uint64_t extra_merges = 0;
};
StatusOr<SimplifyPlan> planSimplification(const GtnReader& reader, uint64_t target_merges);

// Merges for a target simplification ratio (vertices merged away / vertices of level 0, counting the
// vertices tetrahedra use: U + ratio * (points - U), rounded, U read from level 0's merge tree when it
// has one).
StatusOr<uint64_t> mergesForRatio(GtnReader& reader, double ratio);
// U of level 0's merge tree (leadingFreeMerges); 0 when level 0 stores none. The ratio of N merges
// is (N - U) / (points - U).
StatusOr<uint64_t> levelZeroUnreferencedMerges(GtnReader& reader);

// The whole merge tree of level i, in its vertex numbering. A level that names the next level's
// vertices (GtnLevelInfo::base) stores only the merges down to that level; the rest is the next
// level's whole tree, renumbered through the ids the level gives the next level's vertices. nullopt
// when a level of the chain stores no merge tree. `base_ids` (optional): per level, what
// GtnReader::decodeLevel's base_ids gave (a level whose entry is missing or empty is decoded again to
// get them). Fails, naming the file and level, where the stored trees and levels do not fit together.
// `meshes` (optional): per level, its mesh as decoded (null entries, or levels past its end, are decoded
// where a tree needs them).
StatusOr<std::optional<MergeTree>> wholeMergeTree(GtnReader& reader, size_t i,
                                                  const std::vector<std::vector<uint32_t>>* base_ids = nullptr,
                                                  const std::vector<const TetMesh*>* meshes = nullptr);

// Level i's own merge tree, its first `max_merges` merges, for simplifying the level on the fly. A tree
// that is decoded against its level (merge_tree_coder.h, version 3) has the level decoded first, into
// `decoded`, with `fields`; emitLevel then replays it instead of decoding the level again.
struct LevelTree {
  size_t level = 0;
  MergeTree tree;
  std::unique_ptr<TetMeshBuilder> decoded;
};
StatusOr<LevelTree> levelMergeTree(GtnReader& reader, size_t i, uint64_t max_merges, const DecodeFields* fields);
// Streams the level of `level` to `sink` (a StreamSimplifier over level.tree, say).
Status emitLevel(GtnReader& reader, const LevelTree& level, MeshSink& sink, const DecodeFields* fields);

// Streams the mesh after `target_merges` merges to `sink`: decodes the planned level and, when merges
// remain, filters it through a StreamSimplifier with that level's merge tree. Fails with kUsage when
// merges remain and the level stores no merge tree, or the target exceeds the stored merges (unless
// `clamp`, which then applies them all: a ratio beyond what the tree allows gets the coarsest mesh).
// `fields` (optional): the fields to decode (level_codec.h).
Status streamSimplified(GtnReader& reader, uint64_t target_merges, MeshSink& sink, SimplifyPlan* plan_out = nullptr,
                        bool clamp = false, const DecodeFields* fields = nullptr);

}  // namespace gtn
