// Levels that name the next level's vertices (spec section 7.7): every level decodes to the mesh an
// independent level holds, a level's whole merge tree is its own merges then the next level's,
// renumbered, the file is smaller, a coarse level reads nothing of the finer ones, and files whose
// trees and levels do not fit together are refused with the level named.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>

#include "codec/codec_test_util.h"
#include "convert/import.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "format/gtn_records.h"
#include "simplify/apply.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "test_util.h"
#include "validate/validator.h"
#include "validate/write_gtn.h"

namespace gtn::test {
namespace {

TetMesh spx() {
  auto imported = importMesh({dataPath("vtk/spx.vtk")}, ImportOptions{});
  EXPECT_TRUE(imported.isOk()) << imported.status().message();
  return imported.isOk() ? std::move(imported->mesh) : TetMesh{};
}

// One directory for the test program (tempDir empties it when called).
const std::string& dir() {
  static const std::string d = tempDir("gtn-chain");
  return d;
}

std::string write(const TetMesh& mesh, const std::string& name, bool chain, int levels = 3) {
  const std::string path = dir() + "/" + name + ".gtn";
  GtnConvertOptions o;
  o.levels = levels;
  GtnWriteOptions w;
  w.chain_levels = chain;
  const Status st = writeGtnWithLevels(path, mesh, o, w, name);
  EXPECT_TRUE(st.isOk()) << st.message();
  return path;
}

std::unique_ptr<GtnReader> open(const std::string& path) {
  auto r = GtnReader::open(path, GtnOpenOptions{false});
  EXPECT_TRUE(r.isOk()) << r.status().message();
  return r.isOk() ? std::move(r).value() : nullptr;
}

TetMesh decode(GtnReader& r, size_t level) {
  TetMeshBuilder b;
  const Status st = r.decodeLevel(level, b);
  EXPECT_TRUE(st.isOk()) << st.message();
  return std::move(b.mesh());
}

using Point = std::tuple<double, double, double>;
Point pointOf(const TetMesh& m, uint32_t v) { return {m.point(v)[0], m.point(v)[1], m.point(v)[2]}; }

// A merge tree by coordinates (spx's points are distinct): child -> (parent, rank, removed, boundary).
std::map<Point, std::tuple<Point, uint32_t, uint32_t, uint8_t>> treeByPoint(const TetMesh& m, const MergeTree& t) {
  std::map<Point, std::tuple<Point, uint32_t, uint32_t, uint8_t>> out;
  for (uint32_t v = 0; v < t.points(); ++v)
    if (t.rank[v] != 0) out[pointOf(m, v)] = {pointOf(m, t.parent[v]), t.rank[v], t.removed[v], t.boundary[v]};
  return out;
}

TEST(GtnChain, LevelsNameTheNextLevelAndDecodeAsIndependentLevelsDo) {
  const TetMesh mesh = spx();
  ASSERT_GT(mesh.numTets(), 0u);
  const std::string chained = write(mesh, "chained", true), alone = write(mesh, "alone", false);
  auto c = open(chained), a = open(alone);
  ASSERT_TRUE(c && a);
  ASSERT_EQ(c->levels(), 4u);
  ASSERT_EQ(a->levels(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(c->level(i).base, i + 1 < 4 ? 1 : 0) << "level " << i;
    EXPECT_EQ(a->level(i).base, 0) << "level " << i;
    EXPECT_EQ(c->level(i).header.merges, a->level(i).header.merges);
    EXPECT_TRUE(canonicalMesh(decode(*c, i)) == canonicalMesh(decode(*a, i))) << "level " << i;
    // A level's own merge tree holds its merges down to the next level, the last one the rest.
    auto own = c->mergeTreePayload(i);
    ASSERT_TRUE(own.isOk() && own->has_value());
    // Its children are coded among the level's own vertices, which the level's decoding names.
    TetMeshBuilder level;
    std::vector<uint32_t> ids;
    ASSERT_TRUE(c->decodeLevel(i, level, nullptr, nullptr, &ids).isOk());
    ASSERT_EQ(ids.empty(), i + 1 == 4);
    auto tree = decodeMergeTree(**own, c->level(i).header.points, "chained", &level.mesh(), UINT64_MAX,
                                ids.empty() ? nullptr : &ids);
    ASSERT_TRUE(tree.isOk()) << tree.status().message();
    if (!ids.empty()) {
      auto blind = decodeMergeTree(**own, c->level(i).header.points, "chained", &level.mesh());
      ASSERT_FALSE(blind.isOk());
      EXPECT_NE(blind.status().message().find("next level has"), std::string::npos) << blind.status().message();
    }
    if (i + 1 < 4) {
      EXPECT_EQ(tree->merges, c->level(i + 1).header.merges - c->level(i).header.merges);
    }
  }
  // The values are stored once: the chained file is far smaller (spx: 2.6 times level 0 alone with
  // independent levels and a tree per level, 1.5 times chained).
  const uint64_t chained_bytes = c->file().bytes, alone_bytes = a->file().bytes;
  EXPECT_LT(chained_bytes * 10, alone_bytes * 7) << chained_bytes << " against " << alone_bytes;

  // Level 0's whole tree, put together from the four levels' trees, is the independent file's level 0
  // tree (compared by coordinates, since the two files number vertices alike only by chance).
  auto whole = wholeMergeTree(*c, 0);
  ASSERT_TRUE(whole.isOk()) << whole.status().message();
  ASSERT_TRUE(whole->has_value());
  auto ref_payload = a->mergeTreePayload(0);
  ASSERT_TRUE(ref_payload.isOk() && ref_payload->has_value());
  const TetMesh c0 = decode(*c, 0), a0 = decode(*a, 0);
  auto ref = decodeMergeTree(**ref_payload, a->level(0).header.points, "alone", &a0);
  ASSERT_TRUE(ref.isOk());
  EXPECT_EQ((*whole)->merges, ref->merges);
  EXPECT_TRUE(treeByPoint(c0, **whole) == treeByPoint(a0, *ref));

  // Simplification on the fly gives the same meshes from either file, from whichever level it starts.
  for (uint64_t n : {uint64_t{1}, uint64_t{1000}, uint64_t{1448}, uint64_t{1900}, uint64_t{2500}, ref->merges}) {
    TetMeshBuilder bc, ba;
    ASSERT_TRUE(streamSimplified(*c, n, bc).isOk()) << n;
    ASSERT_TRUE(streamSimplified(*a, n, ba).isOk()) << n;
    EXPECT_TRUE(canonicalMesh(bc.mesh()) == canonicalMesh(ba.mesh())) << n << " merges";
  }
  // And the validator replays the whole tree against every level.
  auto report = validateGtnFile(chained, ValidateOptions{});
  ASSERT_TRUE(report.isOk()) << report.status().message();
  EXPECT_EQ(report->count(Severity::kError), 0u);
  EXPECT_EQ(report->info()["merge_tree"]["merges"].get<uint64_t>(), ref->merges);
}

// The storage bound counts every level against level 0 stored alone with its whole tree, and leaves
// out the coarsest levels (the new coarsest then stores all its vertices and the rest of the tree).
TEST(GtnChain, TheStorageBoundLeavesOutTheCoarsestLevels) {
  const TetMesh mesh = spx();
  const std::string alone = dir() + "/level0.gtn";
  GtnConvertOptions o;
  o.levels = 0;
  ASSERT_TRUE(writeGtnWithLevels(alone, mesh, o, GtnWriteOptions{}, "spx").isOk());
  const uint64_t unit = open(alone)->file().bytes;
  size_t previous = 0;
  for (const double bound : {1.01, 1.3, 2.0}) {
    SCOPED_TRACE("bound " + std::to_string(bound));
    const std::string path = dir() + "/bounded.gtn";
    GtnConvertOptions b;
    b.level_storage = bound;
    ASSERT_TRUE(writeGtnWithLevels(path, mesh, b, GtnWriteOptions{}, "spx").isOk());
    auto r = open(path);
    ASSERT_TRUE(r);
    uint64_t total = 0;
    for (size_t i = 0; i < r->levels(); ++i) total += r->level(i).bytes;
    // (the writer counts streams and trees, not chunk framing and tables: a few bytes per chunk)
    EXPECT_LE(double(total), bound * double(unit) + 64.0 * r->levels()) << r->levels() << " levels";
    EXPECT_GE(r->levels(), previous);
    previous = r->levels();
    EXPECT_EQ(r->level(r->levels() - 1).base, 0);
    if (bound == 1.01) {
      EXPECT_EQ(r->levels(), 1u);
    } else if (bound == 2.0) {
      EXPECT_EQ(r->levels(), 2u);  // spx: down to 5775 tetrahedra (the next level would have 2992)
    }
    auto report = validateGtnFile(path, ValidateOptions{});
    ASSERT_TRUE(report.isOk());
    EXPECT_EQ(report->count(Severity::kError), 0u) << report->toText(path);
  }
}

// `gtn convert --independent-levels` stores every level whole; by default levels name the next one.
TEST(GtnChain, ConvertNamesTheNextLevelUnlessAskedForIndependentLevels) {
  const std::string spx_path = dataPath("vtk/spx.vtk");
  const std::string def = dir() + "/cli-default.gtn", ind = dir() + "/cli-independent.gtn";
  const RunResult a = runGtn("convert " + spx_path + " -q --levels 3 -o " + def);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const RunResult b = runGtn("convert " + spx_path + " -q --levels 3 --independent-levels -o " + ind);
  ASSERT_EQ(b.exit_code, 0) << b.err;
  auto d = open(def), i = open(ind);
  ASSERT_TRUE(d && i);
  ASSERT_EQ(d->levels(), i->levels());
  ASSERT_GE(d->levels(), 3u);
  for (size_t k = 0; k < d->levels(); ++k) {
    EXPECT_EQ(d->level(k).base, k + 1 < d->levels() ? 1 : 0) << k;
    EXPECT_EQ(i->level(k).base, 0) << k;
  }
  EXPECT_LT(d->file().bytes * 10, i->file().bytes * 7);
  const RunResult info = runGtn("info " + def);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("merge tree, names level 1's vertices"), std::string::npos) << info.out;
  for (const std::string& f : {def, ind}) {
    const RunResult v = runGtn("validate " + f);
    EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  }
}

// Beside a structured level 0, automatic levels keep only the coarse levels that hold, with the
// coarser ones, at most 1/kStructuredLevelShare of level 0's tetrahedra; the finer ratios are read
// from level 0 on the fly. Asked-for levels are all kept. Both files validate.
TEST(GtnChain, BesideAGridLevel0OnlyTheCoarseLevelsAreStored) {
  auto imported = importMesh({dataPath("plot3d/bluntfinxyz.bin"), dataPath("plot3d/bluntfinq.bin")}, ImportOptions{});
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  const TetMesh& mesh = imported->mesh;
  ASSERT_EQ(mesh.blocks.size(), 1u);
  // The levels the simplifier makes, and which of them the rule keeps.
  auto tree = rankMerges(mesh, RankingOptions{}, nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  auto level0 = encodePieces(mesh, EncodeOptions{}, kDefaultPieceTets);
  ASSERT_TRUE(level0.isOk()) << level0.status().message();
  auto stored = storedMergeTree(mesh, *tree, *level0);
  ASSERT_TRUE(stored.isOk()) << stored.status().message();
  EXPECT_FALSE(stored->level0_form.candidates);
  // Its parents are grid places: the block's dims, its nodes being the decoding ids.
  EXPECT_EQ(stored->level0_form.grid,
            (std::array<uint32_t, 3>{mesh.blocks[0].dims[0], mesh.blocks[0].dims[1], mesh.blocks[0].dims[2]}));
  // The share counts every level down to 256 points; of those it keeps, the ones below the floor of
  // automatic levels (LevelOptions::min_tets, a piece's 4096 tetrahedra) are not stored either.
  LevelOptions unfloored;
  unfloored.min_tets = 0;
  auto all = buildMipLevels(mesh, stored->tree, unfloored);
  ASSERT_TRUE(all.isOk()) << all.status().message();
  const size_t count = all->meshes.size();
  ASSERT_GE(count, 6u);
  std::vector<double> kept_ratios;
  uint64_t chain = 0;
  size_t below_floor = 0;
  for (size_t i = count; i-- > 1;) {
    chain += all->meshes[i].numTets();
    if (chain * kStructuredLevelShare > mesh.numTets()) break;
    if (all->meshes[i].numTets() < LevelOptions{}.min_tets) {
      ++below_floor;
      continue;
    }
    kept_ratios.insert(kept_ratios.begin(), all->ratios[i]);
  }
  ASSERT_FALSE(kept_ratios.empty());
  EXPECT_GT(below_floor, 0u);                // blunt fin's two coarsest levels
  ASSERT_LT(kept_ratios.size(), count - 1);  // some finer levels are left out

  const std::string path = dir() + "/grid-auto.gtn";
  ASSERT_TRUE(writeGtnWithLevels(path, mesh, GtnConvertOptions{}, GtnWriteOptions{}, "bluntfin").isOk());
  auto r = open(path);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->level(0).pieces.size(), 1u);
  EXPECT_EQ(r->level(0).pieces[0].kind, kPieceStructured);
  EXPECT_EQ(r->level(0).base, 0);
  ASSERT_EQ(r->levels(), kept_ratios.size() + 1);
  // The grid's whole tree codes its parents as grid places, and so decodes without the level (the
  // finer ratios all read it on the fly); the coarse levels' trees code them as candidates.
  for (size_t k = 0; k < r->levels(); ++k) {
    auto payload = r->mergeTreePayload(k);
    ASSERT_TRUE(payload.isOk() && payload->has_value()) << k;
    auto header = readMergeTreeHeader(**payload, r->level(k).header.points, "grid");
    ASSERT_TRUE(header.isOk()) << header.status().message();
    EXPECT_EQ(header->version, 5) << k;
    EXPECT_EQ(header->candidates, k > 0) << k;
    // Version 5: the candidates' levels leave the removed counts and boundary bits to the decoder,
    // and a level naming the next one codes its children among its own vertices.
    EXPECT_EQ(header->inferred, (k > 0 ? 3 : 0) | (r->level(k).base == 1 ? 4 : 0)) << k;
    EXPECT_EQ(header->needs_next_ids, r->level(k).base == 1) << k;
    EXPECT_EQ(header->needs_mesh, k > 0) << k;
    const std::array<uint32_t, 3> none = {0, 0, 0};
    EXPECT_EQ(header->grid, k == 0 ? stored->level0_form.grid : none) << k;
  }
  uint64_t stored_chain = 0;
  for (size_t k = r->levels(); k-- > 1;) {
    EXPECT_DOUBLE_EQ(r->level(k).ratio, kept_ratios[k - 1]) << k;
    EXPECT_EQ(r->level(k).base, k + 1 < r->levels() ? 1 : 0) << k;
    stored_chain += r->level(k).header.tets;
    EXPECT_LE(stored_chain * kStructuredLevelShare, mesh.numTets()) << k;
  }
  // A ratio between level 0 and the first stored level is read from level 0, and gives the mesh the
  // simplifier's level at that ratio has.
  auto merges = mergesForRatio(*r, 0.5);
  ASSERT_TRUE(merges.isOk()) << merges.status().message();
  TetMeshBuilder half;
  SimplifyPlan plan;
  ASSERT_TRUE(streamSimplified(*r, *merges, half, &plan).isOk());
  EXPECT_EQ(plan.level, 0u);
  EXPECT_EQ(half.mesh().numTets(), all->meshes[1].numTets());
  EXPECT_EQ(half.mesh().numPoints(), all->meshes[1].numPoints());

  GtnConvertOptions asked;
  asked.levels = 3;
  const std::string explicit_path = dir() + "/grid-asked.gtn";
  ASSERT_TRUE(writeGtnWithLevels(explicit_path, mesh, asked, GtnWriteOptions{}, "bluntfin").isOk());
  auto e = open(explicit_path);
  ASSERT_TRUE(e);
  ASSERT_EQ(e->levels(), 4u);
  for (size_t k = 1; k < 4; ++k) EXPECT_DOUBLE_EQ(e->level(k).ratio, all->ratios[k]) << k;
  EXPECT_LT(r->file().bytes, e->file().bytes);
  for (const std::string& f : {path, explicit_path}) {
    auto report = validateGtnFile(f, ValidateOptions{});
    ASSERT_TRUE(report.isOk());
    EXPECT_EQ(report->count(Severity::kError), 0u) << report->toText(f);
  }
}

// At most 63 levels in a row name the next level (spec 12): a reader refuses a longer run at open,
// before decoding anything, so that no decode can be made to walk an unbounded chain.
TEST(GtnChain, ALongerRunOfNamingLevelsIsRefusedAtOpen) {
  const TetMesh cube = gridMesh(3, 3, 3, 5);
  auto one = encodePieces(cube, EncodeOptions{}, kDefaultPieceTets);
  ASSERT_TRUE(one.isOk()) << one.status().message();
  for (const size_t levels : {size_t{64}, size_t{65}}) {
    SCOPED_TRACE(std::to_string(levels) + " levels");
    std::string bytes;
    GtnStreamWriter w(
        [&](std::span<const uint8_t> b) {
          bytes.append(reinterpret_cast<const char*>(b.data()), b.size());
          return Status::ok();
        },
        GtnWriteOptions{});
    ASSERT_TRUE(w.begin(one->header, levels).isOk());
    for (size_t i = 0; i < levels; ++i) {
      PiecedLevel l = *one;
      l.header.level = static_cast<uint32_t>(i);
      l.header.merges = 0;
      l.base = i + 1 < levels ? 1 : 0;  // (the streams do not name anything: the open must refuse first)
      ASSERT_TRUE(w.addLevel(l, 0.0, std::nullopt).isOk()) << i;
    }
    ASSERT_TRUE(w.finish().isOk());
    auto r = GtnReader::openMemory(bytes, "long-run.gtn");
    if (levels == 64) {
      EXPECT_TRUE(r.isOk()) << r.status().message();
    } else {
      ASSERT_FALSE(r.isOk());
      EXPECT_NE(r.status().message().find("long-run.gtn: levels 0 to 63 each name the next level's vertices, "
                                          "more than 63 in a row"),
                std::string::npos)
          << r.status().message();
    }
  }
}

TEST(GtnChain, ACoarseLevelReadsNothingOfTheFinerLevels) {
  const std::string path = write(spx(), "coarse", true);
  auto r = open(path);
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->openedByDirectory());
  const uint64_t before = r->bytesRead();
  TetMesh level2 = decode(*r, 2);
  EXPECT_EQ(level2.numPoints(), r->level(2).header.points);
  const uint64_t read = r->bytesRead() - before;
  EXPECT_LE(read, r->level(2).bytes + r->level(3).bytes);
  EXPECT_GT(read, r->level(3).bytes);  // level 2 reads level 3, whose vertices it names
}

TEST(GtnChain, AMergeTreeShorterThanItsBandIsRefusedNamingTheLevel) {
  const TetMesh mesh = spx();
  auto tree = rankMerges(mesh, RankingOptions{}, nullptr);
  ASSERT_TRUE(tree.isOk());
  LevelOptions lo;
  lo.levels = 2;
  auto built = buildMipLevels(mesh, *tree, lo);
  ASSERT_TRUE(built.isOk());
  std::vector<GtnLevelInput> inputs = built->inputs(mesh);
  // Level 0 stores one merge fewer than it needs down to level 1.
  const uint64_t band = built->merges[1];
  inputs[0].merge_tree_prefix = [&](const std::vector<uint32_t>& order, uint64_t, const std::vector<uint32_t>&) {
    return encodeMergeTree(prefixTree(*tree, band - 1), order, &mesh);
  };
  const std::string path = dir() + "/short.gtn";
  ASSERT_TRUE(writeGtnFile(path, inputs, GtnWriteOptions{}).isOk());
  auto r = open(path);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->level(0).base, 1);
  auto whole = wholeMergeTree(*r, 0);
  ASSERT_FALSE(whole.isOk());
  EXPECT_NE(whole.status().message().find(path + ", level 0: its merge tree holds " + std::to_string(band - 1) +
                                          " merges, " + std::to_string(band) + " are needed down to level 1"),
            std::string::npos)
      << whole.status().message();
  auto report = validateGtnFile(path, ValidateOptions{});
  ASSERT_TRUE(report.isOk());
  EXPECT_GT(report->count(Severity::kError), 0u);
  // The levels themselves still decode.
  EXPECT_EQ(decode(*r, 0).numTets(), mesh.numTets());
}

