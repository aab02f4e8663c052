// bench-scale (bench/scale/bench_scale.py) on two tiny grids: rounds of every thread count in turn, one
// table row per size and thread count with the tetrahedra the grid has, a row of speed-ups per size,
// the file the same bytes whatever the thread count and round, every figure in the JSON; bad sizes
// and round counts are refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "test_util.h"

namespace gtn {
namespace {

std::string benchCommand(const std::string& args) {
  const std::string build = std::filesystem::path(GTN_BINARY).parent_path().string();
  return "python3 " + std::string(GTN_SOURCE_DIR) + "/bench/scale/bench_scale.py --build " + build + " " + args;
}

TEST(BenchScale, TinyGrids) {
  const std::string dir = test::tempDir("gtn-bench-scale");
  const std::string json_path = dir + "/scale.json";
  const test::RunResult r = test::runShell(
      benchCommand("--sizes 6,9 --threads 2 --reps 2 --validate --work " + dir + "/work --json " + json_path));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(json_path));
  EXPECT_EQ(j.at("all_threads"), 2);
  EXPECT_EQ(j.at("reps"), 2);
  // Per size, two rounds, each running both thread counts, the second in the other order.
  ASSERT_EQ(j.at("runs").size(), 8u);
  int run = 0;
  for (int n : {6, 9}) {
    for (int round : {1, 2}) {
      for (int threads : round == 1 ? std::vector<int>{1, 2} : std::vector<int>{2, 1}) {
        const nlohmann::json& x = j.at("runs").at(run++);
        EXPECT_EQ(x.at("nodes"), n);
        EXPECT_EQ(x.at("round"), round);
        EXPECT_EQ(x.at("threads"), threads);
        EXPECT_EQ(x.at("tets"), 6 * (n - 1) * (n - 1) * (n - 1));
        EXPECT_EQ(x.at("points"), n * n * n);
        EXPECT_EQ(x.at("same_bytes_all_runs"), true);
        EXPECT_GT(x.at("file_bytes").get<double>(), 0.0);
        for (const char* k : {"convert_wall_s", "convert_peak_rss_bytes", "decode_wall_s", "decode_s",
                              "decode_peak_rss_bytes", "validate_wall_s", "validate_peak_rss_bytes"})
          EXPECT_GT(x.at(k).get<double>(), 0.0) << k;
      }
    }
    // The table: one line per size and thread count; then one line of speed-ups per size.
    for (int threads : {1, 2}) {
      const std::string cells = "| " + std::to_string(n) + "^3 | " + std::to_string(6 * (n - 1) * (n - 1) * (n - 1)) +
                                " | " + std::to_string(threads) + " | ";
      EXPECT_NE(r.out.find(cells), std::string::npos) << r.out;
    }
    const size_t speedups = r.out.find("| nodes | convert wall, 2 threads / 1");
    ASSERT_NE(speedups, std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\n| " + std::to_string(n) + "^3 | ", speedups), std::string::npos) << r.out;
  }
  EXPECT_NE(r.out.find("validate wall, 2 threads / 1"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/work/grid6")) << "the grids are removed once measured";
}

TEST(BenchScale, BadSizes) {
  for (const char* sizes : {"1", "64,x", "2000"}) {
    const test::RunResult r = test::runShell(benchCommand(std::string("--sizes ") + sizes));
    EXPECT_NE(r.exit_code, 0) << sizes;
    EXPECT_NE(r.err.find("bench-scale: --sizes"), std::string::npos) << r.err;
  }
  const test::RunResult r = test::runShell(benchCommand("--sizes 6 --reps 0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bench-scale: --reps"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace gtn
