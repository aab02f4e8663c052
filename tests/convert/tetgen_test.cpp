// TetGen import and export: the shared datasets, a lossless round trip, the real tetgen program,
// malformed inputs and the CLI.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "convert/export.h"
#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/mesh_stats.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::dataPath;
using test::fileExists;
using test::readFile;
using test::tempDir;
using test::writeFile;

ImportResult mustImport(const std::string& path) {
  auto r = importTetgen(path, ImportOptions{});
  EXPECT_TRUE(r.isOk()) << r.status().message();
  if (!r.isOk()) return ImportResult{};
  return std::move(r).value();
}

// Same mesh bit for bit: coordinates, tetrahedra, fields (names, types, components, bytes), metadata.
void expectSameMesh(const TetMesh& a, const TetMesh& b) {
  EXPECT_EQ(a.coord_type, b.coord_type);
  ASSERT_EQ(a.coords.size(), b.coords.size());
  EXPECT_EQ(0, std::memcmp(a.coords.data(), b.coords.data(), a.coords.size() * sizeof(double)));
  EXPECT_TRUE(a.tets == b.tets);
  auto same_fields = [](const std::vector<Field>& x, const std::vector<Field>& y) {
    ASSERT_EQ(x.size(), y.size());
    for (size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].name, y[i].name);
      EXPECT_EQ(x[i].components, y[i].components) << x[i].name;
      EXPECT_EQ(x[i].type, y[i].type) << x[i].name;
      EXPECT_TRUE(x[i].bytes == y[i].bytes) << x[i].name;
    }
  };
  same_fields(a.point_fields, b.point_fields);
  same_fields(a.cell_fields, b.cell_fields);
  EXPECT_EQ(a.metadata, b.metadata);
}

const Field* findCellField(const TetMesh& mesh, const std::string& name) {
  for (const Field& f : mesh.cell_fields)
    if (f.name == name) return &f;
  return nullptr;
}

// Distinct faces whose marker is non-zero, and boundary faces whose marker differs from `boundary`.
void countMarkedFaces(const TetMesh& mesh, int32_t boundary, size_t* marked, size_t* odd_boundary) {
  const Field* f = findCellField(mesh, "face_marker");
  ASSERT_NE(f, nullptr);
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  size_t per_side = 0, on_boundary = 0;
  *odd_boundary = 0;
  for (size_t t = 0; t < mesh.numTets(); ++t) {
    for (uint32_t k = 0; k < 4; ++k) {
      const int32_t m = f->data<int32_t>()[4 * t + k];
      const bool is_boundary = adj.neighbor[4 * t + k] == kNoNeighbor;
      if (is_boundary && m != boundary) ++*odd_boundary;
      if (m != 0) (is_boundary ? on_boundary : per_side) += 1;
    }
  }
  *marked = on_boundary + per_side / 2;
}

TEST(TetgenImport, CornellSpheres) {
  const ImportResult r = mustImport(dataPath("tetgen/cornell_spheres.1"));
  EXPECT_EQ(r.mesh.numPoints(), 4089u);
  EXPECT_EQ(r.mesh.numTets(), 24207u);
  EXPECT_EQ(r.mesh.coord_type, ScalarType::kFloat64);
  ASSERT_NE(r.mesh.findMetadata("source.format"), nullptr);
  EXPECT_EQ(*r.mesh.findMetadata("source.format"), "tetgen");
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.boundary_faces, 812u);  // the .face lists all 48820 faces (-f): 2 * 48820 - 4 * 24207
  EXPECT_EQ(s.faces, 48820u);
  // 3844 faces carry marker -1 (outer box and sphere surfaces); every boundary face is one of them.
  size_t marked = 0, odd = 0;
  countMarkedFaces(r.mesh, -1, &marked, &odd);
  EXPECT_EQ(marked, 3844u);
  EXPECT_EQ(odd, 0u);
  EXPECT_TRUE(r.mesh.point_fields.empty());
  ASSERT_EQ(r.mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r.mesh.cell_fields[0].components, 4u);
  EXPECT_EQ(r.mesh.cell_fields[0].type, ScalarType::kInt32);
}

TEST(TetgenImport, CornellboxRegions) {
  const ImportResult r = mustImport(dataPath("tetgen/cornellbox_orig.1.ele"));
  EXPECT_EQ(r.mesh.numPoints(), 331u);
  EXPECT_EQ(r.mesh.numTets(), 1631u);
  EXPECT_EQ(computeMeshStats(r.mesh).inverted, 0u);
  const Field* region = findCellField(r.mesh, "region");
  ASSERT_NE(region, nullptr);
  EXPECT_EQ(region->type, ScalarType::kFloat64);
  std::map<double, int> histogram;
  for (size_t t = 0; t < r.mesh.numTets(); ++t) ++histogram[region->get(t, 0)];
  EXPECT_EQ(histogram, (std::map<double, int>{{1.0, 1437}, {2.0, 88}, {3.0, 106}}));
  size_t marked = 0, odd = 0;
  countMarkedFaces(r.mesh, -1, &marked, &odd);
  EXPECT_EQ(marked, 511u);
  EXPECT_EQ(odd, 0u);
  EXPECT_EQ(computeMeshStats(r.mesh).boundary_faces, 230u);
}

