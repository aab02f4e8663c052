// The merge tree (paper section 4.1) and the coding of a level's merge-tree chunk payload.
//
// A merge tree is a forest over the vertices of one level: every merged vertex v has a parent p (the
// vertex it is merged into, Vv -> Vp) and a rank in 1..M (the order in which the static ranking chose
// the merge); roots are the vertices that are never merged. Along every path ranks strictly increase
// (a vertex can only be merged into a vertex that is still alive), which makes the tree acyclic and
// lets a top-down traversal compute ancestors in one pass.
//
// Payload layout (spec section 11; versions 2 to 5, writers write 5; little-endian; varint =
// unsigned LEB128, at most 10 bytes):
//   u8      version                  = 5 (or 2, 3, 4)
//   varint  points P                 vertices of the level (must equal the level header's count)
//   varint  merges M                 M <= P
//   varint  boundary_merges          merges whose child is a boundary vertex
//   varint  tets_removed             sum over merges of the tetrahedra each merge removes
//   varint  free_merges              versions 3 to 5: leadingFreeMerges (below)
//   u8      parent_form              versions 4 and 5: 3 = parents as candidates, 4 = as grid places,
//                                    2 = as deltas (version 3 has 3, version 2 has 2)
//   varint  batch_divisor d          versions 4 and 5: the batches' rule, ceil(unmerged / d)
//   u8      inferred                 version 5: 1 = removed counts and 2 = boundary bits not coded
//                                    (read off the level's mesh; parent_form 3 only), 4 = the
//                                    children drawn from the level's own vertices (a level naming the
//                                    next level's; decodeMergeTree's next_ids)
//   f64     w_density, w_geometry    weights the ranking used (provenance)
//   varint  n, then n bytes          name of the density field ("" = volume only)
//   u8      q                        number of error quantiles (0 or 9)
//   f64 x q (version 5: f32 x q)     error at the quantiles 0, .01, .1, .25, .5, .75, .9, .99, 1 of the
//                                    merges (error when chosen, normalised as in simplify/ranking.h)
//   varint  body_bytes, then the body: one stream of codec/range_coder.h (adaptive BitModel bits,
//           BitTree symbols, direct bits; the encoder's flush ends it) holding the merges in rank
//           order r = 1..M, so that a reader that applies only the first N merges decodes only the
//           first N records. Versions 4 and 5 code their records in batches, each one's children and their
//           order before its records (encodeBatch in the .cpp, spec section 11 "Batches"): the size
//           (the rule's, or a length code), the children as gaps among the unmerged, then runs of
//           them in key order (batchKeyOfPoint or batchKeyOfId, by parent_form) and the rest as
//           uniform places. Merge r, child c (the vertex merged away) into parent p, ids in the
//           level's vertex numbering 0..P-1 (decoding order):
//       versions 2 and 3:
//       uniform x in [0, U)          U = P - (r - 1), the vertices not merged yet; c is the (x+1)-th
//                                    smallest of them. Truncated binary in direct bits: b =
//                                    bitlen(U-1), u = 2^b - U; b-1 bits y; if y >= u one more bit,
//                                    x = 2y + bit - u. Nothing is coded when U = 1.
//       bit   boundary               one model; 1 = c is a boundary vertex
//       parent_form 3, when c has K > 0 parent candidates (ParentCandidates in the .cpp: the vertices
//       that share a tetrahedron of the level with c or with a vertex merged into c, each replaced by
//       the vertex it has been merged into, nearest c first, ties to the smaller id):
//         BitTree<4> s                 tree per boundary bit; s < 14: p is candidate s; 14: candidate
//                                      14 + uniform in [0, K - 14); 15: p is no candidate, and the
//                                      version 2 parent code follows
//       version 2 parent code: delta = p - c, predicted by D: the deltas of the merges already coded
//       whose children are ids c-1, c+1, c-2, c+2, c-3, c+3, c-4, c+4 (those in range and merged, in
//       that order; values may repeat; DeltaPredictions in the .cpp):
//       if |D| > 0: bit exact          model per boundary bit; 1 = delta == D[h]
//       if exact:   BitTree<3>  h      the first such h
//       else:
//         BitTree<4>  k                k = 0: no prediction; k = j (1 <= j <= |D|): residual from D[j-1]
//                                      (the encoder picks the smallest |residual|, ties to lower k);
//                                      residual = delta - (k ? D[k-1] : 0)
//         BitTree<6>  len              tree per context (k == 0, k > 0); len = bit length of |residual|
//                                      (0..33; 0 means residual 0)
//         if len > 0:
//           bit   sign                 model per context; 1 = residual < 0
//           len-1 direct bits          |residual| below its leading one
//       BitTree<4>  t                  tree per boundary bit; t = tetrahedra the merge removes, 15 =
//                                      escape followed by 32 direct bits holding t
// The decoder rejects: an unknown version, P different from the expected count, M > P, a candidate
// index out of range, h >= |D|, k > |D|, len > 33, a parent out of range, equal to c or already merged
// (its rank must be larger), a body read past its end, and, when it decodes all M merges, counts that
// disagree with the header fields and trailing bytes.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mesh/index.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gtn {

