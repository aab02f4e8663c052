// Simplification on the real datasets: every prefix checked at a dozen merge counts (level boundaries
// included), the on-the-fly filter on the decoded stream against applyMerges, and the stored mip
// levels of a .gtn file against the in-memory results. Each dataset is ranked once per test binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <optional>

#include <tbb/task_arena.h>

#include "codec/codec_test_util.h"
#include "codec/merge_tree_coder.h"
#include "convert/import.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "mesh/predicates.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "simplify/stream_simplifier.h"
#include "simplify_test_util.h"
#include "test_util.h"

namespace gtn::test {
namespace {

struct Ranked {
  TetMesh mesh;     // as imported
  TetMesh with_id;  // plus the "id" point field, for identity through the stream
  MergeTree tree;
  RankingStats stats;
  std::optional<EncodedLevel> encoded;  // of with_id
  uint64_t source_zero = 0;
};

const Ranked& dataset(const std::string& name) {
  static std::map<std::string, Ranked> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  std::vector<std::string> files;
  ImportOptions io;
  if (name == "spx") files = {dataPath("vtk/spx.vtk")};
  if (name == "cornell") files = {dataPath("tetgen/cornell_spheres.1.ele")};
  if (name == "bluntfin") files = {dataPath("plot3d/bluntfinxyz.bin"), dataPath("plot3d/bluntfinq.bin")};
  if (name == "combustion") files = {dataPath("plot3d/combxyz.bin"), dataPath("plot3d/combq.bin")};
  if (name == "bluntfin" || name == "combustion") io.split = 5;  // the paper's split, with coincident points
  Ranked r;
  auto imported = importMesh(files, io);
  EXPECT_TRUE(imported.isOk()) << imported.status().message();
  if (imported.isOk()) {
    r.mesh = std::move(imported->mesh);
    auto tree = rankMerges(r.mesh, RankingOptions{}, &r.stats);
    EXPECT_TRUE(tree.isOk()) << tree.status().message();
    if (tree.isOk()) r.tree = std::move(tree.value());
    r.with_id = r.mesh;
    addIdField(r.with_id);
    r.source_zero = checkMesh(r.mesh).zero_volume;
    auto enc = encodeLevel(r.with_id, EncodeOptions{});
    EXPECT_TRUE(enc.isOk()) << enc.status().message();
    if (enc.isOk()) r.encoded = std::move(enc.value());
  }
  return cache.emplace(name, std::move(r)).first->second;
}

std::vector<uint64_t> sampleMerges(const MergeTree& tree, uint64_t points) {
  std::vector<uint64_t> ns = {0, 1, 3, tree.merges / 5, tree.merges / 2 + 1, tree.merges};
  for (int i = 1; i <= 12; ++i) ns.push_back(levelMerges(i, points, tree.merges));
  std::sort(ns.begin(), ns.end());
  ns.erase(std::unique(ns.begin(), ns.end()), ns.end());
  return ns;
}

// Geometric identity of a tetrahedron: its four points, sorted.
using GeoTet = std::array<std::array<double, 3>, 4>;
std::vector<GeoTet> geoTets(const TetMesh& m) {
  std::vector<GeoTet> out;
  out.reserve(m.numTets());
  for (const Tet& t : m.tets) {
    GeoTet g;
    for (int i = 0; i < 4; ++i) g[i] = {m.point(t[i])[0], m.point(t[i])[1], m.point(t[i])[2]};
    std::sort(g.begin(), g.end());
    out.push_back(g);
  }
  std::sort(out.begin(), out.end());
  return out;
}

class Datasets : public ::testing::TestWithParam<std::string> {};

TEST_P(Datasets, RankingSimplifiesAndEveryPrefixIsValid) {
  const Ranked& d = dataset(GetParam());
  ASSERT_GT(d.mesh.numTets(), 0u);
  ASSERT_TRUE(d.tree.check(GetParam()).isOk());
  const uint64_t points = d.mesh.numPoints();
  EXPECT_GT(d.tree.merges, points * 3 / 4) << "merges " << d.tree.merges << " of " << points << " points";
  RecordProperty("ranking_seconds", std::to_string(d.stats.seconds));
  const MeshChecks src = checkMesh(d.mesh);
  for (uint64_t n : sampleMerges(d.tree, points)) {
    SCOPED_TRACE("n = " + std::to_string(n));
    auto m = applyMerges(d.mesh, d.tree, n);
    ASSERT_TRUE(m.isOk());
    const MeshChecks c = checkMesh(*m);
    EXPECT_EQ(c.inverted, 0u);
    EXPECT_LE(c.zero_volume, src.zero_volume);
    EXPECT_EQ(c.non_manifold, 0u);
    EXPECT_EQ(c.duplicates, 0u);
    EXPECT_EQ(c.boundary_euler, src.boundary_euler);
    EXPECT_EQ(m->numTets(), d.mesh.numTets() - d.tree.tetsRemovedUpTo(n));
  }
}

// The vertices around a merge are evaluated in parallel; the tree must be the one a single thread
// ranks, merge for merge (a race on the shared star runs or an order that depends on the threads
// would change it).
TEST_P(Datasets, RankingOnOneThreadGivesTheSameTree) {
  const Ranked& d = dataset(GetParam());
  ASSERT_GT(d.mesh.numTets(), 0u);
  RankingStats stats;
  std::optional<StatusOr<MergeTree>> one;
  tbb::task_arena arena(1);
  arena.execute([&] { one.emplace(rankMerges(d.mesh, RankingOptions{}, &stats)); });
  ASSERT_TRUE(one->isOk()) << one->status().message();
  const MergeTree& t = one->value();
  EXPECT_EQ(t.merges, d.tree.merges);
  EXPECT_EQ(t.parent, d.tree.parent);
  EXPECT_EQ(t.rank, d.tree.rank);
  EXPECT_EQ(t.removed, d.tree.removed);
  EXPECT_EQ(t.boundary, d.tree.boundary);
  EXPECT_EQ(t.error, d.tree.error);
  EXPECT_EQ(stats.evaluations, d.stats.evaluations);
  EXPECT_EQ(stats.rejected, d.stats.rejected);
}

TEST_P(Datasets, OnTheFlyEqualsApplyOnTheDecodedStream) {
  const Ranked& d = dataset(GetParam());
  const uint64_t points = d.mesh.numPoints();
  std::vector<uint64_t> ns = sampleMerges(d.tree, points);
  ASSERT_TRUE(d.encoded.has_value());
  for (uint64_t n : ns) expectStreamMatchesApply(d.with_id, d.tree, n, true, &*d.encoded);
  expectStreamMatchesApply(d.with_id, d.tree, ns[ns.size() / 2], false);
}

TEST_P(Datasets, StoredLevelsDecodeToTheInMemoryResult) {
  const Ranked& d = dataset(GetParam());
  LevelOptions small;
  small.min_tets = 0;  // levels down to 256 points, however few tetrahedra they keep
  auto levels = buildMipLevels(d.mesh, d.tree, small);
  ASSERT_TRUE(levels.isOk()) << levels.status().message();
  ASSERT_GE(levels->merges.size(), 4u);
  const std::string path = tempDir("simplify-" + GetParam()) + "/levels.gtn";
  GtnWriteOptions wo;
  wo.tool_version = "test";
  ASSERT_TRUE(writeGtnFile(path, levels->inputs(d.mesh), wo).isOk());
  auto reader = GtnReader::open(path);
  ASSERT_TRUE(reader.isOk()) << reader.status().message();
  GtnReader& r = **reader;
  ASSERT_EQ(r.levels(), levels->merges.size());
  for (size_t i = 0; i < r.levels(); ++i) {
    SCOPED_TRACE("level " + std::to_string(i));
    EXPECT_EQ(r.level(i).header.merges, levels->merges[i]);
    EXPECT_TRUE(r.level(i).has_merge_tree);
    TetMeshBuilder b;
    ASSERT_TRUE(r.decodeLevel(i, b).isOk());
    const TetMesh& want = i == 0 ? d.mesh : levels->meshes[i];
    EXPECT_EQ(geoTets(b.mesh()), geoTets(want));
  }
  // The same levels stored independently (--independent-levels): every level whole, with the rest of
  // the merge tree.
  GtnWriteOptions independent = wo;
  independent.chain_levels = false;
  const std::string independent_path = path + ".independent.gtn";
  ASSERT_TRUE(writeGtnFile(independent_path, levels->inputs(d.mesh), independent).isOk());
  auto ir = GtnReader::open(independent_path);
  ASSERT_TRUE(ir.isOk()) << ir.status().message();
  uint64_t level0 = (*ir)->level(0).bytes, total = 0, chained = 0;
  for (size_t i = 0; i < (*ir)->levels(); ++i) total += (*ir)->level(i).bytes;
  for (size_t i = 0; i < r.levels(); ++i) chained += r.level(i).bytes;
  RecordProperty("levels_over_level0", std::to_string(double(total) / level0));
  RecordProperty("chained_levels_over_level0", std::to_string(double(chained) / level0));
  // Independent: every level of the pyramid costs more than half the level above (vertices farther
  // apart predict worse), so the whole series passes 2x level 0 on the grids; more so where level 0 is
  // a structured piece (blunt fin 14.6 bits per tetrahedron against the level codec's 18.3) and the
  // coarse levels are not.
  EXPECT_GE(double(total), 1.5 * double(level0));
  EXPECT_LE(double(total), 2.6 * double(level0));
  // Levels that name the next level's vertices store each value and merge once: the same levels take
  // far fewer bytes (spx 1.4x level 0 alone, against 2.5x; blunt fin, whose level 0 is a grid that
  // stores all its nodes, about 1.7x against 2.6x).
  EXPECT_LT(double(chained), 0.8 * double(total));
  EXPECT_LE(double(chained), 1.9 * double(level0));
  {
    // With the paper's bound ("storage doubled") and independent levels: the finest levels that fit,
    // the same ones as above, within 2x level 0 in the file's own bytes.
    GtnWriteOptions bounded = independent;
    bounded.level_storage_limit = 2.0;
    const std::string bounded_path = path + ".bounded.gtn";
    ASSERT_TRUE(writeGtnFile(bounded_path, levels->inputs(d.mesh), bounded).isOk());
    auto br = GtnReader::open(bounded_path);
    ASSERT_TRUE(br.isOk()) << br.status().message();
    uint64_t btotal = 0;
    for (size_t i = 0; i < (*br)->levels(); ++i) {
      btotal += (*br)->level(i).bytes;
      EXPECT_EQ((*br)->level(i).bytes, (*ir)->level(i).bytes);
      EXPECT_EQ((*br)->level(i).header.merges, levels->merges[i]);
    }
    RecordProperty("bounded_levels", std::to_string((*br)->levels()));
    EXPECT_LE(btotal, 2 * (*br)->level(0).bytes);
    EXPECT_GE((*br)->levels(), 3u);
    if (total <= 2 * level0) EXPECT_EQ((*br)->levels(), (*ir)->levels());
    else EXPECT_LT((*br)->levels(), (*ir)->levels());
    // With chained levels the same bound keeps every level.
    GtnWriteOptions chained_bounded = wo;
    chained_bounded.level_storage_limit = 2.0;
    ASSERT_TRUE(writeGtnFile(bounded_path, levels->inputs(d.mesh), chained_bounded).isOk());
    auto cb = GtnReader::open(bounded_path);
    ASSERT_TRUE(cb.isOk());
    EXPECT_EQ((*cb)->levels(), r.levels());
    // A bound below the first level's cost keeps level 0 alone, with the whole merge tree, either way.
    for (GtnWriteOptions tight : {independent, wo}) {
      tight.level_storage_limit = 1.01;
      ASSERT_TRUE(writeGtnFile(bounded_path, levels->inputs(d.mesh), tight).isOk());
      auto only0 = GtnReader::open(bounded_path);
      ASSERT_TRUE(only0.isOk());
      EXPECT_EQ((*only0)->levels(), 1u);
      EXPECT_TRUE((*only0)->level(0).has_merge_tree);
      EXPECT_EQ((*only0)->level(0).base, 0);
    }
    std::filesystem::remove(bounded_path);
  }
  std::filesystem::remove(independent_path);
  // Reading at a target between two levels starts from the coarser-than-target stored level.
  const uint64_t target = (levels->merges[2] + levels->merges[3]) / 2;
  TetMeshBuilder b;
  SimplifyPlan plan;
  ASSERT_TRUE(streamSimplified(r, target, b, &plan).isOk());
  EXPECT_EQ(plan.level, 2u);
  EXPECT_EQ(plan.extra_merges, target - levels->merges[2]);
  auto want = applyMerges(d.mesh, d.tree, target);
  ASSERT_TRUE(want.isOk());
  EXPECT_EQ(geoTets(b.mesh()), geoTets(*want));
  std::filesystem::remove(path);
}

// A grid's level 0 whose merge tree decodes without the level (its parents are grid places): the
// tree is decoded beside the level's streams (streamSimplified), and a read gives what applying the
// merges to level 0 gives, whatever the threads, at merge counts within the tree and past it
// (clamped to the whole tree, or refused without the clamp, as before).
// Blunt fin converted to level 0 with its whole merge tree and no other level (--levels 0), once per
// test binary (tempDir removes it at the end).
const std::string& bluntFinLevel0Only() {
  static const std::string path = [] {
    const std::string p = tempDir("stream_simplified") + "/bluntfin.gtn";
    const RunResult made = runGtn("convert " + dataPath("plot3d/bluntfinxyz.bin") + " " +
                                  dataPath("plot3d/bluntfinq.bin") + " -o " + p + " --levels 0 -q");
    EXPECT_EQ(made.exit_code, 0) << made.err;
    return p;
  }();
  return path;
}

TEST(StreamSimplified, GridTreeDecodedBesideItsLevelGivesTheMergesOfLevel0) {
  auto r = GtnReader::open(bluntFinLevel0Only());
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ((*r)->levels(), 1u);
  auto payload = (*r)->mergeTreePayload(0);
  ASSERT_TRUE(payload.isOk() && payload->has_value());
  const uint64_t points = (*r)->level(0).header.points;
  auto h = readMergeTreeHeader(**payload, points, "level 0");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  ASSERT_FALSE(h->needs_mesh);
  ASSERT_FALSE(h->needs_next_ids);
  auto tree = decodeMergeTree(**payload, points, "level 0", nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  TetMeshBuilder level0;
  ASSERT_TRUE((*r)->decodeLevel(0, level0).isOk());
  for (uint64_t n : {uint64_t{1}, tree->merges / 3, tree->merges - 1, tree->merges + 1000}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    auto want = applyMerges(level0.mesh(), *tree, std::min(n, tree->merges));
    ASSERT_TRUE(want.isOk()) << want.status().message();
    for (int threads : {1, 2}) {
      TetMeshBuilder b;
      SimplifyPlan plan;
      Status st;
      tbb::task_arena(threads).execute([&] { st = streamSimplified(**r, n, b, &plan, /*clamp=*/true); });
      ASSERT_TRUE(st.isOk()) << st.message();
      EXPECT_EQ(plan.level, 0u);
      EXPECT_EQ(plan.extra_merges, std::min(n, tree->merges)) << threads << " thread(s)";
      EXPECT_EQ(geoTets(b.mesh()), geoTets(*want)) << threads << " thread(s)";
      EXPECT_EQ(b.mesh().numPoints(), want->numPoints()) << threads << " thread(s)";
    }
    if (n > tree->merges) {
      TetMeshBuilder b;
      const Status st = streamSimplified(**r, n, b, nullptr, /*clamp=*/false);
      EXPECT_EQ(st.code(), StatusCode::kUsage);
      EXPECT_NE(st.message().find(std::to_string(n) + " merges requested, the merge tree has " +
                                  std::to_string(tree->merges)),
                std::string::npos)
          << st.message();
    }
  }
}

// A sink that takes a level whole (as TetMeshBuilder does) gets a grid's simplified level whole from
// the filter, made on every thread; a sink that takes events gets the same mesh as events. Both are
// the same points, oriented tetrahedra with their cell values, and boundary triangles.
TEST(StreamSimplified, AGridLevelGivenWholeIsSimplifiedWhole) {
  struct WholeSink : TetMeshBuilder {
    bool takesWholeLevel() const override { return true; }
    Status wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                      std::vector<std::array<uint32_t, 3>>&& boundary) override {
      ++whole_levels;
      return TetMeshBuilder::wholeLevel(header, std::move(mesh), std::move(boundary));
    }
    Status beginLevel(const LevelHeader& header) override {
      ++event_levels;
      return TetMeshBuilder::beginLevel(header);
    }
    int whole_levels = 0, event_levels = 0;
  };
  struct EventSink : TetMeshBuilder {};  // not exactly TetMeshBuilder: takes the events
  auto r = GtnReader::open(bluntFinLevel0Only());
  ASSERT_TRUE(r.isOk()) << r.status().message();
  // Each tetrahedron with its orientation, each boundary triangle, by their points' coordinates.
  auto oriented = [](const TetMesh& m) {
    std::multiset<std::string> out;
    for (const Tet& t : m.tets) {
      std::array<std::string, 4> c;
      for (int i = 0; i < 4; ++i) c[i].assign(reinterpret_cast<const char*>(m.point(t[i])), 24);
      const int sign = orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3]));
      std::sort(c.begin(), c.end());
      out.insert(std::to_string(sign) + c[0] + c[1] + c[2] + c[3]);
    }
    return out;
  };
  auto triangles = [](const TetMesh& m, const std::vector<std::array<uint32_t, 3>>& b) {
    std::multiset<std::string> out;
    for (const auto& f : b) {
      std::array<std::string, 3> c;
      for (int i = 0; i < 3; ++i) c[i].assign(reinterpret_cast<const char*>(m.point(f[i])), 24);
      std::sort(c.begin(), c.end());
      out.insert(c[0] + c[1] + c[2]);
    }
    return out;
  };
  const uint64_t points = (*r)->level(0).header.points;
  for (uint64_t n : {points / 10, points / 2, points * 9 / 10}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    WholeSink whole;
    EventSink events;
    ASSERT_TRUE(streamSimplified(**r, n, whole).isOk());
    ASSERT_TRUE(streamSimplified(**r, n, events).isOk());
    EXPECT_EQ(whole.whole_levels, 1);
    EXPECT_EQ(whole.event_levels, 0);
    EXPECT_EQ(whole.header().points, events.header().points);
    EXPECT_EQ(whole.header().tets, events.header().tets);
    EXPECT_EQ(whole.mesh().numTets(), events.mesh().numTets());
    EXPECT_TRUE(canonicalMesh(whole.mesh()) == canonicalMesh(events.mesh()));
    EXPECT_TRUE(oriented(whole.mesh()) == oriented(events.mesh()));
    EXPECT_TRUE(triangles(whole.mesh(), whole.boundary()) == triangles(events.mesh(), events.boundary()));
    EXPECT_EQ(whole.boundary().size(), events.header().boundary_triangles);
  }
}