TEST(GtnChain, DamageInALevelReachesTheFinerLevelsThatNameItsVertices) {
  const std::string path = write(spx(), "damaged", true);
  std::string bytes = readFile(path);
  size_t geom = 0;
  {
    auto r = open(path);
    ASSERT_TRUE(r);
    for (const GtnChunkInfo& c : r->level(2).chunks)
      if (c.tag == kTagPiece) geom = c.offset;
  }
  ASSERT_GT(geom, 0u);
  bytes[geom + 40] ^= 0x10;
  const std::string damaged = dir() + "/damaged-geom.gtn";
  writeFile(damaged, bytes);
  auto r = open(damaged);
  ASSERT_TRUE(r);
  TetMeshBuilder b;
  EXPECT_TRUE(r->decodeLevel(3, b).isOk());  // coarser than the damage
  for (size_t i : {size_t{0}, size_t{1}, size_t{2}}) {
    TetMeshBuilder bi;
    const Status st = r->decodeLevel(i, bi);
    ASSERT_FALSE(st.isOk()) << "level " << i;
    EXPECT_NE(st.message().find("checksum"), std::string::npos) << st.message();
  }
}

// The writer checks each level as soon as it is final, while others are still being encoded (a grid
// level 0 right after its encoding): a failing check stops the write all the same, the first failure
// in level order is the one returned, nothing is written, and every level is checked once, or again
// after the storage bound has made the writer encode levels anew.
TEST(GtnChain, ALevelsCheckStopsTheWriteWhenItRunsBesideTheEncoding) {
  struct Case {
    std::string name;
    TetMesh mesh;
  };
  std::vector<Case> cases;
  cases.push_back({"spx", spx()});
  auto fin = importMesh({dataPath("plot3d/bluntfinxyz.bin"), dataPath("plot3d/bluntfinq.bin")}, ImportOptions{});
  ASSERT_TRUE(fin.isOk()) << fin.status().message();
  cases.push_back({"blunt fin", std::move(fin->mesh)});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    auto tree = rankMerges(c.mesh, RankingOptions{}, nullptr);
    ASSERT_TRUE(tree.isOk()) << tree.status().message();
    auto level0 = encodePieces(c.mesh, EncodeOptions{}, kDefaultPieceTets);
    ASSERT_TRUE(level0.isOk()) << level0.status().message();
    auto stored = storedMergeTree(c.mesh, *tree, *level0);
    ASSERT_TRUE(stored.isOk()) << stored.status().message();
    LevelOptions lo;
    lo.levels = 3;
    auto levels = buildMipLevels(c.mesh, stored->tree, lo);
    ASSERT_TRUE(levels.isOk()) << levels.status().message();
    ASSERT_EQ(levels->meshes.size(), 4u);
    const std::string path = dir() + "/checked.gtn";
    // Level 0 given encoded (as a convert gives it): a grid's is checked from the start, beside the
    // encoding of its merge tree.
    for (const bool given : {false, true})
      for (const double bound : {0.0, 1.3}) {
        for (const std::vector<size_t>& failing : std::vector<std::vector<size_t>>{{}, {0}, {1}, {3}, {2, 1}}) {
          if (given && (!level0->isGrid() || failing.size() > 1)) continue;
          std::string which;
          for (size_t i : failing) which += " " + std::to_string(i);
          SCOPED_TRACE("bound " + std::to_string(bound) + ", failing levels" + which +
                       (given ? ", level 0 given" : ""));
          std::filesystem::remove(path);
          std::vector<GtnLevelInput> inputs = levels->inputs(c.mesh, stored->level0_form);
          if (given) inputs[0].encoded = std::make_shared<PiecedLevel>(*level0);
          std::vector<std::atomic<int>> checked(inputs.size());
          for (size_t i = 0; i < inputs.size(); ++i)
            inputs[i].check_mesh = [&, i](const TetMesh&) {
              ++checked[i];
              const bool fails = std::find(failing.begin(), failing.end(), i) != failing.end();
              return fails ? invalidData("level " + std::to_string(i) + " refused by the test") : Status::ok();
            };
          GtnWriteOptions wo;
          wo.level_storage_limit = bound;
          const Status st = writeGtnFile(path, inputs, wo);
          if (failing.empty()) {
            ASSERT_TRUE(st.isOk()) << st.message();
            auto r = open(path);
            ASSERT_TRUE(r);
            for (size_t i = 0; i < r->levels(); ++i) EXPECT_GE(checked[i].load(), 1) << "level " << i;
            if (bound == 0.0) {
              ASSERT_EQ(r->levels(), inputs.size());
              for (size_t i = 0; i < inputs.size(); ++i) EXPECT_EQ(checked[i].load(), 1) << "level " << i;
            }
            continue;
          }
          const size_t first = *std::min_element(failing.begin(), failing.end());
          if (bound > 0.0 && st.isOk()) {
            // The bound left the failing levels out of the file: the kept ones passed.
            auto r = open(path);
            ASSERT_TRUE(r);
            EXPECT_LE(r->levels(), first);
            continue;
          }
          ASSERT_FALSE(st.isOk());
          EXPECT_EQ(st.message(), "level " + std::to_string(first) + " refused by the test");
          EXPECT_FALSE(std::filesystem::exists(path));
        }
      }
  }
}

}  // namespace
}  // namespace gtn::test
