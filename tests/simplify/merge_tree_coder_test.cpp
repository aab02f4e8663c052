// The merge-tree chunk payload, versions 5 (what writers write: version 4 with the removed counts
// and boundary bits left to the decoder, and a band's children among the level's own vertices), 4
// (batches whose order is mostly implied; parents as candidates, grid places or deltas), 3 (parents
// among the child's neighbours in the level's mesh) and 2 (parents as id deltas):
// round trip in decoding order, compactness, and clean rejection of truncated, corrupted and
// inconsistent payloads; and the batches the writer makes (batchMerges).
#include <gtest/gtest.h>

#include <array>
#include <numeric>
#include <random>

#include "codec/merge_tree_coder.h"
#include "convert/import.h"
#include "simplify/apply.h"
#include "simplify/ranking.h"
#include "simplify_test_util.h"
#include "test_util.h"
#include "validate/merge_checks.h"

namespace gtn::test {
namespace {

struct Fixture {
  TetMesh mesh;
  MergeTree tree;
  std::vector<uint32_t> order;     // a shuffled decoding order
  TetMesh decoded;                 // mesh as its decoder numbers it (renumbered by order)
  std::vector<uint8_t> payload;    // version 3
  std::vector<uint8_t> payload2;   // version 2
  MergeTree batched;               // tree in batches, by position
  MergeTree batched_ids;           // tree in batches, by decoding id
  BatchStats stats;                // batched's
  std::vector<uint8_t> payload4;   // version 4 of batched, parents as candidates
  std::vector<uint8_t> payload4d;  // version 4 of batched_ids, parents as deltas
  MergeTree batched_grid;          // tree in batches, by node id (the decoding ids are the node ids)
  std::vector<uint8_t> payload4g;  // version 4 of batched_grid, parents as grid places
  std::vector<uint8_t> payload5;   // version 5 of batched, parents as candidates
};

// The fixture's grid: 6 x 5 x 5 cells, 7 x 6 x 6 nodes in node order.
constexpr std::array<uint32_t, 3> kFixtureDims = {7, 6, 6};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x;
    x.mesh = makeGrid(6, 5, 5, 9);
    x.tree = rankMerges(x.mesh, RankingOptions{}, nullptr).value();
    x.order.resize(x.mesh.numPoints());
    std::iota(x.order.begin(), x.order.end(), 0u);
    std::mt19937 rng(4);
    std::shuffle(x.order.begin(), x.order.end(), rng);
    x.decoded = renumberedMesh(x.mesh, x.order);
    x.payload = encodeMergeTree(x.tree, x.order, &x.mesh).value();
    x.payload2 = encodeMergeTree(x.tree, x.order, nullptr).value();
    std::vector<uint64_t> by_point(x.mesh.numPoints()), by_id(x.mesh.numPoints());
    for (size_t v = 0; v < by_point.size(); ++v) {
      by_point[v] = batchKeyOfPoint(x.mesh.point(v));
      by_id[v] = batchKeyOfId(x.order[v]);
    }
    x.batched = batchMerges(x.mesh, x.tree, by_point, kDefaultBatchDivisor, &x.stats).value();
    x.batched_ids = batchMerges(x.mesh, x.tree, by_id, kDefaultBatchDivisor).value();
    x.payload4 = encodeMergeTree(x.batched, x.order, &x.mesh, MergeTreeForm{4, true}).value();
    x.payload4d = encodeMergeTree(x.batched_ids, x.order, &x.mesh, MergeTreeForm{4, false}).value();
    std::vector<uint32_t> identity(x.mesh.numPoints());
    std::iota(identity.begin(), identity.end(), 0u);
    std::vector<uint64_t> by_node(x.mesh.numPoints());
    for (size_t v = 0; v < by_node.size(); ++v) by_node[v] = batchKeyOfId(v);
    x.batched_grid = batchMerges(x.mesh, x.tree, by_node, kDefaultBatchDivisor).value();
    x.payload4g = encodeMergeTree(x.batched_grid, identity, nullptr, MergeTreeForm{4, false, kFixtureDims}).value();
    x.payload5 = encodeMergeTree(x.batched, x.order, &x.mesh, MergeTreeForm{5, true}).value();
    return x;
  }();
  return f;
}

TEST(MergeTreeCoder, RoundTripsInDecodingOrder) {
  const Fixture& f = fixture();
  EXPECT_EQ(f.payload[0], 3);
  EXPECT_EQ(f.payload2[0], 2);
  for (const std::vector<uint8_t>* payload : {&f.payload, &f.payload2}) {
    SCOPED_TRACE("version " + std::to_string((*payload)[0]));
    auto got = decodeMergeTree(*payload, f.mesh.numPoints(), "t", &f.decoded);
    ASSERT_TRUE(got.isOk()) << got.status().message();
    EXPECT_EQ(got->merges, f.tree.merges);
    EXPECT_EQ(got->field, "rho");
    EXPECT_EQ(got->w_density, f.tree.w_density);
    EXPECT_EQ(got->error_quantiles, f.tree.error_quantiles);
    ASSERT_TRUE(got->check("t").isOk());
    for (size_t v = 0; v < f.tree.points(); ++v) {
      const uint32_t id = f.order[v];
      if (f.tree.parent[v] == MergeTree::kRoot) {
        EXPECT_EQ(got->parent[id], MergeTree::kRoot);
        continue;
      }
      EXPECT_EQ(got->parent[id], f.order[f.tree.parent[v]]);
      EXPECT_EQ(got->rank[id], f.tree.rank[v]);
      EXPECT_EQ(got->removed[id], f.tree.removed[v]);
      EXPECT_EQ(got->boundary[id], f.tree.boundary[v]);
    }
  }
  // Deterministic.
  EXPECT_EQ(encodeMergeTree(f.tree, f.order, &f.mesh).value(), f.payload);
  EXPECT_EQ(encodeMergeTree(f.tree, f.order, nullptr).value(), f.payload2);
}

