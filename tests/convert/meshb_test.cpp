// Medit binary (.meshb) import: files of every version (1-4) in both byte orders, built here by a
// small writer that follows libMeshb's layout; keywords skipped by their next-keyword position;
// truncated, oversized and inconsistent files.
#include <gtest/gtest.h>

#include <cstring>

#include "convert/import.h"
#include "mesh/mesh_stats.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::tempDir;
using test::writeFile;

// Writes GMF binary: 32-bit words, 64-bit reals from version 2, 64-bit positions from version 3,
// 64-bit integers (counts, indices, references) in version 4; big-endian when `swap`.
class MeshbWriter {
 public:
  MeshbWriter(int version, bool swap) : version_(version), swap_(swap) {
    word(1, 4);
    word(static_cast<uint64_t>(version), 4);
  }
  // Opens a keyword record; its next-keyword position is filled in by the next begin() or end().
  void begin(uint32_t code) {
    close();
    word(code, 4);
    next_at_ = bytes_.size();
    word(0, version_ >= 3 ? 8 : 4);
  }
  void integer(int64_t v) { word(static_cast<uint64_t>(v), version_ == 4 ? 8 : 4); }
  void int32(int32_t v) { word(static_cast<uint32_t>(v), 4); }
  void real(double v) {
    if (version_ == 1) {
      const float f = static_cast<float>(v);
      uint32_t u;
      std::memcpy(&u, &f, 4);
      word(u, 4);
    } else {
      uint64_t u;
      std::memcpy(&u, &v, 8);
      word(u, 8);
    }
  }
  std::string end() {
    begin(54);  // End, the last keyword: its next position stays 0
    next_at_ = 0;
    return bytes_;
  }
  size_t size() const { return bytes_.size(); }

 private:
  void close() {
    if (next_at_ == 0) return;
    const size_t size = version_ >= 3 ? 8 : 4;
    const std::string pos = encode(bytes_.size(), size);
    bytes_.replace(next_at_, size, pos);
  }
  std::string encode(uint64_t v, size_t size) const {
    std::string s(size, '\0');
    for (size_t i = 0; i < size; ++i) s[swap_ ? size - 1 - i : i] = static_cast<char>((v >> (8 * i)) & 0xFF);
    return s;
  }
  void word(uint64_t v, size_t size) { bytes_ += encode(v, size); }

  int version_;
  bool swap_;
  size_t next_at_ = 0;
  std::string bytes_;
};

// Two unit cubes side by side as hexahedra (references 3, 4), a tetrahedron below them (reference
// -5), a boundary triangle and a keyword the reader does not know, to be skipped.
std::string twoCubesAndATet(int version, bool swap) {
  MeshbWriter w(version, swap);
  w.begin(3);
  w.int32(3);
  w.begin(4);
  const double c[13][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0},      {0, 0, 1},
                           {1, 0, 1}, {2, 0, 1}, {0, 1, 1}, {1, 1, 1}, {2, 1, 1}, {0.5, 0.25, -1}};
  w.integer(13);
  for (int i = 0; i < 13; ++i) {
    for (int d = 0; d < 3; ++d) w.real(c[i][d]);
    w.integer(100 + i);
  }
  w.begin(6);  // Triangles
  w.integer(1);
  for (int v : {1, 2, 4, 7}) w.integer(v);
  w.begin(200);  // unknown to the reader (and to libMeshb 7): skipped by position
  w.int32(12345);
  w.begin(10);  // Hexahedra
  w.integer(2);
  for (int v : {1, 2, 5, 4, 7, 8, 11, 10, 3, 2, 3, 6, 5, 8, 9, 12, 11, 4}) w.integer(v);
  w.begin(8);  // Tetrahedra
  w.integer(1);
  for (int v : {1, 2, 4, 13, -5}) w.integer(v);
  return w.end();
}