struct MergeTree {
  static constexpr uint32_t kRoot = kNoIndex;
  std::vector<uint32_t> parent;   // per vertex: the vertex it merges into, or kRoot
  std::vector<uint32_t> rank;     // per vertex: 1..M for merged vertices, 0 for roots
  std::vector<uint32_t> removed;  // per vertex: tetrahedra its merge removes (0 for roots)
  std::vector<uint8_t> boundary;  // per vertex: 1 if v is a boundary vertex (its merge is a boundary merge)
  std::vector<float> error;       // per vertex: error of its merge when chosen (not coded; may be empty)
  uint64_t merges = 0;            // ranks 1..merges
  // Batches of the ranks (version 4; simplify/ranking.h's batchMerges): the sizes of consecutive runs
  // of ranks, each merged in an order the payload need not code (see batchKeyOfPoint), summing to
  // `merges`; empty = none chosen (the encoder then cuts by the rule, ceil(unmerged / divisor)).
  std::vector<uint32_t> batches;
  uint32_t batch_divisor = 0;  // the rule's divisor the batches were made with (0 = the default)
  // Set by decodeMergeTree, whose trees satisfy check() by construction, so that the stream filter
  // need not check them again; whoever changes such a tree must clear it.
  bool checked = false;

  // Provenance and summary, coded in the payload header.
  std::string field;  // density field, "" = volume only
  double w_density = 0, w_geometry = 0;
  std::vector<double> error_quantiles;  // 0 or 9 values, see the payload layout

  size_t points() const { return parent.size(); }
  // n vertices, every one a root: no merge (errors, provenance and quantiles are left as they are).
  void makeRoots(size_t n);
  // Number of boundary merges and tetrahedra removed among the merges of rank <= n.
  uint64_t boundaryMergesUpTo(uint64_t n) const;
  uint64_t tetsRemovedUpTo(uint64_t n) const;
  // Structural checks of the definition above (sizes, ranks a permutation, parent ranks larger).
  Status check(const std::string& what) const;
};

// The tree of the first n merges (rank order) of `tree`: the later merges' children become roots.
// Provenance, quantiles and the batches (cut at n) are kept.
MergeTree prefixTree(const MergeTree& tree, uint64_t n);

// The batch sizes of the merges ranked in [from, to) (a batch cut by either end keeps its part).
std::vector<uint32_t> sliceBatches(const std::vector<uint32_t>& batches, uint64_t from, uint64_t to);

// Version 4's default batch divisor: a batch merges about 1/8 of the vertices not merged yet.
constexpr uint32_t kDefaultBatchDivisor = 8;

// The keys that order a version 4 batch's children (ties to the smaller id): by position where the
// parents are coded as candidates (the decoder has the level), by decoding id where they are coded as
// deltas. Both are the splitmix64 finaliser m: m(id), and m(m(m(X) ^ Y) ^ Z) of the binary64 bit
// patterns of the coordinates.
uint64_t batchKeyOfId(uint64_t id);
uint64_t batchKeyOfPoint(const double* p);

// The quantile positions of MergeTree::error_quantiles.
extern const double kMergeErrorQuantiles[9];

