// gtn convert / info / export on .gtn files, through the built binary, on real data.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

#include "format/gtn_chunk.h"
#include "test_util.h"

namespace gtn {
namespace {

using nlohmann::json;

json infoJson(const std::string& args) {
  const test::RunResult r = test::runGtn("info " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? json::parse(r.out) : json();
}

// The data-dependent part of `gtn info --json` (what a lossless round trip must keep). Volumes are
// sums of floating-point determinants whose last bits depend on vertex and tetrahedron order (a
// renumbering), so they are rounded to 9 significant digits.
json meshSummary(const json& j) {
  json s;
  for (const char* k : {"points", "tets", "faces", "boundary_faces", "inverted", "zero_volume", "unreferenced_points",
                        "coordinate_type", "bbox", "fields"})
    s[k] = j.at(k);
  for (const char* k : {"min", "max", "total"}) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", j.at("volume").at(k).get<double>());
    s["volume"][k] = buf;
  }
  return s;
}

class GtnCli : public ::testing::Test {
 protected:
  void SetUp() override {
    spx_ = test::dataPath("vtk/spx.vtk");
    ASSERT_TRUE(test::fileExists(spx_)) << "dataset missing: " << spx_;
    dir_ = test::tempDir("gtn-cli-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  std::string spx_, dir_;
};

TEST_F(GtnCli, ConvertInfoAndPipeOnSpx) {
  const std::string out = dir_ + "/spx.gtn";
  test::RunResult r = test::runGtn("convert " + spx_ + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string bytes = test::readFile(out);
  ASSERT_GT(bytes.size(), 16u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0x8E);

  const json j = infoJson(out);
  EXPECT_EQ(j["format"], "gtn");
  EXPECT_EQ(j["format_version"], "2.0");
  EXPECT_EQ(j["draft"], kGtnDraftRevision);
  ASSERT_EQ(j["levels"][0]["piece_count"], 1);  // 12936 tetrahedra: one piece at the default bound
  EXPECT_EQ(j["levels"][0]["pieces"][0]["tets"], 12936);
  EXPECT_EQ(j["points"], 2896);
  EXPECT_EQ(j["tets"], 12936);
  EXPECT_EQ(j["faces"], 27252);
  EXPECT_EQ(j["boundary_faces"], 2760);
  EXPECT_EQ(j["inverted"], 0);
  EXPECT_EQ(j["bytes"], bytes.size());
  uint64_t sum = 0;
  std::set<std::string> names;
  for (const json& s : j["sections"]) {
    sum += s["bytes"].get<uint64_t>();
    names.insert(s["name"]);
  }
  EXPECT_EQ(sum, bytes.size());
  for (const char* n : {"prefix", "header", "level_header", "boundary", "connectivity", "geometry",
                        "point_field:scalars", "directory", "trailer"})
    EXPECT_TRUE(names.count(n)) << n;
  const json& b = j["bits_per_tet"];
  EXPECT_GT(b["connectivity"].get<double>(), 0.5);
  EXPECT_LT(b["connectivity"].get<double>(), 8.0);
  // Level 0's share: the file less the other levels (convert may add mip levels).
  uint64_t other_levels = 0;
  for (size_t i = 1; i < j["levels"].size(); ++i) other_levels += j["levels"][i]["bytes"].get<uint64_t>();
  EXPECT_NEAR(b["total"].get<double>(), 8.0 * (bytes.size() - other_levels) / 12936.0, 1e-9);
  // Far below the source's 12936 x 4 x 4 index bytes + float coordinates and scalars (~265 KB).
  EXPECT_LT(bytes.size() - other_levels, 60000u);
  ASSERT_TRUE(b.contains("merge_tree"));
  const double parts = b["connectivity"].get<double>() + b["geometry"].get<double>() + b["fields"].get<double>() +
                       b["merge_tree"].get<double>();
  EXPECT_LT(parts, b["total"].get<double>());
  EXPECT_GT(parts, 0.97 * b["total"].get<double>());  // headers, framing, directory: small
  EXPECT_GT(j["peak_live_vertices"].get<uint64_t>(), 0u);
  EXPECT_LE(j["peak_live_vertices"].get<uint64_t>(), 2896u);
  EXPECT_EQ(j["provenance"]["tool_version"], GTN_VERSION_STRING);
  EXPECT_EQ(j["provenance"]["command_line"], "gtn convert spx.vtk -o spx.gtn");  // file names, no directories
  ASSERT_GE(j["levels"].size(), 1u);
  EXPECT_EQ(j["levels"][0]["tets"], 12936);
  EXPECT_EQ(j["levels"][0]["merges"], 0);

  // The decoded level holds what the source holds.
  EXPECT_EQ(meshSummary(j), meshSummary(infoJson(spx_)));

  // From a pipe: the same document but for the input name.
  r = test::runShell("cat " + out + " | " + GTN_BINARY + " info - --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json piped = json::parse(r.out);
  json by_path = j;
  piped.erase("input");
  by_path.erase("input");
  EXPECT_EQ(piped, by_path);

  // Text output names the container and the decoded mesh.
  r = test::runGtn("info " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(".gtn format 2.0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("tetrahedra          12936"), std::string::npos) << r.out;
}

TEST_F(GtnCli, ConvertIsDeterministic) {
  const std::string out = dir_ + "/d.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + out).exit_code, 0);
  const std::string first = test::readFile(out);
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + out).exit_code, 0);
  EXPECT_EQ(first, test::readFile(out));
}

// The writer decodes every level back before committing the file (GtnWriteOptions::verify);
// --no-verify skips that and writes the same levels.
TEST_F(GtnCli, NoVerifyWritesTheSameLevels) {
  const std::string a = dir_ + "/checked.gtn", b = dir_ + "/unchecked.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + a).exit_code, 0);
  const test::RunResult r = test::runGtn("convert " + spx_ + " -o " + b + " --no-verify");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json ja = infoJson(a), jb = infoJson(b);
  EXPECT_EQ(meshSummary(ja), meshSummary(jb));
  ASSERT_EQ(ja.at("sections").size(), jb.at("sections").size());
  for (size_t i = 0; i < ja.at("sections").size(); ++i) {
    if (ja["sections"][i].at("name") == "header") continue;  // the command line differs
    EXPECT_EQ(ja["sections"][i], jb["sections"][i]);
  }
  EXPECT_NE(jb.at("provenance").dump().find("--no-verify"), std::string::npos);
}

// A .gtn file is an input like any mesh file: its level 0. To .vtu it is what export writes; to
// .gtn it is re-encoded (here without levels) and still equals its source.
TEST_F(GtnCli, GtnFileAsConvertInput) {
  const std::string gtn = dir_ + "/spx.gtn", again = dir_ + "/again.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + gtn + " --levels 2").exit_code, 0);
  const test::RunResult r = test::runGtn("convert " + gtn + " -o " + dir_ + "/c.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("read level 0, the lossless mesh, of its 3 levels"), std::string::npos) << r.err;
  ASSERT_EQ(test::runGtn("export " + gtn + " -o " + dir_ + "/e.vtu").exit_code, 0);
  EXPECT_EQ(test::readFile(dir_ + "/c.vtu"), test::readFile(dir_ + "/e.vtu"));
  ASSERT_EQ(test::runGtn("convert " + gtn + " -o " + again + " --levels 0 --no-merge-tree").exit_code, 0);
  const test::RunResult v = test::runGtn("validate " + again + " --against " + spx_);
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  EXPECT_EQ(meshSummary(infoJson(again)), meshSummary(infoJson(spx_)));
  EXPECT_EQ(test::runGtn("convert " + gtn + " -o " + gtn).exit_code, 2);  // never over its input
  // From standard input too (a .gtn stream; a mesh file is named instead).
  const test::RunResult piped = test::runShell("cat " + gtn + " | " + GTN_BINARY + " convert - -o " + dir_ + "/p.vtu");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  EXPECT_EQ(test::readFile(dir_ + "/p.vtu"), test::readFile(dir_ + "/e.vtu"));
  const test::RunResult text = test::runShell("cat " + spx_ + " | " + GTN_BINARY + " convert - -o " + dir_ + "/q.vtu");
  EXPECT_EQ(text.exit_code, 1) << text.err;
  EXPECT_NE(text.err.find("standard input is read as a .gtn stream"), std::string::npos) << text.err;
}

// --levels K on a mesh whose merge tree runs out first writes fewer levels: with a warning that says
// how many (it said nothing).
TEST_F(GtnCli, FewerLevelsThanAskedAreReported) {
  const std::string gtn = dir_ + "/spx.gtn";
  test::RunResult r = test::runGtn("convert " + spx_ + " -o " + gtn + " --levels 12");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = infoJson(gtn);
  ASSERT_LT(j["levels"].size(), 13u);
  EXPECT_NE(r.err.find("--levels 12: the merge tree has"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("enough for " + std::to_string(j["levels"].size() - 1) + " level(s) beyond level 0"),
            std::string::npos)
      << r.err;
  r = test::runGtn("convert " + spx_ + " -o " + gtn + " --levels 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("--levels"), std::string::npos) << r.err;
  EXPECT_EQ(infoJson(gtn)["levels"].size(), 4u);
}

TEST_F(GtnCli, ExportRoundTripsToVtuVtkAndTetgen) {
  const std::string gtn = dir_ + "/spx.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + gtn).exit_code, 0);
  test::RunResult r = test::runGtn("export " + gtn + " -o " + dir_ + "/spx.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(meshSummary(infoJson(dir_ + "/spx.vtu")), meshSummary(infoJson(spx_)));
  // Legacy .vtk, from the .gtn and straight from the source: the same file.
  r = test::runGtn("export " + gtn + " -o " + dir_ + "/spx_out.vtk");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(meshSummary(infoJson(dir_ + "/spx_out.vtk")), meshSummary(infoJson(spx_)));
  r = test::runGtn("convert " + dir_ + "/spx.vtu -o " + dir_ + "/spx_conv.vtk");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::readFile(dir_ + "/spx_conv.vtk"), test::readFile(dir_ + "/spx_out.vtk"));
  r = test::runGtn("export " + gtn + " -o " + dir_ + "/spx.node --level 0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::fileExists(dir_ + "/spx.ele"));
  const json t = infoJson(dir_ + "/spx.node");
  EXPECT_EQ(t["points"], 2896);
  EXPECT_EQ(t["tets"], 12936);
  EXPECT_EQ(t["boundary_faces"], 2760);
  // A .gtn through a pipe exports too.
  r = test::runShell("cat " + gtn + " | " + GTN_BINARY + " export - -o " + dir_ + "/piped.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::readFile(dir_ + "/piped.vtu"), test::readFile(dir_ + "/spx.vtu"));
}

TEST_F(GtnCli, RealDatasetWithCellField) {
  // TetGen output with a region attribute: a cell field through .gtn and back.
  const std::string src = test::dataPath("tetgen/cornellbox_orig.1.node");
  const std::string gtn = dir_ + "/box.gtn";
  test::RunResult r = test::runGtn("convert " + src + " -o " + gtn);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = infoJson(gtn);
  EXPECT_EQ(j["points"], 331);
  EXPECT_EQ(j["tets"], 1631);
  EXPECT_EQ(meshSummary(j), meshSummary(infoJson(src)));
  r = test::runGtn("export " + gtn + " -o " + dir_ + "/box.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(meshSummary(infoJson(dir_ + "/box.vtu")), meshSummary(j));
}

// --fields exports the named point and cell fields alone, with the values a full export has (their
// ranges agree), on a stored level and through the simplifier; an unknown name lists the fields.
TEST_F(GtnCli, ExportSomeFields) {
  const std::string gtn = dir_ + "/lv.gtn";
  test::RunResult r = test::runGtn("convert " + test::dataPath("vtu/lv_guccione.vtu") + " -o " + gtn);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& view : {std::string(""), std::string(" --ratio 0.6")}) {
    SCOPED_TRACE(view);
    r = test::runGtn("export " + gtn + view + " -o " + dir_ + "/all.vtu");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = test::runGtn("export " + gtn + view + " -o " + dir_ + "/some.vtu --fields Stress,E_Jacobian");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json all = infoJson(dir_ + "/all.vtu"), some = infoJson(dir_ + "/some.vtu");
    ASSERT_EQ(all["fields"].size(), 12u);
    json want = json::array();
    for (const json& f : all["fields"])
      if (f["name"] == "Stress" || f["name"] == "E_Jacobian") want.push_back(f);
    ASSERT_EQ(want.size(), 2u);
    EXPECT_EQ(some["fields"], want);
    EXPECT_EQ(some["tets"], all["tets"]);
    EXPECT_EQ(some["volume"], all["volume"]);
  }
  r = test::runGtn("export " + gtn + " -o " + dir_ + "/none.vtu --fields Stress,stress");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no field named 'stress' (fields: Displacement, VonMises_stress"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fileExists(dir_ + "/none.vtu"));
}

// An importer's warning that names its file first is not prefixed with the same name again; one
// about a file of a basename input keeps the input's name in front.
TEST_F(GtnCli, WarningsNameTheirFileOnce) {
  const std::string base = dir_ + "/quad";
  {
    std::FILE* f = std::fopen((base + ".node").c_str(), "w");
    ASSERT_TRUE(f);
    std::fputs(
        "10 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.5 0 0\n6 0.5 0.5 0\n7 0 0.5 0\n"
        "8 0 0 0.5\n9 0.5 0 0.5\n10 0 0.5 0.5\n",
        f);
    std::fclose(f);
    f = std::fopen((base + ".ele").c_str(), "w");
    ASSERT_TRUE(f);
    std::fputs("1 10 0\n1 1 2 3 4 5 6 7 8 9 10\n", f);
    std::fclose(f);
  }
  test::RunResult r = test::runGtn("info " + base + ".ele");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gtn: warning: " + base + ".ele: 10-node (quadratic) tetrahedra"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(base + ".ele: " + base + ".ele:"), std::string::npos) << r.err;
  r = test::runGtn("convert " + base + " -o " + dir_ + "/quad.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Given by its basename, the mesh's files are named by the warning itself: no prefix.
  EXPECT_NE(r.err.find("gtn: warning: " + base + ".ele: 10-node"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(base + ": " + base + ".ele:"), std::string::npos) << r.err;
  // Options that do nothing for these inputs or outputs say so (they were ignored without a word).
  r = test::runGtn("convert " + base + " -o " + dir_ + "/quad.vtk --compress");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(dir_ + "/quad.vtk: --compress applies to .vtu outputs only; ignored"), std::string::npos)
      << r.err;
  r = test::runGtn("convert " + base + " -o " + dir_ + "/quad.vtu --compress");
  EXPECT_EQ(r.err.find("--compress"), std::string::npos) << r.err;
  r = test::runGtn("info " + base + ".ele --merge-tree");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--merge-tree describes the merge tree of a .gtn file; a mesh has none"), std::string::npos)
      << r.err;
}

// A mesh file given to export is a usage error that names the command that converts it.
TEST_F(GtnCli, ExportOfAMeshFilePointsToConvert) {
  const test::RunResult r = test::runGtn("export " + spx_ + " -o " + dir_ + "/spx.vtu");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("a legacy VTK file, not .gtn"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("use 'gtn convert " + spx_ + " -o " + dir_ + "/spx.vtu'"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fileExists(dir_ + "/spx.vtu"));
}

TEST_F(GtnCli, ExitCodes) {
  const std::string gtn = dir_ + "/spx.gtn";
  ASSERT_EQ(test::runGtn("convert " + spx_ + " -o " + gtn).exit_code, 0);
  test::RunResult r = test::runGtn("export " + gtn + " -o " + dir_ + "/x.vtu --level 999");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("level(s)"), std::string::npos) << r.err;
  EXPECT_EQ(test::runGtn("export " + gtn + " -o " + dir_ + "/x.png").exit_code, 2);
  EXPECT_EQ(test::runGtn("export " + gtn).exit_code, 2);
  r = test::runGtn("info " + dir_ + "/missing.gtn");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  // Corrupt data in level 0: exit 1 with file, offset and reason; a failed export leaves no output.
  const json j = infoJson(gtn);
  uint64_t level0_begin = 0;
  for (const json& s : j["sections"])
    if (s["name"] == "prefix" || s["name"] == "header") level0_begin += s["bytes"].get<uint64_t>();
  std::string bytes = test::readFile(gtn);
  bytes[level0_begin + j["levels"][0]["bytes"].get<uint64_t>() / 2] ^= 0x20;
  test::writeFile(dir_ + "/bad.gtn", bytes);
  r = test::runGtn("export " + dir_ + "/bad.gtn -o " + dir_ + "/bad.vtu");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("bad.gtn: byte offset"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fileExists(dir_ + "/bad.vtu"));
  r = test::runGtn("info " + dir_ + "/bad.gtn");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  // Not a .gtn file from a pipe.
  r = test::runShell("cat " + spx_ + " | " + GTN_BINARY + " info -");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("not a .gtn file"), std::string::npos) << r.err;
  // A damaged .gtn input to convert fails with the reader's reason and writes nothing.
  r = test::runGtn("convert " + dir_ + "/bad.gtn -o " + dir_ + "/again.vtu");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(dir_ + "/bad.gtn"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fileExists(dir_ + "/again.vtu"));
}

// gtn info exits 0 on every valid conformance file and 1 on every must-fail one, naming the file and
// the reason its NAME.expected gives ("outcome: valid" / "outcome: invalid", "message: ...").
TEST_F(GtnCli, ConformanceFilesThroughInfo) {
  const std::string dir = std::string(GTN_SOURCE_DIR) + "/samples/conformance/";
  size_t valid = 0, invalid = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".expected") continue;
    std::string outcome, message;
    std::istringstream lines(test::readFile(entry.path().string()));
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("outcome: ", 0) == 0) outcome = line.substr(9);
      if (line.rfind("message: ", 0) == 0) message = line.substr(9);
    }
    const std::string gtn = entry.path().stem().string() + ".gtn";
    const test::RunResult r = test::runGtn("info " + dir + gtn);
    if (outcome == "valid") {
      ++valid;
      EXPECT_EQ(r.exit_code, 0) << gtn << ": " << r.err;
    } else {
      ++invalid;
      EXPECT_EQ(outcome, "invalid") << entry.path();
      EXPECT_EQ(r.exit_code, 1) << gtn;
      EXPECT_NE(r.err.find(gtn), std::string::npos) << r.err;
      EXPECT_FALSE(message.empty()) << entry.path();
      EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    }
  }
  EXPECT_GE(valid, 20u);
  EXPECT_GE(invalid, 11u);
}

}  // namespace
}  // namespace gtn
