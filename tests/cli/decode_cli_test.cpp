// gtn decode: the counts it reports are those of the mesh `gtn info` describes and `gtn export` writes,
// on a real dataset and on a generated grid; its JSON keys; --ratio and --fields; bad input.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <set>
#include <string>

#include "test_util.h"

namespace gtn {
namespace {

using nlohmann::json;

json runJson(const std::string& args) {
  const test::RunResult r = test::runGtn(args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
  if (r.exit_code != 0) return json();
  return json::parse(r.out);
}

// The fields of a decode report as {name, location, components, type}, and their value counts.
std::set<std::string> fieldKeys(const json& fields) {
  std::set<std::string> out;
  for (const json& f : fields)
    out.insert(f.at("name").get<std::string>() + "/" + f.at("location").get<std::string>() + "/" +
               std::to_string(f.at("components").get<int>()) + "/" + f.at("type").get<std::string>());
  return out;
}

class DecodeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::tempDir("gtn-decode-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  // A generated 6 x 6 x 6 grid of hexahedra (point field density, cell field block) as .gtn, with two
  // mip levels.
  std::string generatedGtn() {
    const std::string vtk = dir_ + "/grid.vtk", gtn = dir_ + "/grid.gtn";
    test::writeFile(vtk, test::shearedHexGridVtk(6, false, true));
    const test::RunResult r = test::runGtn("convert " + vtk + " -o " + gtn + " -q --levels 2");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return gtn;
  }
  std::string dir_;
};

// Counts of level 0 as `gtn info` gives them (the streaming decoder's level 0) and as the exported
// .vtu holds them, on a real dataset; then --ratio gives fewer tetrahedra, as export does.
TEST_F(DecodeCli, CountsMatchInfoAndExportOnSpx) {
  const std::string spx = test::dataPath("vtk/spx.vtk");
  ASSERT_TRUE(test::fileExists(spx)) << "dataset missing: " << spx;
  const std::string gtn = dir_ + "/spx.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx + " -o " + gtn + " -q").exit_code, 0);

  const json info = runJson("info " + gtn + " --json");
  const json d = runJson("decode " + gtn + " --json");
  ASSERT_FALSE(d.is_null());
  EXPECT_EQ(d.at("points"), info.at("points"));
  EXPECT_EQ(d.at("tets"), info.at("tets"));
  EXPECT_EQ(d.at("tets"), 12936);
  EXPECT_EQ(d.at("level"), 0);
  EXPECT_TRUE(d.at("ratio").is_null());
  std::set<std::string> info_fields;
  for (const json& f : info.at("fields"))
    info_fields.insert(f.at("name").get<std::string>() + "/" + f.at("location").get<std::string>() + "/" +
                       std::to_string(f.at("components").get<int>()) + "/" + f.at("type").get<std::string>());
  EXPECT_EQ(fieldKeys(d.at("fields")), info_fields);
  ASSERT_FALSE(d.at("fields").empty());
  for (const json& f : d.at("fields"))
    EXPECT_EQ(f.at("values"), f.at("location") == "point" ? d.at("points") : d.at("tets")) << f.at("name");

  // --ratio 0.5: the counts of the mesh export writes for that ratio, and fewer tetrahedra.
  const std::string vtu = dir_ + "/spx-half.vtu";
  ASSERT_EQ(test::runGtn("export " + gtn + " --ratio 0.5 -o " + vtu).exit_code, 0);
  const json exported = runJson("info " + vtu + " --json");
  const json half = runJson("decode " + gtn + " --ratio 0.5 --json");
  ASSERT_FALSE(half.is_null());
  EXPECT_EQ(half.at("points"), exported.at("points"));
  EXPECT_EQ(half.at("tets"), exported.at("tets"));
  EXPECT_LT(half.at("tets").get<uint64_t>(), d.at("tets").get<uint64_t>());
  EXPECT_GT(half.at("tets").get<uint64_t>(), 0u);
  EXPECT_EQ(half.at("ratio"), 0.5);
}

// A generated grid: (n+1)^3 points, 6 n^3 tetrahedra, one value per point of density and per
// tetrahedron of block; each stored level as `gtn info` lists it; --fields keeps the one named.
TEST_F(DecodeCli, CountsOnGeneratedGridLevelsAndFields) {
  const std::string gtn = generatedGtn();
  const json d = runJson("decode " + gtn + " --json");
  ASSERT_FALSE(d.is_null());
  EXPECT_EQ(d.at("points"), 7 * 7 * 7);
  EXPECT_EQ(d.at("tets"), 6 * 6 * 6 * 6);
  EXPECT_EQ(fieldKeys(d.at("fields")), (std::set<std::string>{"density/point/1/float64", "block/cell/1/int32"}));
  for (const json& f : d.at("fields"))
    EXPECT_EQ(f.at("values"), f.at("location") == "point" ? d.at("points") : d.at("tets")) << f.at("name");

  const json info = runJson("info " + gtn + " --json");
  ASSERT_GT(info.at("levels").size(), 1u) << "the grid should get mip levels";
  for (const json& l : info.at("levels")) {
    const std::string i = std::to_string(l.at("level").get<int>());
    const json li = runJson("decode " + gtn + " --level " + i + " --json");
    EXPECT_EQ(li.at("level"), l.at("level"));
    EXPECT_EQ(li.at("points"), l.at("points")) << "level " << i;
    EXPECT_EQ(li.at("tets"), l.at("tets")) << "level " << i;
  }
  const json only = runJson("decode " + gtn + " --fields block --json");
  EXPECT_EQ(fieldKeys(only.at("fields")), (std::set<std::string>{"block/cell/1/int32"}));
  EXPECT_EQ(only.at("tets"), d.at("tets"));

  // The ratio's tetrahedra fall as the ratio grows.
  const json r3 = runJson("decode " + gtn + " --ratio 0.3 --json");
  const json r8 = runJson("decode " + gtn + " --ratio 0.8 --json");
  EXPECT_LT(r3.at("tets").get<uint64_t>(), d.at("tets").get<uint64_t>());
  EXPECT_LT(r8.at("tets").get<uint64_t>(), r3.at("tets").get<uint64_t>());
}

TEST_F(DecodeCli, JsonKeysAndText) {
  const std::string gtn = generatedGtn();
  const json d = runJson("decode " + gtn + " --json");
  ASSERT_TRUE(d.is_object());
  std::set<std::string> keys;
  for (auto it = d.begin(); it != d.end(); ++it) keys.insert(it.key());
  EXPECT_EQ(keys, (std::set<std::string>{"input", "bytes", "level", "ratio", "extra_merges", "points", "tets", "fields",
                                         "threads", "wall_s", "decode_s", "tets_per_second", "peak_rss_bytes"}));
  EXPECT_EQ(d.at("input"), gtn);
  EXPECT_EQ(d.at("bytes").get<uint64_t>(), test::readFile(gtn).size());
  EXPECT_GT(d.at("decode_s").get<double>(), 0.0);
  EXPECT_GE(d.at("wall_s").get<double>(), d.at("decode_s").get<double>());
  EXPECT_GT(d.at("tets_per_second").get<double>(), 0.0);
  EXPECT_GT(d.at("peak_rss_bytes").get<uint64_t>(), 0u);
  EXPECT_GE(d.at("threads").get<int>(), 1);

  const test::RunResult text = test::runGtn("decode " + gtn);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("tetrahedra          1296\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("points              343\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("tetrahedra per second"), std::string::npos) << text.out;
  EXPECT_TRUE(text.err.empty()) << text.err;
}

TEST_F(DecodeCli, BadInput) {
  const std::string gtn = generatedGtn();
  auto expectError = [](const std::string& args, int code, const std::vector<std::string>& parts) {
    const test::RunResult r = test::runGtn(args);
    EXPECT_EQ(r.exit_code, code) << args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << args << "\n" << r.out;
    for (const std::string& p : parts) EXPECT_NE(r.err.find(p), std::string::npos) << args << "\n" << r.err;
  };
  const std::string missing = dir_ + "/missing.gtn";
  expectError("decode " + missing, 3, {"gtn: error: ", missing});
  expectError("decode " + gtn + " --level 99", 2, {gtn, "--level 99", "level(s)"});
  expectError("decode " + gtn + " --fields nosuch", 2, {gtn, "--fields", "nosuch"});
  expectError("decode " + gtn + " --ratio 1.5", 2, {"--ratio"});
  expectError("decode " + gtn + " --level 1 --ratio 0.5", 2, {"exclude"});
  const std::string vtk = dir_ + "/grid.vtk";
  expectError("decode " + vtk, 2, {vtk, "not .gtn", "gtn convert"});

  // A file cut short, and one whose level 0 is damaged (a file of level 0 alone, so that the middle
  // byte is in it): named, with the place and the reason.
  const std::string plain = dir_ + "/plain.gtn";
  ASSERT_EQ(test::runGtn("convert " + vtk + " -o " + plain + " -q --levels 0 --no-merge-tree").exit_code, 0);
  const std::string bytes = test::readFile(plain);
  const std::string cut = dir_ + "/cut.gtn";
  test::writeFile(cut, bytes.substr(0, bytes.size() / 2));
  const test::RunResult rc = test::runGtn("decode " + cut);
  EXPECT_NE(rc.exit_code, 0);
  EXPECT_NE(rc.err.find("gtn: error: " + cut + ": "), std::string::npos) << rc.err;
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x55);
  const std::string damaged = dir_ + "/damaged.gtn";
  test::writeFile(damaged, flipped);
  const test::RunResult rd = test::runGtn("decode " + damaged);
  EXPECT_NE(rd.exit_code, 0);
  EXPECT_NE(rd.err.find("gtn: error: " + damaged + ": byte offset "), std::string::npos) << rd.err;
}

// A field with no finite value (all NaN, all infinite) has no range: `gtn info` says so, and its
// JSON gives null for min and max, not a range of [0, 0] that no value has.
TEST_F(DecodeCli, AFieldWithNoFiniteValueHasNoRange) {
  const std::string vtk = dir_ + "/nan.vtk";
  test::writeFile(
      vtk,
      "# vtk DataFile Version 4.2\nnan\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0 1 0 0 0 1 0 "
      "0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS allnan double 1\n"
      "LOOKUP_TABLE default\nnan nan nan nan\nSCALARS some double 1\nLOOKUP_TABLE default\n1 nan 3 inf\n");
  const test::RunResult text = test::runGtn("info " + vtk);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("allnan       1 x float64, no finite value, 4 non-finite"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("some         1 x float64, range [1, 3], 2 non-finite"), std::string::npos) << text.out;
  const json info = runJson("info " + vtk + " --json");
  ASSERT_EQ(info["fields"].size(), 2u);
  EXPECT_TRUE(info["fields"][0]["min"].is_null());
  EXPECT_TRUE(info["fields"][0]["max"].is_null());
  EXPECT_EQ(info["fields"][1]["min"].get<double>(), 1.0);
  EXPECT_EQ(info["fields"][1]["max"].get<double>(), 3.0);
}

}  // namespace
}  // namespace gtn
