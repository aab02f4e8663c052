// The validator on real .gtn files: valid files the project writes validate clean (and --against
// their source), and the CLI contract (exit codes, JSON report).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>

#include <nlohmann/json.hpp>

#include "codec/pieces.h"
#include "convert/import.h"
#include "format/gtn_file.h"
#include "mesh/mesh_stats.h"
#include "validate/validate_fixtures.h"

namespace gtn::test {
namespace {

// A level of several pieces whose piece table gives a piece a box that misses some of its vertices
// (the file otherwise intact): gtn validate says which piece, since a region read would skip it.
TEST(ValidateFile, APieceBoxThatMissesItsVerticesIsReported) {
  const std::string dir = tempDir("validate-piece-box");
  const TetMesh mesh = makeGrid(16, 14, 12);
  auto encoded = encodePieces(mesh, EncodeOptions{}, kMinPieceTets);
  ASSERT_TRUE(encoded.isOk()) << encoded.status().message();
  ASSERT_GE(encoded->pieces.size(), 3u);
  for (const bool shrunk : {false, true}) {
    SCOPED_TRACE(shrunk ? "piece 1's box shrunk" : "as encoded");
    auto level = std::make_shared<PiecedLevel>(*encoded);
    if (shrunk) level->pieces[1].bbox_max[0] = level->pieces[1].bbox_min[0];
    GtnLevelInput in;
    in.mesh = &mesh;
    in.encoded = level;
    GtnWriteOptions wo;
    const std::string path = dir + (shrunk ? "/shrunk.gtn" : "/pieces.gtn");
    ASSERT_TRUE(writeGtnFile(path, {in}, wo).isOk());
    StatusOr<ValidationReport> r = validateGtnFile(path, {});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->count(IssueCode::kBoundingBoxMismatch), shrunk ? 1u : 0u) << r->toText(path);
    if (shrunk) EXPECT_NE(r->toText(path).find("/levels/0/pieces/1"), std::string::npos) << r->toText(path);
  }
}

TEST(ValidateFile, GridWithLevelsIsClean) {
  const std::string dir = tempDir("validate-grid");
  const TetMesh mesh = makeGrid(6, 5, 4);
  writeValidGtn(dir + "/grid.gtn", mesh, 3);
  StatusOr<ValidationReport> r = validateGtnFile(dir + "/grid.gtn", {});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_FALSE(r->hasErrors()) << r->toText("grid.gtn");
  EXPECT_EQ(r->count(Severity::kWarning), 0u) << r->toText("grid.gtn");
  EXPECT_EQ(r->info()["levels"].size(), 4u);
  EXPECT_GT(r->info()["merge_tree"]["merges"].get<uint64_t>(), 0u);
}

}  // namespace
}  // namespace gtn::test

