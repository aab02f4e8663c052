// The render and compare subcommands, end to end on real datasets.
#include <gtest/gtest.h>

#include <cmath>

#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "format/gtn_file.h"
#include "render/image.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::runGtn;

nlohmann::json compareJson(const std::string& a, const std::string& b) {
  const test::RunResult r = runGtn("compare " + a + " " + b + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out, nullptr, false);
}

TEST(CompareCommand, KnownImages) {
  const std::string dir = test::tempDir("compare");
  Image a(4, 2), b(4, 2);
  // Column 0: background in both (ignored). Pixel (1, 0): differs by 10 in one channel. Pixel (2, 0):
  // lit only in b (counted). Others equal and lit.
  for (int x = 1; x < 4; ++x)
    for (int y = 0; y < 2; ++y)
      for (int c = 0; c < 3; ++c) a.pixel(x, y)[c] = b.pixel(x, y)[c] = 100;
  a.pixel(1, 0)[1] = 110;
  a.pixel(2, 0)[0] = a.pixel(2, 0)[1] = a.pixel(2, 0)[2] = 0;
  b.pixel(2, 0)[0] = 30;
  b.pixel(2, 0)[1] = b.pixel(2, 0)[2] = 0;
  ASSERT_TRUE(writePng(dir + "/a.png", a).isOk());
  ASSERT_TRUE(writePng(dir + "/b.png", b).isOk());
  const nlohmann::json j = compareJson(dir + "/a.png", dir + "/b.png");
  // 6 pixels compared (18 channel values), squared differences 100 + 900.
  EXPECT_EQ(j["pixels_compared"], 6);
  EXPECT_NEAR(j["rmse"].get<double>(), std::sqrt(1000.0 / 18.0), 1e-9);
  EXPECT_NEAR(j["psnr"].get<double>(), 20 * std::log10(255.0 / std::sqrt(1000.0 / 18.0)), 1e-9);
  EXPECT_EQ(j["max_difference"], 30);
  const nlohmann::json same = compareJson(dir + "/a.png", dir + "/a.png");
  EXPECT_EQ(same["rmse"], 0.0);
  EXPECT_TRUE(same["psnr"].is_null());
  // Different sizes: a usage error; not a PNG: invalid data.
  ASSERT_TRUE(writePng(dir + "/c.png", Image(3, 3)).isOk());
  EXPECT_EQ(runGtn("compare " + dir + "/a.png " + dir + "/c.png").exit_code, 2);
  test::writeFile(dir + "/not.png", "hello");
  EXPECT_EQ(runGtn("compare " + dir + "/a.png " + dir + "/not.png").exit_code, 1);
  EXPECT_EQ(runGtn("compare " + dir + "/a.png " + dir + "/missing.png").exit_code, 3);
}

TEST(RenderCommand, IntegratedMatchesGenericOnSpx) {
  const std::string dir = test::tempDir("render-spx");
  const std::string spx = test::dataPath("vtk/spx.vtk");
  for (const std::string sampling : {"volume", "face"}) {
    const std::string common = " --size 64x64 --sampling " + sampling;
    const test::RunResult a = runGtn("render " + spx + " -o " + dir + "/i.png --json" + common);
    ASSERT_EQ(a.exit_code, 0) << a.err;
    const nlohmann::json ra = nlohmann::json::parse(a.out);
    EXPECT_EQ(ra["tets_rendered"], 12936);
    EXPECT_LT(ra["peak_tets_held"].get<uint64_t>(), 12936u / 4);
    const test::RunResult b = runGtn("render " + spx + " -o " + dir + "/g.png --pipeline generic" + common);
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const nlohmann::json j = compareJson(dir + "/i.png", dir + "/g.png");
    EXPECT_GT(j["pixels_compared"].get<int>(), 500);
    EXPECT_LE(j["max_difference"].get<int>(), 1);
  }
}

TEST(RenderCommand, RejectsBadArguments) {
  const std::string dir = test::tempDir("render-bad");
  const std::string spx = test::dataPath("vtk/spx.vtk");
  EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png --size 0x10").exit_code, 2);
  EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png --field nosuch").exit_code, 2);
  EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png --transfer rainbow").exit_code, 2);
  EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png --level 0 --ratio 0.5").exit_code, 2);
  EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png --ratio 0.5").exit_code, 2);  // no merge tree
  EXPECT_EQ(runGtn("render " + dir + "/missing.vtk -o " + dir + "/x.png").exit_code, 3);
  EXPECT_FALSE(test::fileExists(dir + "/x.png"));
}

