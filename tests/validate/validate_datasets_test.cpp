// Every .gtn file the project writes from the real datasets validates clean, and --against its source
// passes: `gtn convert` then `gtn validate --json --against`, both through the binary, as a user runs
// them. Warnings are allowed only for what the source itself has (zero-volume tetrahedra of the
// PLOT3D grids); infos (unreferenced points of the source) are allowed.
#include <gtest/gtest.h>

#include <random>

#include <nlohmann/json.hpp>

#include "simplify/levels.h"
#include "validate/validate_fixtures.h"

namespace gtn::test {
namespace {

struct DatasetCase {
  const char* name;
  std::vector<std::string> files;  // relative to the data directory
  std::string convert_options;     // also passed to validate where they concern the import
  std::string import_options;
};

// Test names and failure messages show the case's name, not its bytes.
void PrintTo(const DatasetCase& c, std::ostream* os) { *os << c.name; }

std::string joined(const std::vector<std::string>& files) {
  std::string s;
  for (const std::string& f : files) {
    s += ' ';
    s += dataPath(f);
  }
  return s;
}

class ValidateDatasets : public ::testing::TestWithParam<DatasetCase> {};

TEST_P(ValidateDatasets, ConvertedFileIsCleanAndEqualsItsSource) {
  const DatasetCase& c = GetParam();
  const std::string dir = tempDir(std::string("validate-datasets-") + c.name);
  const std::string gtn = dir + "/" + c.name + ".gtn";
  const RunResult conv =
      runGtn("convert" + joined(c.files) + " -o " + gtn + " " + c.convert_options + " " + c.import_options);
  ASSERT_EQ(conv.exit_code, 0) << conv.err;

  const RunResult val = runGtn("validate --json " + gtn + " --against" + joined(c.files) + " " + c.import_options);
  ASSERT_EQ(val.exit_code, 0) << val.out << val.err;
  const nlohmann::json j = nlohmann::json::parse(val.out);
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["counts"]["error"].get<int>(), 0) << val.out;
  // Checked against its source, a file has no warnings: the zero-volume tetrahedra of the PLOT3D grids
  // are the source's (level 0 equals it, the levels descend from level 0 by the replayed merges).
  EXPECT_EQ(j["counts"]["warning"].get<int>(), 0) << val.out;
  uint64_t flat_from_source = 0;
  for (const auto& m : j["messages"]) {
    if (m["code"] == "ZERO_VOLUME_TET_FROM_SOURCE") flat_from_source += m["count"].get<uint64_t>();
  }
  const bool zero_volume_source = std::string(c.name).rfind("bluntfin", 0) == 0;
  EXPECT_EQ(flat_from_source > 0, zero_volume_source) << val.out;
  // The file has what convert was asked for: a merge tree unless told otherwise, and mip levels
  // down to a small mesh (none for a mesh that is already small, such as cornellbox's 1631
  // tetrahedra: a level stops at 256 points or a piece's 4096 tetrahedra; a level of half the points
  // keeps less than half of the tetrahedra, about).
  const size_t levels = j["info"]["levels"].size();
  if (c.convert_options.find("--levels 0") != std::string::npos) {
    EXPECT_EQ(levels, 1u);
  } else {
    const uint64_t points = j["info"]["levels"][0]["points"].get<uint64_t>();
    const uint64_t tets = j["info"]["levels"][0]["tets"].get<uint64_t>();
    const LevelOptions automatic;
    if (points - points / 2 >= automatic.min_points && tets >= 3 * automatic.min_tets) {
      EXPECT_GE(levels, 2u);
    } else if (points - points / 2 < automatic.min_points || tets < automatic.min_tets) {
      EXPECT_EQ(levels, 1u);
    }
    EXPECT_GT(j["info"]["merge_tree"]["merges"].get<uint64_t>(), 0u);
    // All levels together take at most twice level 0's bytes (the paper's bound, which the automatic
    // levels keep), and the large grids still get several levels within it.
    const RunResult info = runGtn("info --json " + gtn);
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const nlohmann::json ij = nlohmann::json::parse(info.out);
    ASSERT_EQ(ij["levels"].size(), levels);
    // Every level but the last names the next level's vertices where it is one unstructured piece
    // (a grid's level 0 may store all its nodes as a structured piece), the last stores all of its own;
    // reading level i reads it and the coarser levels, about half of what reading level i - 1 reads.
    const auto& ls = ij["levels"];
    EXPECT_FALSE(ls[levels - 1]["names_next_level"].get<bool>()) << info.out;
    for (size_t i = 1; i + 1 < levels; ++i) EXPECT_TRUE(ls[i]["names_next_level"].get<bool>()) << i << info.out;
    std::vector<uint64_t> read(levels + 1, 0);
    for (size_t i = levels; i-- > 0;) read[i] = read[i + 1] + ls[i]["bytes"].get<uint64_t>();
    for (size_t i = 1; i < levels; ++i) EXPECT_LT(double(read[i]), 0.62 * double(read[i - 1])) << i << info.out;
    if (points >= 40000) {
      EXPECT_GE(levels, 2u) << info.out;  // a grid stores only its coarse levels, down to 4096 tetrahedra
    }
  }
  // Without --against only level 0's flat tetrahedra stay warnings: the validator cannot tell that the
  // source had them. The levels' are still known to descend from level 0's.
  const RunResult alone = runGtn("validate --json --max-issues 1000 " + gtn);
  ASSERT_EQ(alone.exit_code, 0) << alone.out << alone.err;
  const nlohmann::json a = nlohmann::json::parse(alone.out);
  for (const auto& m : a["messages"]) {
    if (m["code"] == "ZERO_VOLUME_TET") {
      EXPECT_EQ(m["path"].get<std::string>().rfind("/levels/0/", 0), 0u) << m.dump();
    }
  }
  EXPECT_EQ(a["counts"]["warning"].get<uint64_t>() > 0, zero_volume_source) << alone.out;

