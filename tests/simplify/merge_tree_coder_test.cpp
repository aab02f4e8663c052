// The merge-tree chunk payload: round trip in decoding order, compactness, and clean rejection of
// truncated, corrupted and inconsistent payloads.
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "codec/merge_tree_coder.h"
#include "simplify/apply.h"
#include "simplify/ranking.h"
#include "simplify_test_util.h"

namespace gtn::test {
namespace {

struct Fixture {
  TetMesh mesh;
  MergeTree tree;
  std::vector<uint32_t> order;  // a shuffled decoding order
  std::vector<uint8_t> payload;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x;
    x.mesh = makeGrid(6, 5, 5, 9);
    x.tree = rankMerges(x.mesh, RankingOptions{}, nullptr).value();
    x.order.resize(x.mesh.numPoints());
    std::iota(x.order.begin(), x.order.end(), 0u);
    std::mt19937 rng(4);
    std::shuffle(x.order.begin(), x.order.end(), rng);
    x.payload = encodeMergeTree(x.tree, x.order).value();
    return x;
  }();
  return f;
}

TEST(MergeTreeCoder, RoundTripsInDecodingOrder) {
  const Fixture& f = fixture();
  auto got = decodeMergeTree(f.payload, f.mesh.numPoints(), "t");
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
  // Deterministic.
  EXPECT_EQ(encodeMergeTree(f.tree, f.order).value(), f.payload);
}

// Merges are stored in rank order: decoding only the first n gives the tree of the first n merges
// (the later children as roots), as the full decode restricted to ranks <= n.
TEST(MergeTreeCoder, DecodesAPrefixOfTheRanking) {
  const Fixture& f = fixture();
  auto full = decodeMergeTree(f.payload, f.mesh.numPoints(), "t");
  ASSERT_TRUE(full.isOk());
  for (uint64_t n :
       {uint64_t{0}, uint64_t{1}, f.tree.merges / 3, f.tree.merges - 1, f.tree.merges, f.tree.merges + 5}) {
    SCOPED_TRACE(n);
    auto part = decodeMergeTree(f.payload, f.mesh.numPoints(), "t", n);
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
  }
  // A prefix cut short by truncation is still an error, not a shorter tree.
  auto cut = decodeMergeTree(std::span<const uint8_t>(f.payload.data(), f.payload.size() / 2), f.mesh.numPoints(), "t",
                             f.tree.merges - 1);
  EXPECT_FALSE(cut.isOk());
}

TEST(MergeTreeCoder, IsCompact) {
  const Fixture& f = fixture();
  // log2(M!) bits of ranks alone are about log2(M) - 1.44 per merge; the whole payload must stay
  // within a few bytes per vertex even in a random decoding order.
  EXPECT_LT(f.payload.size(), 4 * f.mesh.numPoints());
  // Identity order: parents are near their children.
  std::vector<uint32_t> identity(f.mesh.numPoints());
  std::iota(identity.begin(), identity.end(), 0u);
  EXPECT_LT(encodeMergeTree(f.tree, identity).value().size(), f.payload.size());
}

TEST(MergeTreeCoder, HandlesEmptyAndRootOnlyTrees) {
  MergeTree empty;
  auto p = encodeMergeTree(empty, {});
  ASSERT_TRUE(p.isOk());
  auto d = decodeMergeTree(*p, 0, "t");
  ASSERT_TRUE(d.isOk()) << d.status().message();
  EXPECT_EQ(d->points(), 0u);
  MergeTree roots;
  roots.parent.assign(5, MergeTree::kRoot);
  roots.rank.assign(5, 0);
  roots.removed.assign(5, 0);
  roots.boundary.assign(5, 0);
  auto q = encodeMergeTree(roots, {4, 3, 2, 1, 0});
  ASSERT_TRUE(q.isOk());
  auto e = decodeMergeTree(*q, 5, "t");
  ASSERT_TRUE(e.isOk());
  EXPECT_EQ(e->merges, 0u);
}

TEST(MergeTreeCoder, RejectsBadInputToTheEncoder) {
  const Fixture& f = fixture();
  std::vector<uint32_t> bad = f.order;
  bad[0] = bad[1];
  EXPECT_FALSE(encodeMergeTree(f.tree, bad).isOk());
  bad.pop_back();
  EXPECT_FALSE(encodeMergeTree(f.tree, bad).isOk());
  MergeTree cyclic = f.tree;
  for (size_t v = 0; v < cyclic.points(); ++v) {
    if (cyclic.parent[v] != MergeTree::kRoot && cyclic.parent[cyclic.parent[v]] != MergeTree::kRoot) {
      std::swap(cyclic.rank[v], cyclic.rank[cyclic.parent[v]]);
      break;
    }
  }
  EXPECT_FALSE(encodeMergeTree(cyclic, f.order).isOk());
}

TEST(MergeTreeCoder, RejectsEveryTruncationAndTrailingBytes) {
  const Fixture& f = fixture();
  for (size_t n = 0; n < f.payload.size(); ++n) {
    auto d = decodeMergeTree(std::span<const uint8_t>(f.payload.data(), n), f.mesh.numPoints(), "t");
    ASSERT_FALSE(d.isOk()) << "prefix of " << n << " bytes";
    EXPECT_EQ(d.status().code(), StatusCode::kInvalidData);
    EXPECT_NE(d.status().message().find("merge tree payload"), std::string::npos);
  }
  std::vector<uint8_t> longer = f.payload;
  longer.push_back(0);
  EXPECT_FALSE(decodeMergeTree(longer, f.mesh.numPoints(), "t").isOk());
  EXPECT_FALSE(decodeMergeTree(f.payload, f.mesh.numPoints() + 1, "t").isOk());
}

TEST(MergeTreeCoder, CorruptedPayloadsFailCleanlyOrDecodeToAValidTree) {
  const Fixture& f = fixture();
  std::mt19937 rng(12);
  int rejected = 0;
  for (int i = 0; i < 400; ++i) {
    std::vector<uint8_t> p = f.payload;
    const size_t at = rng() % p.size();
    p[at] ^= static_cast<uint8_t>(1u << (rng() % 8));
    auto d = decodeMergeTree(p, f.mesh.numPoints(), "t");
    if (!d.isOk()) {
      ++rejected;
      EXPECT_EQ(d.status().code(), StatusCode::kInvalidData);
      continue;
    }
    // Whatever decodes is a structurally valid tree, safe for the stream filter.
    EXPECT_TRUE(d->check("t").isOk());
  }
  EXPECT_GT(rejected, 300);
}

TEST(MergeTreeCoder, DecodedTreeDrivesTheFilterLikeTheOriginal) {
  const Fixture& f = fixture();
  TetMesh m = f.mesh;
  for (uint64_t n : {uint64_t{0}, f.tree.merges / 2, f.tree.merges}) expectStreamMatchesApply(m, f.tree, n, false);
}

}  // namespace
}  // namespace gtn::test
