// bench-front through the built binary: on spx its row carries the decoder's rate and the two
// replays' (which check themselves: every interior face closed once, else exit status 1), and a data
// directory without the datasets is reported, not crashed on.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace gtn {
namespace {

#ifdef GTN_BENCH_FRONT

test::RunResult runBench(const std::string& dir, const std::string& filter) {
  std::string command = GTN_BENCH_FRONT;
  command += " '";
  command += dir;
  command += "' ";
  command += filter;
  return test::runShell(command);
}

// The numbers of the table row of `dataset`, "|" and "%" dropped.
std::vector<double> rowNumbers(const std::string& out, const std::string& dataset) {
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(dataset + " ", 0) != 0) continue;
    std::vector<double> v;
    std::istringstream row(line.substr(dataset.size()));
    for (std::string w; row >> w;) {
      if (w == "|") continue;
      if (!w.empty() && w.back() == '%') w.pop_back();
      v.push_back(std::stod(w));
    }
    return v;
  }
  return {};
}

TEST(BenchFront, SpxRowAgreesWithItself) {
  const test::RunResult r = runBench(test::dataDir(), "spx");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::vector<double> v = rowNumbers(r.out, "spx");
  // tets | decode ns, Mt/s | faces+edges ns, Mt/s, share | faces ns, Mt/s, share
  ASSERT_EQ(v.size(), 9u) << r.out;
  EXPECT_EQ(v[0], 12936);
  for (int i : {1, 3, 6}) {
    ASSERT_GT(v[i], 0) << r.out;
    // A rate is the inverse of its time per tetrahedron (both printed rounded).
    EXPECT_NEAR(v[i + 1], 1e3 / v[i], 0.01 + 1e3 / v[i] * 0.01) << r.out;
  }
  EXPECT_NEAR(v[5], 100 * v[3] / v[1], 1.0) << r.out;
  EXPECT_NEAR(v[8], 100 * v[6] / v[1], 1.0) << r.out;
}

TEST(BenchFront, MissingDatasetIsReported) {
  const std::string dir = test::tempDir("bench-front-empty");
  const test::RunResult r = runBench(dir, "spx");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("spx"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("import failed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("spx.vtk"), std::string::npos) << r.out;
}

#endif

}  // namespace
}  // namespace gtn
