// --budget-ms below what a file allows, and the render cache: where it is, and --no-cache.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "convert/export.h"
#include "flat_mesh.h"
#include "render/image.h"
#include "test_util.h"

namespace gtn {
namespace {

// A torus of 5184 vertices with levels of 1/2, 1/4 and 1/8 of them.
std::string torusGtn(const std::string& dir) {
  const std::string vtk = dir + "/torus.vtk", gtn = dir + "/torus.gtn";
  EXPECT_TRUE(exportVtkLegacy(test::makeFlatTorus(7, false, 64, 8, 8).mesh, vtk).isOk());
  const test::RunResult r = test::runGtn("convert " + vtk + " -o " + gtn + " --levels 3");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return gtn;
}

// Pixels that are not black.
std::vector<bool> litPixels(const std::string& png) {
  auto image = readPng(png);
  EXPECT_TRUE(image.isOk()) << png;
  std::vector<bool> lit;
  if (!image.isOk()) return lit;
  for (size_t i = 0; i < image->rgb.size(); i += 3)
    lit.push_back(image->rgb[i] || image->rgb[i + 1] || image->rgb[i + 2]);
  return lit;
}

// A budget that no plan meets: said on standard error without -v, and the image is the floor, which
// still shows the mesh (it was one tetrahedron), both pipelines.
TEST(RenderBudget, ABudgetNothingMeetsIsSaidAndTheImageStillShowsTheMesh) {
  const std::string dir = test::tempDir("render-budget-floor");
  const std::string gtn = torusGtn(dir);
  const std::string env = "XDG_CACHE_HOME=" + dir + "/cache ";
  ASSERT_EQ(test::runGtn("render " + gtn + " -o " + dir + "/full.png --size 96x96").exit_code, 0);
  const std::vector<bool> full = litPixels(dir + "/full.png");
  const size_t full_lit = static_cast<size_t>(std::count(full.begin(), full.end(), true));
  ASSERT_GT(full_lit, 2000u);
  const nlohmann::json info = nlohmann::json::parse(test::runGtn("info --json " + gtn).out);
  ASSERT_EQ(info["levels"].size(), 4u);
  for (const std::string pipeline : {"integrated", "generic"}) {
    SCOPED_TRACE(pipeline);
    for (int run = 0; run < 2; ++run) {  // calibrating, then from the cache
      const test::RunResult r =
          test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                         "/floor.png --size 96x96 --json --budget-ms 0.001 --pipeline " + pipeline);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_NE(r.err.find(gtn + ": --budget-ms 0.001 cannot be met: the cheapest plan"), std::string::npos) << r.err;
      const nlohmann::json j = nlohmann::json::parse(r.out);
      EXPECT_EQ(j["budget_met"], false);
      EXPECT_EQ(j["level"].get<size_t>(), info["levels"].size() - 1) << j.dump();
      const std::vector<bool> floor = litPixels(dir + "/floor.png");
      size_t both = 0;
      for (size_t i = 0; i < full.size() && i < floor.size(); ++i) both += full[i] && floor[i];
      EXPECT_GT(both, full_lit * 8 / 10) << j.dump();
    }
    // A budget that is met says nothing of the kind.
    const test::RunResult ok = test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                                              "/ok.png --size 96x96 --json --budget-ms 100000 --pipeline " + pipeline);
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(ok.err.find("cannot be met"), std::string::npos) << ok.err;
    EXPECT_EQ(nlohmann::json::parse(ok.out)["budget_met"], true);
  }
}

// The cache lives under $XDG_CACHE_HOME/gatun, else (unset, empty, or relative: the XDG
// specification) under $HOME/.cache/gatun.
TEST(RenderBudget, TheCacheHonoursXdgCacheHome) {
  const std::string dir = test::tempDir("render-budget-xdg");
  const std::string gtn = torusGtn(dir);
  const std::string file = "/gatun/render-calibration.json";
  const std::string render =
      std::string(GTN_BINARY) + " render " + gtn + " -o " + dir + "/x.png --size 32x32 --budget-ms 100000";
  ASSERT_EQ(test::runShell("HOME=" + dir + "/home XDG_CACHE_HOME=" + dir + "/xdg " + render).exit_code, 0);
  EXPECT_TRUE(test::fileExists(dir + "/xdg" + file));
  EXPECT_FALSE(test::fileExists(dir + "/home/.cache" + file));
  ASSERT_EQ(test::runShell("cd " + dir + " && HOME=" + dir + "/home XDG_CACHE_HOME=relative " + render).exit_code, 0);
  EXPECT_FALSE(test::fileExists(dir + "/relative" + file));
  EXPECT_TRUE(test::fileExists(dir + "/home/.cache" + file));
  ASSERT_EQ(test::runShell("unset XDG_CACHE_HOME; HOME=" + dir + "/home2 " + render).exit_code, 0);
  EXPECT_TRUE(test::fileExists(dir + "/home2/.cache" + file));
}

// Without HOME and XDG_CACHE_HOME, and with a TMPDIR that names no folder, a budgeted render still
// runs (it aborted on an uncaught filesystem exception while looking for the cache's place).
TEST(RenderBudget, NoHomeAndABadTmpdirStillRender) {
  const std::string dir = test::tempDir("render-budget-no-home");
  const std::string gtn = torusGtn(dir);
  const test::RunResult r =
      test::runShell("unset HOME XDG_CACHE_HOME; TMPDIR=" + dir + "/missing " GTN_BINARY " render " + gtn + " -o " +
                     dir + "/x.png --size 32x32 --budget-ms 100000 --no-cache");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::fileExists(dir + "/x.png"));
}

// --no-cache neither reads nor writes the cache: budgets calibrate every time, colour ranges are
// read from level 0 again, and a cache already there is left as it is.
TEST(RenderBudget, NoCacheSkipsTheCache) {
  const std::string dir = test::tempDir("render-budget-nocache");
  const std::string gtn = torusGtn(dir);
  const std::string env = "HOME=" + dir + "/home XDG_CACHE_HOME=" + dir + "/xdg ";
  const std::string render = env + GTN_BINARY " render " + gtn + " -o " + dir + "/x.png --size 32x32 ";
  const test::RunResult a = test::runShell(render + "--budget-ms 100000 -v --no-cache");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.err.find("calibrated on levels"), std::string::npos) << a.err;
  EXPECT_NE(a.err.find("not cached (--no-cache)"), std::string::npos) << a.err;
  ASSERT_EQ(test::runShell(render + "--level 2 --no-cache").exit_code, 0);
  EXPECT_FALSE(test::fileExists(dir + "/xdg/gatun"));
  EXPECT_FALSE(test::fileExists(dir + "/home/.cache"));
  // With a cache there: a run without --no-cache reads it, one with it calibrates and leaves it be.
  ASSERT_EQ(test::runShell(render + "--budget-ms 100000").exit_code, 0);
  const std::string cache = dir + "/xdg/gatun/render-calibration.json";
  ASSERT_TRUE(test::fileExists(cache));
  const test::RunResult b = test::runShell(render + "--budget-ms 100000 -v");
  EXPECT_NE(b.err.find("calibration read from " + cache), std::string::npos) << b.err;
  const std::string before = test::readFile(cache);
  const test::RunResult c = test::runShell(render + "--budget-ms 100000 -v --no-cache");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(c.err.find("read from"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("not cached (--no-cache)"), std::string::npos) << c.err;
  ASSERT_EQ(test::runShell(render + "--level 2 --no-cache").exit_code, 0);
  EXPECT_EQ(test::readFile(cache), before);
}

}  // namespace
}  // namespace gtn
