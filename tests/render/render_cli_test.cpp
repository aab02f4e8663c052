// The render and compare subcommands, end to end on real datasets.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "format/gtn_file.h"
#include "render/image.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::compareJson;
using test::runGtn;

// A w x h RGBA PNG (colour type 6), every pixel `rgba`, written with zlib directly (writePng writes RGB).
void writeRgbaPng(const std::string& path, int w, int h, const uint8_t rgba[4]) {
  std::string raw;
  for (int y = 0; y < h; ++y) {
    raw += '\0';
    for (int x = 0; x < w; ++x) raw.append(reinterpret_cast<const char*>(rgba), 4);
  }
  std::vector<uint8_t> z(compressBound(raw.size()));
  uLongf zn = z.size();
  ASSERT_EQ(compress(z.data(), &zn, reinterpret_cast<const Bytef*>(raw.data()), raw.size()), Z_OK);
  auto be32 = [](std::string& s, uint32_t v) {
    for (int i = 3; i >= 0; --i) s += static_cast<char>((v >> (8 * i)) & 0xFF);
  };
  std::string png = "\x89PNG\r\n\x1a\n";
  auto chunk = [&](const char* type, const std::string& data) {
    be32(png, static_cast<uint32_t>(data.size()));
    const std::string body = type + data;
    png += body;
    be32(png, static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size())));
  };
  std::string ihdr;
  be32(ihdr, w), be32(ihdr, h);
  ihdr += std::string("\x08\x06\x00\x00\x00", 5);
  chunk("IHDR", ihdr);
  chunk("IDAT", std::string(reinterpret_cast<const char*>(z.data()), zn));
  chunk("IEND", "");
  test::writeFile(path, png);
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
  const test::RunResult sizes = runGtn("compare " + dir + "/a.png " + dir + "/c.png");
  EXPECT_NE(sizes.err.find(dir + "/a.png, " + dir + "/c.png: images differ in size: 4x2 and 3x3"), std::string::npos)
      << sizes.err;
  // Transparency is background (composited over black): a transparent red image equals a black one,
  // and an opaque red one does not.
  const uint8_t clear_red[4] = {200, 0, 0, 0}, red[4] = {200, 0, 0, 255};
  writeRgbaPng(dir + "/clear.png", 4, 2, clear_red);
  writeRgbaPng(dir + "/red.png", 4, 2, red);
  ASSERT_TRUE(writePng(dir + "/black.png", Image(4, 2)).isOk());
  EXPECT_EQ(compareJson(dir + "/clear.png", dir + "/black.png")["pixels_compared"], 0);
  EXPECT_EQ(compareJson(dir + "/red.png", dir + "/black.png")["max_difference"], 200);
  const test::RunResult nothing = runGtn("compare " + dir + "/clear.png " + dir + "/black.png");
  EXPECT_NE(nothing.out.find("nothing to compare"), std::string::npos) << nothing.out;
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

