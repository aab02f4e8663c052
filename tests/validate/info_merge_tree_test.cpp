// gtn info --merge-tree prints the merge tree as a table whose numbers are those of --json, and
// --plot draws the error curve to a PNG (through the built binary on spx).
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>

#include <nlohmann/json.hpp>

#include "render/image.h"
#include "test_util.h"

namespace gtn::test {
namespace {

class InfoMergeTree : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = tempDir("info-merge-tree");
    const RunResult r = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ + "/spx.gtn --levels 3");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static std::string dir_;
};
std::string InfoMergeTree::dir_;

// The text after `label` padded to 20 columns on the table's line that starts with it.
std::string row(const std::string& text, const std::string& label) {
  const std::string key = "\n    " + label;
  const size_t at = text.find(key + std::string(20 - label.size(), ' '));
  if (at == std::string::npos) return "";
  const size_t begin = at + key.size() + (20 - label.size());
  return text.substr(begin, text.find('\n', begin) - begin);
}

std::string fixed(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

TEST_F(InfoMergeTree, TableAgreesWithJson) {
  const RunResult text = runGtn("info " + dir_ + "/spx.gtn --merge-tree");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  const RunResult json = runGtn("info " + dir_ + "/spx.gtn --merge-tree --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json mt = nlohmann::json::parse(json.out)["merge_tree"];
  ASSERT_TRUE(mt.is_object());
  EXPECT_EQ(text.out.find("{\""), std::string::npos) << "no inline JSON in the text report";
  EXPECT_EQ(row(text.out, "roots"), std::to_string(mt["roots"].get<uint64_t>()));
  EXPECT_EQ(row(text.out, "depth"), "max " + std::to_string(mt["depth"]["max"].get<uint64_t>()) + ", mean " +
                                        fixed("%.3f", mt["depth"]["mean"].get<double>()));
  EXPECT_EQ(row(text.out, "fan-out"), "max " + std::to_string(mt["fanout"]["max"].get<uint64_t>()) + ", mean " +
                                          fixed("%.3f", mt["fanout"]["mean"].get<double>()));
  EXPECT_EQ(row(text.out, "merges").rfind(std::to_string(mt["merges"].get<uint64_t>()) + " of 2896 vertices", 0), 0u);
  // The error quantiles: the line after the names holds the values, %.4g.
  std::istringstream values(text.out.substr(text.out.find('\n', text.out.find("error quantiles")) + 1));
  for (const char* q : {"min", "p01", "p10", "p25", "p50", "p75", "p90", "p99", "max"}) {
    std::string v;
    values >> v;
    EXPECT_EQ(v, fixed("%.4g", mt["error_quantiles"][q].get<double>())) << q;
  }
  // One row per stored level: level, ratio, points, tetrahedra, bytes, merges, largest error.
  ASSERT_EQ(mt["levels"].size(), 4u);
  const size_t header = text.out.find("    level      ratio");
  ASSERT_NE(header, std::string::npos) << text.out;
  std::istringstream rows(text.out.substr(text.out.find('\n', header) + 1));
  for (const nlohmann::json& l : mt["levels"]) {
    std::string level, ratio, points, tets, bytes, merges, largest;
    rows >> level >> ratio >> points >> tets >> bytes >> merges >> largest;
    EXPECT_EQ(level, std::to_string(l["level"].get<size_t>()));
    EXPECT_EQ(ratio, fixed("%.6f", l["ratio"].get<double>()));
    EXPECT_EQ(points, std::to_string(l["points"].get<uint64_t>()));
    EXPECT_EQ(tets, std::to_string(l["tets"].get<uint64_t>()));
    EXPECT_EQ(bytes, std::to_string(l["bytes"].get<uint64_t>()));
    EXPECT_EQ(merges, std::to_string(l["merges"].get<uint64_t>()));
    EXPECT_EQ(largest, l["largest_error"].is_null() ? "-" : fixed("%.4g", l["largest_error"].get<double>()));
  }
  EXPECT_TRUE(mt["levels"][0]["largest_error"].is_null());
  EXPECT_FALSE(mt["levels"][3]["largest_error"].is_null());
  EXPECT_EQ(mt["levels"][2]["points"], 724);
}

// A TMPDIR that names no folder is an error that says so (it aborted on an uncaught exception).
TEST_F(InfoMergeTree, PlotWithABadTmpdirIsAnError) {
  const std::string png = dir_ + "/tmpdir.png";
  const RunResult r = runShell("TMPDIR=" + dir_ + "/missing " GTN_BINARY " info " + dir_ + "/spx.gtn --plot " + png);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find(png + ": --plot: no folder for temporary files"), std::string::npos) << r.err;
  EXPECT_FALSE(fileExists(png));
}

TEST_F(InfoMergeTree, PlotDrawsTheCurve) {
  const std::string png = dir_ + "/errors.png";
  const RunResult r = runGtn("info " + dir_ + "/spx.gtn --plot " + png);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto image = readPng(png);
  ASSERT_TRUE(image.isOk()) << image.status().message();
  EXPECT_EQ(image->width, 800);
  EXPECT_EQ(image->height, 500);
  size_t ink = 0, blue = 0;
  for (size_t i = 0; i < image->rgb.size(); i += 3) {
    const uint8_t* p = &image->rgb[i];
    ink += p[0] < 240 || p[1] < 240 || p[2] < 240;
    blue += p[2] > 128 && p[0] < 80;  // the curve's colour
  }
  EXPECT_GT(ink, 800u * 500u / 50);
  EXPECT_GT(blue, 300u);

  const RunResult none =
      runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir_ + "/flat.gtn --levels 0 --no-merge-tree");
  ASSERT_EQ(none.exit_code, 0) << none.err;
  const RunResult refused = runGtn("info " + dir_ + "/flat.gtn --plot " + dir_ + "/flat.png");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("stores no merge tree"), std::string::npos) << refused.err;
  EXPECT_FALSE(fileExists(dir_ + "/flat.png"));
  const std::string before = readFile(dir_ + "/spx.gtn");
  const RunResult self = runGtn("info " + dir_ + "/spx.gtn --plot " + dir_ + "/spx.gtn");
  EXPECT_EQ(self.exit_code, 2);
  EXPECT_NE(self.err.find("the output would overwrite the input"), std::string::npos) << self.err;
  EXPECT_EQ(readFile(dir_ + "/spx.gtn"), before);
  const RunResult mesh = runGtn("info " + dataPath("vtk/spx.vtk") + " --plot " + dir_ + "/mesh.png");
  EXPECT_EQ(mesh.exit_code, 2);
  EXPECT_NE(mesh.err.find("a mesh has none"), std::string::npos) << mesh.err;
}

}  // namespace
}  // namespace gtn::test