TEST(TetgenImport, AllThreeFileNamesWork) {
  for (const char* name : {"cornellbox_orig.1", "cornellbox_orig.1.node", "cornellbox_orig.1.face"}) {
    const ImportResult r = mustImport(dataPath(std::string("tetgen/") + name));
    EXPECT_EQ(r.mesh.numTets(), 1631u) << name;
  }
}

void roundTrip(const TetMesh& mesh, const std::string& dir) {
  const std::string out = dir + "/rt.node";
  const Status st = exportTetgen(mesh, out);
  ASSERT_TRUE(st.isOk()) << st.message();
  EXPECT_TRUE(fileExists(dir + "/rt.ele"));
  EXPECT_TRUE(fileExists(dir + "/rt.face"));
  const ImportResult back = mustImport(out);
  EXPECT_EQ(back.report.flipped, 0u);
  TetMesh expected = mesh;
  expected.setMetadata("source.format", "tetgen");
  expectSameMesh(expected, back.mesh);
  // Export is deterministic: the re-imported mesh writes the same bytes as the mesh it equals.
  ASSERT_TRUE(exportTetgen(back.mesh, dir + "/rt2.ele").isOk());
  ASSERT_TRUE(exportTetgen(expected, dir + "/rt3").isOk());
  for (const char* ext : {".node", ".ele", ".face"})
    EXPECT_EQ(readFile(dir + "/rt3" + ext), readFile(dir + "/rt2" + ext)) << ext;
}

TEST(TetgenRoundTrip, Datasets) {
  for (const char* name : {"cornell_spheres.1", "cornellbox_orig.1"}) {
    SCOPED_TRACE(name);
    const ImportResult r = mustImport(dataPath(std::string("tetgen/") + name));
    roundTrip(r.mesh, tempDir(std::string("tetgen-rt-") + name));
  }
  // Boundary faces only (the exporter writes boundary triangles and marked interior faces).
  const std::string dir = tempDir("tetgen-rt-faces");
  const ImportResult r = mustImport(dataPath("tetgen/cornellbox_orig.1"));
  ASSERT_TRUE(exportTetgen(r.mesh, dir + "/x.node").isOk());
  EXPECT_EQ(std::stoul(readFile(dir + "/x.face")), 511u);
}

template <class T>
Field makeField(const std::string& name, uint32_t components, ScalarType type, const std::vector<T>& values) {
  Field f(name, components, type, values.size() / components);
  std::memcpy(f.bytes.data(), values.data(), f.bytes.size());
  return f;
}

template <class To, class From>
To bitsTo(From bits) {
  To v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// Two positive tetrahedra sharing face (1,2,3), float32 coordinates, fields of many types with
// awkward values (NaN payloads, -0, subnormals, extremes) and names that need escaping.
TetMesh synthetic() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  const float c[] = {0.1f, -0.0f, 0.0f, 1.3f, 1e-40f, 0.0f, 0.0f, 1.0f, 0.2f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f, 1.0f / 3};
  for (float v : c) m.coords.push_back(v);
  m.tets = {Tet{0, 1, 2, 3}, Tet{1, 2, 3, 4}};
  const float inf = std::numeric_limits<float>::infinity();
  m.point_fields.push_back(makeField<float>("density", 1, ScalarType::kFloat32,
                                            {bitsTo<float>(0x7fc00123u), -inf, -0.0f, 1e-45f, 3.4028235e38f}));
  m.point_fields.push_back(makeField<int32_t>("boundary_marker", 1, ScalarType::kInt32, {1, -2, 0, 2147483647, -7}));
  m.point_fields.push_back(makeField<double>("velocity vec: m/s", 3, ScalarType::kFloat64,
                                             {0.1, 1.0 / 3, 5e-324, -1e308, bitsTo<double>(0xfff0000000000001ull), 2.0,
                                              0, -0.0, 1e-300, 7, 8, 9, 10, 11, std::numeric_limits<double>::max()}));
  m.point_fields.push_back(makeField<uint8_t>("flags#%", 1, ScalarType::kUInt8, {0, 1, 128, 255, 7}));
  m.point_fields.push_back(
      makeField<int64_t>("id", 1, ScalarType::kInt64,
                         {std::numeric_limits<int64_t>::min(), -1, 0, 1, std::numeric_limits<int64_t>::max()}));
  m.point_fields.push_back(makeField<uint64_t>("big", 1, ScalarType::kUInt64, {~0ull, 0, 1, 1ull << 63, 42}));
  m.cell_fields.push_back(makeField<int16_t>("level", 1, ScalarType::kInt16, {-32768, 32767}));
  // Local face 0 of tet 0 and local face 3 of tet 1 are the shared face (1,2,3): same marker.
  m.cell_fields.push_back(makeField<int32_t>("face_marker", 4, ScalarType::kInt32, {7, 0, -3, 5, 1, 0, 2, 7}));
  m.cell_fields.push_back(makeField<double>("region", 1, ScalarType::kFloat64, {1.5, -2.25}));
  m.metadata = {{"source.format", "synthetic"}, {"note with spaces", "100% #1: a\tb\nc"}};
  return m;
}