TEST(MeshbImport, EveryVersionInBothByteOrders) {
  const std::string dir = tempDir("meshb-versions");
  for (int version = 1; version <= 4; ++version) {
    for (bool swap : {false, true}) {
      const std::string path = dir + "/v" + std::to_string(version) + (swap ? "be" : "le") + ".meshb";
      writeFile(path, twoCubesAndATet(version, swap));
      auto r = importMesh({path}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << path << ": " << r.status().message();
      const TetMesh& m = r->mesh;
      ASSERT_EQ(m.numPoints(), 13u) << path;
      EXPECT_EQ(m.coord_type, version == 1 ? ScalarType::kFloat32 : ScalarType::kFloat64);
      EXPECT_EQ(m.point(12)[0], 0.5);
      EXPECT_EQ(m.point(12)[1], 0.25);
      EXPECT_EQ(m.point(12)[2], -1.0);
      EXPECT_EQ(m.point(5)[0], 2.0);
      ASSERT_EQ(m.point_fields.size(), 1u);
      EXPECT_EQ(m.point_fields[0].get(12, 0), 112);
      // The tetrahedron first, then 6 per cube.
      ASSERT_EQ(m.numTets(), 13u) << path;
      EXPECT_TRUE(m.tets[0] == (Tet{0, 1, 3, 12}) || m.tets[0] == (Tet{0, 1, 12, 3})) << path;
      ASSERT_EQ(m.cell_fields.size(), 1u);
      EXPECT_EQ(m.cell_fields[0].get(0, 0), -5);
      EXPECT_EQ(m.cell_fields[0].get(1, 0), 3);
      EXPECT_EQ(m.cell_fields[0].get(12, 0), 4);
      const MeshStats s = computeMeshStats(m);
      EXPECT_NEAR(s.total_volume, 2.0 + 0.5 / 3, 1e-12) << path;
      EXPECT_EQ(s.inverted, 0u);
      EXPECT_EQ(s.non_manifold_faces, 0u);
      ASSERT_NE(m.findMetadata("source.format"), nullptr);
      EXPECT_EQ(*m.findMetadata("source.format"), "meshb");
    }
  }
}

void expectError(const std::string& path, const std::string& bytes, const std::string& what) {
  writeFile(path, bytes);
  auto r = importMesh({path}, ImportOptions{});
  ASSERT_FALSE(r.isOk()) << what;
  EXPECT_NE(r.status().message().find(what), std::string::npos) << r.status().message();
  EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
}

std::string withWord32(std::string bytes, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
  return bytes;
}

TEST(MeshbErrors, BadInputs) {
  const std::string dir = tempDir("meshb-errors");
  const std::string p = dir + "/bad.meshb";
  const std::string good = twoCubesAndATet(2, false);
  // Version 2: header 8 bytes, Dimension record 12, Vertices record: code, position, count at 28.
  expectError(p, withWord32(good, 0, 2), "byte offset 0: not a .meshb file: its first word is 2");
  expectError(p, withWord32(good, 4, 5), "byte offset 4: .meshb version 5 is not supported");
  expectError(p, withWord32(good, 16, 2), "byte offset 8: dimension 2: only 3-dimensional");
  // A vertex count that the bytes before the next keyword cannot hold fails before any allocation.
  expectError(p, withWord32(good, 28, 0x7FFFFFFF), "byte offset 28: Vertices count 2147483647 needs");
  expectError(p, withWord32(good, 28, 0xFFFFFFFF), "byte offset 28: Vertices count -1 is negative");
  // A next-keyword position that points backwards or past the end.
  expectError(p, withWord32(good, 24, 8), "byte offset 20: keyword 4 says the next keyword is at byte offset 8");
  expectError(p, withWord32(good, 24, 1u << 30), "is at byte offset 1073741824, outside");
  // A hexahedron corner out of range, located at its own bytes.
  const size_t hexes = good.find(std::string("\x0A\0\0\0", 4), 200);
  ASSERT_NE(hexes, std::string::npos);
  expectError(p, withWord32(good, hexes + 12, 14),
              "byte offset " + std::to_string(hexes + 12) +
                  ": hexahedron 1 refers to vertex 14; vertices are numbered 1 to 13");
  // No volume elements.
  MeshbWriter surface(3, false);
  surface.begin(3);
  surface.int32(3);
  surface.begin(4);
  surface.integer(1);
  for (int d = 0; d < 3; ++d) surface.real(d);
  surface.integer(0);
  expectError(p, surface.end(), "no volume elements");
}

// Every keyword the reader skips is counted in a warning (boundary triangles, edges, corners, a
// keyword it does not know), several records of one keyword together; single values become metadata.
TEST(MeshbImport, EverySkippedKeywordIsCounted) {
  const std::string dir = tempDir("meshb-left-out");
  for (int version : {1, 4}) {
    MeshbWriter w(version, false);
    w.begin(3);
    w.int32(3);
    w.begin(4);
    w.integer(5);
    const double c[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    for (const auto& p : c) {
      for (double v : p) w.real(v);
      w.integer(0);
    }
    const size_t triangles_at = w.size();
    w.begin(6);  // Triangles
    w.integer(2);
    for (int v : {1, 2, 3, 5, 1, 2, 4, 6}) w.integer(v);
    w.begin(5);  // Edges
    w.integer(1);
    for (int v : {1, 2, 0}) w.integer(v);
    w.begin(6);  // a second Triangles record
    w.integer(1);
    for (int v : {2, 3, 4, 7}) w.integer(v);
    w.begin(13);  // Corners
    w.integer(3);
    for (int v : {1, 2, 3}) w.integer(v);
    w.begin(78);  // Time
    w.real(0.5);
    const size_t unknown_at = w.size();
    w.begin(200);
    w.int32(1);
    w.begin(8);
    w.integer(1);
    for (int v : {1, 2, 3, 4, 9}) w.integer(v);
    const std::string path = dir + "/v" + std::to_string(version) + ".meshb";
    writeFile(path, w.end());
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->mesh.numTets(), 1u);
    const std::string lower =
        ": elements of lower dimension, with their references: only volume elements become tetrahedra";
    const std::vector<std::string> want = {
        "skipped 3 Triangles (byte offset " + std::to_string(triangles_at) + " and 1 more records)" + lower,
        "skipped 1 Edges (byte offset " +
            std::to_string(triangles_at + (version >= 3 ? 12 : 8) + (version == 4 ? 8 * 9 : 4 * 9)) + ")" + lower,
        "skipped 3 Corners (byte offset ",
        "skipped keyword 200 (byte offset " + std::to_string(unknown_at) +
            "): a keyword unknown to this reader, not read",
    };
    ASSERT_EQ(r->report.warnings.size(), 4u) << version;
    EXPECT_EQ(r->report.warnings[0], want[0]);
    EXPECT_EQ(r->report.warnings[1], want[1]);
    EXPECT_EQ(r->report.warnings[2].rfind(want[2], 0), 0u) << r->report.warnings[2];
    EXPECT_EQ(r->report.warnings[3], want[3]);
    ASSERT_NE(r->mesh.findMetadata("medit.Time"), nullptr);
    EXPECT_EQ(*r->mesh.findMetadata("medit.Time"), "0.5");
  }
}

// Higher-order volume elements are skipped by position with a warning; the rest still reads.
// The content, not the extension, tells ASCII from binary Medit: gmsh 4.8 (-format mesh -bin) writes
// ASCII into a file it names .meshb, and a binary file renamed .mesh is still binary.
TEST(MeshbImport, ContentDecidesBetweenAsciiAndBinary) {
  const std::string dir = tempDir("meshb-content");
  const std::string ascii =
      "MeshVersionFormatted 2\nDimension\n3\nVertices\n4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n"
      "Tetrahedra\n1\n1 2 3 4 7\nEnd\n";
  writeFile(dir + "/ascii.meshb", ascii);
  EXPECT_EQ(detectInputFormat(dir + "/ascii.meshb"), InputFormat::kMedit);
  auto a = importMesh({dir + "/ascii.meshb"}, ImportOptions{});
  ASSERT_TRUE(a.isOk()) << a.status().message();
  EXPECT_EQ(a->mesh.numPoints(), 4u);
  ASSERT_EQ(a->mesh.numTets(), 1u);
  ASSERT_EQ(a->mesh.cell_fields.size(), 1u);
  EXPECT_EQ(a->mesh.cell_fields[0].get(0, 0), 7);

  for (bool swap : {false, true}) {
    const std::string path = dir + (swap ? "/binary_be.mesh" : "/binary_le.mesh");
    writeFile(path, twoCubesAndATet(2, swap));
    EXPECT_EQ(detectInputFormat(path), InputFormat::kMeshb) << path;
    auto b = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(b.isOk()) << path << ": " << b.status().message();
    EXPECT_EQ(b->mesh.numPoints(), 13u);
    EXPECT_EQ(b->mesh.numTets(), 13u);
    EXPECT_EQ(*b->mesh.findMetadata("source.format"), "meshb");
  }
}

// TetrahedraP2 and HexahedraQ2 elements are kept by their corners, with a warning; TetrahedraP3
// ones are skipped with a warning (an error when nothing else is left).
TEST(MeshbImport, QuadraticElementsKeepTheirCornersHigherOrderOnesAreSkipped) {
  const std::string dir = tempDir("meshb-p2");
  size_t q2_at = 0;
  auto file = [&](bool with_p2) {
    MeshbWriter w(2, false);
    w.begin(3);
    w.int32(3);
    w.begin(4);
    w.integer(12);
    const double c[12][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, {2, 0, 0},
                             {2, 1, 0}, {1, 1, 0}, {1, 0, 1}, {2, 0, 1}, {2, 1, 1}, {1, 1, 1}};
    for (const auto& p : c) {
      for (double v : p) w.real(v);
      w.integer(0);
    }
    if (with_p2) {
      w.begin(30);  // TetrahedraP2: 4 corners, 6 mid-edge nodes (any vertices here), a reference
      w.integer(1);
      for (int v : {1, 2, 3, 4, 1, 2, 3, 4, 1, 2, 7}) w.integer(v);
    }
    q2_at = w.size();
    w.begin(96);  // TetrahedraP3: 20 nodes and a reference
    w.integer(1);
    for (int k = 0; k < 21; ++k) w.integer(k % 4 + 1);
    if (with_p2) {
      w.begin(33);  // HexahedraQ2: the corners of the cube [1,2] x [0,1] x [0,1], 19 other nodes, a reference
      w.integer(1);
      for (int v : {5, 6, 7, 8, 9, 10, 11, 12}) w.integer(v);
      for (int k = 0; k < 19; ++k) w.integer(1);
      w.integer(8);
    }
    return w.end();
  };
  writeFile(dir + "/p2.meshb", file(true));
  auto r = importMesh({dir + "/p2.meshb"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 7u);
  EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 1.0 / 6.0 + 1.0, 1e-12);
  ASSERT_EQ(r->report.warnings.size(), 3u) << ::testing::PrintToString(r->report.warnings);
  EXPECT_NE(r->report.warnings[0].find("skipped TetrahedraP3 at byte offset " + std::to_string(q2_at)),
            std::string::npos)
      << r->report.warnings[0];
  EXPECT_EQ(r->report.warnings[1],
            "1 TetrahedraP2 elements kept by their 4 corners; their mid-edge nodes are kept as unreferenced points");
  EXPECT_EQ(r->report.warnings[2],
            "1 HexahedraQ2 elements kept by their 8 corners; their other nodes are kept as unreferenced points");
  const Field* ref = test::findField(r->mesh.cell_fields, "ref");
  ASSERT_NE(ref, nullptr);
  EXPECT_EQ(ref->get(0, 0), 7);
  for (size_t t = 1; t < 7; ++t) EXPECT_EQ(ref->get(t, 0), 8) << t;
  // Without the P2 tetrahedron: an error that names what was skipped.
  writeFile(dir + "/only.meshb", file(false));
  auto e = importMesh({dir + "/only.meshb"}, ImportOptions{});
  ASSERT_FALSE(e.isOk());
  EXPECT_NE(
      e.status().message().find("only TetrahedraP3 (byte offset " + std::to_string(q2_at) + "), which are not read"),
      std::string::npos)
      << e.status().message();
}

// Every prefix of a valid file fails with a message that names the file, none crashes, except the
// one that ends where the Tetrahedra record starts: a file may end after any whole record (End is
// needed only to stop early), and that one holds the two cubes.
TEST(MeshbErrors, EveryPrefixFailsCleanly) {
  const std::string dir = tempDir("meshb-prefixes");
  const std::string p = dir + "/prefix.meshb";
  for (int version : {1, 4}) {
    const std::string good = twoCubesAndATet(version, version == 4);
    size_t successes = 0;
    for (size_t n = 0; n < good.size() - (4 + (version >= 3 ? 8 : 4)); ++n) {
      writeFile(p, good.substr(0, n));
      auto r = importMesh({p}, ImportOptions{});
      if (r.isOk()) {
        ++successes;
        EXPECT_EQ(r->mesh.numTets(), 12u) << "version " << version << " prefix " << n;
      } else {
        EXPECT_EQ(r.status().message().rfind(p, 0), 0u) << r.status().message();
      }
    }
    EXPECT_EQ(successes, 1u) << "version " << version;
  }
}

// ---- Medit solution files (.sol, .solb) ----

// Two tetrahedra sharing a face, in ASCII .mesh.
const char kTwoTets[] =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 1\n"
    "Tetrahedra\n2\n1 2 3 4 7\n2 3 4 5 8\nEnd\n";

// SolAtVertices: a scalar and a vector per vertex; SolAtTetrahedra: a symmetric matrix per tetrahedron.
double vertexValue(int v, int c) { return 0.25 * v - c + (c == 2 ? 1e-7 : 0.0); }  // c = 0 scalar, 1-3 vector
double tetValue(int t, int c) { return 10.0 * t + c + 0.5; }

std::string asciiSolution(int version) {
  std::string s =
      "MeshVersionFormatted " + std::to_string(version) + "\n# a comment\nDimension 3\nSolAtVertices\n5\n2 1 2\n";
  char buf[64];
  for (int v = 0; v < 5; ++v) {
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof buf, "%.17g ", vertexValue(v, c));
      s += buf;
    }
    s += "\n";
  }
  s += "SolAtTetrahedra\n2\n1 3\n";
  for (int t = 0; t < 2; ++t) {
    for (int c = 0; c < 6; ++c) s += std::to_string(tetValue(t, c)) + " ";
    s += "\n";
  }
  return s + "End\n";
}

