// A constant field is never the default: a PLOT3D Q file whose density is 1.0 everywhere converts with
// the simplification ranked on the first field that varies, and renders that field, both saying so.
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "test_util.h"

namespace gtn::test {
namespace {

void putBig32(std::string& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xFF));
}
void putFloat(std::string& out, double v) {
  const float f = static_cast<float>(v);
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  putBig32(out, bits);
}

// A 9 x 7 x 6 box grid and its Q file (big-endian float32, whole layout, no record markers, as the
// blunt-fin files): density 1.0 everywhere, momentum and energy varying; or (`swap`) density varying
// and energy 1.0 everywhere.
void writeUniformDensity(const std::string& dir, bool swap = false) {
  const int ni = 9, nj = 7, nk = 6;
  std::string xyz, q;
  for (int d : {ni, nj, nk}) {
    putBig32(xyz, d);
    putBig32(q, d);
  }
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k < nk; ++k)
      for (int j = 0; j < nj; ++j)
        for (int i = 0; i < ni; ++i) putFloat(xyz, axis == 0 ? i * 0.5 : axis == 1 ? j * 0.5 + 0.05 * i : k * 0.5);
  for (double v : {0.5, 0.0, 1.0e5, 0.0}) putFloat(q, v);
  const int n = ni * nj * nk;
  for (int p = 0; p < n; ++p) putFloat(q, swap ? 2.5 + 0.02 * (p % 17) : 1.0);
  for (int c = 0; c < 3; ++c)
    for (int p = 0; p < n; ++p) putFloat(q, 0.1 * (c + 1) * (p % ni) + 0.01 * (p / ni));
  for (int p = 0; p < n; ++p) putFloat(q, swap ? 1.0 : 2.5 + 0.02 * (p % 17));
  writeFile(dir + "/u.xyz", xyz);
  writeFile(dir + "/u.q", q);
}

TEST(ConstantField, SimplificationSkipsTheConstantDensity) {
  const std::string dir = tempDir("constant-field");
  writeUniformDensity(dir);
  const RunResult c = runGtn("convert " + dir + "/u.xyz " + dir + "/u.q -o " + dir + "/u.gtn --levels 1");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.err.find("the simplification ranks on field 'momentum' (constant: 'density'"), std::string::npos)
      << c.err;
  const RunResult info = runGtn("info " + dir + "/u.gtn --merge-tree --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["merge_tree"]["field"], "momentum");
  // Named, even a constant field is taken as asked, without a word.
  const RunResult named =
      runGtn("convert " + dir + "/u.xyz " + dir + "/u.q -o " + dir + "/d.gtn --levels 1 --simplify-field density");
  ASSERT_EQ(named.exit_code, 0) << named.err;
  EXPECT_EQ(named.err.find("ranks on"), std::string::npos) << named.err;
  EXPECT_EQ(nlohmann::json::parse(runGtn("info " + dir + "/d.gtn --merge-tree --json").out)["merge_tree"]["field"],
            "density");
}

TEST(ConstantField, RenderSkipsTheConstantDensity) {
  const std::string dir = tempDir("constant-field-render");
  writeUniformDensity(dir);
  ASSERT_EQ(runGtn("convert " + dir + "/u.xyz " + dir + "/u.q -o " + dir + "/u.gtn --levels 1").exit_code, 0);
  // From the .gtn file and straight from the PLOT3D files.
  for (const std::string& in : {dir + "/u.gtn", dir + "/u.xyz " + dir + "/u.q"}) {
    SCOPED_TRACE(in);
    const RunResult r = runGtn("render " + in + " -o " + dir + "/u.png --size 32x32 --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("showing field 'momentum' (constant: 'density'"), std::string::npos) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["view"]["transfer"]["field"], "momentum:0") << r.out;
    const auto range = j["view"]["transfer"]["range"];
    EXPECT_LT(range[0].get<double>(), range[1].get<double>() - 0.5) << "a range the field spans, not 1 +- 0.5";
    const RunResult named = runGtn("render " + in + " -o " + dir + "/d.png --size 32x32 --field density --json");
    ASSERT_EQ(named.exit_code, 0) << named.err;
    EXPECT_EQ(named.err.find("showing"), std::string::npos) << named.err;
    EXPECT_EQ(nlohmann::json::parse(named.out)["view"]["transfer"]["field"], "density");
  }
}

// A constant field after the first one that varies changes nothing and is not mentioned.
TEST(ConstantField, LaterConstantFieldsAreNotMentioned) {
  const std::string dir = tempDir("constant-field-later");
  writeUniformDensity(dir, true);
  const RunResult c = runGtn("convert " + dir + "/u.xyz " + dir + "/u.q -o " + dir + "/u.gtn --levels 1");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  // The note's own words: the summary line names the input, whose folder says "constant" too.
  EXPECT_EQ(c.err.find("(constant: "), std::string::npos) << c.err;
  EXPECT_EQ(nlohmann::json::parse(runGtn("info " + dir + "/u.gtn --merge-tree --json").out)["merge_tree"]["field"],
            "density");
  const RunResult r = runGtn("render " + dir + "/u.gtn -o " + dir + "/u.png --size 16x16 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("(constant: "), std::string::npos) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["view"]["transfer"]["field"], "density");
}

}  // namespace
}  // namespace gtn::test