TEST(TetgenRoundTrip, SyntheticFieldTypes) {
  const TetMesh m = synthetic();
  ASSERT_TRUE(m.checkConsistency("synthetic").isOk());
  ASSERT_EQ(computeMeshStats(m).inverted, 0u);
  const std::string dir = tempDir("tetgen-rt-synthetic");
  roundTrip(m, dir);
  const std::string node = readFile(dir + "/rt.node");
  EXPECT_NE(node.find("# gtn-coordinates: float32"), std::string::npos);
  EXPECT_NE(node.find("velocity%20vec%3A%20m%2Fs:3:float64"), std::string::npos) << node;
  EXPECT_NE(node.find("boundary_marker:1:int32:marker"), std::string::npos);
  EXPECT_NE(node.find("nan(0x7fc00123)"), std::string::npos);
  EXPECT_NE(node.find("5  3  7  1\n"), std::string::npos) << node;  // 1 + 3 + 1 + 1 + 1 values, then the marker
  const std::string ele = readFile(dir + "/rt.ele");
  EXPECT_NE(ele.find("face_marker:4:int32:face"), std::string::npos) << ele;
  // The .face: 6 boundary triangles (4 of them marked non-zero) and the marked shared face.
  EXPECT_EQ(std::stoul(readFile(dir + "/rt.face")), 7u);
}

TEST(TetgenRoundTrip, InconsistentFaceMarkersBecomeAttributes) {
  TetMesh m = synthetic();
  m.cell_fields[1].set<int32_t>(1, 3, 8);  // the shared face now has two markers
  const std::string dir = tempDir("tetgen-rt-inconsistent");
  roundTrip(m, dir);
  EXPECT_NE(readFile(dir + "/rt.ele").find("face_marker:4:int32 "), std::string::npos);
}

TEST(TetgenRoundTrip, ExportRejectsInconsistentMeshAndLeavesNoFiles) {
  TetMesh m = synthetic();
  m.tets[1][3] = 99;
  const std::string dir = tempDir("tetgen-export-bad");
  const Status st = exportTetgen(m, dir + "/bad.node");
  EXPECT_FALSE(st.isOk());
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

// Every prefix of every file of an export, and single-byte corruptions of it, must import cleanly or
// fail with a message naming the file; never crash (the suite also runs under ASan).
TEST(TetgenRobustness, PrefixesAndCorruptions) {
  const std::string dir = tempDir("tetgen-prefixes");
  ASSERT_TRUE(exportTetgen(synthetic(), dir + "/s.node").isOk());
  size_t failures = 0, runs = 0;
  uint64_t rng = 0x9E3779B97F4A7C15ull;
  auto next = [&rng] {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
  };
  for (const char* ext : {".node", ".ele", ".face"}) {
    const std::string original = readFile(dir + "/s" + ext);
    auto check = [&](const std::string& text) {
      writeFile(dir + "/s" + ext, text);
      auto r = importTetgen(dir + "/s", ImportOptions{});
      ++runs;
      if (r.isOk()) {
        EXPECT_TRUE(r->mesh.checkConsistency("prefix").isOk());
      } else {
        ++failures;
        EXPECT_EQ(r.status().message().rfind(dir + "/s.", 0), 0u) << r.status().message();
      }
    };
    for (size_t n = 0; n < original.size(); ++n) check(original.substr(0, n));
    for (int i = 0; i < 150; ++i) {
      std::string text = original;
      text[next() % text.size()] = " \n#-.0159aex%:"[next() % 15];
      check(text);
    }
    writeFile(dir + "/s" + ext, original);
  }
  EXPECT_GT(failures, runs / 2);  // most damaged files are detected
}

// --- The real tetgen program --------------------------------------------------------------------

const char* kTwoBoxesPoly = R"(# two unit cubes side by side, facets marked 1 and 2, regions 10 and 20
16 3 0 1
0 0 0 0 1
1 1 0 0 1
2 1 1 0 1
3 0 1 0 1
4 0 0 1 1
5 1 0 1 1
6 1 1 1 1
7 0 1 1 1
8 2 0 0 2
9 3 0 0 2
10 3 1 0 2
11 2 1 0 2
12 2 0 1 2
13 3 0 1 2
14 3 1 1 2
15 2 1 1 2
12 1
1 0 1
4 0 1 2 3
1 0 1
4 4 5 6 7
1 0 1
4 0 1 5 4
1 0 1
4 1 2 6 5
1 0 1
4 2 3 7 6
1 0 1
4 3 0 4 7
1 0 2
4 8 9 10 11
1 0 2
4 12 13 14 15
1 0 2
4 8 9 13 12
1 0 2
4 9 10 14 13
1 0 2
4 10 11 15 14
1 0 2
4 11 8 12 15
0
2
1 0.5 0.5 0.5 10 0
2 2.5 0.5 0.5 20 0
)";

