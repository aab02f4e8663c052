// Static ranking of edge collapses (paper section 4.1, after Van Gelder, Verma and Wilhelms, GVW99):
// greedy selection of vertex merges Vi -> Vj along mesh edges by smallest error, producing the merge
// tree (codec/merge_tree_coder.h). Rank = the order the merges were chosen, so every prefix of the
// ranked list applied to the source gives a valid mesh.
//
// Error of a candidate merge v -> w (w keeps its position and values):
//   E = w_density * Error_density / total_mass + w_geometry * Error_geometry / boundary_area
// where, over the tetrahedra t incident to v (the affected tetrahedra),
//   mass(t) = (mean of the density at t's four vertices) * volume(t)   (volume in floating point),
//   change(t) = mass_after(t) - mass_before(t), with mass_after = 0 for the tetrahedra that contain w
//               and collapse (so their whole mass counts),
//   Error_density = | sum_t change(t) | + (1/16) * sum_t | change(t) |
//                   (the net change of the mass of the affected tetrahedra, as in GVW99, plus a small
//                   share of the local redistribution so that merges with no net change are still
//                   ordered by how much they move mass around; the net term alone keeps the shape:
//                   a merge that cuts off volume changes the net mass, an interior one does not),
//   total_mass = sum over all tetrahedra of |mass| (total volume if that is 0, then 1);
// and, only for a boundary v, over the boundary triangles incident to v (the affected old faces, of
// total area A): every new triangle f' (an old triangle (v, x, y) not containing w, with v replaced by
// w) is paired with each old triangle g that shares an edge with f' (its own old triangle and the
// collapsing triangles (v, w, x) / (v, w, y)); Error_geometry = sum over pairs |area(f') - area(g)|
// * area(g) / A; boundary_area = total boundary area of the source (1 if 0).
// The density is the chosen point field's first component (non-finite values count as 0); with no
// point field (or field "none", or only constant ones by default) the density is 1 and the mass is the
// volume.
//
// Constraints (a candidate violating one is never chosen):
//  - a boundary vertex merges only into a boundary vertex along a boundary edge in exactly two
//    boundary triangles (the two a boundary merge removes, as readers assume: an edge where the
//    boundary is non-manifold, in four or more, never collapses); interior vertices merge into any
//    neighbour;
//  - every tetrahedron that changes (contains v, not w) keeps a positive orientation by the exact
//    predicate orient3d: no tetrahedron is inverted or newly flattened. Exception: when w has exactly
//    v's coordinates the geometry of every changed tetrahedron is unchanged, so tetrahedra that were
//    already flat in the source (coincident PLOT3D points) may stay flat; flat ones collapse;
//  - no boundary triangle flips: the old and new normals of every changed boundary triangle satisfy
//    n_old . n_new > 1e-3 |n_old| |n_new| (a conservative margin against rounding), and n_old . n_new
//    exceeds a bound on its rounding error, so that its sign is certain (a new triangle flat up to
//    rounding has a meaningless float normal; the validator decides the sign exactly);
//  - the link condition of Dey, Edelsbrunner, Guha and Nekhayev for the complex with the boundary
//    coned to a virtual vertex: Lk(v) ∩ Lk(w) = Lk(vw). It keeps every intermediate mesh a
//    manifold tetrahedral mesh of the same topology (no duplicate tetrahedron, no face in three);
//  - vertices on faces shared by three or more tetrahedra (non-manifold input) are never merged;
//  - the vertices of a tetrahedron that lists a shared face in the same direction as its neighbour
//    does (a flat tetrahedron oriented against its neighbours; mesh_stats.h's orientFlatTets gives
//    flat ones their neighbours' orientation where it can) are never merged away: every changed or
//    collapsing tetrahedron then has consistently oriented faces, so the faces a collapse glues
//    together run in opposite directions and the two tetrahedra on a face, both positive or flat, lie
//    on its two sides. A collapse next to a flat tetrahedron is judged on the tetrahedra it produces.
//
// Points no tetrahedron uses that sit at an edge's midpoint (the mid-edge nodes of quadratic cells,
// codec/edge_points.h) are merged first, each into its edge's first end: merges 1..U remove nothing,
// and every mip level and simplified mesh leaves them out (level 0 alone keeps them). Ratios and level
// targets count the other merges against the referenced vertices (simplify/levels.h).
//
// Candidates are kept per vertex (its best target) in an indexed priority queue ordered by (error, v,
// w), one entry per vertex, replaced in place, and each popped candidate is checked exactly before it
// is applied. After a merge v -> w, w's candidate is recomputed; v's former neighbours' candidates are
// recomputed too (greedy), or by default only marked stale (lazy): a stale candidate that comes to the
// top of the queue is recomputed and queued again by its new error, and only a fresh one is applied.
// In parts (RankingOptions::parts; large meshes by default): the vertices are first split into P parts
// of about equal counts by recursive bisection of their positions, and each part, on its own thread,
// ranks merges between its vertices that share no tetrahedron with another part's (the seams), with
// its own queue, up to the round's bound on the error: 0.6 quantile of the errors of the best
// candidates of the round's vertices as it starts, the same for every part, so that the parts stop
// at about the same error (a part of a busy field does not run ahead of a smooth one, as it did when
// each part merged a fixed share of its vertices). Such merges touch no tetrahedron another part
// reads, so the parts' merges commute: they are interleaved by error, each part's in its own order,
// and every prefix is still a valid mesh. Up to six rounds do the same with the vertices left, in
// P - 1, P - 2, ... parts (at least 2), whose cuts fall elsewhere, so that most of the last round's
// seams are inside the next one's parts. Large meshes are ranked in many parts of a bounded size
// (their data stays near the processor); where P is 16 or more, such a fine series of rounds (its
// cuts shifted from round to round) is followed by another, in parts of the same size on the mesh
// left, and at last by a series in 8, 7, ... 3 parts, which takes most of the fine rounds' seams
// (nextRankingSeries). The whole mesh's queue then goes on with every vertex left, the seams
// included, which releases them: the coarse levels are not frozen along the parts' seams.
// The tree depends on the number of parts, never on the number of threads.
//
// Lazy evaluation computes about a third of the candidates (a merge changes the stars of some eight
// vertices, and most are merged or changed again before they come to the top), and a vertex whose
// error a nearby merge lowered waits until its old error comes up: the order differs from the greedy
// one, and so does the tree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "codec/merge_tree_coder.h"
#include "mesh/progress.h"
#include "mesh/tet_mesh.h"

