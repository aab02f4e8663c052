// Quadratic tetrahedra (VTK_QUADRATIC_TETRA): the importer keeps the corners and leaves the mid-edge
// points as unreferenced points. Simplification counts only the referenced vertices, so such a mesh
// gets the same levels, ratios and merge-tree statistics as the same mesh with linear tetrahedra.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "simplify_test_util.h"
#include "test_util.h"

namespace gtn::test {
namespace {

// `m` as legacy ASCII VTK with a point field "rho": linear tetrahedra (type 10), or quadratic ones
// (type 24) whose six mid-edge points (at the edge's midpoint, rho the mean of its ends) follow the
// corners in the file, VTK's edge order.
std::string vtkText(const TetMesh& m, bool quadratic) {
  std::vector<double> coords = m.coords;
  const Field* rho_field = m.findPointField("rho");
  std::vector<double> rho;
  for (size_t v = 0; v < m.numPoints(); ++v) rho.push_back(rho_field->get(v, 0));
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
  std::vector<std::vector<uint32_t>> cells;
  static const int kEdges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  for (const Tet& t : m.tets) {
    std::vector<uint32_t> c(t.begin(), t.end());
    if (quadratic) {
      for (const auto& e : kEdges) {
        const uint32_t a = std::min(t[e[0]], t[e[1]]), b = std::max(t[e[0]], t[e[1]]);
        auto [it, inserted] = mid.emplace(std::make_pair(a, b), static_cast<uint32_t>(rho.size()));
        if (inserted) {
          for (int k = 0; k < 3; ++k) coords.push_back(0.5 * (m.coords[3 * a + k] + m.coords[3 * b + k]));
          rho.push_back(0.5 * (rho[a] + rho[b]));
        }
        c.push_back(it->second);
      }
    }
    cells.push_back(std::move(c));
  }
  std::string s = "# vtk DataFile Version 3.0\ngenerated\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  char buf[128];
  s += "POINTS " + std::to_string(rho.size()) + " double\n";
  for (size_t i = 0; i < rho.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
    s += buf;
  }
  const size_t per = quadratic ? 10 : 4;
  s += "CELLS " + std::to_string(cells.size()) + " " + std::to_string(cells.size() * (per + 1)) + "\n";
  for (const auto& c : cells) {
    s += std::to_string(per);
    for (uint32_t v : c) {
      s += ' ';
      s += std::to_string(v);
    }
    s += "\n";
  }
  s += "CELL_TYPES " + std::to_string(cells.size()) + "\n";
  for (size_t i = 0; i < cells.size(); ++i) s += quadratic ? "24\n" : "10\n";
  s += "POINT_DATA " + std::to_string(rho.size()) + "\nSCALARS rho double 1\nLOOKUP_TABLE default\n";
  for (double r : rho) {
    std::snprintf(buf, sizeof buf, "%.17g\n", r);
    s += buf;
  }
  return s;
}

class Quadratic : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = tempDir("quadratic");
    TetMesh m = makeGrid(16, 15, 14, 3);
    writeFile(dir_ + "/linear.vtk", vtkText(m, false));
    writeFile(dir_ + "/quadratic.vtk", vtkText(m, true));
    points_ = m.numPoints();
  }
  static nlohmann::json info(const std::string& args) {
    const RunResult r = runGtn("info " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
  }
  static std::string dir_;
  static size_t points_;
};
std::string Quadratic::dir_;
size_t Quadratic::points_ = 0;

TEST_F(Quadratic, DefaultConversionMakesTheSameLevels) {
  for (const char* name : {"linear", "quadratic"}) {
    const RunResult r = runGtn("convert " + dir_ + "/" + name + ".vtk -o " + dir_ + "/" + name + ".gtn");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("--levels"), std::string::npos) << r.err;
  }
  const nlohmann::json lin = info(dir_ + "/linear.gtn --merge-tree"), quad = info(dir_ + "/quadratic.gtn --merge-tree");
  const uint64_t mid = info(dir_ + "/quadratic.gtn")["unreferenced_points"].get<uint64_t>();
  EXPECT_GT(mid, 5 * points_);
  ASSERT_GE(lin["levels"].size(), 3u);
  ASSERT_EQ(quad["levels"].size(), lin["levels"].size()) << quad.dump(1);
  for (size_t i = 1; i < lin["levels"].size(); ++i) {
    SCOPED_TRACE("level " + std::to_string(i));
    // The same mesh: the mid-edge points are merged first, then the same ranked merges.
    EXPECT_EQ(quad["levels"][i]["points"], lin["levels"][i]["points"]);
    EXPECT_EQ(quad["levels"][i]["tets"], lin["levels"][i]["tets"]);
    EXPECT_EQ(quad["levels"][i]["merges"].get<uint64_t>(), lin["levels"][i]["merges"].get<uint64_t>() + mid);
    EXPECT_DOUBLE_EQ(quad["levels"][i]["ratio"].get<double>(), lin["levels"][i]["ratio"].get<double>());
  }
  // Reading level i reads it and the coarser levels whose vertices it names: about half of what
  // reading level i - 1 reads.
  std::vector<double> read(quad["levels"].size() + 1, 0.0);
  for (size_t i = quad["levels"].size(); i-- > 0;) read[i] = read[i + 1] + quad["levels"][i]["bytes"].get<double>();
  for (size_t i = 1; i < lin["levels"].size(); ++i) EXPECT_LT(read[i], 0.6 * read[i - 1]) << "level " << i;
  // Merge-tree statistics count the vertices tetrahedra use.
  for (const char* key : {"merges", "roots", "boundary_merges", "tets_removed"})
    EXPECT_EQ(quad["merge_tree"][key], lin["merge_tree"][key]) << key;
  const RunResult v = runGtn("validate " + dir_ + "/quadratic.gtn");
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
}