size_t statistic(const std::string& out, const std::string& label) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(label + ":\\s*([0-9]+)"))) return 0;
  return std::stoul(m[1].str());
}

TEST(TetgenProgram, MeshesTwoBoxesAndImports) {
  if (!fileExists("/usr/bin/tetgen")) GTEST_SKIP() << "/usr/bin/tetgen is not installed";
  const std::string dir = tempDir("tetgen-program");
  writeFile(dir + "/boxes.poly", kTwoBoxesPoly);
  const test::RunResult run = test::runShell("cd " + dir + " && /usr/bin/tetgen -pq1.4a0.01Az boxes.poly");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const size_t points = statistic(run.out, "Mesh points"), tets = statistic(run.out, "Mesh tetrahedra");
  const size_t facet_faces = statistic(run.out, "Mesh faces on facets");
  ASSERT_GT(tets, 0u) << run.out;

  const ImportResult r = mustImport(dir + "/boxes.1");
  EXPECT_EQ(r.mesh.numPoints(), points);
  EXPECT_EQ(r.mesh.numTets(), tets);
  EXPECT_EQ(r.mesh.numTets(), std::stoul(readFile(dir + "/boxes.1.ele")));
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.zero_volume, 0u);
  EXPECT_EQ(s.boundary_faces, std::stoul(readFile(dir + "/boxes.1.face")));
  EXPECT_EQ(s.boundary_faces, facet_faces);
  EXPECT_NEAR(s.total_volume, 2.0, 1e-12);
  // Region attributes 10 and 20, one per cube; boundary faces carry their cube's facet marker.
  const Field* region = findCellField(r.mesh, "region");
  ASSERT_NE(region, nullptr);
  std::set<double> regions;
  for (size_t t = 0; t < r.mesh.numTets(); ++t) regions.insert(region->get(t, 0));
  EXPECT_EQ(regions, (std::set<double>{10.0, 20.0}));
  const Field* markers = findCellField(r.mesh, "face_marker");
  ASSERT_NE(markers, nullptr);
  const FaceAdjacency adj = computeFaceAdjacency(r.mesh);
  for (size_t t = 0; t < r.mesh.numTets(); ++t) {
    for (uint32_t k = 0; k < 4; ++k) {
      if (adj.neighbor[4 * t + k] != kNoNeighbor) continue;
      EXPECT_EQ(markers->data<int32_t>()[4 * t + k], region->get(t, 0) == 10.0 ? 1 : 2);
    }
  }
  // Our export is readable by tetgen itself (-r reconstructs the mesh from .node/.ele).
  ASSERT_TRUE(exportTetgen(r.mesh, dir + "/ours.node").isOk());
  const test::RunResult again = test::runShell("cd " + dir + " && /usr/bin/tetgen -rzQ ours");
  EXPECT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_EQ(std::stoul(readFile(dir + "/ours.1.ele")), tets);
}