namespace gtn {

class RuleGridTets;  // codec/grid_coder.h

// What the ranking learns of the mesh's faces before its first merge: the vertices on the boundary,
// those on a face of three or more tetrahedra (never merged), those on a face both its tetrahedra
// list in the same direction (never merged away), and the boundary's area (the geometric error's
// scale). batchMerges takes them from the ranking of the same mesh (RankingStats::faces) instead of
// matching the faces again.
struct RankingFaces {
  std::vector<uint8_t> boundary, frozen, pinned;  // per point
  double area_scale = 1;
};

// The ranking's face flags of `mesh` (from mesh/faces.h's classifyFaces: 2 bytes a tetrahedron
// while they are made, besides the face matching's own).
RankingFaces rankingFaces(const TetMesh& mesh);

struct RankingOptions {
  // Point field that gives the density: "" = the first point field whose first component is not
  // constant (mesh_stats.h's defaultPointField; volume only when every one is), "none" = volume only.
  std::string field;
  double w_density = 1.0;
  double w_geometry = 1.0;
  uint64_t max_merges = UINT64_MAX;  // stop after this many merges
  // Recompute the candidates a merge makes stale when they come to the top of the queue (lazy, the
  // default) rather than after every merge (greedy); see above.
  bool lazy = true;
  // Rank in this many parts first (see above), 1 = not in parts; 0 = automatic: for meshes of 2^20
  // tetrahedra or more, one part per 2^18 tetrahedra (8 at least, 256 at most), else 1. The tree
  // depends on it (not on the threads).
  uint32_t parts = 0;
  // Called once, on the ranking's thread, as the ranking's tail starts: the coarse rounds after the
  // fine ones (see above), or else the whole mesh's queue (after the rounds of parts, whose star lists
  // are gone by then, or at once). Where a caller starts work to run beside the tail, which leaves
  // threads idle: the whole mesh's queue is one thread's work, and the coarse rounds' few parts
  // differ in size.
  std::function<void()> beside_ranking_tail{};
  // The face flags where the caller has them (rankingFaces of the same mesh); made otherwise.
  const RankingFaces* faces = nullptr;
  // The mesh's tetrahedra where its caller has released them (mesh.tets empty) to hold 16 bytes a
  // tetrahedron less while the merges are ranked and batched: a grid of rule cells, each tetrahedron
  // made from its index (codec/grid_coder.h). `faces` must then be given. The tree is the same.
  const RuleGridTets* grid_tets = nullptr;
};

// The part count of the series of rounds after a series in `parts` parts, with `live_tets` tetrahedra
// left; 0 where that series was the last (see above and ranking.cpp).
uint32_t nextRankingSeries(uint32_t parts, size_t live_tets);

// A round of the ranking in parts (see above): how many merges it made (the ranks after those of the
// rounds before it, and after the unused points' merges), in how many parts, each vertex's part, and
// the bound on the errors of its merges.
struct RankingRound {
  uint64_t merges = 0;
  uint32_t parts = 0;
  std::vector<uint8_t> part;
  float error_limit = 0;
};

struct RankingStats {
  double seconds = 0;
  uint64_t merges = 0, boundary_merges = 0;
  uint64_t popped = 0;                       // queue entries examined
  uint64_t rejected = 0;                     // popped candidates that failed the exact checks
  uint64_t stale = 0;                        // popped candidates recomputed because they were stale (lazy)
  uint32_t parts = 1;                        // parts ranked first (RankingOptions::parts)
  uint64_t part_merges = 0;                  // merges made in the parts, before the whole mesh's queue
  uint64_t evaluations = 0;                  // candidate errors computed
  uint64_t star_pool_corners = 0;            // the room the largest pool of corner lists took (4 bytes each)
  uint64_t star_compactions = 0;             // times the corner lists were moved down over abandoned ones
  std::vector<RankingRound> rounds;          // the rounds of parts, in order (batchMerges follows them)
  RankingFaces faces;                        // for batchMerges; empty where RankingOptions::faces gave them
  std::string field;                         // density field used ("" = volume)
  std::vector<std::string> constant_fields;  // the default skipped these point fields (constant)
};

// What `gtn convert` says when the default density skipped constant fields: "the simplification
// ranks on field 'X' (constant: 'A', 'B'; --simplify-field chooses another)"; "" when none was skipped.
std::string defaultFieldNote(const RankingStats& stats);

// The usage errors rankMerges returns before any work: a mesh too large for 32-bit ids, a field
// that is not a point field of `mesh`, weights that are negative or not finite.
Status checkRankingOptions(const TetMesh& mesh, const RankingOptions& options);

// Ranks the merges of `mesh` (tetrahedra positively oriented, zero-volume ones allowed). The tree's
// error vector and quantiles are filled. Fails with kUsage if `options.field` names no point field.
// `progress` (optional) is told "rank merges" with the share of the points merged so far.
StatusOr<MergeTree> rankMerges(const TetMesh& mesh, const RankingOptions& options, RankingStats* stats,
                               const ProgressFn& progress = {});

// Batches (MTRE payload version 4, spec section 11): the ranked merges regrouped so that most of their
// order need not be coded. Batch after batch, the next ceil(U / divisor) merges by rank (U = the
// vertices not merged yet; the leading merges of unused points are a batch of their own) are made in
// passes (at most 8) in the order of keys[child] (ties to the smaller child): a merge waits while a
// merge of the batch ranked before it has its child in the star of its own child, and is made when
// the ranking's checks allow it (ranking.h's constraints, the link condition included, in the mesh the
// merges before it made), into the vertex its ranked parent has been merged into by then. The ones
// left follow by rank; one whose parent the new order no longer allows takes the target the ranking's
// error prefers among those allowed; any that still cannot merge goes on to the next batch, where it
// comes first (and one that can merge in no batch stays a root). So a batch normally ends where the
// ranking's prefix of the same merges does, and every prefix of the result is a valid mesh, as it is
// of the ranking's. The keys are those the payload orders a batch by (codec/merge_tree_coder.h): by
// position, or by decoding id. The tree's error, provenance and quantiles are the ranking's.
//
// Given the ranking's rounds of parts (RankingStats::rounds), each round's merges are batched in its
// parts, in parallel: a part's merges touch no other part (the ranking's restriction holds in the
// batches too: no merge, retargeted ones included, into or from a vertex next to another part), so
// each part makes its batches as above from its own merges, with U its own vertices not merged yet,
// carried merges stay in the part, and the i-th batch of the round is the parts' i-th batches
// together, in the order of their passes and within a pass by key (then the deferred ones, by
// rank). Any interleaving of merges of distinct parts is a valid order, since they commute. The
// merges after the rounds are batched on the whole mesh. The tree depends on the rounds, never on
// the number of threads. `faces`, where given, are the ranking's of the same mesh (RankingStats::faces);
// `grid_tets` as RankingOptions::grid_tets (then `faces` must be given).
// The keys the batches order merges by (above), per vertex: given, or made from the vertices'
// decoding ids (codec/merge_tree_coder.h's batchKeyOfId), which holds no array of keys (8 bytes a
// vertex). Refers to the caller's vector, which must outlive it.
class BatchKeys {
 public:
  BatchKeys(const std::vector<uint64_t>& keys) : keys_(&keys) {}  // NOLINT: a vector of keys is keys
  static BatchKeys ofIds(const std::vector<uint32_t>& ids) { return BatchKeys(&ids); }
  size_t size() const { return keys_ ? keys_->size() : ids_->size(); }
  uint64_t operator[](uint32_t v) const { return keys_ ? (*keys_)[v] : batchKeyOfId((*ids_)[v]); }

 private:
  explicit BatchKeys(const std::vector<uint32_t>* ids) : ids_(ids) {}
  const std::vector<uint64_t>* keys_ = nullptr;
  const std::vector<uint32_t>* ids_ = nullptr;
};

struct BatchStats {
  uint64_t batches = 0;
  uint64_t deferred = 0;    // merges the passes left (then merged by rank)
  uint64_t carried = 0;     // merges moved to the next batch
  uint64_t passes = 0;      // passes in key order, over all batches
  uint64_t unchecked = 0;   // merges made in the neighbourhood the ranking made them in (not checked again)
  uint64_t retargeted = 0;  // merged into another target than the ranking's (its parent was not allowed)
  uint64_t dropped = 0;     // merges left out (their children stay roots)
  double seconds = 0;
};
StatusOr<MergeTree> batchMerges(const TetMesh& mesh, const MergeTree& ranked, const BatchKeys& keys, uint32_t divisor,
                                BatchStats* stats = nullptr, const std::vector<RankingRound>& rounds = {},
                                const RankingFaces* faces = nullptr, const RuleGridTets* grid_tets = nullptr);

}  // namespace gtn