// StreamSimplifier::wholeLevel on its own: blunt fin's level 0 given whole gives what applying the
// merges gives; a level with a tetrahedron beyond its points, or a tree whose removed counts disagree
// with the level, is refused as the event path refuses it.
TEST(StreamSimplified, WholeLevelRefusesWhatTheEventsRefuse) {
  auto r = GtnReader::open(bluntFinLevel0Only());
  ASSERT_TRUE(r.isOk()) << r.status().message();
  TetMeshBuilder level0;
  ASSERT_TRUE((*r)->decodeLevel(0, level0).isOk());
  auto payload = (*r)->mergeTreePayload(0);
  ASSERT_TRUE(payload.isOk() && payload->has_value());
  auto tree = decodeMergeTree(**payload, level0.header().points, "level 0", nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  const uint64_t n = tree->merges / 2;
  auto run = [&](const MergeTree& t, TetMesh mesh) {
    TetMeshBuilder out;
    StreamSimplifier filter(t, n, out);
    auto boundary = level0.boundary();
    const Status st = filter.wholeLevel(level0.header(), std::move(mesh), std::move(boundary));
    return std::make_pair(st, std::move(out.mesh()));
  };
  auto [ok, simplified] = run(*tree, level0.mesh());
  ASSERT_TRUE(ok.isOk()) << ok.message();
  auto want = applyMerges(level0.mesh(), *tree, n);
  ASSERT_TRUE(want.isOk());
  EXPECT_TRUE(canonicalMesh(simplified) == canonicalMesh(*want));
  TetMesh beyond = level0.mesh();
  beyond.tets[beyond.tets.size() / 2][1] = static_cast<uint32_t>(beyond.numPoints());
  const Status b = run(*tree, std::move(beyond)).first;
  EXPECT_EQ(b.code(), StatusCode::kInvalidData);
  EXPECT_NE(b.message().find("refers to a vertex beyond the level"), std::string::npos) << b.message();
  MergeTree miscounted = *tree;
  for (size_t v = 0; v < miscounted.points(); ++v)
    if (miscounted.rank[v] == 1) miscounted.removed[v] += 1;
  miscounted.checked = false;
  const Status m = run(miscounted, level0.mesh()).first;
  EXPECT_EQ(m.code(), StatusCode::kInvalidData);
  EXPECT_NE(m.message().find("the merge tree implies"), std::string::npos) << m.message();
}

INSTANTIATE_TEST_SUITE_P(Simplify, Datasets, ::testing::Values("spx", "cornell", "bluntfin", "combustion"));

}  // namespace
}  // namespace gtn::test
