// Ranking, in-memory application, on-the-fly simplification and mip levels on synthetic meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <set>

#include <tbb/global_control.h>

#include "codec/grid_coder.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"

#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "simplify_test_util.h"
#include "validate/merge_checks.h"
#include "validate/write_gtn.h"

namespace gtn::test {
namespace {

struct Ranked {
  TetMesh mesh;
  MergeTree tree;
  RankingStats stats;
};

const Ranked& grid() {
  static const Ranked r = [] {
    Ranked x;
    x.mesh = makeGrid(9, 8, 7);
    auto t = rankMerges(x.mesh, RankingOptions{}, &x.stats);
    EXPECT_TRUE(t.isOk()) << t.status().message();
    x.tree = std::move(t.value());
    return x;
  }();
  return r;
}

std::vector<uint64_t> sampleMerges(const MergeTree& tree, uint64_t points) {
  std::vector<uint64_t> ns = {0, 1, 2, 5, 17, tree.merges / 3, tree.merges - 1, tree.merges};
  for (int i = 1; i <= 8; ++i) ns.push_back(levelMerges(i, points, tree.merges));
  std::sort(ns.begin(), ns.end());
  ns.erase(std::unique(ns.begin(), ns.end()), ns.end());
  return ns;
}

TEST(Ranking, SimplifiesMostOfAGrid) {
  const Ranked& g = grid();
  ASSERT_TRUE(g.tree.check("grid").isOk());
  EXPECT_EQ(g.tree.field, "rho");
  EXPECT_EQ(g.stats.merges, g.tree.merges);
  // A box keeps its 8 corners at least; most of the rest must go.
  EXPECT_GT(g.tree.merges, g.mesh.numPoints() * 9 / 10);
  EXPECT_GT(g.tree.boundaryMergesUpTo(g.tree.merges), 100u);
  EXPECT_EQ(g.tree.error_quantiles.size(), 9u);
  EXPECT_LE(g.tree.error_quantiles.front(), g.tree.error_quantiles.back());
  // Ranks strictly increase towards the roots and every merge follows a mesh edge of its time: the
  // child's parent is never merged before it.
  for (size_t v = 0; v < g.tree.points(); ++v) {
    if (g.tree.parent[v] == MergeTree::kRoot) continue;
    const uint32_t p = g.tree.parent[v];
    if (g.tree.parent[p] != MergeTree::kRoot) {
      EXPECT_GT(g.tree.rank[p], g.tree.rank[v]);
    }
  }
  // Moving a corner of the box changes its volume: corners go late, and the first half of the
  // merges keeps the volume of the box closely.
  for (uint32_t corner : {0u, 9u}) {
    if (g.tree.parent[corner] != MergeTree::kRoot) {
      EXPECT_GT(g.tree.rank[corner], g.tree.merges / 2);
    }
  }
  auto half = applyMerges(g.mesh, g.tree, levelMerges(1, g.mesh.numPoints(), g.tree.merges));
  ASSERT_TRUE(half.isOk());
  const double v0 = computeMeshStats(g.mesh).total_volume, v1 = computeMeshStats(*half).total_volume;
  EXPECT_NEAR(v1, v0, 0.01 * v0);
}

// A book of 600 tetrahedra around one edge: its two hubs are in every tetrahedron. Ranking took
// minutes (a vertex costs its star times its targets, again after every merge beside it); vertices
// in more than 256 tetrahedra are now left alone while they are, and the rest still simplifies into
// valid meshes.
TEST(Ranking, CrowdedStarsAreLeftAlone) {
  constexpr int kPages = 600;
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  m.coords = {0, 0, -1, 0, 0, 1};      // the hubs, points 0 and 1
  for (int i = 0; i <= kPages; ++i) {  // an open book: pages from angle 0 to 3/2 pi
    const double a = 1.5 * M_PI * i / kPages;
    m.coords.insert(m.coords.end(), {std::cos(a), std::sin(a), 0.0});
  }
  for (int i = 0; i < kPages; ++i) m.tets.push_back({0, 1, static_cast<uint32_t>(2 + i), static_cast<uint32_t>(3 + i)});
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  RankingStats stats;
  auto tree = rankMerges(m, RankingOptions(), &stats);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  ASSERT_TRUE(tree->check("book").isOk());
  // The work, counted (not timed): 71419 target evaluations, against 370177 of up to 600 star
  // tetrahedra each before (50 s).
  EXPECT_LT(stats.evaluations, 150000u);
  EXPECT_GT(tree->merges, static_cast<uint64_t>(kPages / 2));
  auto half = applyMerges(m, *tree, tree->merges / 2);
  ASSERT_TRUE(half.isOk()) << half.status().message();
  EXPECT_EQ(computeMeshStats(*half).inverted, 0u);
}

TEST(Ranking, IsDeterministic) {
  TetMesh m = makeGrid(4, 4, 4, 3);
  auto a = rankMerges(m, RankingOptions{}, nullptr);
  auto b = rankMerges(m, RankingOptions{}, nullptr);
  ASSERT_TRUE(a.isOk() && b.isOk());
  EXPECT_EQ(a->parent, b->parent);
  EXPECT_EQ(a->rank, b->rank);
}

TEST(Ranking, TheTreeIsTheSameForAnyThreadCount) {
  // The evaluations around a merge run in parallel; their results are queued in the list's order.
  const TetMesh mesh = makeGrid(7, 6, 5);
  std::vector<MergeTree> trees;
  for (const size_t threads : {1, 2, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    auto t = rankMerges(mesh, RankingOptions{}, nullptr);
    ASSERT_TRUE(t.isOk()) << t.status().message();
    trees.push_back(std::move(t).value());
  }
  for (size_t i = 1; i < trees.size(); ++i) {
    EXPECT_EQ(trees[i].merges, trees[0].merges);
    EXPECT_EQ(trees[i].parent, trees[0].parent);
    EXPECT_EQ(trees[i].rank, trees[0].rank);
    EXPECT_EQ(trees[i].error, trees[0].error);
  }
}

// Every sampled prefix of `tree` is a consistent mesh with no inverted tetrahedron.
void expectEveryPrefixValid(const TetMesh& mesh, const MergeTree& tree) {
  for (uint64_t n : sampleMerges(tree, mesh.numPoints())) {
    auto m = applyMerges(mesh, tree, n);
    ASSERT_TRUE(m.isOk()) << n << " merges: " << m.status().message();
    EXPECT_TRUE(m->checkConsistency("prefix").isOk()) << n;
    EXPECT_EQ(computeMeshStats(*m).inverted, 0u) << n;
  }
}

// At levels 1-3, `tree`'s mesh is off the source's volume by at most twice `reference`'s (plus 0.1%).
void expectKeepsTheVolumeAsWellAs(const TetMesh& mesh, const MergeTree& tree, const MergeTree& reference) {
  const double v0 = computeMeshStats(mesh).total_volume;
  for (int level : {1, 2, 3}) {
    SCOPED_TRACE("level " + std::to_string(level));
    auto a = applyMerges(mesh, tree, levelMerges(level, mesh.numPoints(), tree.merges));
    auto b = applyMerges(mesh, reference, levelMerges(level, mesh.numPoints(), reference.merges));
    ASSERT_TRUE(a.isOk() && b.isOk());
    const MeshStats sa = computeMeshStats(*a), sb = computeMeshStats(*b);
    EXPECT_EQ(sa.inverted, 0u);
    EXPECT_LE(std::fabs(sa.total_volume - v0), 2 * std::fabs(sb.total_volume - v0) + 1e-3 * v0);
  }
}

// Lazy evaluation (the default) recomputes a stale candidate when it comes to the top of the queue:
// far fewer candidates are computed than by the greedy order, every prefix of its tree is still a
// valid mesh, and the simplified meshes keep the volume about as well as the greedy ones.
TEST(Ranking, LazyEvaluationComputesFewerCandidatesAndKeepsTheShape) {
  const TetMesh mesh = makeGrid(12, 11, 10);
  RankingOptions greedy;
  greedy.lazy = false;
  RankingStats lazy_stats, greedy_stats;
  auto lazy = rankMerges(mesh, RankingOptions{}, &lazy_stats);
  auto exact = rankMerges(mesh, greedy, &greedy_stats);
  ASSERT_TRUE(lazy.isOk() && exact.isOk());
  ASSERT_TRUE(lazy->check("lazy").isOk());
  EXPECT_GT(lazy_stats.stale, 0u);
  EXPECT_EQ(greedy_stats.stale, 0u);
  EXPECT_LT(lazy_stats.evaluations * 2, greedy_stats.evaluations);
  EXPECT_NE(lazy->rank, exact->rank);
  // Both simplify nearly all of the grid.
  EXPECT_GT(lazy->merges, exact->merges * 99 / 100);
  expectKeepsTheVolumeAsWellAs(mesh, *lazy, *exact);
  // Every prefix is a valid mesh, as the greedy order's are.
  expectEveryPrefixValid(mesh, *lazy);
}

// Ranked in parts, then as a whole: the parts' merges come first, interleaved by error; every prefix
// is a valid mesh; the tree is the same for any thread count; the seams are released afterwards, so
// the coarse levels keep the shape as the ranking of the whole mesh does. Small meshes are ranked
// whole by default.
TEST(Ranking, InPartsThePrefixesAreValidAndTheThreadsChangeNothing) {
  const TetMesh mesh = makeGrid(14, 13, 12);
  RankingOptions in_parts;
  in_parts.parts = 4;
  std::vector<MergeTree> trees;
  RankingStats stats;
  for (const size_t threads : {1, 2, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    auto t = rankMerges(mesh, in_parts, &stats);
    ASSERT_TRUE(t.isOk()) << t.status().message();
    trees.push_back(std::move(t).value());
  }
  for (size_t i = 1; i < trees.size(); ++i) {
    EXPECT_EQ(trees[i].parent, trees[0].parent);
    EXPECT_EQ(trees[i].rank, trees[0].rank);
  }
  const MergeTree& tree = trees[0];
  ASSERT_TRUE(tree.check("in parts").isOk());
  EXPECT_EQ(stats.parts, 4u);
  EXPECT_GT(stats.part_merges, tree.merges / 2);  // two rounds
  EXPECT_LT(stats.part_merges, tree.merges * 4 / 5);
  RankingStats whole_stats;
  auto whole = rankMerges(mesh, RankingOptions{}, &whole_stats);
  ASSERT_TRUE(whole.isOk());
  EXPECT_EQ(whole_stats.parts, 1u);
  EXPECT_EQ(whole_stats.part_merges, 0u);
  EXPECT_NE(whole->rank, tree.rank);
  EXPECT_GT(tree.merges, whole->merges * 99 / 100);
  expectEveryPrefixValid(mesh, tree);
  expectKeepsTheVolumeAsWellAs(mesh, tree, *whole);
}

// Many parts (16 or more): six fine rounds in P, P - 1, ... parts, then six coarse rounds in 8, 7, ...
// 3 parts, which take the fine rounds' seams before the whole mesh's queue. The tree is the same for
// any thread count, and the tail's hook runs once, as the coarse rounds start (the progress then
// counts the fine rounds' merges).
TEST(Ranking, ManyPartsRankInFineThenCoarseRounds) {
  const TetMesh mesh = makeGrid(24, 23, 22);
  RankingOptions in_parts;
  in_parts.parts = 16;
  std::vector<MergeTree> trees;
  RankingStats stats;
  for (const size_t threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    double last = -1, at_tail = -1;
    int tails = 0;
    RankingOptions o = in_parts;
    o.beside_ranking_tail = [&] {
      ++tails;
      at_tail = last;
    };
    auto t = rankMerges(mesh, o, &stats, [&](const std::string& stage, double fraction) {
      if (stage == "rank merges") last = fraction;
    });
    ASSERT_TRUE(t.isOk()) << t.status().message();
    EXPECT_EQ(tails, 1);
    ASSERT_EQ(stats.rounds.size(), 12u);
    uint64_t fine = 0;
    for (size_t r = 0; r < 6; ++r) {
      EXPECT_EQ(stats.rounds[r].parts, 16u - r);
      EXPECT_EQ(stats.rounds[r + 6].parts, 8u - r);
      EXPECT_GT(stats.rounds[r + 6].merges, 0u);
      fine += stats.rounds[r].merges;
    }
    EXPECT_NEAR(at_tail, static_cast<double>(fine) / static_cast<double>(mesh.numPoints()), 1e-12);
    trees.push_back(std::move(t).value());
  }
  EXPECT_EQ(trees[1].parent, trees[0].parent);
  EXPECT_EQ(trees[1].rank, trees[0].rank);
  ASSERT_TRUE(trees[0].check("in many parts").isOk());
  // The coarse rounds leave the whole mesh's queue less than the fine rounds alone would.
  RankingOptions fine_only = in_parts;
  fine_only.parts = 15;  // fine rounds alone (below 16 parts)
  RankingStats fine_stats;
  auto fine_tree = rankMerges(mesh, fine_only, &fine_stats);
  ASSERT_TRUE(fine_tree.isOk());
  ASSERT_EQ(fine_stats.rounds.size(), 6u);
  EXPECT_LT(trees[0].merges - stats.part_merges, (fine_tree->merges - fine_stats.part_merges) / 2);
  expectEveryPrefixValid(mesh, trees[0]);
}

// The series after a fine one: parts of 2^18 tetrahedra on the mesh left, at most half as many as
// before, 8 parts where that comes to fewer than 16; a series of fewer than 16 parts is the last.
TEST(Ranking, TheSeriesOfRoundsShrinkWithTheMeshLeft) {
  const size_t part = size_t{1} << 18;
  EXPECT_EQ(nextRankingSeries(8, 100 * part), 0u);
  EXPECT_EQ(nextRankingSeries(15, 100 * part), 0u);
  EXPECT_EQ(nextRankingSeries(180, 30 * part + 5), 30u);
  EXPECT_EQ(nextRankingSeries(180, 170 * part), 90u);
  EXPECT_EQ(nextRankingSeries(46, 15 * part), 8u);
  EXPECT_EQ(nextRankingSeries(16, 0), 8u);
  // Every chain of series ends, whatever is left.
  for (uint32_t p : {16u, 46u, 180u, 256u}) {
    int series = 0;
    for (uint32_t s = p; s != 0; s = nextRankingSeries(s, size_t{1} << 40)) ASSERT_LT(++series, 10);
  }
}

// Batched in the ranking's rounds of parts (batchMerges with RankingStats::rounds): each round's
// merges are batched in its parts, in parallel. The batched tree is the same for any thread count,
// every merge passes the validator's replay, the batches end where each round of the ranking does
// (when no merge moved to a later batch), and the payload is no larger than 3% over the batches made
// on the whole mesh.
TEST(Ranking, BatchesInTheRoundsPartsAreValidAndTheThreadsChangeNothing) {
  const TetMesh mesh = makeGrid(14, 13, 12);
  RankingOptions in_parts;
  in_parts.parts = 4;
  RankingStats stats;
  auto ranked = rankMerges(mesh, in_parts, &stats);
  ASSERT_TRUE(ranked.isOk()) << ranked.status().message();
  // Rounds in 4, 3 and 2 parts; each round's merges are ranked after the rounds before it, and none
  // has a larger error than the round's bound, which is finite and below the tree's largest error.
  ASSERT_EQ(stats.rounds.size(), 3u);
  EXPECT_EQ(stats.rounds[0].parts, 4u);
  EXPECT_EQ(stats.rounds[1].parts, 3u);
  EXPECT_EQ(stats.rounds[2].parts, 2u);
  EXPECT_EQ(stats.rounds[0].merges + stats.rounds[1].merges + stats.rounds[2].merges, stats.part_merges);
  {
    const float largest = *std::max_element(ranked->error.begin(), ranked->error.end());
    uint64_t end = leadingFreeMerges(*ranked);
    for (const RankingRound& r : stats.rounds) {
      EXPECT_EQ(r.part.size(), mesh.numPoints());
      EXPECT_GT(r.merges, 0u);
      EXPECT_TRUE(std::isfinite(r.error_limit));
      EXPECT_LT(r.error_limit, largest);
      for (size_t v = 0; v < mesh.numPoints(); ++v) {
        if (ranked->rank[v] <= end || ranked->rank[v] > end + r.merges) continue;
        ASSERT_LE(ranked->error[v], r.error_limit) << "vertex " << v << " of the round of " << r.parts << " parts";
      }
      end += r.merges;
    }
  }
  std::vector<uint64_t> keys(mesh.numPoints());
  for (size_t v = 0; v < keys.size(); ++v) keys[v] = batchKeyOfPoint(mesh.point(v));
  std::vector<MergeTree> trees;
  BatchStats bs;
  for (const size_t threads : {1, 2, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    auto t = batchMerges(mesh, *ranked, keys, kDefaultBatchDivisor, &bs, stats.rounds);
    ASSERT_TRUE(t.isOk()) << t.status().message();
    trees.push_back(std::move(t).value());
  }
  for (size_t i = 1; i < trees.size(); ++i) {
    EXPECT_EQ(trees[i].parent, trees[0].parent);
    EXPECT_EQ(trees[i].rank, trees[0].rank);
    EXPECT_EQ(trees[i].batches, trees[0].batches);
  }
  const MergeTree& tree = trees[0];
  ASSERT_TRUE(tree.check("batched in parts").isOk());
  // With the ranking's face flags (what the writer passes) instead of its own face adjacency: the
  // same tree. The flags are the grid's: its boundary nodes, nothing frozen or pinned.
  ASSERT_EQ(stats.faces.boundary.size(), mesh.numPoints());
  ASSERT_EQ(stats.faces.frozen.size(), mesh.numPoints());
  ASSERT_EQ(stats.faces.pinned.size(), mesh.numPoints());
  EXPECT_EQ(std::count(stats.faces.boundary.begin(), stats.faces.boundary.end(), 1), 15 * 14 * 13 - 13 * 12 * 11);
  EXPECT_EQ(std::count(stats.faces.frozen.begin(), stats.faces.frozen.end(), 1), 0);
  EXPECT_EQ(std::count(stats.faces.pinned.begin(), stats.faces.pinned.end(), 1), 0);
  auto with_faces = batchMerges(mesh, *ranked, keys, kDefaultBatchDivisor, nullptr, stats.rounds, &stats.faces);
  ASSERT_TRUE(with_faces.isOk()) << with_faces.status().message();
  EXPECT_EQ(with_faces->parent, tree.parent);
  EXPECT_EQ(with_faces->rank, tree.rank);
  EXPECT_EQ(with_faces->batches, tree.batches);
  ValidationReport report;
  checkMergeTree(mesh, forestFromTree(tree), {}, report);
  EXPECT_EQ(report.count(Severity::kError), 0u) << report.toText("batched in parts");
  EXPECT_EQ(bs.dropped, 0u);
  EXPECT_EQ(tree.merges, ranked->merges);
  auto whole = batchMerges(mesh, *ranked, keys, kDefaultBatchDivisor);
  ASSERT_TRUE(whole.isOk());
  // The parts' batches differ from the whole mesh's: each part's first batch is an eighth of its own
  // vertices, whatever the errors of the other parts' merges.
  EXPECT_NE(whole->rank, tree.rank);
  if (bs.carried == 0 && bs.retargeted == 0) {
    uint64_t end = 0;
    size_t b = 0;
    for (const RankingRound& r : stats.rounds) {
      const uint64_t round_end = end + r.merges;
      while (end < round_end && b < tree.batches.size()) end += tree.batches[b++];
      ASSERT_EQ(end, round_end) << "the batches cross the end of a round";
      for (size_t v = 0; v < mesh.numPoints(); ++v) {
        const bool in_ranking = ranked->rank[v] != 0 && ranked->rank[v] <= end;
        const bool in_batches = tree.rank[v] != 0 && tree.rank[v] <= end;
        ASSERT_EQ(in_ranking, in_batches) << "vertex " << v << ", round ending at " << end;
      }
    }
  }
  std::vector<uint32_t> identity(mesh.numPoints());
  for (uint32_t v = 0; v < identity.size(); ++v) identity[v] = v;
  auto parts_bytes = encodeMergeTree(tree, identity, &mesh, MergeTreeForm{4, true});
  auto whole_bytes = encodeMergeTree(*whole, identity, &mesh, MergeTreeForm{4, true});
  ASSERT_TRUE(parts_bytes.isOk() && whole_bytes.isOk());
  EXPECT_LE(parts_bytes->size(), whole_bytes->size() * 103 / 100);
}

TEST(Ranking, TheStarListsStayInTheirRoom) {
  // Each vertex's corner list lives in one pool; a merge writes the target's new list after the used
  // part. The pool holds every corner and a quarter more (4096 at least) and is compacted in place
  // when a list does not fit, instead of growing (it doubled, to 8 corners per tetrahedron and more).
  const TetMesh mesh = makeGrid(16, 15, 14);
  RankingStats stats;
  auto tree = rankMerges(mesh, RankingOptions{}, &stats);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  const uint64_t nt = mesh.numTets();
  EXPECT_GT(stats.star_compactions, 0u);
  EXPECT_LE(stats.star_pool_corners, 4 * nt + std::max<uint64_t>(nt, 4096));
  EXPECT_GT(tree->merges, mesh.numPoints() / 2);
  auto half = applyMerges(mesh, *tree, tree->merges / 2);
  ASSERT_TRUE(half.isOk()) << half.status().message();
  EXPECT_EQ(computeMeshStats(*half).inverted, 0u);
}

TEST(Ranking, OptionsSelectFieldAndWeights) {
  TetMesh m = makeGrid(4, 4, 4, 5);
  auto missing = rankMerges(m, RankingOptions{"nope", 1, 1, UINT64_MAX}, nullptr);
  ASSERT_FALSE(missing.isOk());
  EXPECT_EQ(missing.status().code(), StatusCode::kUsage);
  EXPECT_NE(missing.status().message().find("rho"), std::string::npos);
  auto volume = rankMerges(m, RankingOptions{"none", 1, 1, UINT64_MAX}, nullptr);
  ASSERT_TRUE(volume.isOk());
  EXPECT_EQ(volume->field, "");
  auto capped = rankMerges(m, RankingOptions{"", 1, 0, 10}, nullptr);
  ASSERT_TRUE(capped.isOk());
  EXPECT_EQ(capped->merges, 10u);
  auto bad = rankMerges(m, RankingOptions{"", -1, 1, UINT64_MAX}, nullptr);
  EXPECT_FALSE(bad.isOk());
}

// The errors the validator's replay of `tree` on `mesh` reports (validate/merge_checks.h).
std::vector<std::string> replayErrors(const TetMesh& mesh, const MergeTree& tree) {
  ValidationReport report;
  checkMergeTree(mesh, forestFromTree(tree), {}, report);
  return report.errorCodes();
}

// After every merge, the mesh has the boundary triangles a reader infers from the tree (two fewer per
// boundary merge: all the stream simplifier knows), and the stream simplifier agrees at the end.
void expectTreeKeepsBoundaryCounts(const TetMesh& mesh, const MergeTree& tree) {
  const uint64_t source = checkMesh(mesh).boundary_triangles;
  for (uint64_t n = 1; n <= tree.merges; ++n) {
    auto m = applyMerges(mesh, tree, n);
    ASSERT_TRUE(m.isOk());
    ASSERT_EQ(checkMesh(*m).boundary_triangles, source - 2 * tree.boundaryMergesUpTo(n)) << "after merge " << n;
  }
  expectStreamMatchesApply(mesh, tree, tree.merges, false);
}

// Two boxes of 3x3x3 cells touching along one edge of each, the line x = y = 0 (a TetGen mesh of a
// brain had seven such edges): the boundary edges on it are in four boundary triangles, two of each
// box. Collapsing one passed the link condition (of a complex that is no manifold there) and removed
// all four, while readers, who know only the boundary flag, remove two: every simplification past it
// failed ("27346 boundary triangles, the merge tree implies 27348") and the validator said nothing.
TEST(Ranking, NeverCollapsesANonManifoldBoundaryEdge) {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  std::map<std::array<double, 3>, uint32_t> index;  // welds the points of the shared line
  for (int box = 0; box < 2; ++box) {
    const TetMesh g = makeGrid(3, 3, 3, 1 + box);
    const double shift = box == 0 ? 0.0 : -3.0;
    std::vector<uint32_t> to(g.numPoints());
    for (size_t v = 0; v < g.numPoints(); ++v) {
      const std::array<double, 3> p{g.point(v)[0] + shift, g.point(v)[1] + shift, g.point(v)[2]};
      auto [it, added] = index.emplace(p, static_cast<uint32_t>(m.numPoints()));
      if (added) m.coords.insert(m.coords.end(), p.begin(), p.end());
      to[v] = it->second;
    }
    for (const Tet& t : g.tets) m.tets.push_back({to[t[0]], to[t[1]], to[t[2]], to[t[3]]});
  }
  Field rho("rho", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) rho.set<double>(v, 0, 1.0 + 0.1 * m.point(v)[2]);
  m.point_fields.push_back(std::move(rho));
  addIdField(m);
  ASSERT_EQ(m.numPoints(), 2 * 64 - 4u);
  for (const char* field : {"", "none"}) {
    SCOPED_TRACE(std::string("field '") + field + "'");
    auto tree = rankMerges(m, RankingOptions{field, 1, 1, UINT64_MAX}, nullptr);
    ASSERT_TRUE(tree.isOk()) << tree.status().message();
    EXPECT_GT(tree->merges, m.numPoints() / 2);
    EXPECT_EQ(replayErrors(m, *tree), std::vector<std::string>());
    expectTreeKeepsBoundaryCounts(m, *tree);
  }
}

TEST(Apply, EveryPrefixIsAValidMesh) {
  const Ranked& g = grid();
  const MeshChecks src = checkMesh(g.mesh);
  for (uint64_t n : sampleMerges(g.tree, g.mesh.numPoints())) {
    SCOPED_TRACE("n = " + std::to_string(n));
    auto m = applyMerges(g.mesh, g.tree, n);
    ASSERT_TRUE(m.isOk());
    EXPECT_EQ(m->numPoints(), g.mesh.numPoints() - n);
    EXPECT_EQ(m->numTets(), g.mesh.numTets() - g.tree.tetsRemovedUpTo(n));
    const MeshChecks c = checkMesh(*m);
    EXPECT_EQ(c.inverted, 0u);
    EXPECT_LE(c.zero_volume, src.zero_volume);
    EXPECT_EQ(c.non_manifold, 0u);
    EXPECT_EQ(c.duplicates, 0u);
    EXPECT_EQ(c.boundary_euler, src.boundary_euler);
    EXPECT_EQ(c.boundary_triangles, src.boundary_triangles - 2 * g.tree.boundaryMergesUpTo(n));
    ASSERT_EQ(m->cell_fields.size(), 1u);
    EXPECT_EQ(m->cell_fields[0].itemCount(), m->numTets());
  }
}

TEST(Apply, EveryMergeKeepsTheMeshValid) {
  // Exhaustive on a small grid: after every single merge.
  TetMesh m = makeGrid(3, 3, 2, 11);
  auto tree = rankMerges(m, RankingOptions{}, nullptr);
  ASSERT_TRUE(tree.isOk());
  const MeshChecks src = checkMesh(m);
  for (uint64_t n = 0; n <= tree->merges; ++n) {
    auto s = applyMerges(m, *tree, n);
    ASSERT_TRUE(s.isOk());
    const MeshChecks c = checkMesh(*s);
    ASSERT_EQ(c.inverted + c.zero_volume + c.non_manifold + c.duplicates, 0u) << "after merge " << n;
    ASSERT_EQ(c.boundary_euler, src.boundary_euler) << "after merge " << n;
  }
}

TEST(Apply, AncestorsFollowThePaperExample) {
  // Figure 2-like forest: 0 <- 1 (rank 1), 0 <- 2 (rank 3), 2 <- 3 (rank 2); 4 alone.
  MergeTree t;
  t.parent = {MergeTree::kRoot, 0, 0, 2, MergeTree::kRoot};
  t.rank = {0, 1, 3, 2, 0};
  t.removed = {0, 1, 1, 1, 0};
  t.boundary = {0, 0, 0, 0, 0};
  t.merges = 3;
  ASSERT_TRUE(t.check("t").isOk());
  EXPECT_EQ(computeAncestors(t, 0), (std::vector<uint32_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(computeAncestors(t, 2), (std::vector<uint32_t>{0, 0, 2, 2, 4}));
  EXPECT_EQ(computeAncestors(t, 3), (std::vector<uint32_t>{0, 0, 0, 0, 4}));
  t.rank = {0, 1, 2, 3, 0};  // 3 merges into 2 after 2 was merged: invalid
  EXPECT_FALSE(t.check("t").isOk());
}

TEST(StreamSimplifier, MatchesApplyWithAShuffledEmitter) {
  const Ranked& g = grid();
  for (uint64_t n : sampleMerges(g.tree, g.mesh.numPoints())) expectStreamMatchesApply(g.mesh, g.tree, n, false);
}

TEST(StreamSimplifier, MatchesApplyThroughTheLevelCodec) {
  const Ranked& g = grid();
  for (uint64_t n : sampleMerges(g.tree, g.mesh.numPoints())) expectStreamMatchesApply(g.mesh, g.tree, n, true);
}

TEST(StreamSimplifier, RejectsATreeOfAnotherLevel) {
  const Ranked& g = grid();
  TetMesh small = makeGrid(2, 2, 2);
  RecordingSink rec;
  StreamSimplifier simp(g.tree, 5, rec);
  std::vector<uint32_t> perm(small.numPoints());
  for (size_t i = 0; i < perm.size(); ++i) perm[i] = static_cast<uint32_t>(i);
  const Status st = emitMesh(small, perm, simp);
  EXPECT_EQ(st.code(), StatusCode::kInvalidData);
}

TEST(Levels, EachLevelIsThePrefixAndRefinesFurther) {
  const Ranked& g = grid();
  auto levels = buildMipLevels(g.mesh, g.tree, LevelOptions{-1, 32, true, 0});
  ASSERT_TRUE(levels.isOk()) << levels.status().message();
  ASSERT_GE(levels->merges.size(), 4u);
  const uint64_t points = g.mesh.numPoints();
  for (size_t i = 1; i < levels->merges.size(); ++i) {
    SCOPED_TRACE("level " + std::to_string(i));
    EXPECT_EQ(levels->merges[i], levelMerges(int(i), points, g.tree.merges));
    EXPECT_GE(points - levels->merges[i], 32u);
    const TetMesh& lm = levels->meshes[i];
    const MergeTree& lt = *levels->trees[i];
    ASSERT_TRUE(lt.check("level").isOk());
    EXPECT_EQ(lt.merges, g.tree.merges - levels->merges[i]);
    auto want = applyMerges(g.mesh, g.tree, levels->merges[i]);
    ASSERT_TRUE(want.isOk());
    EXPECT_EQ(lm.coords, want->coords);
    EXPECT_EQ(lm.tets, want->tets);
    // Each level is made from the one above it: its tree is the one the source's gives.
    std::vector<uint32_t> index;
    ASSERT_TRUE(applyMerges(g.mesh, g.tree, levels->merges[i], &index).isOk());
    const MergeTree rest = remainingTree(g.tree, levels->merges[i], index);
    EXPECT_EQ(lt.parent, rest.parent);
    EXPECT_EQ(lt.rank, rest.rank);
    EXPECT_EQ(lt.removed, rest.removed);
    EXPECT_EQ(lt.boundary, rest.boundary);
    EXPECT_EQ(lt.error, rest.error);
    EXPECT_EQ(lt.error_quantiles, rest.error_quantiles);
    // Applying m more merges of the level's own tree equals applying N_i + m to the source.
    for (uint64_t m : {uint64_t{1}, lt.merges / 2, lt.merges}) {
      auto a = applyMerges(lm, lt, m);
      auto b = applyMerges(g.mesh, g.tree, levels->merges[i] + m);
      ASSERT_TRUE(a.isOk() && b.isOk());
      EXPECT_EQ(tetsById(*a, vertexIds(*a)), tetsById(*b, vertexIds(*b)));
    }
    // The on-the-fly filter on the level's own stream.
    expectStreamMatchesApply(lm, lt, lt.merges / 3, true);
  }
  EXPECT_EQ(chooseLevel(levels->merges, 0), 0u);
  EXPECT_EQ(chooseLevel(levels->merges, levels->merges[2]), 2u);
  EXPECT_EQ(chooseLevel(levels->merges, levels->merges[2] - 1), 1u);
  auto none = buildMipLevels(g.mesh, g.tree, LevelOptions{0, 64, true});
  ASSERT_TRUE(none.isOk());
  EXPECT_EQ(none->merges.size(), 1u);
  auto two = buildMipLevels(g.mesh, g.tree, LevelOptions{2, 64, false});
  ASSERT_TRUE(two.isOk());
  EXPECT_EQ(two->merges.size(), 3u);
  EXPECT_FALSE(two->trees[1]);
  const auto inputs = two->inputs(g.mesh);
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_EQ(inputs[0].mesh, &g.mesh);
  EXPECT_DOUBLE_EQ(inputs[1].ratio, 0.5 * 0 + double(two->merges[1]) / double(points));
  EXPECT_FALSE(inputs[1].merge_tree);
}

// Independent levels (--independent-levels); chained levels are encoded coarsest first, every one
// (tests/format/gtn_chain_test.cpp).
TEST(Levels, ABoundedWriteEncodesNoLevelBeyondTheBound) {
  const Ranked& g = grid();
  auto levels = buildMipLevels(g.mesh, g.tree, LevelOptions{-1, 32, true, 0});
  ASSERT_TRUE(levels.isOk()) << levels.status().message();
  ASSERT_GE(levels->merges.size(), 4u);
  const std::string path = ::testing::TempDir() + "/bounded_levels.gtn";
  for (const double bound : {1.01, 1.6}) {
    SCOPED_TRACE("bound " + std::to_string(bound));
    std::vector<std::string> stages;
    GtnWriteOptions wo;
    wo.level_storage_limit = bound;
    wo.chain_levels = false;
    wo.progress = [&](const std::string& stage, double) { stages.push_back(stage); };
    ASSERT_TRUE(writeGtnFile(path, levels->inputs(g.mesh), wo).isOk());
    auto r = GtnReader::open(path);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const size_t kept = (*r)->levels();
    ASSERT_LT(kept, levels->merges.size());
    // The kept levels and the first one past the bound are encoded (its bytes decide); no coarser one.
    std::vector<std::string> want;
    for (size_t i = 0; i <= kept; ++i)
      want.push_back("encode and verify level " + std::to_string(i) + " (" + std::to_string(levels->merges.size()) +
                     " levels)");
    EXPECT_EQ(stages, want);
  }
  std::filesystem::remove(path);
}

TEST(Levels, TheBuilderMakesEachLevelWhenAskedFor) {
  const Ranked& g = grid();
  const LevelOptions lo{-1, 32, true, 0};
  auto all = buildMipLevels(g.mesh, g.tree, lo);
  ASSERT_TRUE(all.isOk()) << all.status().message();
  ASSERT_GE(all->merges.size(), 4u);
  auto builder = MipLevelBuilder::create(g.mesh, g.tree, lo);
  ASSERT_TRUE(builder.isOk()) << builder.status().message();
  // The plan is known before any level is made.
  EXPECT_EQ(builder->count(), all->merges.size());
  EXPECT_EQ(builder->merges(), all->merges);
  EXPECT_EQ(builder->ratios(), all->ratios);
  EXPECT_EQ(builder->built(), 1u);
  auto zero = builder->level(0);
  ASSERT_TRUE(zero.isOk());
  EXPECT_EQ(*zero, &g.mesh);
  EXPECT_EQ(builder->built(), 1u);
  // Asking for level 2 makes levels 1 and 2 and no more; each is buildMipLevels's.
  auto two = builder->level(2);
  ASSERT_TRUE(two.isOk()) << two.status().message();
  EXPECT_EQ(builder->built(), 3u);
  EXPECT_EQ((*two)->tets, all->meshes[2].tets);
  EXPECT_EQ((*two)->coords, all->meshes[2].coords);
  ASSERT_TRUE(builder->tree(2));
  EXPECT_EQ(builder->tree(2)->rank, all->trees[2]->rank);
  EXPECT_FALSE(builder->tree(3));
  auto one = builder->level(1);
  ASSERT_TRUE(one.isOk());
  EXPECT_EQ((*one)->tets, all->meshes[1].tets);
  EXPECT_EQ(builder->built(), 3u);
  const size_t last = builder->count() - 1;
  auto coarsest = builder->level(last);
  ASSERT_TRUE(coarsest.isOk());
  EXPECT_EQ((*coarsest)->tets, all->meshes[last].tets);
  EXPECT_EQ(builder->level(last + 1).status().code(), StatusCode::kUsage);
}

// A writer that stores level 0 and the coarse levels only skips the levels between: their tetrahedra
// are known from the tree, the first stored level is made from level 0 in one pass, and the levels
// from there on are the same meshes and trees as when every level is made.
TEST(Levels, TheBuilderSkipsTheLevelsAWriterLeavesOut) {
  const Ranked& g = grid();
  const LevelOptions lo{-1, 32, true, 0};
  auto all = buildMipLevels(g.mesh, g.tree, lo);
  ASSERT_TRUE(all.isOk()) << all.status().message();
  ASSERT_GE(all->merges.size(), 5u);
  auto builder = MipLevelBuilder::create(g.mesh, g.tree, lo);
  ASSERT_TRUE(builder.isOk());
  EXPECT_EQ(builder->tetsOf(0), g.mesh.numTets());
  for (size_t i = 1; i < builder->count(); ++i) EXPECT_EQ(builder->tetsOf(i), all->meshes[i].numTets()) << i;
  builder->skipTo(3);
  auto three = builder->level(3);
  ASSERT_TRUE(three.isOk()) << three.status().message();
  EXPECT_EQ((*three)->tets, all->meshes[3].tets);
  EXPECT_EQ((*three)->coords, all->meshes[3].coords);
  ASSERT_TRUE(builder->tree(3));
  EXPECT_EQ(builder->tree(3)->rank, all->trees[3]->rank);
  EXPECT_EQ(builder->tree(3)->parent, all->trees[3]->parent);
  EXPECT_FALSE(builder->tree(2));
  EXPECT_TRUE(builder->nextIndex(2).empty());
  EXPECT_EQ(builder->level(2).status().code(), StatusCode::kUsage);
  auto four = builder->level(4);
  ASSERT_TRUE(four.isOk());
  EXPECT_EQ((*four)->tets, all->meshes[4].tets);
  EXPECT_EQ(builder->nextIndex(3), all->next_index[3]);
}

// With independent levels, convert makes only the mip levels the storage bound lets the file keep and
// the first one past it (its encoded bytes decide), and checks the structure of the kept ones only; the
// file is the one the levels made up front give.
TEST(Levels, ConvertMakesAndChecksOnlyTheLevelsItStores) {
  TetMesh mesh = makeGrid(20, 20, 20);
  RankingStats stats;
  auto tree = rankMerges(mesh, RankingOptions{}, &stats);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  auto level0 = encodePieces(mesh, EncodeOptions{}, kDefaultPieceTets);
  ASSERT_TRUE(level0.isOk()) << level0.status().message();
  auto stored = storedMergeTree(mesh, *tree, *level0);
  ASSERT_TRUE(stored.isOk()) << stored.status().message();
  auto all = buildMipLevels(mesh, stored->tree, LevelOptions{});
  ASSERT_TRUE(all.isOk()) << all.status().message();
  const size_t count = all->merges.size();
  const std::string path = ::testing::TempDir() + "/lazy_levels.gtn";
  GtnConvertOptions convert;
  convert.level_storage = 1.6;
  GtnWriteOptions eager;
  eager.level_storage_limit = convert.level_storage;
  eager.chain_levels = false;
  ASSERT_TRUE(writeGtnFile(path, all->inputs(mesh, stored->level0_form), eager).isOk());
  auto want = readWholeFile(path);
  ASSERT_TRUE(want.isOk()) << want.status().message();
  for (const bool verify : {true, false}) {
    SCOPED_TRACE(verify ? "verify" : "no verify");
    std::mutex lock;
    std::vector<std::string> built, checked;
    GtnWriteOptions wo;
    wo.verify = verify;
    wo.chain_levels = false;
    wo.progress = [&](const std::string& stage, double) {
      std::lock_guard<std::mutex> hold(lock);
      if (stage.rfind("build level ", 0) == 0) built.push_back(stage);
      if (stage.rfind("check level ", 0) == 0) checked.push_back(stage);
    };
    ASSERT_TRUE(writeGtnWithLevels(path, mesh, convert, wo, "grid").isOk());
    auto r = GtnReader::open(path);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const size_t kept = (*r)->levels();
    ASSERT_GE(kept, 2u);
    ASSERT_LT(kept + 1, count) << "the bound must leave levels out for the test to mean anything";
    std::vector<std::string> want_built, want_checked;
    for (size_t i = 1; i <= kept; ++i)
      want_built.push_back("build level " + std::to_string(i) + " (" + std::to_string(count) + " levels)");
    for (size_t i = 1; verify && i < kept; ++i)
      want_checked.push_back("check level " + std::to_string(i) + " (" + std::to_string(count) + " levels)");
    std::sort(checked.begin(), checked.end());  // checks may run on other threads
    EXPECT_EQ(built, want_built);
    EXPECT_EQ(checked, want_checked);
    auto got = readWholeFile(path);
    ASSERT_TRUE(got.isOk()) << got.status().message();
    // The provenance is the same (empty) in both, so the whole files compare.
    EXPECT_TRUE(*got == *want);
  }
  std::filesystem::remove(path);
}

TEST(Levels, ConvertWritesTheSameBytesForAnyThreadCount) {
  // writeGtnWithLevels encodes level 0 while the merges are ranked (on another thread where there is
  // one); the file is the one the levels give encoded one after the other, for any thread count.
  const Ranked& g = grid();
  const std::string path = ::testing::TempDir() + "/threads.gtn";
  auto bytesOf = [&](const std::string& p) {
    auto b = readWholeFile(p);
    EXPECT_TRUE(b.isOk()) << b.status().message();
    return b.isOk() ? *b : std::string();
  };
  GtnWriteOptions wo;
  wo.level_storage_limit = 2.0;
  auto level0 = encodePieces(g.mesh, EncodeOptions{}, wo.piece_tets);
  ASSERT_TRUE(level0.isOk()) << level0.status().message();
  auto stored = storedMergeTree(g.mesh, g.tree, *level0);
  ASSERT_TRUE(stored.isOk()) << stored.status().message();
  auto levels = buildMipLevels(g.mesh, stored->tree, LevelOptions{});
  ASSERT_TRUE(levels.isOk()) << levels.status().message();
  ASSERT_TRUE(writeGtnFile(path, levels->inputs(g.mesh, stored->level0_form), wo).isOk());
  const std::string sequential = bytesOf(path);
  ASSERT_FALSE(sequential.empty());
  // A level given already encoded is written as the writer would have encoded it.
  auto encoded = encodePieces(g.mesh, EncodeOptions{}, wo.piece_tets);
  ASSERT_TRUE(encoded.isOk()) << encoded.status().message();
  std::vector<GtnLevelInput> inputs = levels->inputs(g.mesh, stored->level0_form);
  inputs[0].encoded = std::make_shared<PiecedLevel>(std::move(encoded).value());
  ASSERT_TRUE(writeGtnFile(path, inputs, wo).isOk());
  EXPECT_EQ(bytesOf(path), sequential);
  for (const size_t threads : {1, 2}) {
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    ASSERT_TRUE(writeGtnWithLevels(path, g.mesh, GtnConvertOptions{}, GtnWriteOptions{}, "grid").isOk());
    EXPECT_EQ(bytesOf(path), sequential);
  }
  std::filesystem::remove(path);
}

// A large grid of rule cells has its tetrahedra released while the merges are ranked and batched,
// read from their indices (RuleGridTets): the trees, the file and, after, the mesh are the same.
TEST(Levels, AGridsTetrahedraReleasedWhileRankedGiveTheSameFile) {
  TetMesh m = makeGrid(14, 12, 10);
  StructuredBlock block;
  block.dims[0] = 15, block.dims[1] = 13, block.dims[2] = 11;
  m.blocks.push_back(block);
  const std::vector<Tet> tets = m.tets;
  GtnConvertOptions o;
  o.ranking.parts = 4;  // in rounds of parts, as a large mesh is ranked
  // The ranking and the batches alone, from the tetrahedra and from the grid.
  auto layout = matchGridLayout(m, block.dims);
  ASSERT_TRUE(layout.isOk()) << layout.status().message();
  ASSERT_TRUE(layout->exceptions.empty());
  const RuleGridTets grid(*layout);
  ASSERT_TRUE(grid.sameAs(m.tets));
  RankingStats held_stats, released_stats;
  auto held = rankMerges(m, o.ranking, &held_stats);
  ASSERT_TRUE(held.isOk()) << held.status().message();
  const RankingFaces faces = rankingFaces(m);
  TetMesh bare = m;
  bare.tets.clear();
  RankingOptions from_grid = o.ranking;
  from_grid.grid_tets = &grid;
  EXPECT_FALSE(rankMerges(bare, from_grid, nullptr).isOk()) << "a grid's tetrahedra need the face flags";
  from_grid.faces = &faces;
  auto released = rankMerges(bare, from_grid, &released_stats);
  ASSERT_TRUE(released.isOk()) << released.status().message();
  ASSERT_GT(held_stats.rounds.size(), 1u);
  EXPECT_EQ(released->parent, held->parent);
  EXPECT_EQ(released->rank, held->rank);
  EXPECT_EQ(released->removed, held->removed);
  EXPECT_EQ(released->error, held->error);
  std::vector<uint64_t> keys(m.numPoints());
  for (size_t v = 0; v < keys.size(); ++v) keys[v] = batchKeyOfId(static_cast<uint32_t>(v));
  auto batched = batchMerges(m, *held, keys, 0, nullptr, held_stats.rounds, &held_stats.faces);
  auto batched_grid = batchMerges(bare, *held, keys, 0, nullptr, held_stats.rounds, &held_stats.faces, &grid);
  ASSERT_TRUE(batched.isOk() && batched_grid.isOk());
  EXPECT_EQ(batched_grid->parent, batched->parent);
  EXPECT_EQ(batched_grid->rank, batched->rank);
  EXPECT_EQ(batched_grid->batches, batched->batches);
  // The writer: the same bytes with the tetrahedra held and released, which the progress sees: from
  // the ranking to the file's end, but where level 0 may name the next level's vertices (levels asked
  // for, not automatic), whose encoding from the mesh needs them back before the file is written.
  const std::string path = ::testing::TempDir() + "/released.gtn";
  for (const int levels : {-1, 2}) {
    o.levels = levels;
    o.release_grid_tets = uint64_t{1} << 22;
    ASSERT_TRUE(writeGtnWithLevels(path, m, o, GtnWriteOptions{}, "grid").isOk());
    auto want = readWholeFile(path);
    ASSERT_TRUE(want.isOk()) << want.status().message();
    for (const uint64_t from : {uint64_t{0}, uint64_t{1} << 40}) {
      SCOPED_TRACE("levels " + std::to_string(levels) + ", released from " + std::to_string(from) + " tetrahedra");
      o.release_grid_tets = from;
      std::mutex lock;
      std::set<std::string> released_at, held_at;
      GtnWriteOptions wo;
      wo.progress = [&](const std::string& stage, double) {
        const std::string what = stage.substr(0, stage.find(" level"));
        std::lock_guard<std::mutex> hold(lock);
        (m.tets.empty() ? released_at : held_at).insert(what);
      };
      ASSERT_TRUE(writeGtnWithLevels(path, &m, o, wo, "grid").isOk());
      if (from == 0) {
        EXPECT_TRUE(released_at.count("batch merges"));
        EXPECT_TRUE(held_at.count("rank merges"));  // the ranking's first report comes before
        EXPECT_EQ(released_at.count("encode"), levels < 0 ? 1u : 0u);
        EXPECT_EQ(held_at.count("encode"), levels < 0 ? 0u : 1u);
      } else {
        EXPECT_TRUE(released_at.empty());
      }
      EXPECT_TRUE(m.tets == tets);
      auto got = readWholeFile(path);
      ASSERT_TRUE(got.isOk()) << got.status().message();
      EXPECT_TRUE(*got == *want);
    }
  }
  o.levels = -1;
  // A grid with a cell off the rule (an exception) keeps its tetrahedra.
  std::swap(m.tets[7][0], m.tets[7][1]);
  std::swap(m.tets[7][2], m.tets[7][3]);
  const std::vector<Tet> changed = m.tets;
  o.release_grid_tets = 0;
  bool seen_released = false;
  GtnWriteOptions wo;
  wo.progress = [&](const std::string&, double) { seen_released = seen_released || m.tets.empty(); };
  ASSERT_TRUE(writeGtnWithLevels(path, &m, o, wo, "grid").isOk());
  EXPECT_FALSE(seen_released);
  EXPECT_TRUE(m.tets == changed);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace gtn::test