namespace gtn::test {
namespace {

struct SpxFile {
  std::string dir, gtn;
  Bytes bytes;
};

// spx.vtk with three mip levels, written once for the tests below.
const SpxFile& spxFile() {
  static SpxFile f = [] {
    SpxFile s;
    s.dir = tempDir("validate-spx");
    s.gtn = s.dir + "/spx.gtn";
    StatusOr<ImportResult> imported = importMesh({dataPath("vtk/spx.vtk")}, {});
    EXPECT_TRUE(imported.isOk()) << imported.status().message();
    writeValidGtn(s.gtn, imported->mesh, 3);
    s.bytes = readBytes(s.gtn);
    return s;
  }();
  return f;
}

TEST(ValidateFile, SpxIsCleanAndEqualsItsSource) {
  const SpxFile& f = spxFile();
  ASSERT_FALSE(f.bytes.empty());
  ValidateOptions options;
  options.against = {dataPath("vtk/spx.vtk")};
  StatusOr<ValidationReport> r = validateGtnFile(f.gtn, options);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_FALSE(r->hasErrors()) << r->toText(f.gtn);
  EXPECT_EQ(r->info()["levels"].size(), 4u);
  EXPECT_EQ(r->info()["levels"][0]["inverted"].get<uint64_t>(), 0u);

  // A different source is caught: spx with one coordinate changed in its last bit.
  StatusOr<ImportResult> imported = importMesh({dataPath("vtk/spx.vtk")}, {});
  ASSERT_TRUE(imported.isOk());
  TetMesh other = imported->mesh;
  other.coords[7] = std::nextafter(other.coords[7], 1e300);
  ValidationReport against(100);
  compareWithSource(r.isOk() ? imported->mesh : other, other, against);
  EXPECT_EQ(errorCodeSet(against), (std::set<std::string>{"SOURCE_MESH_MISMATCH"})) << against.toText("x");
}

// A mesh with errors of its own (two tetrahedra overlapping) is refused: convert names the errors
// `gtn validate` would report, exits 1 and writes nothing (a file already there is left as it was), so
// that every file it writes validates. --keep-invalid stores it as it is, with a warning, and validate
// then reports the errors. A clean mesh gets neither.
TEST(ValidateFile, ConvertRefusesAMeshWithErrorsOfItsOwn) {
  const std::string dir = tempDir("validate-overlap");
  writeFile(dir + "/m.node", "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.1 0.1 0.1\n");
  writeFile(dir + "/m.ele", "2 4 0\n1 1 2 3 4\n2 1 2 3 5\n");
  for (const char* levels : {"", " --levels 0 --no-merge-tree"}) {
    SCOPED_TRACE(levels);
    writeFile(dir + "/m.gtn", "what was there");
    const RunResult c = runGtn("convert " + dir + "/m.node -o " + dir + "/m.gtn" + std::string(levels));
    EXPECT_EQ(c.exit_code, 1) << c.err;
    EXPECT_NE(c.err.find("m.node: the mesh has errors that `gtn validate` would report on the file "
                         "(BOUNDARY_ORIENTATION"),
              std::string::npos)
        << c.err;
    EXPECT_NE(c.err.find("nothing was written (--keep-invalid"), std::string::npos) << c.err;
    EXPECT_EQ(readFile(dir + "/m.gtn"), "what was there");
    const RunResult k = runGtn("convert " + dir + "/m.node -o " + dir + "/m.gtn --keep-invalid" + std::string(levels));
    ASSERT_EQ(k.exit_code, 0) << k.err;
    EXPECT_NE(k.err.find("the mesh has errors that `gtn validate` reports on the file too (BOUNDARY_ORIENTATION"),
              std::string::npos)
        << k.err;
    const RunResult v = runGtn("validate " + dir + "/m.gtn");
    EXPECT_EQ(v.exit_code, 1) << v.out;
    EXPECT_NE(v.out.find("BOUNDARY_ORIENTATION"), std::string::npos) << v.out;
  }
  // Three tetrahedra on one face: a mesh the encoder cannot store at all is refused for that, with
  // or without --keep-invalid, which is not offered.
  writeFile(dir + "/n.node", "6 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0 0 -1\n6 0.2 0.2 0.5\n");
  writeFile(dir + "/n.ele", "3 4 0\n1 1 2 3 4\n2 1 3 2 5\n3 1 2 3 6\n");
  for (const char* extra : {"", " --keep-invalid", " --levels 0 --no-merge-tree", " --no-merge-tree --keep-invalid"}) {
    SCOPED_TRACE(extra);
    const RunResult n = runGtn("convert " + dir + "/n.node -o " + dir + "/n.gtn" + std::string(extra));
    EXPECT_EQ(n.exit_code, 1) << n.err;
    EXPECT_NE(n.err.find("n.node: cannot be encoded: 1 faces are shared by three or more tetrahedra"),
              std::string::npos)
        << n.err;
    EXPECT_EQ(n.err.find("--keep-invalid"), std::string::npos) << n.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/n.gtn"));
  }
  const RunResult clean = runGtn("convert " + dataPath("vtk/spx.vtk") + " -o " + dir + "/spx.gtn");
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  EXPECT_EQ(clean.err.find("the mesh has errors"), std::string::npos) << clean.err;
}

TEST(ValidateFile, CliExitCodesAndJson) {
  const SpxFile& f = spxFile();
  RunResult ok = runGtn("validate " + f.gtn + " --json --against " + dataPath("vtk/spx.vtk"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  const nlohmann::json j = nlohmann::json::parse(ok.out);
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["counts"]["error"].get<int>(), 0);
  EXPECT_FALSE(j["truncated"].get<bool>());
  EXPECT_TRUE(j["info"].contains("levels"));

  RunResult text = runGtn("validate " + f.gtn);
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("valid (0 errors"), std::string::npos) << text.out;

  RunResult quick = runGtn("validate --quick " + f.gtn);
  EXPECT_EQ(quick.exit_code, 0) << quick.out;

  Bytes bad = f.bytes;
  bad[bad.size() / 2] ^= 0x10;
  writeBytes(f.dir + "/bad.gtn", bad);
  RunResult invalid = runGtn("validate --json " + f.dir + "/bad.gtn");
  EXPECT_EQ(invalid.exit_code, 1);
  const nlohmann::json b = nlohmann::json::parse(invalid.out);
  EXPECT_FALSE(b["valid"].get<bool>());
  ASSERT_GE(b["messages"].size(), 1u);
  EXPECT_EQ(b["messages"][0]["code"], "CHECKSUM_MISMATCH");
  EXPECT_TRUE(b["messages"][0].contains("offset"));

  EXPECT_EQ(runGtn("validate " + f.dir + "/missing.gtn").exit_code, 3);
  EXPECT_EQ(runGtn("validate").exit_code, 2);
  EXPECT_EQ(runGtn("validate --max-issues 0 " + f.gtn).exit_code, 2);
}

// The JSON report through the binary on a file with defects of several kinds: logical paths of the
// occurrences, aggregation with a count, --max-issues truncating the messages but not the counts, and
// --quick checking the container only (which is intact here).
TEST(ValidateFile, CliJsonPathsAggregationMaxIssuesAndQuick) {
  const std::string dir = tempDir("validate-json");
  TetMesh m;  // the octahedron around vertex 0, two tetrahedra turned inside out, one point unused
  m.coords = {0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 5, 5, 5};
  for (uint32_t x : {1u, 2u})
    for (uint32_t y : {3u, 4u})
      for (uint32_t z : {5u, 6u}) m.tets.push_back({0, x, y, z});
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  std::swap(m.tets[2][2], m.tets[2][3]);
  std::swap(m.tets[5][2], m.tets[5][3]);
  GtnLevelInput l0;
  l0.mesh = &m;
  const std::string path = dir + "/inverted.gtn";
  ASSERT_TRUE(writeGtnFile(path, {l0}, GtnWriteOptions{}).isOk());

  const RunResult full = runGtn("validate --json " + path);
  EXPECT_EQ(full.exit_code, 1) << full.err;
  const nlohmann::json j = nlohmann::json::parse(full.out);
  EXPECT_EQ(j["file"], path);
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_FALSE(j["truncated"].get<bool>());
  EXPECT_EQ(j["counts"]["error"].get<int>(), 2);
  EXPECT_EQ(j["counts"]["warning"].get<int>(), 0);
  EXPECT_EQ(j["counts"]["info"].get<int>(), 2);  // the unused point, no merge tree
  ASSERT_GE(j["messages"].size(), 3u);
  const nlohmann::json& inv = j["messages"][0];
  EXPECT_EQ(inv["code"], "INVERTED_TET");
  EXPECT_EQ(inv["severity"], "error");
  EXPECT_EQ(inv["count"].get<int>(), 2);
  EXPECT_EQ(inv["total"].get<int>(), 8);
  EXPECT_EQ(inv["paths"].size(), 2u);
  EXPECT_EQ(inv["path"].get<std::string>().rfind("/levels/0/tets/", 0), 0u) << inv.dump();
  EXPECT_NE(inv["message"].get<std::string>().find("2 inverted tetrahedra"), std::string::npos) << inv.dump();
  bool unreferenced = false;
  for (const auto& msg : j["messages"]) {
    if (msg["code"] != "UNREFERENCED_POINT") continue;
    unreferenced = true;
    EXPECT_EQ(msg["severity"], "info");
    EXPECT_EQ(msg["path"].get<std::string>().rfind("/levels/0/points/", 0), 0u) << msg.dump();
  }
  EXPECT_TRUE(unreferenced) << full.out;
  EXPECT_EQ(j["info"]["levels"][0]["inverted"].get<int>(), 2);
  EXPECT_EQ(j["info"]["levels"][0]["unreferenced_points"].get<int>(), 1);
  EXPECT_TRUE(j["info"].contains("file_bytes"));
  EXPECT_TRUE(j["info"].contains("sections"));

  const RunResult one = runGtn("validate --json --max-issues 1 " + path);
  EXPECT_EQ(one.exit_code, 1);
  const nlohmann::json t = nlohmann::json::parse(one.out);
  EXPECT_TRUE(t["truncated"].get<bool>());
  EXPECT_EQ(t["messages"].size(), 1u);
  EXPECT_EQ(t["counts"], j["counts"]);
  const RunResult text = runGtn("validate --max-issues 1 " + path);
  EXPECT_NE(text.out.find("--max-issues"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("INVALID (1 error (2 items), 0 warnings, 2 infos)"), std::string::npos) << text.out;

  const RunResult quick = runGtn("validate --quick --json " + path);
  EXPECT_EQ(quick.exit_code, 0) << quick.out;
  const nlohmann::json q = nlohmann::json::parse(quick.out);
  EXPECT_TRUE(q["valid"].get<bool>());
  EXPECT_FALSE(q["info"].contains("levels"));
  EXPECT_EQ(runGtn("validate --quick --against " + path + " " + path).exit_code, 2);
}

// Single-bit flips at random positions and truncations at random lengths: every one is an error,
// none crashes or hangs.
TEST(ValidateFile, BitFlipsAndTruncationsAreAllErrors) {
  const SpxFile& f = spxFile();
  ASSERT_FALSE(f.bytes.empty());
  std::mt19937_64 rng(20261122);
  ValidateOptions options;
  options.max_issues = 8;
  int flips_clean = 0, truncations_clean = 0;
  for (int i = 0; i < 1000; ++i) {
    Bytes b = f.bytes;
    const size_t pos = rng() % b.size();
    b[pos] ^= static_cast<uint8_t>(1u << (rng() % 8));
    const ValidationReport r = validateBytesForTest(b, options);
    if (!r.hasErrors()) {
      ++flips_clean;
      ADD_FAILURE() << "bit flip at byte " << pos << " not reported";
    }
  }
  for (int i = 0; i < 100; ++i) {
    Bytes b = f.bytes;
    b.resize(rng() % b.size());
    const ValidationReport r = validateBytesForTest(b, options);
    if (!r.hasErrors()) ++truncations_clean;
  }
  EXPECT_EQ(flips_clean, 0);
  EXPECT_EQ(truncations_clean, 0);
}

// Mesh files instead of a .gtn file: what the importer changed (import layer), then the mesh checks.
TEST(ValidateMeshFiles, RealDatasetsAreValid) {
  RunResult spx = runGtn("validate --json " + dataPath("vtk/spx.vtk"));
  EXPECT_EQ(spx.exit_code, 0) << spx.err;
  const nlohmann::json j = nlohmann::json::parse(spx.out);
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["info"]["mesh"]["tets"].get<int>(), 12936);
  EXPECT_EQ(j["info"]["mesh"]["points"].get<int>(), 2896);
  EXPECT_EQ(j["info"]["mesh"]["format"], "legacy VTK");

  // Blunt fin split into 5: its 77 flat tetrahedra are warnings, the Q file's padding an import note.
  RunResult fin = runGtn("validate --json --split 5 " + dataPath("plot3d/bluntfinxyz.bin") + " " +
                         dataPath("plot3d/bluntfinq.bin"));
  EXPECT_EQ(fin.exit_code, 0) << fin.err;
  const nlohmann::json f = nlohmann::json::parse(fin.out);
  EXPECT_EQ(f["counts"]["error"].get<int>(), 0);
  std::map<std::string, int> counts;
  for (const nlohmann::json& m : f["messages"]) counts[m["code"].get<std::string>()] = m["count"].get<int>();
  EXPECT_EQ(counts["ZERO_VOLUME_TET"], 77);
  EXPECT_EQ(counts["IMPORT_WARNING"], 1);
  EXPECT_EQ(f["info"]["mesh"]["tets"].get<int>(), 187395);
}

TEST(ValidateMeshFiles, DefectsImportFailuresAndUsage) {
  const std::string dir = tempDir("validate-mesh-files");
  // Tetrahedron 1 repeats tetrahedron 0 with the opposite orientation, and the face (0, 1, 2) has a
  // third tetrahedron, below it: tetrahedra 1 and 2 are stored negatively oriented.
  const std::string head =
      "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n"
      "0 0 0 1 0 0 0 1 0 0 0 1 1 1 -1\n";
  writeFile(dir + "/dup.vtk", head + "CELLS 3 15\n4 0 1 2 3\n4 0 2 1 3\n4 0 1 2 4\nCELL_TYPES 3\n10 10 10\n");
  RunResult dup = runGtn("validate --json " + dir + "/dup.vtk");
  EXPECT_EQ(dup.exit_code, 1) << dup.err;
  const nlohmann::json d = nlohmann::json::parse(dup.out);
  std::map<std::string, int> counts;
  for (const nlohmann::json& m : d["messages"]) counts[m["code"].get<std::string>()] = m["count"].get<int>();
  EXPECT_EQ(counts["DUPLICATE_TET"], 1);
  EXPECT_EQ(counts["NON_MANIFOLD_FACE"], 1);
  EXPECT_EQ(counts["CELLS_REORIENTED"], 2) << dup.out;

  // A file the importer rejects is reported, with the importer's place and reason.
  writeFile(dir + "/short.vtk", head.substr(0, head.size() - 10));
  RunResult bad = runGtn("validate " + dir + "/short.vtk");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.out.find("IMPORT_FAILED: " + dir + "/short.vtk:"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("INVALID (1 error,"), std::string::npos) << bad.out;

  EXPECT_EQ(runGtn("validate " + dir + "/missing.vtk").exit_code, 3);
  EXPECT_EQ(runGtn("validate --quick " + dir + "/dup.vtk").exit_code, 2);
  EXPECT_EQ(runGtn("validate " + dir + "/dup.vtk --against " + dir + "/dup.vtk").exit_code, 2);
  const SpxFile& f = spxFile();
  EXPECT_EQ(runGtn("validate " + f.gtn + " " + f.gtn).exit_code, 2);
}

}  // namespace
}  // namespace gtn::test
