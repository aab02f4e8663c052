// bench-scale (bench/scale/bench_scale.py) on two tiny grids: one table row per size and thread count
// with the tetrahedra the grid has, the file the same bytes whatever the thread count, every figure
// in the JSON; bad sizes are refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

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
  const test::RunResult r =
      test::runShell(benchCommand("--sizes 6,9 --threads 2 --work " + dir + "/work --json " + json_path));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(json_path));
  EXPECT_EQ(j.at("all_threads"), 2);
  ASSERT_EQ(j.at("rows").size(), 4u);
  int row = 0;
  for (int n : {6, 9}) {
    for (int threads : {1, 2}) {
      const nlohmann::json& x = j.at("rows").at(row++);
      EXPECT_EQ(x.at("nodes"), n);
      EXPECT_EQ(x.at("threads"), threads);
      EXPECT_EQ(x.at("tets"), 6 * (n - 1) * (n - 1) * (n - 1));
      EXPECT_EQ(x.at("points"), n * n * n);
      EXPECT_EQ(x.at("same_bytes_all_threads"), true);
      EXPECT_GT(x.at("file_bytes").get<double>(), 0.0);
      for (const char* k :
           {"convert_wall_s", "convert_peak_rss_bytes", "decode_wall_s", "decode_s", "decode_peak_rss_bytes"})
        EXPECT_GT(x.at(k).get<double>(), 0.0) << k;
      // The table: one line per row, after the header and the rule.
      const std::string cells =
          "| " + std::to_string(n) + "^3 | " + x.at("tets").dump() + " | " + std::to_string(threads) + " | ";
      EXPECT_NE(r.out.find(cells), std::string::npos) << r.out;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/work/grid6")) << "the grids are removed once measured";
}

TEST(BenchScale, BadSizes) {
  for (const char* sizes : {"1", "64,x", "2000"}) {
    const test::RunResult r = test::runShell(benchCommand(std::string("--sizes ") + sizes));
    EXPECT_NE(r.exit_code, 0) << sizes;
    EXPECT_NE(r.err.find("bench-scale: --sizes"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace gtn
