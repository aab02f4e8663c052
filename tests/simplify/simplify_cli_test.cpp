// gtn convert --levels / --no-merge-tree, gtn export --level / --ratio / --merges and
// gtn info --merge-tree, through the built binary on spx.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_util.h"

namespace gtn::test {
namespace {

class SimplifyCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = tempDir("simplify-cli");
    const RunResult r = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ + "/spx.gtn");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const RunResult l0 =
        runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ + "/l0.gtn --levels 0 --no-merge-tree");
    ASSERT_EQ(l0.exit_code, 0) << l0.err;
  }
  static nlohmann::json info(const std::string& args) {
    const RunResult r = runGtn("info " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
  }
  static std::string dir_;
};
std::string SimplifyCli::dir_;

TEST_F(SimplifyCli, ConvertStoresLevelsAndTrees) {
  const nlohmann::json j = info(dir_ + "/spx.gtn --merge-tree");
  ASSERT_TRUE(j.contains("merge_tree") && j["merge_tree"].is_object());
  const nlohmann::json& mt = j["merge_tree"];
  EXPECT_GT(mt["merges"].get<uint64_t>(), 2800u);
  EXPECT_EQ(mt["merges"].get<uint64_t>() + mt["roots"].get<uint64_t>(), 2896u);
  EXPECT_GT(mt["boundary_merges"].get<uint64_t>(), 0u);
  EXPECT_GE(mt["depth"]["max"].get<double>(), mt["depth"]["mean"].get<double>());
  EXPECT_GE(mt["fanout"]["max"].get<double>(), mt["fanout"]["mean"].get<double>());
  EXPECT_LE(mt["error_quantiles"]["p50"].get<double>(), mt["error_quantiles"]["max"].get<double>());
  EXPECT_EQ(mt["field"], "scalars");
  // Automatic levels stop before a level of fewer than 4096 tetrahedra (the smallest piece): spx's
  // level 1 has 1448 points and 5775 tetrahedra, its level 2 would have 724 and 2992 (read on the fly:
  // ExportSimplifiesOnTheFly, --ratio 0.75).
  ASSERT_EQ(j["levels"].size(), 2u);
  EXPECT_EQ(j["levels"][1]["points"], 1448);
  EXPECT_EQ(j["levels"][1]["tets"], 5775);
  EXPECT_DOUBLE_EQ(j["levels"][1]["ratio"].get<double>(), 0.5);
  for (const auto& l : j["levels"]) EXPECT_TRUE(l["merge_tree"].get<bool>());
}

TEST_F(SimplifyCli, ConvertOptionsTurnLevelsOff) {
  nlohmann::json j = info(dir_ + "/l0.gtn --merge-tree");
  EXPECT_EQ(j["levels"].size(), 1u);
  EXPECT_TRUE(j["merge_tree"].is_null());
  ASSERT_EQ(runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ +
                   "/l2.gtn --levels 2 --simplify-field none "
                   "--w-density 2 --w-geometry 0.5")
                .exit_code,
            0);
  j = info(dir_ + "/l2.gtn --merge-tree");
  EXPECT_EQ(j["levels"].size(), 3u);
  EXPECT_EQ(j["merge_tree"]["field"], "");
  EXPECT_EQ(j["merge_tree"]["w_density"], 2.0);
  const RunResult bad = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ + "/bad.gtn --simplify-field nope");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("scalars"), std::string::npos) << bad.err;
  EXPECT_FALSE(fileExists(dir_ + "/bad.gtn"));
}

// Mip levels are checked against the merge tree they come from: without a tree, convert stores level 0
// alone (a file the validator accepts), and refuses levels asked for.
TEST_F(SimplifyCli, NoMergeTreeStoresLevelZeroAloneAndRefusesLevels) {
  const std::string flat = dir_ + "/no-tree.gtn";
  const RunResult r = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + flat + " --no-merge-tree");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = info(flat + " --merge-tree");
  EXPECT_EQ(j["levels"].size(), 1u);
  EXPECT_TRUE(j["merge_tree"].is_null());
  const RunResult v = runGtn("validate " + flat);
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  const std::string asked = dir_ + "/no-tree-levels.gtn";
  const RunResult bad = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + asked + " --no-merge-tree --levels 2");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("2 mip level(s) asked for with no merge tree"), std::string::npos) << bad.err;
  EXPECT_FALSE(fileExists(asked));
}

// --greedy-ranking ranks in the greedy order: another tree than the default lazy one, in a file that
// validates, and the same file again when run again.
TEST_F(SimplifyCli, GreedyRankingGivesTheGreedyTree) {
  const std::string a = dir_ + "/greedy-a.gtn", b = dir_ + "/greedy-b.gtn";
  for (const std::string& out : {a, b}) {
    const RunResult r = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + out + " --greedy-ranking");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(runGtn("validate " + a).exit_code, 0);
  const nlohmann::json greedy = info(a + " --merge-tree"), lazy = info(dir_ + "/spx.gtn --merge-tree");
  ASSERT_TRUE(greedy.contains("merge_tree") && lazy.contains("merge_tree"));
  EXPECT_NE(greedy["merge_tree"]["error_quantiles"], lazy["merge_tree"]["error_quantiles"]);
  EXPECT_EQ(greedy["merge_tree"]["merges"].get<uint64_t>() + greedy["merge_tree"]["roots"].get<uint64_t>(), 2896u);
  const nlohmann::json again = info(b + " --merge-tree");
  EXPECT_EQ(again["merge_tree"], greedy["merge_tree"]);
}

TEST_F(SimplifyCli, ExportSimplifiesOnTheFly) {
  const std::string in = dir_ + "/spx.gtn";
  struct Case {
    std::string args;
    uint64_t points;
  } cases[] = {{"--level 1", 1448}, {"--ratio 0.8", 2896 - 2317}, {"--merges 100", 2796}, {"--ratio 0.75", 724}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const std::string out = dir_ + "/out.vtu";
    const RunResult r = runGtn("export " + in + " -o " + out + " " + c.args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = info(out);
    EXPECT_EQ(j["points"].get<uint64_t>(), c.points);
    EXPECT_EQ(j["inverted"], 0);
    EXPECT_EQ(j["zero_volume"], 0);
    EXPECT_EQ(j["non_manifold_faces"], 0);
  }
  EXPECT_EQ(runGtn("export " + in + " -o " + dir_ + "/x.vtu --level 1 --ratio 0.5").exit_code, 2);
  EXPECT_EQ(runGtn("export " + in + " -o " + dir_ + "/x.vtu --merges 999999").exit_code, 2);
  const RunResult no_tree = runGtn("export " + dir_ + "/l0.gtn -o " + dir_ + "/x.vtu --ratio 0.5");
  EXPECT_EQ(no_tree.exit_code, 2);
  EXPECT_NE(no_tree.err.find("no merge tree"), std::string::npos) << no_tree.err;
}

}  // namespace
}  // namespace gtn::test
