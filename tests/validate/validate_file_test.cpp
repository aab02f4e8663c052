// The validator on real .gtn files: valid files the project writes validate clean (and --against
// their source), and the CLI contract (exit codes, JSON report).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "validate/validate_fixtures.h"

namespace gtn::test {
namespace {

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

}  // namespace
}  // namespace gtn::test