// Fills error_quantiles from `error` (empty when there are no merges or no errors).
void computeErrorQuantiles(MergeTree& tree);

// Merges 1..U that remove no tetrahedron and are no boundary merges: those of the points no tetrahedron
// uses, which simplify/ranking.h merges first (mid-edge points); the largest such U. Version 3 stores it
// in the header (free_merges).
uint64_t leadingFreeMerges(const MergeTree& tree);

// How a payload is coded: its version, and in version 4 the parents' code: as version 3's candidates,
// which needs the level's tetrahedra; as places among the roots of the grid nodes next to the child,
// where the level is an ni x nj x nk block whose nodes are its first decoding ids in node order (i
// fastest), which needs nothing of the level but `grid` (a grid of no nodes: not this form); or as
// version 2's deltas, which needs nothing of the level.
struct MergeTreeForm {
  uint8_t version = 5;
  bool candidates = true;
  std::array<uint32_t, 3> grid = {0, 0, 0};  // without candidates: the block's ni, nj, nk
  // Version 5, a level that names the next level's vertices (spec section 7.7) and whose tree holds
  // the merges down to it: next_index[v] is vertex v's id in the next level, kNoIndex for the
  // vertices the tree merges (every other one). The children are then coded among those.
  const std::vector<uint32_t>* next_index = nullptr;
};

// Encodes `tree` (vertex numbering of the source mesh) with vertex v stored at vertex_order[v], the
// id the level decoder gives it. vertex_order must be a permutation of 0..P-1. `mesh` is the level (in
// the tree's numbering): versions 3 and 4 with candidates need it, and version 4 its points. The
// three-argument form writes version 3 with a mesh and version 2 without.
StatusOr<std::vector<uint8_t>> encodeMergeTree(const MergeTree& tree, const std::vector<uint32_t>& vertex_order,
                                               const TetMesh* mesh, const MergeTreeForm& form);
StatusOr<std::vector<uint8_t>> encodeMergeTree(const MergeTree& tree, const std::vector<uint32_t>& vertex_order,
                                               const TetMesh* mesh);

// A payload's header, read and checked without its body (and without the level's mesh).
struct MergeTreeHeader {
  uint8_t version = 0;
  uint64_t merges = 0, boundary_merges = 0, tets_removed = 0;
  uint64_t free_merges = 0;                  // versions 3 and 4; 0 in version 2 (count them with leadingFreeMerges)
  bool candidates = false;                   // parents coded as candidates (version 3, and version 4 where it says so)
  bool needs_mesh = false;                   // decoding merges needs the level's mesh (candidates)
  bool needs_next_ids = false;               // decoding merges needs the level's next-level ids (version 5)
  uint8_t inferred = 0;                      // version 5: what the body leaves to the decoder (spec section 11)
  std::array<uint32_t, 3> grid = {0, 0, 0};  // version 4 grid places: the block's ni, nj, nk; else 0
};
StatusOr<MergeTreeHeader> readMergeTreeHeader(std::span<const uint8_t> payload, uint64_t expected_points,
                                              const std::string& what);

// Decodes a payload; `expected_points` is the level's vertex count (it bounds every allocation).
// `what` names the source in messages (file and level). `mesh` is the level as decoded (points and
// tetrahedra in decoding order): candidates (version 3, or versions 4 and 5 that say so) need it to
// decode any merge (kUsage without it); otherwise it is ignored. `next_ids`: per vertex of the level,
// its id in the next level (kNoIndex for its own vertices), as GtnReader::decodeLevel gives them; a
// version 5 tree that draws its children from the own vertices needs it (kUsage without it,
// MergeTreeHeader::needs_next_ids). Only the first `max_merges` merges are decoded (the tree of a
// prefix of the ranking is itself a merge tree, with the later merges' children as roots); the checks
// that need the whole body (header counts, trailing bytes) run only when the whole body is read.
StatusOr<MergeTree> decodeMergeTree(std::span<const uint8_t> payload, uint64_t expected_points, const std::string& what,
                                    const TetMesh* mesh, uint64_t max_merges = UINT64_MAX,
                                    const std::vector<uint32_t>* next_ids = nullptr);

}  // namespace gtn