TEST(TetgenProgram, QuadraticTetsAndFaces) {
  if (!fileExists("/usr/bin/tetgen")) GTEST_SKIP() << "/usr/bin/tetgen is not installed";
  const std::string dir = tempDir("tetgen-program-o2");
  writeFile(dir + "/boxes.poly", kTwoBoxesPoly);
  const test::RunResult run = test::runShell("cd " + dir + " && /usr/bin/tetgen -pq1.4a0.05Azo2 boxes.poly");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  std::istringstream header(readFile(dir + "/boxes.1.ele"));
  size_t count = 0, per_tet = 0;
  header >> count >> per_tet;
  ASSERT_EQ(per_tet, 10u);
  const ImportResult r = mustImport(dir + "/boxes.1.ele");
  EXPECT_EQ(r.mesh.numTets(), std::stoul(readFile(dir + "/boxes.1.ele")));
  EXPECT_EQ(r.mesh.numPoints(), std::stoul(readFile(dir + "/boxes.1.node")));
  // The corner-only tetrahedra, and the boundary edges TetGen writes beside them (not read).
  ASSERT_EQ(r.report.warnings.size(), 2u);
  EXPECT_EQ(r.report.warnings[1], dir + "/boxes.1.edge beside it (" +
                                      std::to_string(std::stoul(readFile(dir + "/boxes.1.edge"))) +
                                      " edges) is not read");
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.boundary_faces, std::stoul(readFile(dir + "/boxes.1.face")));
  EXPECT_GT(s.unreferenced_points, 0u);  // the edge nodes
  EXPECT_NEAR(s.total_volume, 2.0, 1e-12);
}

// A point set (no -p): TetGen -o2 lists the convex hull's faces with their three corners only.
TEST(TetgenProgram, QuadraticTetsOfAPointSetWithHullFaces) {
  if (!fileExists("/usr/bin/tetgen")) GTEST_SKIP() << "/usr/bin/tetgen is not installed";
  const std::string dir = tempDir("tetgen-program-o2-points");
  std::string node = "27 3 0 0\n";
  for (int i = 0; i < 27; ++i)
    node += std::to_string(i + 1) + " " + std::to_string(i % 3 + 0.1 * (i % 5)) + " " + std::to_string(i / 3 % 3) +
            " " + std::to_string(i / 9 + 0.05 * (i % 7)) + "\n";
  writeFile(dir + "/cloud.node", node);
  const test::RunResult run = test::runShell("cd " + dir + " && /usr/bin/tetgen -Qo2 cloud.node");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  std::istringstream face_header(readFile(dir + "/cloud.1.face"));
  size_t faces = 0;
  face_header >> faces;
  std::string first_row;
  std::getline(face_header, first_row);
  std::getline(face_header, first_row);
  std::istringstream row(first_row);
  size_t values = 0;
  for (std::string token; row >> token;) ++values;
  EXPECT_EQ(values, 4u) << "TetGen now writes edge nodes on hull faces: " << first_row;
  const ImportResult r = mustImport(dir + "/cloud.1");
  EXPECT_EQ(r.mesh.numTets(), std::stoul(readFile(dir + "/cloud.1.ele")));
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.boundary_faces, faces);
  EXPECT_GT(s.unreferenced_points, 0u);  // the edge nodes
}

// --- Hand-written files: syntax variants and malformed inputs -------------------------------------

std::string writeTetgen(const std::string& dir, const std::string& node, const std::string& ele,
                        const std::string& face = "") {
  writeFile(dir + "/m.node", node);
  writeFile(dir + "/m.ele", ele);
  if (!face.empty()) writeFile(dir + "/m.face", face);
  return dir + "/m";
}

const char* kNodes1 =
    "# one-based\n5\t3 1 1\n\n1 0 0 0  0.5 3\n2 1 0 0 1.5 3 # a comment\n3 0 1 0 2.5 3\n"
    "   4 0 0 1 3.5 0\n5 1 1 1 4.5 0\n";

TEST(TetgenImport, OneBasedCommentsTabsAttributesMarkers) {
  const std::string dir = tempDir("tetgen-onebased");
  // Tet 2 is negatively oriented: it gets flipped, and its face markers follow the flip.
  const std::string base =
      writeTetgen(dir, kNodes1, "2 4 0\n1 1 2 3 4\n2 2 4 3 5\n", "# faces\n2 1\n1 1 2 3 9\n2 2 3 4 4\n");
  const ImportResult r = mustImport(base);
  EXPECT_EQ(r.mesh.numPoints(), 5u);
  EXPECT_EQ(r.report.flipped, 1u);
  EXPECT_EQ(computeMeshStats(r.mesh).inverted, 0u);
  ASSERT_EQ(r.mesh.point_fields.size(), 2u);
  EXPECT_EQ(r.mesh.point_fields[0].name, "attribute_0");
  EXPECT_EQ(r.mesh.point_fields[0].type, ScalarType::kFloat64);
  EXPECT_EQ(r.mesh.point_fields[0].get(4, 0), 4.5);
  EXPECT_EQ(r.mesh.point_fields[1].name, "boundary_marker");
  EXPECT_EQ(r.mesh.point_fields[1].type, ScalarType::kInt32);
  EXPECT_EQ(r.mesh.point_fields[1].get(0, 0), 3);
  const Field* fm = findCellField(r.mesh, "face_marker");
  ASSERT_NE(fm, nullptr);
  // Tet 0 = (0,1,2,3): face 1 2 3 (1-based) is opposite vertex 3. The shared face 2 3 4 (1-based)
  // is opposite vertex 0 in tet 0; in flipped tet 1 it is opposite the vertex now holding point 4.
  const int32_t* v = fm->data<int32_t>();
  EXPECT_EQ(v[0], 4);
  EXPECT_EQ(v[3], 9);
  const Tet& t1 = r.mesh.tets[1];
  for (uint32_t k = 0; k < 4; ++k) EXPECT_EQ(v[4 + k], t1[k] == 4 ? 4 : 0) << k;
}