// Version 3 decodes against the level's mesh: without it only the header and a prefix of no merges
// read; a mesh of another size is refused; the header alone reads without it.
TEST(MergeTreeCoder, Version3NeedsTheLevelsMesh) {
  const Fixture& f = fixture();
  auto none = decodeMergeTree(f.payload, f.mesh.numPoints(), "t", nullptr);
  ASSERT_FALSE(none.isOk());
  EXPECT_EQ(none.status().code(), StatusCode::kUsage);
  auto head = decodeMergeTree(f.payload, f.mesh.numPoints(), "t", nullptr, 0);
  ASSERT_TRUE(head.isOk()) << head.status().message();
  EXPECT_EQ(head->error_quantiles, f.tree.error_quantiles);
  TetMesh smaller = f.decoded;
  smaller.coords.resize(smaller.coords.size() - 3);
  EXPECT_FALSE(decodeMergeTree(f.payload, f.mesh.numPoints(), "t", &smaller).isOk());
  auto h = readMergeTreeHeader(f.payload, f.mesh.numPoints(), "t");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_EQ(h->version, 3);
  EXPECT_TRUE(h->needs_mesh);
  EXPECT_EQ(h->merges, f.tree.merges);
  EXPECT_EQ(h->tets_removed, f.tree.tetsRemovedUpTo(f.tree.merges));
  EXPECT_EQ(h->free_merges, leadingFreeMerges(f.tree));
  auto h2 = readMergeTreeHeader(f.payload2, f.mesh.numPoints(), "t");
  ASSERT_TRUE(h2.isOk());
  EXPECT_FALSE(h2->needs_mesh);
  // The same mesh in another numbering than the decoder's gives another tree or an error, never a crash.
  auto wrong = decodeMergeTree(f.payload, f.mesh.numPoints(), "t", &f.mesh);
  if (wrong.isOk()) {
    EXPECT_TRUE(wrong->check("t").isOk());
  }
}

// A parent that is not one of the child's neighbours (a merge no edge carries) still codes, through
// the escape to the id delta; so does a child no tetrahedron uses.
TEST(MergeTreeCoder, Version3CodesParentsThatAreNotNeighbours) {
  const Fixture& f = fixture();
  TetMesh mesh = f.mesh;
  const uint32_t lone = static_cast<uint32_t>(mesh.numPoints());
  mesh.coords.insert(mesh.coords.end(), {0.5, 0.5, 0.5});  // a point no tetrahedron uses
  MergeTree tree;
  const size_t n = mesh.numPoints();
  tree.makeRoots(n);
  // Rank 1: the lone point into vertex 3; rank 2: vertex 0 into the last grid vertex (far away).
  tree.parent[lone] = 3;
  tree.rank[lone] = 1;
  tree.parent[0] = lone - 1;
  tree.rank[0] = 2;
  tree.removed[0] = 2;   // not what the mesh says: version 3 stores the count, like version 2
  tree.boundary[0] = 1;  // a corner of the grid
  tree.merges = 2;
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 rng(9);
  std::shuffle(order.begin(), order.end(), rng);
  auto payload = encodeMergeTree(tree, order, &mesh);
  ASSERT_TRUE(payload.isOk()) << payload.status().message();
  const TetMesh decoded = renumberedMesh(mesh, order);
  auto got = decodeMergeTree(*payload, n, "t", &decoded);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  EXPECT_EQ(got->parent[order[lone]], order[3]);
  EXPECT_EQ(got->parent[order[0]], order[lone - 1]);
  EXPECT_EQ(got->rank[order[0]], 2u);
  EXPECT_EQ(got->removed[order[0]], 2u);
  auto h = readMergeTreeHeader(*payload, n, "t");
  ASSERT_TRUE(h.isOk());
  EXPECT_EQ(h->free_merges, 1u);
}

// On a real mesh the parents cost a few bits, not an id: version 3 takes at most two thirds of
// version 2's bytes for the bunny's ranked tree, in its level codec's decoding order.
// The bunny, its ranked tree and its level codec's encoding.
struct Bunny {
  TetMesh mesh;
  MergeTree tree;
  EncodedLevel enc;
};
const Bunny& bunny() {
  static const Bunny b = [] {
    Bunny x;
    auto imported = importMesh({dataDir() + "/medit/bunny.mesh"}, ImportOptions{});
    EXPECT_TRUE(imported.isOk()) << imported.status().message();
    if (!imported.isOk()) return x;
    x.mesh = std::move(imported->mesh);
    x.tree = rankMerges(x.mesh, RankingOptions{}, nullptr).value();
    x.enc = encodeLevel(x.mesh, EncodeOptions{}).value();
    return x;
  }();
  return b;
}

