// What a new user sees: convert's summary line and progress (-q silences both; progress only on a
// terminal), the .gtn header's command line without directories, validate --against taking the split
// and --weld from the file, validation of a source mesh file with one line per kind of finding.
// Meshes are generated here.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "test_util.h"

namespace gtn {
namespace {

using test::runGtn;
using test::RunResult;

// A PLOT3D multi-grid file (big-endian, no record markers, float32): blocks of ni x nj x nk points
// side by side along x, each sharing its last i-plane with the next block's first, bit for bit.
std::string plot3dBlocks(int blocks, int ni, int nj, int nk) {
  std::string s;
  auto i32 = [&](uint32_t v) {
    for (int b = 3; b >= 0; --b) s.push_back(static_cast<char>((v >> (8 * b)) & 0xFF));
  };
  i32(static_cast<uint32_t>(blocks));
  for (int b = 0; b < blocks; ++b) {
    i32(static_cast<uint32_t>(ni));
    i32(static_cast<uint32_t>(nj));
    i32(static_cast<uint32_t>(nk));
  }
  for (int b = 0; b < blocks; ++b) {
    const double origin = b * (ni - 1);
    for (int axis = 0; axis < 3; ++axis)
      for (int k = 0; k < nk; ++k)
        for (int j = 0; j < nj; ++j)
          for (int i = 0; i < ni; ++i) {
            const double x = origin + i + 0.125 * j, y = j + 0.25 * k, z = k + 0.0625 * (origin + i);
            i32(std::bit_cast<uint32_t>(static_cast<float>(axis == 0 ? x : axis == 1 ? y : z)));
          }
  }
  return s;
}

uint64_t fileSize(const std::string& path) { return test::readFile(path).size(); }

class UsabilityCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        test::tempDir("gtn-usability-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    vtk_ = dir_ + "/grid.vtk";
    test::writeFile(vtk_, test::shearedHexGridVtk(6));
  }
  std::string dir_, vtk_;
};

// ---- convert's summary line and progress (item 11) ----------------------------------------------

TEST_F(UsabilityCli, ConvertEndsWithASummaryLineWhoseFiguresAreTheFiles) {
  for (const char* ext : {"gtn", "vtu"}) {
    SCOPED_TRACE(ext);
    const std::string out = dir_ + "/grid." + ext;
    const RunResult r = runGtn("convert " + vtk_ + " -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Redirected: no progress, exactly one line.
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
    ASSERT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    std::smatch m;
    const std::regex line(
        "^gtn: (.*) \\(([0-9]+) bytes\\) -> (.*) \\(([0-9]+) bytes\\): ([0-9.]+)% of the input, "
        "([0-9.]+) bits/tet \\(([0-9]+) tetrahedra\\), ([0-9.]+) s\n$");
    ASSERT_TRUE(std::regex_match(r.err, m, line)) << r.err;
    EXPECT_EQ(m[1], vtk_);
    EXPECT_EQ(std::stoull(m[2]), fileSize(vtk_));
    EXPECT_EQ(m[3], out);
    const uint64_t out_bytes = fileSize(out);
    EXPECT_EQ(std::stoull(m[4]), out_bytes);
    char want[64];
    std::snprintf(want, sizeof want, "%.2f",
                  100.0 * static_cast<double>(out_bytes) / static_cast<double>(fileSize(vtk_)));
    EXPECT_EQ(m[5], want);
    const uint64_t tets = std::stoull(m[7]);
    EXPECT_EQ(tets, 6u * 6 * 6 * 6);  // 216 hexahedra, 6 tetrahedra each
    std::snprintf(want, sizeof want, "%.2f", 8.0 * static_cast<double>(out_bytes) / static_cast<double>(tets));
    EXPECT_EQ(m[6], want);
    EXPECT_GE(std::stod(m[8]), 0.0);

    const RunResult q = runGtn("convert " + vtk_ + " -o " + out + " -q");
    ASSERT_EQ(q.exit_code, 0) << q.err;
    EXPECT_EQ(q.err, "");
  }
  // A TetGen output is three files; their sizes add up, and so do those of a TetGen input.
  const RunResult t = runGtn("convert " + vtk_ + " -o " + dir_ + "/t.ele");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const uint64_t tetgen_bytes = fileSize(dir_ + "/t.node") + fileSize(dir_ + "/t.ele") + fileSize(dir_ + "/t.face");
  EXPECT_NE(t.err.find(" -> " + dir_ + "/t.node + " + dir_ + "/t.ele + " + dir_ + "/t.face (" +
                       std::to_string(tetgen_bytes) + " bytes)"),
            std::string::npos)
      << t.err;
  const RunResult back = runGtn("convert " + dir_ + "/t -o " + dir_ + "/t.gtn");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_NE(back.err.find("gtn: " + dir_ + "/t.node + " + dir_ + "/t.ele + " + dir_ + "/t.face (" +
                          std::to_string(tetgen_bytes) + " bytes) -> "),
            std::string::npos)
      << back.err;
  // Several inputs: their sizes add up.
  const std::string xyz = dir_ + "/two.xyz";
  test::writeFile(xyz, plot3dBlocks(2, 5, 4, 3));
  const RunResult r = runGtn("convert " + xyz + " -o " + dir_ + "/two.gtn --weld");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gtn: " + xyz + " (" + std::to_string(fileSize(xyz)) + " bytes) -> " + dir_ + "/two.gtn (" +
                       std::to_string(fileSize(dir_ + "/two.gtn")) + " bytes)"),
            std::string::npos)
      << r.err;
}

// Under a pseudo-terminal (script(1) runs the command on one) convert draws its progress line on
// standard error: stages with a percentage, redrawn in place; -q draws nothing.
TEST_F(UsabilityCli, ProgressShowsOnATerminalOnly) {
  if (test::runShell("command -v script").exit_code != 0) GTEST_SKIP() << "script(1) (util-linux) is not installed";
  // A chroot without /dev/pts has no pseudo-terminal to give a program: nothing can be a terminal there.
  if (test::runShell("script -qec true /dev/null").exit_code != 0)
    GTEST_SKIP() << "this system cannot create a pseudo-terminal (no /dev/pts)";
  const std::string cmd = std::string(GTN_BINARY) + " convert " + vtk_ + " -o " + dir_ + "/p.gtn --levels 2";
  const RunResult tty = test::runShell("script -qec '" + cmd + "' /dev/null");
  ASSERT_EQ(tty.exit_code, 0) << tty.out << tty.err;
  for (const char* stage : {"gtn convert: import", "gtn convert: rank merges", "gtn convert: encode level 0 (3 levels)",
                            "gtn convert: verify level 2 (3 levels)"})
    EXPECT_NE(tty.out.find(stage), std::string::npos) << stage << "\n" << tty.out;
  EXPECT_TRUE(std::regex_search(tty.out, std::regex("encode level 1 \\(3 levels\\) +[0-9]+%"))) << tty.out;
  EXPECT_NE(tty.out.find('\r'), std::string::npos);
  // The summary line follows the cleared progress line.
  EXPECT_NE(tty.out.find(" bits/tet "), std::string::npos) << tty.out;

  const RunResult quiet = test::runShell("script -qec '" + cmd + " -q' /dev/null");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.out << quiet.err;
  EXPECT_EQ(quiet.out.find("gtn convert:"), std::string::npos) << quiet.out;
  EXPECT_EQ(quiet.out.find("bits/tet"), std::string::npos) << quiet.out;

  const RunResult redirected = test::runShell(cmd);
  ASSERT_EQ(redirected.exit_code, 0) << redirected.err;
  EXPECT_EQ(redirected.err.find("gtn convert:"), std::string::npos) << redirected.err;
  EXPECT_EQ(redirected.err.find('\r'), std::string::npos) << redirected.err;

  // export and render show the share of the level decoded, on a terminal only.
  const std::string gtn = dir_ + "/p.gtn";
  const std::vector<std::pair<std::string, std::string>> decoders = {
      {"export " + gtn + " -o " + dir_ + "/p.vtu", "gtn export: decode"},
      {"render " + gtn + " --size 16x16 -o " + dir_ + "/p.png", "gtn render: decode and render level 0"}};
  for (const auto& [args, stage] : decoders) {
    SCOPED_TRACE(args);
    const RunResult shown = test::runShell("script -qec '" + std::string(GTN_BINARY) + " " + args + "' /dev/null");
    ASSERT_EQ(shown.exit_code, 0) << shown.out;
    EXPECT_NE(shown.out.find(stage), std::string::npos) << shown.out;
    const RunResult plain = runGtn(args);
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    EXPECT_EQ(plain.err.find(stage), std::string::npos) << plain.err;
  }
}

// ---- the header's command line (item 12a) -------------------------------------------------------

// On glibc, gtn starts itself again once with glibc.malloc.hugetlb=1 added to GLIBC_TUNABLES: its
// arguments and its standard input reach the command as given (the decode of a file piped in reports
// what the decode of the file does), a tunable the user set is kept, and one the user set for huge
// pages is left alone (nothing is started again, so nothing loops).
#if defined(__GLIBC__) && defined(__linux__)
TEST_F(UsabilityCli, StartsItselfAgainOnceAskingMallocForHugePages) {
  const std::string gtn = dir_ + "/grid.gtn";
  ASSERT_EQ(runGtn("convert " + vtk_ + " -o " + gtn + " -q").exit_code, 0);
  const RunResult direct = runGtn("decode " + gtn + " --json");
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  const nlohmann::json want = nlohmann::json::parse(direct.out);
  for (const std::string env :
       {"env -u GLIBC_TUNABLES", "GLIBC_TUNABLES=glibc.malloc.check=0", "GLIBC_TUNABLES=glibc.malloc.hugetlb=0"}) {
    SCOPED_TRACE(env);
    const RunResult r = test::runShell(env + " " + GTN_BINARY + " decode - --json < " + gtn);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json got = nlohmann::json::parse(r.out, nullptr, false);
    ASSERT_FALSE(got.is_discarded()) << r.out;
    EXPECT_EQ(got["points"], want["points"]);
    EXPECT_EQ(got["tets"], want["tets"]);
    EXPECT_EQ(got["bytes"], want["bytes"]);
    EXPECT_EQ(got["input"], "-");
  }
  // Started through the dynamic loader, it is not started again (the loader would read the
  // arguments as its own) and runs as it is.
  const RunResult loader = test::runShell("$(readelf -p .interp " + std::string(GTN_BINARY) +
                                          " | awk '/\\]/ {print $NF}') " + GTN_BINARY + " --version");
  ASSERT_EQ(loader.exit_code, 0) << loader.err;
  EXPECT_EQ(loader.out.rfind("gtn ", 0), 0u) << loader.out;
  // The environment of the command started again, while it waits for its input ...
  const RunResult seen = test::runShell("(sleep 2; cat " + gtn + ") | env -u GLIBC_TUNABLES " + GTN_BINARY +
                                        " decode - > /dev/null & pid=$!; sleep 1; tr '\\0' '\\n' < /proc/$pid/environ "
                                        "| grep '^GLIBC_TUNABLES='; cat /proc/$pid/comm; wait $pid");
  ASSERT_EQ(seen.exit_code, 0) << seen.err;
  // ... and its name, the program's (ps, top and perf show it).
  EXPECT_EQ(seen.out, "GLIBC_TUNABLES=glibc.malloc.hugetlb=1\ngtn\n");
}
#endif

TEST_F(UsabilityCli, TheHeaderStoresFileNamesWithoutDirectories) {
  const std::string out = dir_ + "/named.gtn";
  ASSERT_EQ(runGtn("convert " + vtk_ + " --output=" + out + " --levels 1 -q").exit_code, 0);
  const std::string bytes = test::readFile(out);
  EXPECT_EQ(bytes.find(dir_), std::string::npos) << "the file holds the directory " << dir_;
  const RunResult info = runGtn("info " + out + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out);
  ASSERT_TRUE(j.contains("provenance")) << info.out;
  EXPECT_EQ(j["provenance"]["command_line"], "gtn convert grid.vtk --output=named.gtn --levels 1 -q");
}

// ---- validate --against reads the split and --weld (item 12b) ----------------------------------

TEST_F(UsabilityCli, ValidateAgainstTakesSplitAndWeldFromTheFile) {
  const std::string xyz = dir_ + "/blocks.xyz";
  test::writeFile(xyz, plot3dBlocks(2, 5, 4, 3));
  const std::string gtn = dir_ + "/blocks.gtn";
  const RunResult c = runGtn("convert " + xyz + " -o " + gtn + " --split 5 --weld -q");
  ASSERT_EQ(c.exit_code, 0) << c.err;

  const RunResult v = runGtn("validate " + gtn + " --against " + xyz + " --json");
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  const nlohmann::json j = nlohmann::json::parse(v.out);
  EXPECT_TRUE(j["valid"].get<bool>()) << v.out;
  EXPECT_EQ(j["info"]["against"]["from_metadata"], "--split 5, --weld") << v.out;

  // Given on the command line, --split wins; the mismatch then says how the file was made.
  const RunResult six = runGtn("validate " + gtn + " --against " + xyz + " --split 6");
  EXPECT_EQ(six.exit_code, 1) << six.out;
  EXPECT_NE(six.out.find("SOURCE_COUNT_MISMATCH"), std::string::npos) << six.out;
  EXPECT_NE(six.out.find("imported with --split 6 --weld (--weld from the file's metadata)"), std::string::npos)
      << six.out;
  EXPECT_NE(six.out.find("the file was made by: gtn convert blocks.xyz -o blocks.gtn --split 5 --weld -q"),
            std::string::npos)
      << six.out;

  // A file converted with the defaults records nothing, and validates against the defaults.
  ASSERT_EQ(runGtn("convert " + xyz + " -o " + dir_ + "/plain.gtn -q").exit_code, 0);
  const RunResult info = runGtn("info " + dir_ + "/plain.gtn --json");
  EXPECT_EQ(info.out.find("import.split"), std::string::npos) << info.out;
  const RunResult plain = runGtn("validate " + dir_ + "/plain.gtn --against " + xyz);
  EXPECT_EQ(plain.exit_code, 0) << plain.out;
}

// ---- validating a source mesh file: one line per kind (item 12c) --------------------------------

TEST_F(UsabilityCli, ValidatingAMeshFileGivesOneLinePerKind) {
  const std::string mirrored = dir_ + "/mirrored.vtk";
  test::writeFile(mirrored, test::shearedHexGridVtk(5, /*mirrored=*/true));
  const RunResult v = runGtn("validate " + mirrored);
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  // 125 hexahedra stored inside out (750 tetrahedra once split): one line for them all, and the summary
  // counts that line.
  std::vector<std::string> lines;
  for (size_t at = 0, next; at < v.out.size(); at = next + 1) {
    next = v.out.find('\n', at);
    if (next == std::string::npos) next = v.out.size();
    lines.push_back(v.out.substr(at, next - at));
  }
  ASSERT_EQ(lines.size(), 2u) << v.out;
  EXPECT_EQ(lines[0].rfind("warning: CELLS_REORIENTED: 750 cells stored with negative orientation", 0), 0u) << v.out;
  EXPECT_EQ(lines[0].find("first:"), std::string::npos) << v.out;
  EXPECT_EQ(lines[1], mirrored + ": valid (0 errors, 1 warning (750 items), 0 infos)");
}

}  // namespace
}  // namespace gtn