// Nothing is left out without a word: a .face without markers that lists a face inside the mesh (the
// list is then kept nowhere), and the files of the mesh that are not read (.edge, .vol, .mtr).
TEST(TetgenImport, WhatIsNotReadIsSaid) {
  const std::string dir = tempDir("tetgen-not-read");
  const std::string base = writeTetgen(dir, kNodes1, "2 4 0\n1 1 2 3 4\n2 2 4 3 5\n", "2 0\n1 1 2 3\n2 2 3 4\n");
  ImportResult r = mustImport(base);
  EXPECT_EQ(r.report.warnings, std::vector<std::string>{
                                   dir + "/m.face: 1 of its 2 faces lie inside the mesh; without markers, which faces "
                                         "it lists is not kept"});
  // Boundary faces alone without markers lose nothing: no warning.
  writeFile(dir + "/m.face", "2 0\n1 1 2 3\n2 1 2 4\n");
  EXPECT_TRUE(mustImport(base).report.warnings.empty());
  writeFile(dir + "/m.edge", "# edges\n3 1\n1 1 2 5\n2 2 3 5\n3 1 3 0\n");
  writeFile(dir + "/m.vol", "2\n1 0.1\n2 -1\n");
  r = mustImport(base);
  EXPECT_EQ(r.report.warnings, (std::vector<std::string>{dir + "/m.edge beside it (3 edges) is not read",
                                                         dir + "/m.vol beside it (2 volume constraints) is not read"}));
  // gtn info shows them.
  const test::RunResult info = test::runGtn("info " + base);
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.err.find("m.edge beside it (3 edges) is not read"), std::string::npos) << info.err;
}

TEST(TetgenImport, QuadraticTetsKeepCornersWithWarning) {
  const std::string dir = tempDir("tetgen-quadratic");
  const std::string base =
      writeTetgen(dir, "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 .5 0 0\n", "1 10 0\n0 0 1 2 3 4 4 4 4 4 4\n");
  const ImportResult r = mustImport(base);
  ASSERT_EQ(r.mesh.numTets(), 1u);
  EXPECT_TRUE(r.mesh.tets[0] == (Tet{0, 1, 2, 3}));
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("10-node"), std::string::npos);
}

void expectError(const std::string& path, const std::string& file, const std::string& where) {
  auto r = importTetgen(path, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData) << r.status().message();
  EXPECT_NE(r.status().message().find(file + where), std::string::npos) << r.status().message();
}

const char* kNodes0 = "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n";

TEST(TetgenErrors, EleNamesMissingNode) {
  const std::string dir = tempDir("tetgen-missing-node");
  expectError(writeTetgen(dir, kNodes0, "2 4 0\n0 0 1 2 3\n1 1 2 3 7\n"), dir + "/m.ele", ":3:");
  auto r = importTetgen(dir + "/m", ImportOptions{});
  EXPECT_NE(r.status().message().find("node 7"), std::string::npos) << r.status().message();
  // The tetrahedron as the file numbers it (the second row, numbered 1), not by its place.
  EXPECT_NE(r.status().message().find("tetrahedron 1 refers"), std::string::npos) << r.status().message();
  expectError(writeTetgen(dir, kNodes0, "2 4 0\n10 0 1 2 3\n20 1 2 3 7\n"), dir + "/m.ele",
              ":3: tetrahedron 20 refers");
  // One-based nodes: 0 is missing.
  expectError(writeTetgen(dir, kNodes1, "1 4 0\n1 0 1 2 3\n"), dir + "/m.ele", ":2:");
}

TEST(TetgenErrors, NonNumericToken) {
  const std::string dir = tempDir("tetgen-nonnumeric");
  expectError(writeTetgen(dir, "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 x1 0\n3 0 0 1\n4 1 1 1\n", "0 4 0\n"), dir + "/m.node",
              ":4:");
  auto r = importTetgen(dir + "/m", ImportOptions{});
  EXPECT_NE(r.status().message().find("'x1'"), std::string::npos) << r.status().message();
  expectError(writeTetgen(dir, kNodes0, "1 4 0\n0 0 1 2 3.5\n"), dir + "/m.ele", ":2:");
  // A coordinate that is a number but not a finite one: its line, node and axis.
  expectError(writeTetgen(dir, "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 -inf 0\n3 0 0 1\n4 1 1 1\n", "0 4 0\n"), dir + "/m.node",
              ":4: node 2 has a non-finite y coordinate '-inf'");
}