TEST(MergeTreeCoder, Version3IsSmallerOnARealMesh) {
  const Bunny& b = bunny();
  ASSERT_GT(b.mesh.numTets(), 0u);
  const TetMesh& mesh = b.mesh;
  const MergeTree* tree = &b.tree;
  const EncodedLevel* enc = &b.enc;
  auto v3 = encodeMergeTree(*tree, enc->vertex_order, &mesh);
  auto v2 = encodeMergeTree(*tree, enc->vertex_order, nullptr);
  ASSERT_TRUE(v3.isOk() && v2.isOk());
  EXPECT_LT(v3->size() * 3, v2->size() * 2) << v3->size() << " against " << v2->size();
  TetMeshBuilder decoded;
  ASSERT_TRUE(decodeLevel(enc->header, payloadOf(*enc), decoded, nullptr, "bunny").isOk());
  auto got = decodeMergeTree(*v3, mesh.numPoints(), "bunny", &decoded.mesh());
  auto want = decodeMergeTree(*v2, mesh.numPoints(), "bunny", nullptr);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  ASSERT_TRUE(want.isOk());
  EXPECT_EQ(got->parent, want->parent);
  EXPECT_EQ(got->rank, want->rank);
  EXPECT_EQ(got->removed, want->removed);
}

// Merges are stored in rank order: decoding only the first n gives the tree of the first n merges
// (the later children as roots), as the full decode restricted to ranks <= n.
TEST(MergeTreeCoder, DecodesAPrefixOfTheRanking) {
  const Fixture& f = fixture();
  for (const std::vector<uint8_t>* payload : {&f.payload, &f.payload4}) {
    SCOPED_TRACE("version " + std::to_string((*payload)[0]));
    auto full = decodeMergeTree(*payload, f.mesh.numPoints(), "t", &f.decoded);
    ASSERT_TRUE(full.isOk());
    for (uint64_t n :
         {uint64_t{0}, uint64_t{1}, f.tree.merges / 3, f.tree.merges - 1, f.tree.merges, f.tree.merges + 5}) {
      SCOPED_TRACE(n);
      auto part = decodeMergeTree(*payload, f.mesh.numPoints(), "t", &f.decoded, n);
      ASSERT_TRUE(part.isOk()) << part.status().message();
      EXPECT_EQ(part->merges, std::min(n, f.tree.merges));
      EXPECT_TRUE(part->checked);
      EXPECT_TRUE(part->check("t").isOk());
      for (size_t v = 0; v < full->points(); ++v) {
        const bool kept = full->rank[v] != 0 && full->rank[v] <= n;
        EXPECT_EQ(part->parent[v], kept ? full->parent[v] : MergeTree::kRoot);
        EXPECT_EQ(part->rank[v], kept ? full->rank[v] : 0u);
        EXPECT_EQ(part->removed[v], kept ? full->removed[v] : 0u);
        EXPECT_EQ(part->boundary[v], kept ? full->boundary[v] : 0u);
      }
      EXPECT_EQ(computeAncestors(*part, n), computeAncestors(*full, n));
      if ((*payload)[0] == 4) {
        EXPECT_EQ(part->batches, sliceBatches(full->batches, 0, n));
      }
    }
    // A prefix cut short by truncation is still an error, not a shorter tree.
    auto cut = decodeMergeTree(std::span<const uint8_t>(payload->data(), payload->size() / 2), f.mesh.numPoints(), "t",
                               &f.decoded, f.tree.merges - 1);
    EXPECT_FALSE(cut.isOk());
  }
}

// The tree `got` (decoding ids) is `want` (source ids) renumbered by `order`.
void expectSameTree(const MergeTree& got, const MergeTree& want, const std::vector<uint32_t>& order) {
  ASSERT_EQ(got.points(), want.points());
  EXPECT_EQ(got.merges, want.merges);
  for (size_t v = 0; v < want.points(); ++v) {
    const uint32_t id = order[v];
    if (want.parent[v] == MergeTree::kRoot) {
      EXPECT_EQ(got.parent[id], MergeTree::kRoot) << v;
      continue;
    }
    EXPECT_EQ(got.parent[id], order[want.parent[v]]) << v;
    EXPECT_EQ(got.rank[id], want.rank[v]) << v;
    EXPECT_EQ(got.removed[id], want.removed[v]) << v;
    EXPECT_EQ(got.boundary[id], want.boundary[v]) << v;
  }
}