  EXPECT_EQ(runGtn("validate --quick " + gtn).exit_code, 0);
}

INSTANTIATE_TEST_SUITE_P(
    RealData, ValidateDatasets,
    ::testing::Values(
        DatasetCase{"spx", {"vtk/spx.vtk"}, "", ""}, DatasetCase{"spx_compressed", {"vtk/spx.vtk"}, "--compress", ""},
        DatasetCase{"spx_level0_only", {"vtk/spx.vtk"}, "--levels 0 --no-merge-tree", ""},
        DatasetCase{"cornell_spheres", {"tetgen/cornell_spheres.1.ele"}, "", ""},
        DatasetCase{"cornellbox", {"tetgen/cornellbox_orig.1.ele"}, "", ""},
        DatasetCase{"bunny", {"medit/bunny.mesh"}, "", ""}, DatasetCase{"lv_guccione", {"vtu/lv_guccione.vtu"}, "", ""},
        DatasetCase{"raptor", {"vtu/raptorTetra_19409.vtu"}, "", ""},
        DatasetCase{"ossicles", {"vtu/Ossicles.vtu"}, "", ""},
        DatasetCase{"fire_hexahedra", {"vtu/fire_ug.vtu"}, "", "--split 5"},
        DatasetCase{"bluntfin", {"plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"}, "", ""},
        DatasetCase{"bluntfin_split5", {"plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"}, "", "--split 5"},
        DatasetCase{"combustion", {"plot3d/combxyz.bin", "plot3d/combq.bin"}, "", ""}),
    [](const ::testing::TestParamInfo<DatasetCase>& info) { return std::string(info.param.name); });

// The CLI contract on damaged real files: a bit flip or a truncation is exit code 1 (invalid data),
// never a crash (a signal or a sanitizer's exit code) nor a hang. The in-process test in
// validate_file_test.cpp does a thousand flips; this checks the same through the binary.
TEST(ValidateDatasetsCli, DamagedFilesExitWithOne) {
  const std::string dir = tempDir("validate-datasets-damaged");
  const std::string gtn = dir + "/cornellbox.gtn";
  ASSERT_EQ(runGtn("convert " + dataPath("tetgen/cornellbox_orig.1.ele") + " -o " + gtn).exit_code, 0);
  const Bytes bytes = readBytes(gtn);
  ASSERT_GT(bytes.size(), 1000u);
  std::mt19937_64 rng(6);
  for (int i = 0; i < 24; ++i) {
    Bytes b = bytes;
    size_t at = 0;
    if (i % 3 == 2) {
      b.resize(rng() % b.size());
    } else {
      at = rng() % b.size();
      b[at] ^= static_cast<uint8_t>(1u << (rng() % 8));
    }
    const std::string path = dir + "/damaged-" + std::to_string(i) + ".gtn";
    writeBytes(path, b);
    const RunResult r = runGtn("validate --json --max-issues 5 " + path);
    EXPECT_EQ(r.exit_code, 1) << "case " << i << " (byte " << at << ", size " << b.size() << "): " << r.err;
    if (r.exit_code == 1) {
      const nlohmann::json j = nlohmann::json::parse(r.out);
      EXPECT_GE(j["counts"]["error"].get<int>(), 1);
      EXPECT_LE(j["messages"].size(), 5u);
    }
  }
}

}  // namespace
}  // namespace gtn::test