TEST(RenderCommand, DumpViewDescribesTheCameraAndTransferFunction) {
  const std::string dir = test::tempDir("render-view");
  const std::string spx = test::dataPath("vtk/spx.vtk");
  nlohmann::json views[2];
  for (int generic = 0; generic < 2; ++generic) {
    const test::RunResult r = runGtn("render " + spx + " -o " + dir + "/v.png --size 96x64 --dump-view " + dir +
                                     "/view.json" + (generic ? " --pipeline generic" : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    views[generic] = nlohmann::json::parse(test::readFile(dir + "/view.json"));
  }
  EXPECT_EQ(views[0], views[1]);  // both pipelines resolve the same view
  const nlohmann::json& v = views[0];
  const nlohmann::json& cam = v["camera"];
  EXPECT_EQ(cam["width"], 96);
  EXPECT_EQ(cam["height"], 64);
  EXPECT_EQ(cam["projection"], "ortho");
  // Default azimuth 30, elevation 20 (VTK's conventions): the camera sits in that direction from the
  // focal point, twice the framed radius (the parallel scale at zoom 1) away, with a unit view up
  // perpendicular to the view direction.
  double dir_v[3], up[3], dist2 = 0, dot = 0, up2 = 0;
  for (int i = 0; i < 3; ++i) {
    dir_v[i] = cam["position"][i].get<double>() - cam["focal_point"][i].get<double>();
    up[i] = cam["view_up"][i].get<double>();
    dist2 += dir_v[i] * dir_v[i];
    dot += dir_v[i] * up[i];
    up2 += up[i] * up[i];
  }
  const double scale = cam["parallel_scale"].get<double>(), dist = std::sqrt(dist2);
  EXPECT_NEAR(dist, 2 * scale, 1e-9 * scale);
  const double kPi = 3.14159265358979323846, az = 30 * kPi / 180, el = 20 * kPi / 180;
  EXPECT_NEAR(dir_v[0] / dist, std::cos(el) * std::sin(az), 1e-9);
  EXPECT_NEAR(dir_v[1] / dist, std::sin(el), 1e-9);
  EXPECT_NEAR(dir_v[2] / dist, std::cos(el) * std::cos(az), 1e-9);
  EXPECT_NEAR(dot, 0, 1e-9 * dist);
  EXPECT_NEAR(up2, 1, 1e-12);
  // The cool-warm preset over the boundary's range of spx's scalars (0..2.254), D = diagonal / 40.
  const nlohmann::json& tf = v["transfer"];
  EXPECT_EQ(tf["field"], "scalars");
  ASSERT_EQ(tf["points"].size(), 5u);
  const double lo = tf["range"][0].get<double>(), hi = tf["range"][1].get<double>();
  EXPECT_LT(lo, hi);
  EXPECT_DOUBLE_EQ(tf["points"][0]["value"].get<double>(), lo);
  EXPECT_DOUBLE_EQ(tf["points"][4]["value"].get<double>(), hi);
  EXPECT_DOUBLE_EQ(tf["points"][4]["opacity"].get<double>(), 0.6);
  EXPECT_NEAR(tf["opacity_unit_distance"].get<double>(), 2 * scale / 40, 1e-9 * scale);
  // A perspective view reports its vertical view angle (30 degrees at zoom 1, narrower zoomed in).
  ASSERT_EQ(runGtn("render " + spx + " -o " + dir + "/p.png --size 32x32 --projection persp --zoom 2 --dump-view " +
                   dir + "/p.json")
                .exit_code,
            0);
  const nlohmann::json p = nlohmann::json::parse(test::readFile(dir + "/p.json"));
  EXPECT_NEAR(p["camera"]["view_angle"].get<double>(), 2 * std::atan(std::tan(15 * kPi / 180) / 2) * 180 / kPi, 1e-9);
}

// VTK's vtkUnstructuredGridVolumeRayCastMapper on the same mesh, camera and transfer function
// (bench/render/vtk_compare.py): the images differ by an RMSE under 3. VTK comes from Debian's
// python3-paraview (its vtkmodules), run under xvfb-run.
TEST(RenderCommand, AgreesWithVtkOnSpx) {
  if (test::runShell("/usr/bin/python3 -c 'import vtk' 2>/dev/null && command -v xvfb-run >/dev/null").exit_code != 0)
    GTEST_FAIL() << "/usr/bin/python3 cannot import vtk, or xvfb-run is missing (scripts/setup.sh installs "
                    "python3-paraview and xvfb)";
  const std::string dir = test::tempDir("render-vtk");
  const std::string spx = test::dataPath("vtk/spx.vtk");
  ASSERT_EQ(runGtn("convert " + spx + " -o " + dir + "/spx.gtn").exit_code, 0);
  ASSERT_EQ(runGtn("export " + dir + "/spx.gtn -o " + dir + "/spx.vtu").exit_code, 0);
  ASSERT_EQ(
      runGtn("render " + dir + "/spx.gtn -o " + dir + "/ours.png --size 256x256 --dump-view " + dir + "/view.json")
          .exit_code,
      0);
  const test::RunResult r = test::runShell(
      "xvfb-run -a -n 160 /usr/bin/python3 " GTN_SOURCE_DIR "/bench/render/vtk_compare.py " + dir + "/spx.vtu " + dir +
      "/view.json " + dir + "/vtk.png --frames 1 --json --ours " + dir + "/ours.png --gtn " GTN_BINARY);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_GT(j["pixels_compared"].get<int>(), 8000);
  EXPECT_LT(j["rmse"].get<double>(), 3.0);
  EXPECT_GT(j["mean_frame_s"].get<double>(), 0.0);
}

// The paper's figure: blunt fin (5-split) at ratio 0.9 differs from the full image by an RMSE of at
// most 1.32 (volume sampling, default transfer function). Colours and framing must not move between
// levels for this to hold (RenderInput::fixView).
TEST(RenderCommand, BluntFinAtRatioNineTenthsStaysClose) {
  const std::string dir = test::tempDir("render-blunt");
  const std::string gtn = dir + "/blunt.gtn";
  ASSERT_EQ(runGtn("convert " + test::dataPath("plot3d/bluntfinxyz.bin") + " " +
                   test::dataPath("plot3d/bluntfinq.bin") + " --split 5 -o " + gtn)
                .exit_code,
            0);
  ASSERT_EQ(runGtn("render " + gtn + " -o " + dir + "/full.png --field density").exit_code, 0);
  ASSERT_EQ(runGtn("render " + gtn + " -o " + dir + "/r.png --field density --ratio 0.9").exit_code, 0);
  const nlohmann::json d = compareJson(dir + "/full.png", dir + "/r.png");
  EXPECT_GT(d["pixels_compared"].get<int>(), 15000);
  EXPECT_GT(d["rmse"].get<double>(), 0.0);
  EXPECT_LE(d["rmse"].get<double>(), 1.32);
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
  // Numbers that are not finite (a NaN azimuth made the render hang).
  for (const char* option : {"--azimuth nan", "--elevation inf", "--zoom inf", "--step nan", "--ratio nan",
                             "--budget-ms inf", "--range 0 inf", "--opacity-unit-distance -inf"}) {
    const test::RunResult r = runGtn("render " + spx + " -o " + dir + "/x.png " + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_NE(r.err.find("finite"), std::string::npos) << option << ": " << r.err;
  }
  EXPECT_FALSE(test::fileExists(dir + "/x.png"));
  // Values that were ignored or ran away: negative selections (-1 meant "not given"), a step of
  // a billion samples, a transfer file that is not there (reported as an unknown preset), a field on
  // a mesh without point fields.
  for (const char* option :
       {"--ratio -0.5", "--merges -5", "--level -2", "--budget-ms -50", "--budget-ms 0", "--step 1e-9"})
    EXPECT_EQ(runGtn("render " + spx + " -o " + dir + "/x.png " + option).exit_code, 2) << option;
  const test::RunResult tf = runGtn("render " + spx + " -o " + dir + "/x.png --transfer " + dir + "/none.tf");
  EXPECT_EQ(tf.exit_code, 3) << tf.err;
  EXPECT_NE(tf.err.find(dir + "/none.tf: cannot open the transfer function file (no such file)"), std::string::npos)
      << tf.err;
  const std::string spheres = test::dataPath("tetgen/cornell_spheres.1");
  const test::RunResult nofield = runGtn("render " + spheres + " -o " + dir + "/x.png --field face_marker");
  EXPECT_EQ(nofield.exit_code, 2) << nofield.err;
  EXPECT_NE(nofield.err.find(spheres + ": no point field named 'face_marker' (the mesh has no point fields); "
                                       "'face_marker' is a cell field, and render shows point fields"),
            std::string::npos)
      << nofield.err;
  EXPECT_FALSE(test::fileExists(dir + "/x.png"));
  // Coordinates beyond what the crossing arithmetic holds are refused (the image came out blank).
  for (const char* scale : {"1e120", "1e-120"}) {
    const std::string big = dir + "/scaled.vtk";
    test::writeFile(big,
                    std::string("# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n") +
                        "0 0 0 " + scale + " 0 0 0 " + scale + " 0 0 0 " + scale +
                        "\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n");
    const test::RunResult r = runGtn("render " + big + " -o " + dir + "/x.png --size 8x8");
    EXPECT_EQ(r.exit_code, 1) << scale << ": " << r.err;
    EXPECT_NE(r.err.find("cannot be rendered"), std::string::npos) << r.err;
  }
  // The image or the view never replaces an input (it did: -o input.gtn).
  const std::string copy = dir + "/copy.vtk";
  test::writeFile(copy, test::readFile(spx));
  EXPECT_EQ(runGtn("render " + copy + " -o " + copy).exit_code, 2);
  EXPECT_EQ(runGtn("render " + copy + " -o " + dir + "/y.png --dump-view " + copy).exit_code, 2);
  EXPECT_EQ(test::readFile(copy), test::readFile(spx));
  // Nor does the view replace the image (it did: --dump-view x.png -o x.png left JSON in x.png), nor
  // do two documents share standard output (-o - --json interleaved the PNG and the report).
  const test::RunResult same = runGtn("render " + spx + " -o " + dir + "/z.png --dump-view " + dir + "/./z.png");
  EXPECT_EQ(same.exit_code, 2) << same.err;
  EXPECT_NE(same.err.find("-o and --dump-view name the same file"), std::string::npos) << same.err;
  EXPECT_FALSE(test::fileExists(dir + "/z.png"));
  for (const char* option : {"-o - --json", "-o - --dump-view -", "-o /dev/null --dump-view - --json"}) {
    const test::RunResult r = runGtn("render " + spx + " " + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << option;
    EXPECT_NE(r.err.find("standard output"), std::string::npos) << option << ": " << r.err;
  }
  // Samples so far apart that most rays take none: a warning says why the image is (nearly) blank.
  const test::RunResult sparse = runGtn("render " + spx + " -o " + dir + "/sparse.png --size 16x16 --step 20");
  ASSERT_EQ(sparse.exit_code, 0) << sparse.err;
  EXPECT_NE(sparse.err.find("--step 20 takes fewer than 4 samples across the bounding box"), std::string::npos)
      << sparse.err;
  const test::RunResult faces =
      runGtn("render " + spx + " -o " + dir + "/sparse.png --size 16x16 --step 20 --sampling face");
  EXPECT_EQ(faces.err.find("--step"), std::string::npos) << faces.err;  // face sampling takes no steps
  // A --range wider than the largest double (HI - LO overflows) put every sample at LO: a blank
  // image. spx's scalars lie at the middle of it, as they do of a narrower range around 0.
  ASSERT_EQ(runGtn("render " + spx + " -o " + dir + "/wide.png --size 48x48 --range -1e308 1e308").exit_code, 0);
  ASSERT_EQ(runGtn("render " + spx + " -o " + dir + "/narrow.png --size 48x48 --range -1e300 1e300").exit_code, 0);
  const std::string wide = test::readFile(dir + "/wide.png");
  EXPECT_EQ(wide, test::readFile(dir + "/narrow.png"));
  const test::RunResult blank = runGtn("render " + spx + " -o " + dir + "/blank.png --size 48x48 --range 10 20");
  ASSERT_EQ(blank.exit_code, 0) << blank.err;
  EXPECT_NE(wide, test::readFile(dir + "/blank.png"));  // the range's low end has no opacity: blank
}

// spx as a .gtn file with mip levels and merge trees, made with the library (as `gtn convert` does).
// `mesh` with its merge tree and `num_levels` stored levels, written to `path`.
void writeGtnOf(const TetMesh& mesh, const std::string& path, int num_levels) {
  RankingStats rstats;
  auto tree = rankMerges(mesh, RankingOptions(), &rstats);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  LevelOptions lopt;
  lopt.levels = num_levels;
  auto levels = buildMipLevels(mesh, tree.value(), lopt);
  ASSERT_TRUE(levels.isOk()) << levels.status().message();
  const Status st = writeGtnFile(path, levels->inputs(mesh), GtnWriteOptions());
  EXPECT_TRUE(st.isOk()) << st.message();
}

std::string makeSpxGtn(const std::string& dir) {
  auto imported = importMesh({test::dataPath("vtk/spx.vtk")}, ImportOptions());
  EXPECT_TRUE(imported.isOk());
  const std::string path = dir + "/spx.gtn";
  writeGtnOf(imported->mesh, path, 3);
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
  // Every level and ratio is seen with level 0's camera and colours (simplification moves boundary
  // vertices: spx's box shrinks and its boundary range changes from level 2 on).
  const nlohmann::json l2 = render(gtn, "l2.png", "--level 2");
  EXPECT_EQ(l2["view"], full["view"]);
  EXPECT_EQ(r["view"], full["view"]);
  EXPECT_EQ(l2["level"], 2);
  EXPECT_EQ(l2["extra_merges"], 0);
  EXPECT_EQ(render(gtn, "m.png", "--merges 100")["extra_merges"], 100);
  EXPECT_EQ(runGtn("render " + gtn + " -o " + dir + "/x.png --level 9").exit_code, 2);
  // A .gtn stream on standard input renders as the file does.
  const test::RunResult piped =
      test::runShell("cat " + gtn + " | " + GTN_BINARY + " render - -o " + dir + "/piped.png --level 2 --size 32x32");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  ASSERT_EQ(runGtn("render " + gtn + " -o " + dir + "/named.png --level 2 --size 32x32").exit_code, 0);
  EXPECT_EQ(test::readFile(dir + "/piped.png"), test::readFile(dir + "/named.png"));
  // More merges than the tree holds: an error by number (it rendered the whole tree and reported the
  // number asked for), and a ratio of 1 stops where the tree ends.
  const test::RunResult many = runGtn("render " + gtn + " -o " + dir + "/x.png --merges 100000000");
  EXPECT_EQ(many.exit_code, 2) << many.err;
  EXPECT_NE(many.err.find(": 100000000 merges requested, the merge tree has "), std::string::npos) << many.err;
  const nlohmann::json all = render(gtn, "all.png", "--ratio 1");
  EXPECT_LT(all["ratio"].get<double>(), 1.0);
  EXPECT_GT(all["ratio"].get<double>(), 0.9);
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
  // The run that read the calibration folded its measured time into the cached offset; the
  // calibration holds whole runs and decoding alone for the same levels.
  const nlohmann::json cache = nlohmann::json::parse(test::readFile(dir + "/cache/gatun/render-calibration.json"));
  size_t calibrations = 0, ranges = 0;
  for (const auto& [key, entry] : cache.items()) {
    if (key.rfind("range|", 0) == 0) {
      // Level 0's boundary range, kept so that coarse levels need not decode level 0's boundary.
      ++ranges;
      ASSERT_EQ(entry.size(), 2u);
      EXPECT_LT(entry[0].get<double>(), entry[1].get<double>());
      continue;
    }
    ++calibrations;
    ASSERT_TRUE(entry.contains("offset_ms")) << entry.dump();
    EXPECT_EQ(entry["tets"].size(), entry["ms"].size());
    ASSERT_EQ(entry["decode_ms"].size(), entry["ms"].size());
    for (size_t i = 0; i < entry["ms"].size(); ++i) {
      EXPECT_GT(entry["decode_ms"][i].get<double>(), 0.0);
      EXPECT_LE(entry["decode_ms"][i].get<double>(), entry["ms"][i].get<double>());
    }
  }
  EXPECT_EQ(calibrations, 1u);
  EXPECT_EQ(ranges, 1u);
  // The cached range gives the same image as decoding level 0's boundary again.
  ASSERT_EQ(
      test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir + "/cached.png --size 64x64 --level 3").exit_code,
      0);
  ASSERT_EQ(test::runShell("XDG_CACHE_HOME=" + dir + "/fresh-cache " GTN_BINARY " render " + gtn + " -o " + dir +
                           "/fresh.png --size 64x64 --level 3")
                .exit_code,
            0);
  EXPECT_TRUE(test::fileExists(dir + "/fresh-cache/gatun/render-calibration.json"));
  EXPECT_EQ(compareJson(dir + "/cached.png", dir + "/fresh.png")["max_difference"].get<int>(), 0);
  // Standard input is another stream every time: nothing is cached for it. (Every stream had the key
  // of "-": one stream's calibration planned the next with more merges than its tree held, an error,
  // and its colour range coloured the next.)
  const std::string other = dir + "/other.gtn";
  ASSERT_EQ(runGtn("convert " + spx + " -o " + other + " --levels 1").exit_code, 0);
  const std::string stdin_env = "XDG_CACHE_HOME=" + dir + "/stdin-cache ";
  for (const std::string& f : {gtn, other, gtn}) {
    const test::RunResult s = test::runShell("cat " + f + " | " + stdin_env + GTN_BINARY " render - -o " + dir +
                                             "/s.png --size 32x32 --budget-ms 0.001 -v");
    ASSERT_EQ(s.exit_code, 0) << f << ": " << s.err;
    EXPECT_NE(s.err.find("not cached (standard input is no regular file)"), std::string::npos) << s.err;
  }
  EXPECT_FALSE(test::fileExists(dir + "/stdin-cache/gatun/render-calibration.json"));

  // The plans for a range of budgets, from a calibration written here (so that the choice does not
  // depend on this machine's speed): a larger budget never gives a coarser plan, the finest plan
  // is level 0, and between stored levels the choice uses merges on the fly.
  const nlohmann::json info = nlohmann::json::parse(runGtn("info --json " + gtn).out);
  const auto& levels = info["levels"];
  ASSERT_EQ(levels.size(), 4u);
  const double n0 = levels[0]["tets"].get<double>(), n3 = levels[3]["tets"].get<double>();
  nlohmann::json synthetic = cache;
  for (auto& [key, entry] : synthetic.items()) {
    if (key.rfind("range|", 0) == 0) continue;
    entry = {{"tets", {n3, n0}}, {"ms", {100.0, 1000.0}}, {"decode_ms", {10.0, 400.0}}, {"offset_ms", 0.0}};
  }
  int64_t previous = -1;
  bool merged_plan = false;
  std::set<int> levels_seen;
  for (double budget : {20.0, 150.0, 250.0, 400.0, 500.0, 600.0, 700.0, 800.0, 950.0, 1100.0, 1300.0, 5000.0}) {
    {
      std::ofstream out(dir + "/cache/gatun/render-calibration.json", std::ios::trunc);
      out << synthetic.dump();
    }
    const test::RunResult b = test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                                             "/b.png --size 64x64 --json --budget-ms " + std::to_string(budget));
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const nlohmann::json j = nlohmann::json::parse(b.out);
    SCOPED_TRACE("budget " + std::to_string(budget) + ": " + j["budget_choice"].get<std::string>());
    const int64_t merges = j["stored_merges"].get<int64_t>() + j["extra_merges"].get<int64_t>();
    if (previous >= 0) {
      EXPECT_LE(merges, previous);
    }
    previous = merges;
    levels_seen.insert(j["level"].get<int>());
    if (j["extra_merges"].get<int64_t>() > 0) {
      merged_plan = true;
      EXPECT_LT(j["level"].get<int>(), 3);  // on the fly from a level towards the next one
      EXPECT_LT(merges, levels[j["level"].get<int>() + 1]["merges"].get<int64_t>());
    }
  }
  EXPECT_TRUE(merged_plan);
  EXPECT_EQ(previous, 0);  // the largest budget: level 0 as is
  EXPECT_GE(levels_seen.size(), 3u);

  // Below the coarsest level's time, its own tree's merges apply on the fly, down to the floor (all
  // of them) that the calibration timed; a budget even the floor misses gets the floor.
  uint64_t floor_merges = 0;
  for (const auto& [key, entry] : cache.items()) {
    if (key.rfind("range|", 0) == 0) continue;
    ASSERT_TRUE(entry.contains("floor") && entry["floor"].is_object()) << entry.dump();
    floor_merges = entry["floor"]["merges"].get<uint64_t>();
    EXPECT_LT(entry["floor"]["tets"].get<double>(), n3);
    EXPECT_GT(entry["floor"]["ms"].get<double>(), 0.0);
  }
  ASSERT_GT(floor_merges, 0u);
  const int64_t merges3 = levels[3]["merges"].get<int64_t>();
  // The plan for a budget from a calibration written here.
  auto planWith = [&](const nlohmann::json& calibration, double budget) {
    {
      std::ofstream out(dir + "/cache/gatun/render-calibration.json", std::ios::trunc);
      out << calibration.dump();
    }
    const test::RunResult b = test::runShell(env + GTN_BINARY " render " + gtn + " -o " + dir +
                                             "/b.png --size 64x64 --json --budget-ms " + std::to_string(budget));
    EXPECT_EQ(b.exit_code, 0) << b.err;
    return nlohmann::json::parse(b.out);
  };
  auto floorPlan = [&](double budget) {
    nlohmann::json with_floor = synthetic;
    for (auto& [key, entry] : with_floor.items())
      if (key.rfind("range|", 0) != 0) entry["floor"] = {{"merges", floor_merges}, {"tets", n3 / 10}, {"ms", 30.0}};
    return planWith(with_floor, budget);
  };
  const nlohmann::json between = floorPlan(80);  // aims at 64 ms: between the floor (30) and level 3 (100)
  EXPECT_EQ(between["level"], 3) << between.dump();
  EXPECT_GT(between["extra_merges"].get<int64_t>(), 0);
  EXPECT_LT(between["extra_merges"].get<uint64_t>(), floor_merges);
  EXPECT_EQ(between["stored_merges"].get<int64_t>(), merges3);
  const nlohmann::json cheapest = floorPlan(1);
  EXPECT_EQ(cheapest["level"], 3);
  EXPECT_EQ(cheapest["extra_merges"].get<uint64_t>(), floor_merges);
  EXPECT_NE(cheapest["budget_choice"].get<std::string>().find("cannot be met"), std::string::npos);
  EXPECT_EQ(floorPlan(150)["extra_merges"], 0);  // level 3 as is fits

  // Between two timed levels the coarser one is the plan, not merges on the fly from the finer one:
  // at the coarse end time falls in steps with the merges. The same budget with level 2 untimed
  // takes merges on the fly from level 2.
  nlohmann::json dense = synthetic;
  const double n2 = levels[2]["tets"].get<double>();
  for (auto& [key, entry] : dense.items())
    if (key.rfind("range|", 0) != 0)
      entry = {{"tets", {n3, n2, n0}},
               {"ms", {100.0, 300.0, 1000.0}},
               {"decode_ms", {10.0, 100.0, 400.0}},
               {"offset_ms", 0.0}};
  const nlohmann::json stepped = planWith(dense, 300);  // aims at 240 ms: level 2 (300) misses, level 3 fits
  EXPECT_EQ(stepped["level"], 3) << stepped.dump();
  EXPECT_EQ(stepped["extra_merges"], 0) << stepped.dump();
  const nlohmann::json interpolated = planWith(synthetic, 300);
  EXPECT_EQ(interpolated["level"], 2) << interpolated.dump();
  EXPECT_GT(interpolated["extra_merges"].get<int64_t>(), 0) << interpolated.dump();
}

// A .gtn whose field name is not UTF-8 (files from before import made names UTF-8): --json output
// replaces the bad bytes instead of aborting.
TEST(JsonOutput, NamesThatAreNotUtf8DoNotAbort) {
  const std::string dir = test::tempDir("json-latin1");
  auto imported = importMesh({test::dataPath("vtk/spx.vtk")}, ImportOptions());
  ASSERT_TRUE(imported.isOk());
  TetMesh mesh = std::move(imported->mesh);
  ASSERT_FALSE(mesh.point_fields.empty());
  mesh.point_fields[0].name = "caf\xE9";
  const std::string path = dir + "/latin1.gtn";
  writeGtnOf(mesh, path, 1);
  ASSERT_TRUE(test::fileExists(path));
  for (const char* command : {"info ", "validate "}) {
    const test::RunResult r = runGtn(std::string(command) + path + " --json");
    EXPECT_EQ(r.exit_code, 0) << command << r.err;
    EXPECT_NE(r.out.find("caf\xEF\xBF\xBD"), std::string::npos) << command << r.out.substr(0, 400);
    EXPECT_TRUE(nlohmann::json::accept(r.out)) << command;
  }
}

// Rendering a mesh file says what its importer left out, as convert, info and validate do.
TEST(RenderCommand, SaysWhatTheImporterLeftOut) {
  const std::string dir = test::tempDir("render-import-warnings");
  test::writeFile(dir + "/t.vtk",
                  "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
                  "0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 2 9\n4 0 1 2 3\n3 0 1 3\nCELL_TYPES 2\n10\n5\n");
  const test::RunResult r = runGtn("render " + dir + "/t.vtk -o " + dir + "/t.png --size 16x16");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gtn: warning: " + dir + "/t.vtk: skipped 1 cells of lower dimension"), std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace gtn