TEST(TetgenErrors, EmptyFile) {
  const std::string dir = tempDir("tetgen-empty");
  expectError(writeTetgen(dir, "", "0 4 0\n"), dir + "/m.node", ":1:");
  expectError(writeTetgen(dir, "# only a comment\n\n", "0 4 0\n"), dir + "/m.node", ":");
  expectError(writeTetgen(dir, kNodes0, ""), dir + "/m.ele", ":1:");
}

TEST(TetgenErrors, DirectoryAsInput) {
  const std::string dir = tempDir("tetgen-dir");
  std::filesystem::create_directories(dir + "/d.node");
  writeFile(dir + "/d.ele", "0 4 0\n");
  auto r = importTetgen(dir + "/d.node", ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kIo);
  EXPECT_NE(r.status().message().find(dir + "/d.node"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("directory"), std::string::npos) << r.status().message();
  auto m = importMesh({dir}, ImportOptions{});
  EXPECT_FALSE(m.isOk());
  EXPECT_NE(m.status().message().find(dir), std::string::npos) << m.status().message();
}

TEST(TetgenErrors, TruncatedFiles) {
  const std::string dir = tempDir("tetgen-truncated");
  // The header announces more rows than there are: caught before allocating when the bytes left
  // cannot hold them (header line), and after the last row otherwise (its line).
  expectError(writeTetgen(dir, "1000000000 3 0 0\n0 0 0 0\n", "0 4 0\n"), dir + "/m.node", ":1:");
  expectError(writeTetgen(dir, "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n", "0 4 0\n"), dir + "/m.node",
              ":1:");
  const std::string padding = "# a long comment that keeps the byte count plausible\n";
  expectError(writeTetgen(dir, "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n" + padding, "0 4 0\n"),
              dir + "/m.node", ":6:");
  auto r = importTetgen(dir + "/m", ImportOptions{});
  EXPECT_NE(r.status().message().find("after 5 of the 6 nodes"), std::string::npos) << r.status().message();
  expectError(writeTetgen(dir, kNodes0, "3 4 0\n0 0 1 2 3\n1 1 2 3 4\n" + padding), dir + "/m.ele", ":3:");
  expectError(writeTetgen(dir, kNodes0, "1 4 0\n0 0 1 2\n" + padding), dir + "/m.ele", ":2:");
  expectError(writeTetgen(dir, kNodes0, "1 4 0\n0 0 1 2 3\n", "2 0\n0 0 1 2\n" + padding), dir + "/m.face", ":2:");
}

TEST(TetgenErrors, DimensionTwoAndOtherHeaders) {
  const std::string dir = tempDir("tetgen-dim2");
  expectError(writeTetgen(dir, "3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n", "0 4 0\n"), dir + "/m.node", ":1:");
  auto r = importTetgen(dir + "/m", ImportOptions{});
  EXPECT_NE(r.status().message().find("dimension 2"), std::string::npos) << r.status().message();
  expectError(writeTetgen(dir, kNodes0, "1 6 0\n0 0 1 2 3 4 4\n"), dir + "/m.ele", ":1:");
  expectError(writeTetgen(dir, "# c\n2 3 0 0\n0 0 0 0\n2 1 0 0\n", "0 4 0\n"), dir + "/m.node", ":4:");
  expectError(writeTetgen(dir, "2 3 0 0\n5 0 0 0\n6 1 0 0\n", "0 4 0\n"), dir + "/m.node", ":2:");
}

TEST(TetgenErrors, FaceNotOfAnyTet) {
  const std::string dir = tempDir("tetgen-face");
  expectError(writeTetgen(dir, kNodes0, "1 4 0\n0 0 1 2 3\n", "2 1\n0 0 1 2 5\n1 0 1 4 5\n"), dir + "/m.face", ":3:");
}

// --- The CLI --------------------------------------------------------------------------------------

TEST(TetgenCli, MissingNodeFailsWithoutOutput) {
  const std::string dir = tempDir("tetgen-cli-bad");
  writeTetgen(dir, kNodes0, "2 4 0\n0 0 1 2 3\n1 1 2 3 7\n");
  const test::RunResult r = test::runGtn("convert " + dir + "/m.ele -o " + dir + "/out.vtu");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(dir + "/m.ele:3:"), std::string::npos) << r.err;
  EXPECT_FALSE(fileExists(dir + "/out.vtu"));
}