// Version 4: the batched trees round trip with their batches, the one with deltas without the level;
// the decoded tree, coded again in its own numbering, gives the same bytes; and a tree in rank order
// with no batches (cut by the rule) round trips too.
TEST(MergeTreeCoder, Version4RoundTripsItsBatches) {
  const Fixture& f = fixture();
  EXPECT_EQ(f.payload4[0], 4);
  EXPECT_EQ(f.payload4d[0], 4);
  auto got = decodeMergeTree(f.payload4, f.mesh.numPoints(), "t", &f.decoded);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  expectSameTree(*got, f.batched, f.order);
  EXPECT_EQ(got->batches, f.batched.batches);
  EXPECT_EQ(got->batch_divisor, kDefaultBatchDivisor);
  auto h = readMergeTreeHeader(f.payload4d, f.mesh.numPoints(), "t");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_FALSE(h->candidates);
  EXPECT_FALSE(h->needs_mesh);
  auto deltas = decodeMergeTree(f.payload4d, f.mesh.numPoints(), "t", nullptr);
  ASSERT_TRUE(deltas.isOk()) << deltas.status().message();
  expectSameTree(*deltas, f.batched_ids, f.order);
  EXPECT_EQ(deltas->batches, f.batched_ids.batches);
  // Candidates need the level.
  EXPECT_EQ(decodeMergeTree(f.payload4, f.mesh.numPoints(), "t", nullptr).status().code(), StatusCode::kUsage);
  std::vector<uint32_t> identity(f.mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0u);
  EXPECT_EQ(encodeMergeTree(*got, identity, &f.decoded, MergeTreeForm{4, true}).value(), f.payload4);
  EXPECT_EQ(encodeMergeTree(*deltas, identity, &f.decoded, MergeTreeForm{4, false}).value(), f.payload4d);
  // The ranking's own order, in batches of the rule: larger, but the same tree.
  auto ranked = encodeMergeTree(f.tree, f.order, &f.mesh, MergeTreeForm{4, true});
  ASSERT_TRUE(ranked.isOk()) << ranked.status().message();
  auto back = decodeMergeTree(*ranked, f.mesh.numPoints(), "t", &f.decoded);
  ASSERT_TRUE(back.isOk()) << back.status().message();
  expectSameTree(*back, f.tree, f.order);
  EXPECT_LT(f.payload4.size(), ranked->size());
}

// The offset of a version 5 payload's `inferred` byte: after the version, five varints (points,
// merges, boundary merges, tetrahedra removed, free merges), parent_form, the grid's dims where
// parent_form is 4, and the divisor.
size_t inferredOffset(const std::vector<uint8_t>& p) {
  size_t at = 1;
  auto skipVarint = [&] {
    while (p[at] & 0x80) ++at;
    ++at;
  };
  for (int i = 0; i < 5; ++i) skipVarint();
  const uint8_t form = p[at++];
  if (form == 4)
    for (int i = 0; i < 3; ++i) skipVarint();
  skipVarint();
  return at;
}

// Version 5 with candidates leaves each merge's removed count and boundary bit to the decoder, which
// reads them off the mesh the earlier merges made: the same tree as version 4, in fewer bytes. A
// tree whose counts or flags are not the mesh's (here one count off) still codes, with them in the
// body.
TEST(MergeTreeCoder, Version5InfersTheRemovedCountsAndBoundaryBits) {
  const Fixture& f = fixture();
  ASSERT_EQ(f.payload5[0], 5);
  auto h = readMergeTreeHeader(f.payload5, f.mesh.numPoints(), "t");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_EQ(h->inferred, 3);
  EXPECT_TRUE(h->needs_mesh);
  EXPECT_FALSE(h->needs_next_ids);
  auto got = decodeMergeTree(f.payload5, f.mesh.numPoints(), "t", &f.decoded);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  expectSameTree(*got, f.batched, f.order);
  EXPECT_EQ(got->batches, f.batched.batches);
  std::vector<float> quantiles(f.batched.error_quantiles.begin(), f.batched.error_quantiles.end());
  EXPECT_EQ(std::vector<float>(got->error_quantiles.begin(), got->error_quantiles.end()), quantiles);
  EXPECT_LT(f.payload5.size() * 10, f.payload4.size() * 9) << f.payload5.size() << " against " << f.payload4.size();
  for (uint64_t n : {uint64_t{1}, f.batched.merges / 3}) {
    auto part = decodeMergeTree(f.payload5, f.mesh.numPoints(), "t", &f.decoded, n);
    ASSERT_TRUE(part.isOk()) << part.status().message();
    expectSameTree(*part, prefixTree(f.batched, n), f.order);
  }

  MergeTree odd = f.batched;
  for (size_t v = 0; v < odd.points(); ++v)
    if (odd.rank[v] == odd.merges / 2) ++odd.removed[v];
  auto coded = encodeMergeTree(odd, f.order, &f.mesh, MergeTreeForm{5, true});
  ASSERT_TRUE(coded.isOk()) << coded.status().message();
  EXPECT_EQ((*coded)[inferredOffset(*coded)], 0);
  auto back = decodeMergeTree(*coded, f.mesh.numPoints(), "t", &f.decoded);
  ASSERT_TRUE(back.isOk()) << back.status().message();
  expectSameTree(*back, odd, f.order);

  // Unknown bits, and inferred values without candidates, are refused.
  for (const uint8_t bits : {uint8_t{8}, uint8_t{0x80}}) {
    std::vector<uint8_t> p = f.payload5;
    p[inferredOffset(p)] |= bits;
    auto bad = readMergeTreeHeader(p, f.mesh.numPoints(), "t");
    ASSERT_FALSE(bad.isOk());
    EXPECT_NE(bad.status().message().find("inferred"), std::string::npos) << bad.status().message();
  }
  auto deltas = encodeMergeTree(f.batched_ids, f.order, &f.mesh, MergeTreeForm{5, false});
  ASSERT_TRUE(deltas.isOk());
  ASSERT_EQ((*deltas)[inferredOffset(*deltas)], 0);
  std::vector<uint8_t> p = *deltas;
  p[inferredOffset(p)] = 1;
  EXPECT_FALSE(readMergeTreeHeader(p, f.mesh.numPoints(), "t").isOk());
}

