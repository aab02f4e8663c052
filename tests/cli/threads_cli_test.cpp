// --threads N on every command: the same bytes out whatever N (convert, render, export), the bound
// applied (decode reports it), and a clear error for N that is not 1 or more.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "test_util.h"

namespace gtn {
namespace {

class ThreadsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::tempDir("gtn-threads-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    vtk_ = dir_ + "/grid.vtk";
    test::writeFile(vtk_, test::shearedHexGridVtk(8, false, true));
  }
  std::string dir_, vtk_;
};

// convert (level 0, the ranking, mip levels, the checks beside the encoding) and export write the
// same bytes with 1 and 2 threads; the stored command line leaves --threads out.
TEST_F(ThreadsCli, ConvertAndExportByteIdentical) {
  // The same output name in two directories: the header records it.
  std::filesystem::create_directories(dir_ + "/t1");
  std::filesystem::create_directories(dir_ + "/t2");
  const std::string one = dir_ + "/t1/grid.gtn", two = dir_ + "/t2/grid.gtn";
  test::RunResult r = test::runGtn("convert " + vtk_ + " -o " + one + " -q --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = test::runGtn("convert " + vtk_ + " -o " + two + " -q --threads=2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string a = test::readFile(one), b = test::readFile(two);
  ASSERT_GT(a.size(), 100u);
  EXPECT_TRUE(a == b) << "convert wrote different files with 1 and 2 threads";
  EXPECT_EQ(a.find("--threads"), std::string::npos);

  const std::string e1 = dir_ + "/one.vtu", e2 = dir_ + "/two.vtu";
  ASSERT_EQ(test::runGtn("export " + one + " --ratio 0.4 -o " + e1 + " --threads 1").exit_code, 0);
  ASSERT_EQ(test::runGtn("export " + one + " --ratio 0.4 -o " + e2 + " --threads 2").exit_code, 0);
  EXPECT_TRUE(test::readFile(e1) == test::readFile(e2));
}

// The streaming renderer and the generic one, from a .gtn file and from a mesh file: the same image.
TEST_F(ThreadsCli, RenderByteIdentical) {
  const std::string gtn = dir_ + "/grid.gtn";
  ASSERT_EQ(test::runGtn("convert " + vtk_ + " -o " + gtn + " -q").exit_code, 0);
  const std::string spx = test::dataPath("vtk/spx.vtk");
  ASSERT_TRUE(test::fileExists(spx)) << "dataset missing: " << spx;
  int n = 0;
  for (const std::string& input : {gtn, spx}) {
    for (const std::string& extra : {std::string(), std::string(" --pipeline generic"), std::string(" --ratio 0.5")}) {
      if (input == spx && extra == " --ratio 0.5") continue;  // a mesh file has no merge tree
      const std::string p1 = dir_ + "/r" + std::to_string(n) + "-1.png",
                        p2 = dir_ + "/r" + std::to_string(n) + "-2.png";
      ++n;
      test::RunResult r =
          test::runGtn("render " + input + " -o " + p1 + " --no-cache --size 96x80" + extra + " --threads 1");
      ASSERT_EQ(r.exit_code, 0) << r.err;
      r = test::runGtn("render " + input + " -o " + p2 + " --no-cache --size 96x80" + extra + " --threads 2");
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const std::string a = test::readFile(p1);
      ASSERT_GT(a.size(), 100u);
      EXPECT_TRUE(a == test::readFile(p2)) << input << extra << ": the images differ";
    }
  }
}

// decode says how many threads it had: the bound when given.
TEST_F(ThreadsCli, BoundApplied) {
  const std::string gtn = dir_ + "/grid.gtn";
  ASSERT_EQ(test::runGtn("convert " + vtk_ + " -o " + gtn + " -q").exit_code, 0);
  for (int n : {1, 2, 3}) {
    const test::RunResult r = test::runGtn("decode " + gtn + " --json --threads " + std::to_string(n));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("threads"), n);
  }
}

// Every command takes --threads, and refuses a count that is not a whole number of 1 or more.
TEST_F(ThreadsCli, EveryCommandAndBadCounts) {
  const std::string gtn = dir_ + "/grid.gtn", png = dir_ + "/grid.png";
  ASSERT_EQ(test::runGtn("convert " + vtk_ + " -o " + gtn + " -q --threads 1").exit_code, 0);
  const std::string commands[] = {
      "convert " + vtk_ + " -o " + dir_ + "/again.gtn -q",
      "info " + gtn,
      "export " + gtn + " -o " + dir_ + "/out.vtu",
      "validate " + gtn,
      "render " + gtn + " -o " + png + " --no-cache --size 32x32",
      "compare " + png + " " + png,
      "decode " + gtn,
  };
  for (const std::string& c : commands) {
    const test::RunResult ok = test::runGtn(c + " --threads 1");
    EXPECT_EQ(ok.exit_code, 0) << c << "\n" << ok.err;
    for (const char* bad : {"0", "-1", "-8", "two", "1.5", "99999"}) {
      const test::RunResult r = test::runGtn(c + " --threads " + bad);
      EXPECT_EQ(r.exit_code, 2) << c << " --threads " << bad << "\n" << r.err;
      EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
      std::string expected = "'";
      expected.append(bad).append("' is not a number of threads");
      EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    }
  }
}

}  // namespace
}  // namespace gtn