TEST(TetgenCli, ConvertToTetgenAndInfo) {
  const std::string dir = tempDir("tetgen-cli");
  const test::RunResult c =
      test::runGtn("convert " + dataPath("tetgen/cornellbox_orig.1.node") + " -o " + dir + "/out.node");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_TRUE(fileExists(dir + "/out.ele"));
  EXPECT_TRUE(fileExists(dir + "/out.face"));
  const test::RunResult i = test::runGtn("info " + dir + "/out.node --json");
  ASSERT_EQ(i.exit_code, 0) << i.err;
  const nlohmann::json j = nlohmann::json::parse(i.out);
  EXPECT_EQ(j["points"], 331);
  EXPECT_EQ(j["tets"], 1631);
  EXPECT_EQ(j["inverted"], 0);
  EXPECT_EQ(j["boundary_faces"], 230);
  EXPECT_EQ(j["metadata"]["source.format"], "tetgen");
}

TEST(TetgenCli, InfoOnBasename) {
  // "cornell_spheres.1" names no file; its .node and .ele make it a TetGen basename.
  const test::RunResult i = test::runGtn("info " + dataPath("tetgen/cornell_spheres.1") + " --json");
  ASSERT_EQ(i.exit_code, 0) << i.err;
  const nlohmann::json j = nlohmann::json::parse(i.out);
  EXPECT_EQ(j["points"], 4089);
  EXPECT_EQ(j["tets"], 24207);
  EXPECT_EQ(j["inverted"], 0);
}

TEST(TetgenImport, WeldAppliesWhenTheMeshIsNamedByItsFiles) {
  // Point 5 repeats point 1: the second tetrahedron keeps four corners, the third loses one.
  const std::string dir = tempDir("tetgen_weld");
  writeFile(dir + "/w.node", "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n5 1 0 0\n");
  writeFile(dir + "/w.ele", "3 4 0\n0 0 1 2 3\n1 5 2 3 4\n2 1 5 2 3\n");
  ImportOptions weld;
  weld.weld = true;
  for (const std::vector<std::string>& inputs :
       {std::vector<std::string>{dir + "/w"}, std::vector<std::string>{dir + "/w.node", dir + "/w.ele"}}) {
    auto r = importMesh(inputs, weld);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->report.welded_points, 1u);
    EXPECT_EQ(r->report.collapsed_tets, 1u);
    EXPECT_EQ(r->mesh.numPoints(), 5u);
    EXPECT_EQ(r->mesh.numTets(), 2u);
    EXPECT_EQ(r->report.zero_volume, 0u);
  }
  auto plain = importMesh({dir + "/w.node", dir + "/w.ele"}, ImportOptions{});
  ASSERT_TRUE(plain.isOk()) << plain.status().message();
  EXPECT_EQ(plain->mesh.numPoints(), 6u);
  EXPECT_EQ(plain->mesh.numTets(), 3u);
}

// meshio's TetGen writer puts a point field into the boundary-marker column and names it in a
// comment: a column of reals is read as that field.
TEST(TetgenImport, MeshioPointFieldInTheMarkerColumn) {
  const std::string dir = tempDir("tetgen_meshio");
  writeFile(dir + "/m.node",
            "# This file was created by meshio v5.0.0\n# attribute and marker names: temp\n5 3 0 1\n"
            "0 0 0 0 1\n1 1 0 0 -0.5\n2 0 1 0 2.25\n3 0 0 1 3\n4 1 1 1 4e-3\n");
  writeFile(dir + "/m.ele", "2 4 0\n0 0 1 2 3\n1 1 2 3 4\n");
  auto r = importMesh({dir + "/m.node"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.point_fields.size(), 1u);
  const Field& f = r->mesh.point_fields[0];
  EXPECT_EQ(f.name, "temp");
  EXPECT_EQ(f.type, ScalarType::kFloat64);
  EXPECT_EQ(f.data<double>()[0], 1.0);
  EXPECT_EQ(f.data<double>()[1], -0.5);
  EXPECT_EQ(f.data<double>()[4], 4e-3);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("read as the float64 field 'temp'"), std::string::npos) << r->report.warnings[0];
  // Integer markers stay int32 boundary markers.
  writeFile(dir + "/i.node", "5 3 0 1\n0 0 0 0 1\n1 1 0 0 -5\n2 0 1 0 2\n3 0 0 1 3\n4 1 1 1 4\n");
  writeFile(dir + "/i.ele", "2 4 0\n0 0 1 2 3\n1 1 2 3 4\n");
  auto i = importMesh({dir + "/i.node"}, ImportOptions{});
  ASSERT_TRUE(i.isOk()) << i.status().message();
  EXPECT_EQ(i->mesh.point_fields[0].type, ScalarType::kInt32);
  EXPECT_TRUE(i->report.warnings.empty());
}

}  // namespace
}  // namespace gtn