// spx as a .gtn file with mip levels and merge trees, made with the library (as `gtn convert` does).
std::string makeSpxGtn(const std::string& dir) {
  auto imported = importMesh({test::dataPath("vtk/spx.vtk")}, ImportOptions());
  EXPECT_TRUE(imported.isOk());
  const TetMesh& mesh = imported->mesh;
  RankingStats rstats;
  auto tree = rankMerges(mesh, RankingOptions(), &rstats);
  EXPECT_TRUE(tree.isOk()) << tree.status().message();
  LevelOptions lopt;
  lopt.levels = 3;
  auto levels = buildMipLevels(mesh, tree.value(), lopt);
  EXPECT_TRUE(levels.isOk()) << levels.status().message();
  const std::string path = dir + "/spx.gtn";
  const Status st = writeGtnFile(path, levels->inputs(mesh), GtnWriteOptions());
  EXPECT_TRUE(st.isOk()) << st.message();
  return path;
}

TEST(RenderCommand, SimplifiedViewsOfAGtnFile) {
  const std::string dir = test::tempDir("render-gtn");
  const std::string gtn = makeSpxGtn(dir);
  const std::string spx = test::dataPath("vtk/spx.vtk");
  const std::string common = " --size 64x64 --json";
  auto render = [&](const std::string& in, const std::string& out, const std::string& extra) {
    const test::RunResult r = runGtn("render " + in + " -o " + dir + "/" + out + common + " " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
  };
  // Level 0 of the file is spx itself: the same image as rendering the .vtk.
  const nlohmann::json full = render(gtn, "l0.png", "");
  render(spx, "vtk.png", "");
  EXPECT_LE(compareJson(dir + "/l0.png", dir + "/vtk.png")["max_difference"].get<int>(), 1);
  EXPECT_EQ(full["tets_rendered"], 12936);
  // A ratio between levels 1 (0.5) and 2 (0.75): level 1 plus merges on the fly.
  const nlohmann::json r = render(gtn, "r.png", "--ratio 0.6");
  EXPECT_EQ(r["level"], 1);
  EXPECT_GT(r["extra_merges"].get<uint64_t>(), 0u);
  EXPECT_NEAR(r["ratio"].get<double>(), 0.6, 0.001);
  EXPECT_LT(r["tets_rendered"].get<uint64_t>(), r["tets_decoded"].get<uint64_t>());
  // The same view through the generic pipeline: the same image.
  render(gtn, "rg.png", "--ratio 0.6 --pipeline generic");
  EXPECT_LE(compareJson(dir + "/r.png", dir + "/rg.png")["max_difference"].get<int>(), 1);
  // Simplification degrades the image gracefully: close to the original, not identical.
  const nlohmann::json d = compareJson(dir + "/l0.png", dir + "/r.png");
  EXPECT_GT(d["rmse"].get<double>(), 0.0);
  EXPECT_LT(d["rmse"].get<double>(), 25.0);
  const nlohmann::json l2 = render(gtn, "l2.png", "--level 2");
  EXPECT_EQ(l2["level"], 2);
  EXPECT_EQ(l2["extra_merges"], 0);
  EXPECT_EQ(render(gtn, "m.png", "--merges 100")["extra_merges"], 100);
  EXPECT_EQ(runGtn("render " + gtn + " -o " + dir + "/x.png --level 9").exit_code, 2);
  // A time budget: calibrates once (cached under XDG_CACHE_HOME), then reads the cache.
  const std::string env = "XDG_CACHE_HOME=" + dir + "/cache ";
  const test::RunResult b1 = test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                                            "/b.png --size 64x64 --budget-ms 100000 --json -v");
  ASSERT_EQ(b1.exit_code, 0) << b1.err;
  EXPECT_NE(b1.err.find("calibrated"), std::string::npos) << b1.err;
  EXPECT_EQ(nlohmann::json::parse(b1.out)["level"], 0);  // a generous budget: the full mesh
  EXPECT_TRUE(test::fileExists(dir + "/cache/gatun/render-calibration.json"));
  const test::RunResult b2 = test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                                            "/b.png --size 64x64 --budget-ms 0.001 --json -v");
  ASSERT_EQ(b2.exit_code, 0) << b2.err;
  EXPECT_NE(b2.err.find("read from"), std::string::npos) << b2.err;
  EXPECT_EQ(nlohmann::json::parse(b2.out)["level"], 3);  // an impossible budget: the coarsest level
}

}  // namespace
}  // namespace gtn