std::string binarySolution(int version, bool swap) {
  MeshbWriter w(version, swap);
  w.begin(3);
  w.int32(3);
  w.begin(64);  // SolAtTriangles: skipped
  w.integer(1);
  w.int32(1);
  w.int32(1);
  w.real(42);
  w.begin(62);  // SolAtVertices: the count an integer, the type count and types 32-bit
  w.integer(5);
  w.int32(2);
  w.int32(1);
  w.int32(2);
  for (int v = 0; v < 5; ++v)
    for (int c = 0; c < 4; ++c) w.real(vertexValue(v, c));
  w.begin(66);  // SolAtTetrahedra
  w.integer(2);
  w.int32(1);
  w.int32(3);
  for (int t = 0; t < 2; ++t)
    for (int c = 0; c < 6; ++c) w.real(tetValue(t, c));
  return w.end();
}

void expectSolutionFields(const TetMesh& m, int version, const std::string& where) {
  // "ref" from the mesh, then the solution's fields, named after the file.
  ASSERT_EQ(m.point_fields.size(), 3u) << where;
  ASSERT_EQ(m.cell_fields.size(), 2u) << where;
  const Field& scalar = m.point_fields[1];
  const Field& vector = m.point_fields[2];
  const Field& matrix = m.cell_fields[1];
  EXPECT_EQ(scalar.name, "u_1") << where;
  EXPECT_EQ(vector.name, "u_2") << where;
  EXPECT_EQ(matrix.name, "u") << where;
  EXPECT_EQ(scalar.components, 1u);
  EXPECT_EQ(vector.components, 3u);
  EXPECT_EQ(matrix.components, 6u);
  const ScalarType type = version == 1 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  EXPECT_EQ(scalar.type, type) << where;
  EXPECT_EQ(matrix.type, type) << where;
  auto expected = [&](double v) { return version == 1 ? static_cast<double>(static_cast<float>(v)) : v; };
  for (int v = 0; v < 5; ++v) {
    EXPECT_EQ(scalar.get(v, 0), expected(vertexValue(v, 0))) << where << " vertex " << v;
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(vector.get(v, c), expected(vertexValue(v, c + 1))) << where << " vertex " << v;
  }
  // The symmetric matrix, m11 m21 m22 m31 m32 m33 in the file, in VTK's order XX YY ZZ XY YZ XZ.
  constexpr int kFromMedit[6] = {0, 2, 5, 1, 4, 3};
  for (int t = 0; t < 2; ++t)
    for (int c = 0; c < 6; ++c) EXPECT_EQ(matrix.get(t, c), expected(tetValue(t, kFromMedit[c]))) << where;
}