TEST_F(Quadratic, LevelsAndRatiosCountReferencedVertices) {
  for (const char* name : {"linear", "quadratic"}) {
    const RunResult r = runGtn("convert " + dir_ + "/" + name + ".vtk -o " + dir_ + "/" + name + "3.gtn --levels 3");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const nlohmann::json quad = info(dir_ + "/quadratic3.gtn");
  ASSERT_EQ(quad["levels"].size(), 4u) << quad.dump(1);
  for (size_t i = 1; i < 4; ++i) EXPECT_LT(quad["levels"][i]["tets"], quad["levels"][i - 1]["tets"]);
  // --ratio: the same share of the referenced vertices merged away, so the same mesh.
  for (const char* ratio : {"0.16", "0.5", "0.9"}) {
    SCOPED_TRACE(ratio);
    uint64_t tets[2];
    for (int q = 0; q < 2; ++q) {
      const std::string out = dir_ + "/r" + std::to_string(q) + ".vtu";
      const RunResult r =
          runGtn("export " + dir_ + (q ? "/quadratic3.gtn" : "/linear3.gtn") + " -o " + out + " --ratio " + ratio);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      tets[q] = info(out)["tets"].get<uint64_t>();
    }
    EXPECT_EQ(tets[1], tets[0]);
    // gtn render counts the same way.
    uint64_t decoded[2];
    double reported[2];
    for (int q = 0; q < 2; ++q) {
      const RunResult r = runGtn("render " + dir_ + (q ? "/quadratic3.gtn" : "/linear3.gtn") + " -o " + dir_ +
                                 "/r.png --size 16x16 --json --ratio " + ratio);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const nlohmann::json j = nlohmann::json::parse(r.out);
      decoded[q] = j["tets_rendered"].get<uint64_t>();
      reported[q] = j["ratio"].get<double>();
    }
    EXPECT_EQ(decoded[1], decoded[0]);
    // The ratio it reports is over the referenced vertices too: the one asked for, both files alike.
    EXPECT_DOUBLE_EQ(reported[1], reported[0]);
    EXPECT_NEAR(reported[1], std::stod(ratio), 0.01);
  }
}

}  // namespace
}  // namespace gtn::test
