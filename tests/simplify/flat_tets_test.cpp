// Simplification of meshes with zero-volume tetrahedra on and near the boundary: every mip level the
// converter makes is a valid mesh (the validator's mesh checks find no error), in memory and through
// `gtn convert` and `gtn validate`.
#include <gtest/gtest.h>

#include <thread>

#include <nlohmann/json.hpp>

#include "convert/export.h"
#include "flat_tets_util.h"
#include "mesh/predicates.h"
#include "simplify/apply.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "test_util.h"
#include "validate/mesh_checks.h"

namespace gtn::test {
namespace {

std::string errorsOf(const ValidationReport& report) {
  std::string out;
  for (const ReportedIssue& i : report.issues())
    if (issueInfo(i.code).severity == Severity::kError)
      out += std::string(issueInfo(i.code).code) + ": " + i.message() + "\n";
  return out;
}

TEST(FlatTets, GeneratorMakesFlatTetsOnAndNearTheBoundary) {
  for (FlatShape shape : {FlatShape::kBox, FlatShape::kRing, FlatShape::kEll}) {
    size_t flat = 0;
    const TetMesh m = makeFlatTetMesh(shape, 6, 1, &flat);
    SCOPED_TRACE(flatShapeName(shape));
    EXPECT_GT(flat, 20u);
    ValidationReport report;
    MeshCheckStats st;
    checkMesh(m, "/mesh", report, &st);
    EXPECT_FALSE(report.hasErrors()) << errorsOf(report);
    EXPECT_EQ(st.zero_volume, flat);
    EXPECT_EQ(st.inverted, 0u);
  }
}

// Every prefix of the ranking's tree (each one a mesh a reader may ask for, the stored levels among
// them) passes the validator's mesh checks; `min_share`: the merges the tree must hold, as a share of
// the points.
void expectEveryPrefixValid(const TetMesh& m, double min_share) {
  auto tree = rankMerges(m, RankingOptions{}, nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  EXPECT_GT(static_cast<double>(tree->merges), min_share * static_cast<double>(m.numPoints()));
  for (uint64_t n = 1; n <= tree->merges; n += std::max<uint64_t>(1, tree->merges / 40)) {
    auto level = applyMerges(m, *tree, n);
    ASSERT_TRUE(level.isOk()) << level.status().message();
    ValidationReport report;
    checkMesh(*level, "/levels/x", report);
    ASSERT_FALSE(report.hasErrors()) << n << " merges:\n" << errorsOf(report);
  }
}

// Flat tetrahedra listed against their neighbours' orientation: the faces they share are left as they
// are (the ranking merges none of their vertices away), and nothing next to them overlaps.
TEST(FlatTets, EveryLevelIsValidWhateverTheFlatTetsOrientation) {
  for (FlatShape shape : {FlatShape::kBox, FlatShape::kRing, FlatShape::kEll}) {
    for (uint32_t seed : {1u, 2u, 3u, 4u}) {
      SCOPED_TRACE(std::string(flatShapeName(shape)) + " seed " + std::to_string(seed));
      expectEveryPrefixValid(makeFlatTetMesh(shape, 7, seed), 0.05);
    }
  }
}

// As the importers leave them: flat tetrahedra oriented as their neighbours (orientFlatTets), which
// then simplify like the rest.
TEST(FlatTets, EveryLevelIsValidOnceFlatTetsAreOriented) {
  for (FlatShape shape : {FlatShape::kBox, FlatShape::kRing, FlatShape::kEll}) {
    for (uint32_t seed : {1u, 2u, 3u, 4u}) {
      SCOPED_TRACE(std::string(flatShapeName(shape)) + " seed " + std::to_string(seed));
      TetMesh m = makeFlatTetMesh(shape, 7, seed);
      EXPECT_GT(orientFlatTets(m), 0u);
      EXPECT_EQ(orientFlatTets(m), 0u) << "oriented once and for all";
      expectEveryPrefixValid(m, 0.4);
    }
  }
}

// The structural check convert runs: a mip level with an error level 0 does not have fails, naming the
// level and the error and saying it is a bug; errors level 0 already has are the source's.
TEST(FlatTets, LevelStructureCheckCatchesOverlaps) {
  const TetMesh good = makeFlatTetMesh(FlatShape::kBox, 4, 1);
  EXPECT_TRUE(checkLevelStructure({&good, &good}, "x.gtn").isOk());
  // Two positive tetrahedra on the same side of their common face: boundary edges used in one
  // direction only.
  TetMesh bad;
  bad.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.2, 0.2, 0.4};
  bad.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
  ASSERT_GT(orient3d(bad.point(0), bad.point(1), bad.point(2), bad.point(4)), 0);
  const Status st = checkLevelStructure({&good, &good, &bad}, "x.gtn");
  ASSERT_FALSE(st.isOk());
  EXPECT_EQ(st.code(), StatusCode::kInvalidData);
  EXPECT_NE(st.message().find("x.gtn: mip level 2 is not a valid mesh"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("BOUNDARY_ORIENTATION"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("bug"), std::string::npos) << st.message();
  EXPECT_TRUE(checkLevelStructure({&bad, &bad}, "x.gtn").isOk()) << "the source's own errors";
}

// Convert finds level 0's own errors while the merges are ranked (checkLevel0, on another thread):
// they are still excused in every mip level, and a new error still fails.
TEST(FlatTets, LevelZeroCheckedAheadExcusesItsOwnErrors) {
  const TetMesh good = makeFlatTetMesh(FlatShape::kBox, 4, 1);
  TetMesh bad;
  bad.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.2, 0.2, 0.4};
  bad.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
  LevelStructureCheck from_bad(bad, "x.gtn");
  std::thread ahead([&] { from_bad.checkLevel0(); });
  ahead.join();
  from_bad.checkLevel0();  // once only
  EXPECT_TRUE(from_bad.check(bad, 1).isOk());
  LevelStructureCheck from_good(good, "x.gtn");
  from_good.checkLevel0();
  EXPECT_TRUE(from_good.check(good, 1).isOk());
  const Status st = from_good.check(bad, 2);
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("mip level 2 is not a valid mesh"), std::string::npos) << st.message();
}

// Through the CLI: a legacy VTK file of each shape, flat tetrahedra listed with either orientation,
// converted with levels; `gtn validate` finds every level valid.
TEST(FlatTets, ConvertedFilesValidate) {
  const std::string dir = tempDir("flat-tets");
  for (FlatShape shape : {FlatShape::kBox, FlatShape::kRing, FlatShape::kEll}) {
    for (uint32_t seed : {5u, 6u}) {
      const std::string name = dir + "/" + flatShapeName(shape) + std::to_string(seed);
      SCOPED_TRACE(name);
      ASSERT_TRUE(exportMesh(makeFlatTetMesh(shape, 8, seed), name + ".vtk", ExportOptions{}).isOk());
      const RunResult c = runGtn("convert " + name + ".vtk -o " + name + ".gtn --levels 3");
      ASSERT_EQ(c.exit_code, 0) << c.err;
      const RunResult v = runGtn("validate " + name + ".gtn --json");
      EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
      const nlohmann::json j = nlohmann::json::parse(v.out, nullptr, false);
      ASSERT_TRUE(j.is_object()) << v.out;
      EXPECT_TRUE(j["valid"].get<bool>()) << v.out;
      const RunResult info = runGtn("info " + name + ".gtn --json");
      ASSERT_EQ(info.exit_code, 0) << info.err;
      EXPECT_GE(nlohmann::json::parse(info.out)["levels"].size(), 3u);
    }
  }
}

}  // namespace
}  // namespace gtn::test