bool saysMatrixOrder(const std::string& warning) {
  return warning.find(
             "the symmetric matrix 'u' is stored in VTK's component order (XX YY ZZ XY YZ XZ), not Medit's "
             "(m11 m21 m22 m31 m32 m33)") != std::string::npos;
}

TEST(MeditSolution, AsciiAndBinaryFilesBecomeFields) {
  const std::string dir = tempDir("medit-sol");
  writeFile(dir + "/m.mesh", kTwoTets);
  for (int version : {1, 2}) {
    writeFile(dir + "/u.sol", asciiSolution(version));
    auto r = importMesh({dir + "/m.mesh", dir + "/u.sol"}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    expectSolutionFields(r->mesh, version, "u.sol version " + std::to_string(version));
    ASSERT_EQ(r->report.warnings.size(), 1u);
    EXPECT_TRUE(saysMatrixOrder(r->report.warnings[0])) << r->report.warnings[0];
    EXPECT_NE(r->report.warnings[0].find("u.sol: line 12: "), std::string::npos) << r->report.warnings[0];
  }
  for (int version = 1; version <= 4; ++version)
    for (bool swap : {false, true}) {
      const std::string where = "u.solb version " + std::to_string(version) + (swap ? " big-endian" : "");
      writeFile(dir + "/u.solb", binarySolution(version, swap));
      auto r = importMesh({dir + "/m.mesh", dir + "/u.solb"}, ImportOptions{});
      ASSERT_TRUE(r.isOk()) << where << ": " << r.status().message();
      expectSolutionFields(r->mesh, version, where);
      ASSERT_EQ(r->report.warnings.size(), 2u) << where;
      EXPECT_NE(r->report.warnings[0].find("solution keyword 64 skipped"), std::string::npos) << r->report.warnings[0];
      EXPECT_TRUE(saysMatrixOrder(r->report.warnings[1])) << r->report.warnings[1];
    }
  // A binary mesh takes them too.
  writeFile(dir + "/m.meshb", twoCubesAndATet(2, false));
  writeFile(dir + "/c.sol",
            "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n13\n1 1\n"
            "0 1 2 3 4 5 6 7 8 9 10 11 12\nSolAtTetrahedra\n1\n1 1\n7\nEnd\n");
  auto r = importMesh({dir + "/m.meshb", dir + "/c.sol"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.point_fields.size(), 2u);
  EXPECT_EQ(r->mesh.point_fields[1].name, "c");
  EXPECT_EQ(r->mesh.point_fields[1].get(12, 0), 12.0);
  // Its hexahedra were split: element values do not follow the tetrahedra, and are left out.
  EXPECT_EQ(r->mesh.cell_fields.size(), 1u);
  ASSERT_EQ(r->report.warnings.size(), 3u);  // after the mesh's skipped triangle and unknown keyword
  EXPECT_EQ(r->report.warnings[0].rfind("skipped 1 Triangles (byte offset ", 0), 0u) << r->report.warnings[0];
  EXPECT_EQ(r->report.warnings[1].rfind("skipped keyword 200 (byte offset ", 0), 0u) << r->report.warnings[1];
  EXPECT_NE(r->report.warnings[2].find("SolAtTetrahedra skipped"), std::string::npos) << r->report.warnings[2];
}

// A Medit hexahedron with a warped face is split around an added point (cell_split.h); the vertex
// solution is read before the split, so it counts the file's 8 vertices, and the added point gets
// the mean of the corners' values.
TEST(MeditSolution, VertexValuesFollowAPointAddedInAWarpedHexahedron) {
  const std::string dir = tempDir("medit-sol-steiner");
  writeFile(dir + "/w.mesh",
            "MeshVersionFormatted 2\nDimension 3\nVertices\n8\n0 0 -1 0\n1 0 -1 0\n1 1 -1 0\n0 1 -1 0\n"
            "0.3 0.3 -1.3 0\n0.7 0.3 -2 0\n0.7 0.7 -2 0\n0.3 0.7 -2 0\nHexahedra\n1\n5 6 7 8 1 2 3 4 3\nEnd\n");
  writeFile(dir + "/w.sol",
            "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n8\n1 1\n1\n2\n3\n4\n5\n6\n7\n9\nEnd\n");
  auto r = importMesh({dir + "/w.mesh", dir + "/w.sol"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->report.steiner_points, 1u);
  ASSERT_EQ(r->mesh.numPoints(), 9u);
  EXPECT_EQ(r->mesh.numTets(), 12u);
  EXPECT_EQ(computeMeshStats(r->mesh).inverted, 0u);
  const Field* w = r->mesh.findPointField("w");
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(w->get(8, 0), 37.0 / 8.0);
  ASSERT_EQ(r->mesh.cell_fields.size(), 1u);
  for (size_t t = 0; t < r->mesh.numTets(); ++t) EXPECT_EQ(r->mesh.cell_fields[0].get(t, 0), 3.0);
}

TEST(MeditSolution, MismatchedOrMalformedFilesAreRejected) {
  const std::string dir = tempDir("medit-sol-bad");
  writeFile(dir + "/m.mesh", kTwoTets);
  auto expectError = [&](const std::string& name, const std::string& text, const std::string& part) {
    writeFile(dir + "/" + name, text);
    auto r = importMesh({dir + "/m.mesh", dir + "/" + name}, ImportOptions{});
    ASSERT_FALSE(r.isOk()) << name;
    EXPECT_NE(r.status().message().find(dir + "/" + name), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message() << "\nlacks: " << part;
  };
  expectError("count.sol", "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n4\n1 1\n0 1 2 3\nEnd\n",
              "SolAtVertices has 4 entries but the mesh has 5 vertices");
  expectError("type.sol", "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n5\n1 7\n0 1 2 3 4\nEnd\n",
              "solution type 7");
  expectError("short.sol", "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n5\n1 2\n0 1 2 3 4\nEnd\n",
              "SolAtVertices values");
  expectError("dim.sol", "MeshVersionFormatted 2\nDimension 2\nSolAtVertices\n5\n1 1\n0 1 2 3 4\nEnd\n", "dimension 2");
  expectError("words.sol", "MeshVersionFormatted 2\nDimension 3\nVertices\n5\nEnd\n",
              "unknown section 'Vertices' in a solution file");
  std::string cut = binarySolution(2, false);
  cut.resize(cut.size() - 40);
  expectError("cut.solb", cut, "byte offset");
  std::string huge = binarySolution(3, true);
  expectError("huge.solb", huge.substr(0, 60), "byte offset");
  // Only solution files may follow a Medit mesh.
  auto r = importMesh({dir + "/m.mesh", dir + "/m.mesh"}, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find("solution files (.sol, .solb)"), std::string::npos) << r.status().message();
  // And a solution file is no mesh.
  r = importMesh({dir + "/count.sol"}, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUsage) << r.status().message();
  EXPECT_NE(r.status().message().find("count.sol: a Medit solution file holds values, not a mesh"), std::string::npos)
      << r.status().message();
}

TEST(MeditSolution, AFileBesideTheMeshIsPointedOut) {
  const std::string dir = tempDir("medit-sol-beside");
  writeFile(dir + "/m.mesh", kTwoTets);
  writeFile(dir + "/m.sol", asciiSolution(2));
  auto r = importMesh({dir + "/m.mesh"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.point_fields.size(), 1u);  // not read unless named
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find(dir + "/m.sol beside it holds solution values"), std::string::npos)
      << r->report.warnings[0];
}

}  // namespace
}  // namespace gtn