// A level that names the next level's vertices codes the merges down to it: its children are exactly
// its own vertices, which the decoder knows from the level, and version 5 codes them among those.
TEST(MergeTreeCoder, Version5CodesABandsChildrenAmongTheLevelsOwnVertices) {
  const Fixture& f = fixture();
  const size_t n = f.mesh.numPoints();
  const MergeTree band = prefixTree(f.batched, f.batched.merges / 2);
  std::vector<uint32_t> next_index(n, kNoIndex);  // the tree's numbering
  uint32_t kept = 0;
  for (size_t v = 0; v < n; ++v)
    if (band.parent[v] == MergeTree::kRoot) next_index[v] = kept++;
  std::vector<uint32_t> next_ids(n, kNoIndex);  // the decoder's numbering
  for (size_t v = 0; v < n; ++v) next_ids[f.order[v]] = next_index[v];
  MergeTreeForm form{5, true};
  form.next_index = &next_index;
  auto own = encodeMergeTree(band, f.order, &f.mesh, form);
  ASSERT_TRUE(own.isOk()) << own.status().message();
  auto plain = encodeMergeTree(band, f.order, &f.mesh, MergeTreeForm{5, true});
  ASSERT_TRUE(plain.isOk());
  EXPECT_LT(own->size(), plain->size());
  auto h = readMergeTreeHeader(*own, n, "t");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_EQ(h->inferred, 7);
  EXPECT_TRUE(h->needs_next_ids);
  auto got = decodeMergeTree(*own, n, "t", &f.decoded, UINT64_MAX, &next_ids);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  expectSameTree(*got, band, f.order);
  EXPECT_EQ(got->batches, band.batches);
  auto part = decodeMergeTree(*own, n, "t", &f.decoded, band.merges / 2, &next_ids);
  ASSERT_TRUE(part.isOk()) << part.status().message();
  expectSameTree(*part, prefixTree(band, band.merges / 2), f.order);
  // Without the ids, or with ids that name one vertex too many, it is refused.
  auto blind = decodeMergeTree(*own, n, "t", &f.decoded);
  ASSERT_FALSE(blind.isOk());
  EXPECT_EQ(blind.status().code(), StatusCode::kUsage);
  std::vector<uint32_t> more = next_ids;
  for (uint32_t& id : more)
    if (id == kNoIndex) {
      id = kept;
      break;
    }
  auto wrong = decodeMergeTree(*own, n, "t", &f.decoded, UINT64_MAX, &more);
  ASSERT_FALSE(wrong.isOk());
  EXPECT_EQ(wrong.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(wrong.status().message().find("vertices the next level lacks"), std::string::npos);
  // A corrupted payload fails cleanly or decodes to a valid tree, and every truncation fails.
  std::mt19937 rng(21);
  int rejected = 0;
  for (int i = 0; i < 400; ++i) {
    std::vector<uint8_t> p = *own;
    p[rng() % p.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
    auto d = decodeMergeTree(p, n, "t", &f.decoded, UINT64_MAX, &next_ids);
    if (!d.isOk()) {
      ++rejected;
      EXPECT_EQ(d.status().code(), StatusCode::kInvalidData) << d.status().message();
      continue;
    }
    EXPECT_TRUE(d->check("t").isOk());
  }
  EXPECT_GT(rejected, 250);
  for (size_t k = 0; k < own->size(); ++k)
    EXPECT_FALSE(
        decodeMergeTree(std::span<const uint8_t>(own->data(), k), n, "t", &f.decoded, UINT64_MAX, &next_ids).isOk());
  // The encoder refuses ids that do not match the tree's children.
  std::vector<uint32_t> mismatched = next_index;
  for (uint32_t& id : mismatched)
    if (id == kNoIndex) {
      id = kept;
      break;
    }
  form.next_index = &mismatched;
  EXPECT_FALSE(encodeMergeTree(band, f.order, &f.mesh, form).isOk());
}

// The batches regroup the ranking's merges: every merge of the batched tree passes the validator's
// replay (no inversion, the link condition, boundary rules, its count of removed tetrahedra), and
// where no merge had to move to a later batch, every batch ends with the same merges made as the
// ranking's prefix of that length.
TEST(MergeTreeCoder, BatchesKeepTheRankingsPrefixesAndEveryMergeValid) {
  const Fixture& f = fixture();
  for (const MergeTree* t : {&f.batched, &f.batched_ids}) {
    ASSERT_TRUE(t->check("t").isOk());
    ValidationReport report;
    checkMergeTree(f.mesh, forestFromTree(*t), {}, report);
    EXPECT_EQ(report.count(Severity::kError), 0u) << report.toText("batched");
    ASSERT_FALSE(t->batches.empty());
    EXPECT_GT(t->batches.size(), 4u);
  }
  EXPECT_EQ(f.stats.dropped, 0u);
  EXPECT_EQ(f.batched.merges, f.tree.merges);
  if (f.stats.carried == 0) {
    uint64_t end = 0;
    for (uint32_t b : f.batched.batches) {
      end += b;
      for (size_t v = 0; v < f.tree.points(); ++v) {
        const bool ranked = f.tree.rank[v] != 0 && f.tree.rank[v] <= end;
        const bool batched = f.batched.rank[v] != 0 && f.batched.rank[v] <= end;
        ASSERT_EQ(ranked, batched) << "vertex " << v << ", batches ending at " << end;
      }
    }
  }
}

// On a real mesh the batches make the children cheap: the bunny's tree, batched, takes at most 80% of
// version 3's bytes for its ranked tree, and decodes to the batched tree; version 5 takes at most 75%
// of version 4's.
TEST(MergeTreeCoder, Version4IsSmallerOnARealMesh) {
  const Bunny& b = bunny();
  ASSERT_GT(b.mesh.numTets(), 0u);
  const TetMesh& mesh = b.mesh;
  const MergeTree* tree = &b.tree;
  const EncodedLevel* enc = &b.enc;
  std::vector<uint64_t> keys(mesh.numPoints());
  for (size_t v = 0; v < keys.size(); ++v) keys[v] = batchKeyOfPoint(mesh.point(v));
  auto batched = batchMerges(mesh, *tree, keys, kDefaultBatchDivisor);
  ASSERT_TRUE(batched.isOk()) << batched.status().message();
  auto v4 = encodeMergeTree(*batched, enc->vertex_order, &mesh, MergeTreeForm{4, true});
  auto v3 = encodeMergeTree(*tree, enc->vertex_order, &mesh);
  ASSERT_TRUE(v4.isOk() && v3.isOk());
  EXPECT_LT(v4->size() * 5, v3->size() * 4) << v4->size() << " against " << v3->size();
  TetMeshBuilder decoded;
  ASSERT_TRUE(decodeLevel(enc->header, payloadOf(*enc), decoded, nullptr, "bunny").isOk());
  auto got = decodeMergeTree(*v4, mesh.numPoints(), "bunny", &decoded.mesh());
  ASSERT_TRUE(got.isOk()) << got.status().message();
  expectSameTree(*got, *batched, enc->vertex_order);
  // Version 5 infers every merge's removed count and boundary bit from the mesh: about a third less.
  auto v5 = encodeMergeTree(*batched, enc->vertex_order, &mesh, MergeTreeForm{5, true});
  ASSERT_TRUE(v5.isOk());
  auto h = readMergeTreeHeader(*v5, mesh.numPoints(), "bunny");
  ASSERT_TRUE(h.isOk());
  EXPECT_EQ(h->inferred, 3);
  EXPECT_LT(v5->size() * 4, v4->size() * 3) << v5->size() << " against " << v4->size();
  auto got5 = decodeMergeTree(*v5, mesh.numPoints(), "bunny", &decoded.mesh());
  ASSERT_TRUE(got5.isOk()) << got5.status().message();
  expectSameTree(*got5, *batched, enc->vertex_order);
}

// Grid places: the parents of a grid's tree as places among the roots of the child's grid neighbours.
// The payload names the block's dims and decodes without the level; the same tree codes back to the
// same bytes, and is smaller than with deltas. Any tree still codes: a decoding order that is not the
// node order, a parent no neighbour leads to, and a point past the block's nodes go through the escape.
TEST(MergeTreeCoder, Version4GridPlacesNeedOnlyTheDims) {
  const Fixture& f = fixture();
  const size_t n = f.mesh.numPoints();
  auto h = readMergeTreeHeader(f.payload4g, n, "t");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_EQ(h->version, 4);
  EXPECT_FALSE(h->candidates);
  EXPECT_FALSE(h->needs_mesh);
  EXPECT_EQ(h->grid, kFixtureDims);
  auto got = decodeMergeTree(f.payload4g, n, "t", nullptr);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  std::vector<uint32_t> identity(n);
  std::iota(identity.begin(), identity.end(), 0u);
  expectSameTree(*got, f.batched_grid, identity);
  EXPECT_EQ(got->batches, f.batched_grid.batches);
  EXPECT_EQ(encodeMergeTree(*got, identity, nullptr, MergeTreeForm{4, false, kFixtureDims}).value(), f.payload4g);
  auto deltas = encodeMergeTree(f.batched_grid, identity, nullptr, MergeTreeForm{4, false});
  ASSERT_TRUE(deltas.isOk());
  EXPECT_EQ(readMergeTreeHeader(*deltas, n, "t")->grid, (std::array<uint32_t, 3>{0, 0, 0}));
  EXPECT_LT(f.payload4g.size() * 10, deltas->size() * 9) << f.payload4g.size() << " against " << deltas->size();
  // A prefix decodes as the first merges.
  auto part = decodeMergeTree(f.payload4g, n, "t", nullptr, got->merges / 3);
  ASSERT_TRUE(part.isOk()) << part.status().message();
  for (size_t v = 0; v < n; ++v) {
    const bool kept = got->rank[v] != 0 && got->rank[v] <= got->merges / 3;
    EXPECT_EQ(part->parent[v], kept ? got->parent[v] : MergeTree::kRoot);
  }
  // The shuffled decoding order: the ids are not the nodes', and the tree still round trips.
  auto shuffled = encodeMergeTree(f.batched_grid, f.order, nullptr, MergeTreeForm{4, false, kFixtureDims});
  ASSERT_TRUE(shuffled.isOk()) << shuffled.status().message();
  auto back = decodeMergeTree(*shuffled, n, "t", nullptr);
  ASSERT_TRUE(back.isOk()) << back.status().message();
  expectSameTree(*back, f.batched_grid, f.order);
  // A point past the nodes merged into a node, then a corner node into the far corner.
  MergeTree tree;
  tree.makeRoots(n + 1);
  tree.parent[n] = 3;
  tree.rank[n] = 1;
  tree.parent[0] = static_cast<uint32_t>(n - 1);
  tree.rank[0] = 2;
  tree.boundary[0] = 1;
  tree.removed[0] = 2;
  tree.merges = 2;
  std::vector<uint32_t> order(n + 1);
  std::iota(order.begin(), order.end(), 0u);
  auto odd = encodeMergeTree(tree, order, nullptr, MergeTreeForm{4, false, kFixtureDims});
  ASSERT_TRUE(odd.isOk()) << odd.status().message();
  auto odd_back = decodeMergeTree(*odd, n + 1, "t", nullptr);
  ASSERT_TRUE(odd_back.isOk()) << odd_back.status().message();
  expectSameTree(*odd_back, tree, order);
  // A grid of more nodes than vertices is refused by the encoder; the decoder refuses such dims, and
  // dims of 0.
  EXPECT_EQ(encodeMergeTree(tree, order, nullptr, MergeTreeForm{4, false, {7, 6, 7}}).status().code(),
            StatusCode::kUsage);
  auto bad_dims = [&](uint32_t ni, uint32_t nj, uint32_t nk) {
    std::vector<uint8_t> p = *odd;
    // The header: version, points, merges, boundary merges, removed, free merges, parent_form, dims.
    size_t at = 1;
    for (int field = 0; field < 5; ++field)
      while (p[at++] & 0x80) {
      }
    EXPECT_EQ(p[at], 4) << "parent_form";
    std::vector<uint8_t> dims;
    for (uint32_t d : {ni, nj, nk}) {
      for (; d >= 0x80; d >>= 7) dims.push_back(static_cast<uint8_t>(d | 0x80));
      dims.push_back(static_cast<uint8_t>(d));
    }
    size_t end = at + 1;
    for (int field = 0; field < 3; ++field)
      while (p[end++] & 0x80) {
      }
    p.erase(p.begin() + static_cast<std::ptrdiff_t>(at + 1), p.begin() + static_cast<std::ptrdiff_t>(end));
    p.insert(p.begin() + static_cast<std::ptrdiff_t>(at + 1), dims.begin(), dims.end());
    return decodeMergeTree(p, n + 1, "t", nullptr).status();
  };
  EXPECT_TRUE(bad_dims(7, 6, 6).isOk());
  for (const std::array<uint32_t, 3>& d : {std::array<uint32_t, 3>{0, 6, 6}, {7, 6, 7}, {253, 253, 253}}) {
    const Status st = bad_dims(d[0], d[1], d[2]);
    EXPECT_EQ(st.code(), StatusCode::kInvalidData) << d[0] << " x " << d[1] << " x " << d[2];
    EXPECT_NE(st.message().find("grid dims"), std::string::npos) << st.message();
  }
}

// On a real grid the grid places cost a third of the deltas' parents: blunt fin's tree (the ranking
// batched by node id, as the writer stores a structured level 0's) takes at most 85% of its bytes
// with deltas, and decodes to the same tree.
TEST(MergeTreeCoder, GridPlacesAreSmallerOnARealGrid) {
  auto imported = importMesh({dataPath("plot3d/bluntfinxyz.bin"), dataPath("plot3d/bluntfinq.bin")}, ImportOptions{});
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  const TetMesh& mesh = imported->mesh;
  ASSERT_EQ(mesh.blocks.size(), 1u);
  const StructuredBlock& b = mesh.blocks[0];
  ASSERT_EQ(uint64_t{b.dims[0]} * b.dims[1] * b.dims[2], mesh.numPoints());
  auto ranked = rankMerges(mesh, RankingOptions{}, nullptr);
  ASSERT_TRUE(ranked.isOk());
  std::vector<uint64_t> keys(mesh.numPoints());
  for (size_t v = 0; v < keys.size(); ++v) keys[v] = batchKeyOfId(v);
  auto batched = batchMerges(mesh, *ranked, keys, kDefaultBatchDivisor);
  ASSERT_TRUE(batched.isOk()) << batched.status().message();
  std::vector<uint32_t> identity(mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0u);
  auto grid = encodeMergeTree(*batched, identity, nullptr, MergeTreeForm{4, false, {b.dims[0], b.dims[1], b.dims[2]}});
  auto deltas = encodeMergeTree(*batched, identity, nullptr, MergeTreeForm{4, false});
  ASSERT_TRUE(grid.isOk() && deltas.isOk());
  EXPECT_LT(grid->size() * 100, deltas->size() * 85) << grid->size() << " against " << deltas->size();
  auto got = decodeMergeTree(*grid, mesh.numPoints(), "blunt fin", nullptr);
  ASSERT_TRUE(got.isOk()) << got.status().message();
  expectSameTree(*got, *batched, identity);
}

TEST(MergeTreeCoder, IsCompact) {
  const Fixture& f = fixture();
  // log2(M!) bits of ranks alone are about log2(M) - 1.44 per merge; the whole payload must stay
  // within a few bytes per vertex even in a random decoding order.
  EXPECT_LT(f.payload2.size(), 4 * f.mesh.numPoints());
  // Version 2, identity order: parents are near their children.
  std::vector<uint32_t> identity(f.mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0u);
  EXPECT_LT(encodeMergeTree(f.tree, identity, nullptr).value().size(), f.payload2.size());
  // Version 3 does not depend on the order, and codes parents in a few bits rather than as deltas.
  EXPECT_LT(f.payload.size() * 4, f.payload2.size() * 3) << f.payload.size() << " against " << f.payload2.size();
}

TEST(MergeTreeCoder, HandlesEmptyAndRootOnlyTrees) {
  MergeTree empty;
  TetMesh nothing;
  auto p = encodeMergeTree(empty, {}, &nothing);
  ASSERT_TRUE(p.isOk());
  auto d = decodeMergeTree(*p, 0, "t", &nothing);
  ASSERT_TRUE(d.isOk()) << d.status().message();
  EXPECT_EQ(d->points(), 0u);
  MergeTree roots;
  roots.makeRoots(5);
  auto q = encodeMergeTree(roots, {4, 3, 2, 1, 0}, nullptr);
  ASSERT_TRUE(q.isOk());
  auto e = decodeMergeTree(*q, 5, "t", nullptr);
  ASSERT_TRUE(e.isOk());
  EXPECT_EQ(e->merges, 0u);
}

TEST(MergeTreeCoder, RejectsBadInputToTheEncoder) {
  const Fixture& f = fixture();
  std::vector<uint32_t> bad = f.order;
  bad[0] = bad[1];
  EXPECT_FALSE(encodeMergeTree(f.tree, bad, &f.mesh).isOk());
  bad.pop_back();
  EXPECT_FALSE(encodeMergeTree(f.tree, bad, &f.mesh).isOk());
  TetMesh fewer = f.mesh;
  fewer.coords.resize(fewer.coords.size() - 3);
  EXPECT_FALSE(encodeMergeTree(f.tree, f.order, &fewer).isOk());

  MergeTree cyclic = f.tree;
  for (size_t v = 0; v < cyclic.points(); ++v) {
    if (cyclic.parent[v] != MergeTree::kRoot && cyclic.parent[cyclic.parent[v]] != MergeTree::kRoot) {
      std::swap(cyclic.rank[v], cyclic.rank[cyclic.parent[v]]);
      break;
    }
  }
  EXPECT_FALSE(encodeMergeTree(cyclic, f.order, &f.mesh).isOk());
}

TEST(MergeTreeCoder, RejectsEveryTruncationAndTrailingBytes) {
  const Fixture& f = fixture();
  for (const std::vector<uint8_t>* payload : {&f.payload, &f.payload4, &f.payload4d, &f.payload4g, &f.payload5}) {
    SCOPED_TRACE("version " + std::to_string((*payload)[0]) + (payload == &f.payload4g ? ", grid places" : ""));
    for (size_t n = 0; n < payload->size(); ++n) {
      auto d = decodeMergeTree(std::span<const uint8_t>(payload->data(), n), f.mesh.numPoints(), "t", &f.decoded);
      ASSERT_FALSE(d.isOk()) << "prefix of " << n << " bytes";
      EXPECT_EQ(d.status().code(), StatusCode::kInvalidData);
      EXPECT_NE(d.status().message().find("merge tree payload"), std::string::npos);
    }
    std::vector<uint8_t> longer = *payload;
    longer.push_back(0);
    EXPECT_FALSE(decodeMergeTree(longer, f.mesh.numPoints(), "t", &f.decoded).isOk());
    EXPECT_FALSE(decodeMergeTree(*payload, f.mesh.numPoints() + 1, "t", &f.decoded).isOk());
  }
}

TEST(MergeTreeCoder, CorruptedPayloadsFailCleanlyOrDecodeToAValidTree) {
  const Fixture& f = fixture();
  std::mt19937 rng(12);
  int rejected = 0;
  for (int i = 0; i < 1000; ++i) {
    const std::vector<uint8_t>* payloads[] = {&f.payload,   &f.payload2,  &f.payload4,
                                              &f.payload4d, &f.payload4g, &f.payload5};
    std::vector<uint8_t> p = *payloads[i % 6];
    const size_t at = rng() % p.size();
    p[at] ^= static_cast<uint8_t>(1u << (rng() % 8));
    auto d = decodeMergeTree(p, f.mesh.numPoints(), "t", &f.decoded);
    if (!d.isOk()) {
      ++rejected;
      EXPECT_EQ(d.status().code(), StatusCode::kInvalidData);
      continue;
    }
    // Whatever decodes is a structurally valid tree, safe for the stream filter.
    EXPECT_TRUE(d->check("t").isOk());
  }
  EXPECT_GT(rejected, 750);
}

TEST(MergeTreeCoder, DecodedTreeDrivesTheFilterLikeTheOriginal) {
  const Fixture& f = fixture();
  TetMesh m = f.mesh;
  for (uint64_t n : {uint64_t{0}, f.tree.merges / 2, f.tree.merges}) expectStreamMatchesApply(m, f.tree, n, false);
  for (uint64_t n : {f.batched.merges / 3, f.batched.merges}) expectStreamMatchesApply(m, f.batched, n, false);
}

}  // namespace
}  // namespace gtn::test
