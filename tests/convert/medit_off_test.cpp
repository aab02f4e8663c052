// Medit .mesh and tetrahedral OFF import: the bunny dataset, OFF written from a TetGen mesh, syntax
// variants and malformed inputs.
#include <gtest/gtest.h>

#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "convert/import.h"
#include "mesh/mesh_stats.h"
#include "mesh/predicates.h"
#include "test_util.h"

namespace gtn {
namespace {

using test::dataPath;
using test::tempDir;
using test::writeFile;

// Negatively oriented tetrahedra of a Medit file, counted by a separate minimal reader.
size_t countNegativeMedit(const std::string& path) {
  std::ifstream in(path);
  std::string word;
  std::vector<double> xyz;
  size_t negative = 0;
  while (in >> word) {
    if (word == "Vertices") {
      size_t n;
      in >> n;
      xyz.resize(3 * n);
      for (size_t i = 0; i < n; ++i) {
        int ref;
        in >> xyz[3 * i] >> xyz[3 * i + 1] >> xyz[3 * i + 2] >> ref;
      }
    } else if (word == "Tetrahedra") {
      size_t n;
      in >> n;
      for (size_t t = 0; t < n; ++t) {
        size_t v[4];
        int ref;
        in >> v[0] >> v[1] >> v[2] >> v[3] >> ref;
        if (orient3d(&xyz[3 * (v[0] - 1)], &xyz[3 * (v[1] - 1)], &xyz[3 * (v[2] - 1)], &xyz[3 * (v[3] - 1)]) < 0)
          ++negative;
      }
    }
  }
  return negative;
}

TEST(MeditImport, Bunny) {
  const std::string path = dataPath("medit/bunny.mesh");
  auto r = importMedit(path, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  EXPECT_EQ(m.numPoints(), 5433u);
  EXPECT_EQ(m.numTets(), 34055u);
  EXPECT_EQ(m.coord_type, ScalarType::kFloat64);
  const MeshStats s = computeMeshStats(m);
  EXPECT_EQ(s.inverted, 0u);
  // The file's tetrahedra are all positive already: nothing is flipped, as an independent count says.
  EXPECT_EQ(countNegativeMedit(path), 0u);
  EXPECT_EQ(r->report.flipped, 0u);
  EXPECT_EQ(r->report.zero_volume, 0u);
  ASSERT_EQ(m.point_fields.size(), 1u);
  EXPECT_EQ(m.point_fields[0].name, "ref");
  EXPECT_EQ(m.point_fields[0].type, ScalarType::kInt32);
  ASSERT_EQ(m.cell_fields.size(), 1u);
  EXPECT_EQ(m.cell_fields[0].name, "ref");
  ASSERT_NE(m.findMetadata("source.format"), nullptr);
  EXPECT_EQ(*m.findMetadata("source.format"), "medit");
  // The dispatcher picks Medit from the extension.
  auto d = importMesh({path}, ImportOptions{});
  ASSERT_TRUE(d.isOk());
  EXPECT_EQ(d->mesh.numTets(), 34055u);
}

TEST(MeditImport, BunnyReversedIsFlippedBack) {
  // The bunny with vertices 3 and 4 of every tetrahedron swapped: all negative, all flipped back.
  std::istringstream in(test::readFile(dataPath("medit/bunny.mesh")));
  std::ostringstream out;
  std::string line;
  size_t remaining = 0;
  bool in_tets = false;
  while (std::getline(in, line)) {
    if (in_tets && remaining > 0) {
      std::istringstream row(line);
      std::string a, b, c, d, ref;
      row >> a >> b >> c >> d >> ref;
      out << a << ' ' << b << ' ' << d << ' ' << c << ' ' << ref << '\n';
      --remaining;
      continue;
    }
    out << line << '\n';
    if (line == "Tetrahedra") {
      std::getline(in, line);
      out << line << '\n';
      remaining = std::stoul(line);
      in_tets = true;
    }
  }
  const std::string dir = tempDir("medit-reversed");
  writeFile(dir + "/r.mesh", out.str());
  EXPECT_EQ(countNegativeMedit(dir + "/r.mesh"), 34055u);
  auto r = importMedit(dir + "/r.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->report.flipped, 34055u);
  EXPECT_EQ(computeMeshStats(r->mesh).inverted, 0u);
  auto original = importMedit(dataPath("medit/bunny.mesh"), ImportOptions{});
  ASSERT_TRUE(original.isOk());
  EXPECT_TRUE(r->mesh.tets == original->mesh.tets);
}

const char* kMedit = R"(# a cube corner and a tip
MeshVersionFormatted 2
Dimension
3
Vertices
5
0 0 0 10
1 0 0 11
0 1 0 12
0 0 1 13
1 1 1 14
Edges 2
1 2 0
2 3 0
Triangles
2
1 2 3 5
2 3 4 6
Corners 1 1
Ridges
1
1
# the second tet is negatively oriented
Tetrahedra
2
1 2 3 4 7
2 4 3 5 8
Normals 1
0 0 1
NormalAtVertices 1
1 1
End
)";

TEST(MeditImport, SkipsOtherSectionsAndKeepsRefs) {
  const std::string dir = tempDir("medit-sections");
  writeFile(dir + "/a.mesh", kMedit);
  auto r = importMedit(dir + "/a.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numPoints(), 5u);
  ASSERT_EQ(m.numTets(), 2u);
  EXPECT_EQ(r->report.flipped, 1u);
  EXPECT_TRUE(m.tets[0] == (Tet{0, 1, 2, 3}));
  EXPECT_TRUE(m.tets[1] == (Tet{1, 3, 4, 2}));
  EXPECT_EQ(m.point_fields[0].get(4, 0), 14);
  EXPECT_EQ(m.cell_fields[0].get(0, 0), 7);
  EXPECT_EQ(m.cell_fields[0].get(1, 0), 8);
  // Nothing is left out without a word: one warning per skipped keyword, with its entries.
  const std::vector<std::string> want = {
      "skipped 2 Edges (line 12): elements of lower dimension, with their references: only volume elements become "
      "tetrahedra",
      "skipped 2 Triangles (line 15): elements of lower dimension, with their references: only volume elements "
      "become tetrahedra",
      "skipped 1 Corners (line 19): marks on vertices and elements, not read",
      "skipped 1 Ridges (line 20): marks on vertices and elements, not read",
      "skipped 1 Normals (line 28): normals and tangents, not read",
      "skipped 1 NormalAtVertices (line 30): normals and tangents, not read",
  };
  EXPECT_EQ(r->report.warnings, want);
}

void expectError(StatusOr<ImportResult> r, const std::string& where) {
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().code(), StatusCode::kOk);
  EXPECT_NE(r.status().message().find(where), std::string::npos) << r.status().message();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

// The sections MMG writes after a remeshing (mmg3d's own examples carry them all): tangents at
// vertices, required entities, a Geometry file name with a space, comments between sections.
TEST(MeditImport, SkipsTheSectionsMmgWrites) {
  const std::string dir = tempDir("medit-mmg");
  const std::string text = replaced(kMedit, "Tetrahedra\n",
                                    "Geometry\n\"the cube.mesh\"\nIdentifier \"cube\"\n"
                                    "RequiredVertices\n2\n1\n2\nTangents\n1\n1 0 0\n"
                                    "TangentAtVertices\n1\n3 1\n# tetrahedra follow\nTetrahedra\n");
  writeFile(dir + "/mmg.mesh", text);
  auto r = importMedit(dir + "/mmg.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 5u);
  ASSERT_EQ(r->mesh.numTets(), 2u);
  EXPECT_EQ(r->mesh.cell_fields[0].get(1, 0), 8);
  // A string left open is an error on its line.
  writeFile(dir + "/open.mesh", replaced(kMedit, "Tetrahedra\n", "Geometry \"the cube\n3\nTetrahedra\n"));
  auto bad = importMedit(dir + "/open.mesh", ImportOptions{});
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find(dir + "/open.mesh:24: Geometry: the quoted string is not closed"),
            std::string::npos)
      << bad.status().message();
}

// GMF lets keywords come in any order and meshio writes one section per block of cells: a second
// Tetrahedra section before the Vertices is read, joined to the first with a warning, and its vertex
// numbers are checked once the vertices are known. Links to a geometry (whose entries changed layout
// between libMeshb versions) are skipped line by line, and Iterations, Time, AngleOfCornerBound and
// BoundingBox by their values.
TEST(MeditImport, AnyKeywordOrderSeveralSectionsAndGeometryLinks) {
  const std::string dir = tempDir("medit-order");
  const std::string moved = replaced(replaced(kMedit, "2 4 3 5 8\n", ""), "Tetrahedra\n2\n", "Tetrahedra\n1\n");
  const std::string text =
      replaced(moved, "Vertices\n",
               "Tetrahedra 1\n2 4 3 5 8\nIterations 12\nTime\n0.25\nAngleOfCornerBound 45.0\nBoundingBox\n0 1 0 1 0 1\n"
               "VertexOnGeometricEdge\n2\n1 3 0.5\n2 3 0.25\nVerticesOnGeometricVertices 1\n4 1 0.0\n"
               "SubDomainFromMesh 1\n3 1 1 2\nEdgeOnGeometricEdge\n1\n1 1\nVertices\n");
  writeFile(dir + "/o.mesh", text);
  auto r = importMedit(dir + "/o.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.numPoints(), 5u);
  ASSERT_EQ(r->mesh.numTets(), 2u);
  // File order: the section before the vertices first.
  EXPECT_TRUE(r->mesh.tets[0] == (Tet{1, 3, 4, 2}));
  EXPECT_TRUE(r->mesh.tets[1] == (Tet{0, 1, 2, 3}));
  EXPECT_EQ(r->mesh.cell_fields[0].get(0, 0), 8);
  EXPECT_EQ(r->mesh.cell_fields[0].get(1, 0), 7);
  ASSERT_EQ(r->report.warnings.size(), 11u);  // the 6 sections of kMedit it skips last
  EXPECT_NE(r->report.warnings[0].find("2 Tetrahedra sections (line 5, line "), std::string::npos)
      << r->report.warnings[0];
  EXPECT_EQ(r->report.warnings[1], "skipped 2 VertexOnGeometricEdge (line 13): links to a geometry, not read");
  EXPECT_EQ(r->report.warnings[4], "skipped 1 EdgeOnGeometricEdge (line 21): links to a geometry, not read");
  // The single values are kept as metadata.
  ASSERT_NE(r->mesh.findMetadata("medit.Time"), nullptr);
  EXPECT_EQ(*r->mesh.findMetadata("medit.Time"), "0.25");
  EXPECT_EQ(*r->mesh.findMetadata("medit.Iterations"), "12");
  EXPECT_EQ(*r->mesh.findMetadata("medit.BoundingBox"), "0 1 0 1 0 1");
  // A vertex number beyond the vertices that follow is reported where it was read.
  writeFile(dir + "/far.mesh", replaced(text, "Tetrahedra 1\n2 4 3 5 8\n", "Tetrahedra 1\n2 4 3 9 8\n"));
  expectError(importMedit(dir + "/far.mesh", ImportOptions{}),
              dir + "/far.mesh:6: tetrahedron 1 refers to vertex 9; vertices are numbered 1 to 5");
}

// Sections of other programs are skipped up to the next keyword, with a warning: ParMmg's
// communicators (the second without a count), libMeshb's ISolAtTetrahedra, one holding a NaN.
TEST(MeditImport, SkipsSectionsOfOtherProgramsToTheNextKeyword) {
  const std::string dir = tempDir("medit-unknown");
  const std::string text = replaced(kMedit, "Tetrahedra\n",
                                    "ParallelTriangleCommunicators\n1\n1 2\nParallelCommunicatorTriangles\n"
                                    "1 1 0\n2 2 0\nMyValues 2\nnan 1.5e3\n-inf\nTetrahedra\n");
  writeFile(dir + "/p.mesh", replaced(text, "End\n", "ISolAtTetrahedra\n1\n1 0 0 0\nEnd\n"));
  auto r = importMedit(dir + "/p.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 5u);
  ASSERT_EQ(r->mesh.numTets(), 2u);  // the Tetrahedra after the skipped sections
  EXPECT_EQ(r->mesh.cell_fields[0].get(1, 0), 8);
  ASSERT_EQ(r->report.warnings.size(), 10u);  // and the 6 sections of kMedit it skips
  EXPECT_EQ(r->report.warnings[0],
            "skipped the unknown section 'ParallelTriangleCommunicators' (line 24, 3 numbers up to the next keyword)");
  EXPECT_EQ(r->report.warnings[1],
            "skipped the unknown section 'ParallelCommunicatorTriangles' (line 27, 6 numbers up to the next keyword)");
  EXPECT_EQ(r->report.warnings[2],
            "skipped the unknown section 'MyValues' (line 30, 4 numbers up to the next keyword)");
  EXPECT_NE(r->report.warnings[3].find("'ISolAtTetrahedra'"), std::string::npos) << r->report.warnings[3];
  // A file that starts with an unknown word is still no Medit file.
  writeFile(dir + "/q.mesh", "Foo 1\n" + text);
  auto q = importMedit(dir + "/q.mesh", ImportOptions{});
  ASSERT_FALSE(q.isOk());
  EXPECT_EQ(q.status().code(), StatusCode::kNotOurFile);
}

// Item by item, what a Medit file holds besides its volume (boundary triangles and quadrilaterals with
// their references, edges, corners, ridges, required entities, tangents), counted over several
// sections of a keyword; gtn info and gtn validate show it.
TEST(MeditImport, EverySkippedSectionIsCountedAndShown) {
  const std::string dir = tempDir("medit-left-out");
  const std::string text =
      replaced(kMedit, "Corners 1 1\n",
               "Corners 1 1\nQuadrilaterals 1\n1 2 5 3 9\nTriangles 1\n1 3 4 6\nRequiredVertices 2\n1 2\n"
               "RequiredTriangles 1 2\nTangents 1\n1 0 0\nTangentAtVertices 1\n2 1\nTrianglesP2 0\n");
  writeFile(dir + "/b.mesh", text);
  auto r = importMesh({dir + "/b.mesh"}, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r->mesh.numTets(), 2u);
  const std::string lower =
      ": elements of lower dimension, with their references: only volume elements become tetrahedra";
  const std::vector<std::string> want = {
      "skipped 2 Edges (line 12)" + lower,
      "skipped 3 Triangles (line 15 and 1 more sections)" + lower,
      "skipped 1 Corners (line 19): marks on vertices and elements, not read",
      "skipped 1 Quadrilaterals (line 20)" + lower,
      "skipped 2 RequiredVertices (line 24): marks on vertices and elements, not read",
      "skipped 1 RequiredTriangles (line 26): marks on vertices and elements, not read",
      "skipped 1 Tangents (line 27): normals and tangents, not read",
      "skipped 1 TangentAtVertices (line 29): normals and tangents, not read",
      "skipped 1 Ridges (line 32): marks on vertices and elements, not read",
      "skipped 1 Normals (line 40): normals and tangents, not read",
      "skipped 1 NormalAtVertices (line 42): normals and tangents, not read",
  };
  EXPECT_EQ(r->report.warnings, want);
  // The command line shows them: info on standard error, validate as import warnings.
  auto info = test::runGtn("info " + dir + "/b.mesh");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.err.find("skipped 3 Triangles (line 15 and 1 more sections)"), std::string::npos) << info.err;
  auto validate = test::runGtn("validate --json " + dir + "/b.mesh");
  EXPECT_NE(validate.out.find("skipped 1 Quadrilaterals (line 20)"), std::string::npos) << validate.out;
  EXPECT_NE(validate.out.find("skipped 2 Edges (line 12)"), std::string::npos) << validate.out;
}

// TetGen -g writes a point attribute as the vertex reference: reals keep every reference as float64.
TEST(MeditImport, RealVertexReferencesBecomeFloat64) {
  const std::string dir = tempDir("medit-real-refs");
  writeFile(dir + "/g.mesh", replaced(replaced(kMedit, "0 0 1 13", "0 0 1 13.5"), "1 1 1 14", "1 1 1 1e10"));
  auto r = importMedit(dir + "/g.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const Field& ref = r->mesh.point_fields[0];
  EXPECT_EQ(ref.type, ScalarType::kFloat64);
  EXPECT_EQ(ref.get(0, 0), 10.0);
  EXPECT_EQ(ref.get(3, 0), 13.5);
  EXPECT_EQ(ref.get(4, 0), 1e10);
  ASSERT_EQ(r->report.warnings.size(), 7u);  // and the 6 sections of kMedit it skips
  EXPECT_NE(r->report.warnings[0].find("vertex 4 (line 10) has the reference 13.5"), std::string::npos)
      << r->report.warnings[0];
  EXPECT_EQ(r->mesh.cell_fields[0].type, ScalarType::kInt32);  // element references stay integers
  writeFile(dir + "/bad.mesh", replaced(kMedit, "0 0 1 13", "0 0 1 thirteen"));
  expectError(importMedit(dir + "/bad.mesh", ImportOptions{}),
              dir + "/bad.mesh:10: expected vertex 4's reference (a number), found 'thirteen'");
}

TEST(MeditErrors, BadInputs) {
  const std::string dir = tempDir("medit-errors");
  const std::string p = dir + "/b.mesh";
  writeFile(p, replaced(kMedit, "Dimension\n3", "Dimension 2"));
  expectError(importMedit(p, ImportOptions{}), p + ":3:");
  writeFile(p, replaced(kMedit, "2 4 3 5 8", "2 4 3 6 8"));
  expectError(importMedit(p, ImportOptions{}), p + ":27:");
  writeFile(p, replaced(kMedit, "1 0 0 11", "1 zero 0 11"));
  expectError(importMedit(p, ImportOptions{}), p + ":8:");
  // An unknown section is skipped with a warning (SkipsSectionsOfOtherProgramsToTheNextKeyword);
  // the section it ends is not: Corners' second count is no keyword.
  writeFile(p, replaced(kMedit, "Corners 1 1", "Wonders 1 1"));
  auto w = importMedit(p, ImportOptions{});
  ASSERT_TRUE(w.isOk()) << w.status().message();
  ASSERT_EQ(w->report.warnings.size(), 6u);  // and the 5 known sections of kMedit it skips
  EXPECT_EQ(w->report.warnings[0], "skipped the unknown section 'Wonders' (line 19, 2 numbers up to the next keyword)");
  writeFile(p, replaced(kMedit, "Corners 1 1", "Corners 2 1"));
  expectError(importMedit(p, ImportOptions{}),
              p + ":20: Corners (line 19) announces 2 entries of 1 values; found 'Ridges' after 1 values");
  writeFile(p, replaced(kMedit, "Corners 1 1", "Corners 1 1 4"));
  expectError(
      importMedit(p, ImportOptions{}),
      p + ":19: expected a section keyword, found '4' (the section before holds more values than its count says)");
  writeFile(p, replaced(kMedit, "Tetrahedra\n2\n", "Tetrahedra\n3\n"));
  expectError(importMedit(p, ImportOptions{}), "b.mesh:");
  writeFile(p, std::string(kMedit).substr(0, std::string(kMedit).find("2 4 3 5 8")));
  expectError(importMedit(p, ImportOptions{}), p + ":");
  writeFile(p, "");
  expectError(importMedit(p, ImportOptions{}), p);
  writeFile(p, "MeshVersionFormatted 1\nDimension 3\nVertices\n100000000\n0 0 0 0\n");
  expectError(importMedit(p, ImportOptions{}), p + ":4:");
  writeFile(p, replaced(kMedit, "1 0 0 11", "1 0 inf 11"));
  expectError(importMedit(p, ImportOptions{}), p + ":8: vertex 2 has a non-finite z coordinate");
}

// Two unit cubes side by side as Medit hexahedra (corners 1-4 round the bottom face, 5-8 above them),
// references 3 and 4, with a boundary quadrilateral and no Tetrahedra section.
const char* kMeditHexes = R"(MeshVersionFormatted 2
Dimension 3
Vertices
12
0 0 0 0
1 0 0 0
2 0 0 0
0 1 0 0
1 1 0 0
2 1 0 0
0 0 1 0
1 0 1 0
2 0 1 0
0 1 1 0
1 1 1 0
2 1 1 0
Quadrilaterals
1
1 2 5 4 1
Hexahedra
2
1 2 5 4 7 8 11 10 3
2 3 6 5 8 9 12 11 4
End
)";

TEST(MeditImport, HexahedraAreSplitLikeVtkCells) {
  const std::string dir = tempDir("medit-hexes");
  writeFile(dir + "/h.mesh", kMeditHexes);
  for (int split : {6, 5}) {
    ImportOptions options;
    options.split = split;
    auto r = importMesh({dir + "/h.mesh"}, options);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh& m = r->mesh;
    // Numbered in order, the cubes' face diagonals do not allow 5 tetrahedra: 6 each, with the VTK
    // importers' warning under --split 5.
    ASSERT_EQ(m.numTets(), 12u) << split;
    const MeshStats s = computeMeshStats(m);
    // Read with any other corner order the cubes would not fill the box [0,2]x[0,1]x[0,1].
    EXPECT_NEAR(s.total_volume, 2.0, 1e-12);
    EXPECT_EQ(s.inverted, 0u);
    EXPECT_EQ(s.zero_volume, 0u);
    // Conforming: the shared face is cut the same way from both sides (2 triangles per cube face).
    EXPECT_EQ(s.boundary_faces, 20u);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    // Each tetrahedron carries its hexahedron's reference.
    ASSERT_EQ(m.cell_fields.size(), 1u);
    EXPECT_EQ(m.cell_fields[0].name, "ref");
    for (size_t t = 0; t < m.numTets(); ++t) EXPECT_EQ(m.cell_fields[0].get(t, 0), t < 6 ? 3 : 4) << t;
    // The boundary quadrilateral is skipped, with a word.
    ASSERT_EQ(r->report.warnings.size(), split == 6 ? 1u : 2u);
    EXPECT_EQ(r->report.warnings[0],
              "skipped 1 Quadrilaterals (line 17): elements of lower dimension, with their references: only volume "
              "elements become tetrahedra");
    if (split == 5) {
      EXPECT_NE(r->report.warnings[1].find("2 of 2 hexahedra split into 6"), std::string::npos)
          << r->report.warnings[1];
    }
    ASSERT_NE(m.findMetadata("source.format"), nullptr);
    EXPECT_EQ(*m.findMetadata("source.format"), "medit");
  }
  // One unit cube whose corners 1, 3, 6, 8 have the smallest numbers: --split 5 gives 5 tetrahedra.
  writeFile(dir + "/five.mesh",
            "MeshVersionFormatted 2\nDimension 3\nVertices\n8\n"
            "0 0 0 1\n1 1 0 1\n1 0 1 1\n0 1 1 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 1\n"
            "Hexahedra\n1\n1 5 2 6 7 3 8 4 9\nEnd\n");
  ImportOptions five;
  five.split = 5;
  auto r = importMesh({dir + "/five.mesh"}, five);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 5u);
  EXPECT_TRUE(r->report.warnings.empty());
  EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 1.0, 1e-12);
}

TEST(MeditImport, MixedElementsKeepTheirReferences) {
  // A tetrahedron, a prism (half of a unit cube) and a pyramid (a unit square base, apex at height 1),
  // each on points of its own; the old spelling Hexaedra with no elements is accepted.
  const std::string text = R"(MeshVersionFormatted 1
Dimension 3
Vertices
15
0 0 0 0
1 0 0 0
0 1 0 0
0 0 1 0
10 0 0 0
11 0 0 0
10 1 0 0
10 0 1 0
11 0 1 0
10 1 1 0
20 0 0 0
21 0 0 0
21 1 0 0
20 1 0 0
20.5 0.5 1 0
Pyramids
1
11 12 13 14 15 30
Prisms
1
5 6 7 8 9 10 20
Hexaedra
0
Tetrahedra
1
1 2 3 4 10
End
)";
  const std::string dir = tempDir("medit-mixed");
  writeFile(dir + "/m.mesh", text);
  auto r = importMedit(dir + "/m.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numTets(), 1u + 2u + 3u);
  const MeshStats s = computeMeshStats(m);
  EXPECT_NEAR(s.total_volume, 1.0 / 6 + 1.0 / 3 + 0.5, 1e-12);
  EXPECT_EQ(s.zero_volume, 0u);
  // Tetrahedra first, then the other elements in file order: the pyramid's 2, the prism's 3.
  const int32_t want[] = {10, 30, 30, 20, 20, 20};
  for (size_t t = 0; t < 6; ++t) EXPECT_EQ(m.cell_fields[0].get(t, 0), want[t]) << t;
  EXPECT_TRUE(m.tets[0] == (Tet{0, 1, 2, 3}));
}

// Pentahedra is an old name of Prisms; TetrahedraP2, HexahedraQ2, PrismsP2 and PyramidsP2 elements
// are kept by their corners (their other nodes stay as unreferenced points, as other formats'
// quadratic cells' do), with a warning.
TEST(MeditImport, PentahedraAndQuadraticVolumeElements) {
  const std::string dir = tempDir("medit-pentahedra");
  const std::string prism =
      "MeshVersionFormatted 2\nDimension 3\nVertices\n10\n"
      "0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n1 0 1 0\n0 1 1 0\n"
      "5 0 0 0\n6 0 0 0\n5 1 0 0\n5 0 1 0\n";
  const std::string p2 = "TetrahedraP2\n1\n7 8 9 10 7 8 9 10 7 8 5\n";
  writeFile(dir + "/p.mesh", prism + "Pentahedra\n1\n1 2 3 4 5 6 2\n" + p2 + "End\n");
  auto r = importMedit(dir + "/p.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 4u);
  EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 0.5 + 1.0 / 6.0, 1e-12);
  EXPECT_EQ(
      r->report.warnings,
      std::vector<std::string>{
          "1 TetrahedraP2 elements kept by their 4 corners; their mid-edge nodes are kept as unreferenced points"});
  // The P2 tetrahedron, last, keeps its reference.
  const Field* ref = test::findField(r->mesh.cell_fields, "ref");
  ASSERT_NE(ref, nullptr);
  EXPECT_EQ(ref->get(3, 0), 5);
  // Only P2 tetrahedra: a mesh of their corners.
  writeFile(dir + "/only_p2.mesh", prism + p2 + "End\n");
  auto only = importMedit(dir + "/only_p2.mesh", ImportOptions{});
  ASSERT_TRUE(only.isOk()) << only.status().message();
  EXPECT_EQ(only->mesh.numTets(), 1u);
  EXPECT_NEAR(computeMeshStats(only->mesh).total_volume, 1.0 / 6.0, 1e-12);
  // A Q2 hexahedron (the unit cube), a P2 prism and a P2 pyramid, each listing its linear form's
  // corners first (their other nodes: vertex 20, away from them).
  std::string q2 =
      "MeshVersionFormatted 2\nDimension 3\nVertices\n20\n"
      "0 0 0 0\n1 0 0 0\n1 1 0 0\n0 1 0 0\n0 0 1 0\n1 0 1 0\n1 1 1 0\n0 1 1 0\n"
      "2 0 0 0\n3 0 0 0\n2 1 0 0\n2 0 1 0\n3 0 1 0\n2 1 1 0\n"
      "4 0 0 0\n5 0 0 0\n5 1 0 0\n4 1 0 0\n4.5 0.5 1 0\n9 9 9 0\n";
  auto element = [](const char* keyword, std::vector<int> corners, int nodes, int ref) {
    std::string e = std::string(keyword) + "\n1\n";
    corners.resize(static_cast<size_t>(nodes), 20);
    for (int v : corners) e += std::to_string(v) + " ";
    return e + std::to_string(ref) + "\n";
  };
  q2 += element("HexahedraQ2", {1, 2, 3, 4, 5, 6, 7, 8}, 27, 3) + element("PrismsP2", {9, 10, 11, 12, 13, 14}, 18, 4) +
        element("PyramidsP2", {15, 16, 17, 18, 19}, 14, 5) + "End\n";
  writeFile(dir + "/q2.mesh", q2);
  auto higher = importMedit(dir + "/q2.mesh", ImportOptions{});
  ASSERT_TRUE(higher.isOk()) << higher.status().message();
  const TetMesh& m = higher->mesh;
  ASSERT_EQ(m.numTets(), 6u + 3u + 2u);
  EXPECT_NEAR(computeMeshStats(m).total_volume, 1.0 + 0.5 + 1.0 / 3.0, 1e-12);
  EXPECT_EQ(higher->report.warnings,
            (std::vector<std::string>{
                "1 HexahedraQ2 elements kept by their 8 corners; their other nodes are kept as unreferenced points",
                "1 PrismsP2 elements kept by their 6 corners; their other nodes are kept as unreferenced points",
                "1 PyramidsP2 elements kept by their 5 corners; their other nodes are kept as unreferenced points"}));
  const Field* refs = test::findField(m.cell_fields, "ref");
  ASSERT_NE(refs, nullptr);
  for (size_t t = 0; t < m.numTets(); ++t) {
    const int want = t < 6 ? 3 : t < 9 ? 4 : 5;
    EXPECT_EQ(refs->get(t, 0), want) << t;
    for (uint32_t v : m.tets[t]) EXPECT_NE(v, 19u) << t;  // no tetrahedron uses the other nodes
  }
}

// gmsh writes second-order hexahedra and quadrilaterals under the linear keywords, one element per
// line (Hexahedra with 27 nodes, Quadrilaterals with 9): the first element's line tells them apart.
TEST(MeditImport, SecondOrderElementsUnderLinearKeywordsAsGmshWritesThem) {
  const std::string dir = tempDir("medit-gmsh-q2");
  std::string text =
      "MeshVersionFormatted 2\nDimension\n3\nVertices\n9\n"
      "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n0 0 1 1\n1 0 1 1\n1 1 1 1\n0 1 1 1\n0.5 0.5 0.5 1\n"
      "Quadrilaterals\n2\n";
  for (int q = 0; q < 2; ++q) text += " 1 2 3 4 9 9 9 9 9 5\n";
  text += "Hexahedra\n1\n 1 2 3 4 5 6 7 8";
  for (int k = 0; k < 19; ++k) text += " 9";
  text += " 3\nEnd\n";
  writeFile(dir + "/q2.mesh", text);
  auto r = importMedit(dir + "/q2.mesh", ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 6u);
  EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, 1.0, 1e-12);
  EXPECT_TRUE(test::hasWarning(r->report,
                               "the Hexahedra section (line 19) holds 27 nodes per element (second-order elements, as "
                               "gmsh writes them): read as HexahedraQ2"))
      << ::testing::PrintToString(r->report.warnings);
  EXPECT_TRUE(test::hasWarning(r->report, "skipped 2 Quadrilaterals (line 15)"))
      << ::testing::PrintToString(r->report.warnings);
  // The same elements with their linear nodes only are read as before, without that warning.
  const std::string linear =
      "MeshVersionFormatted 2\nDimension\n3\nVertices\n8\n"
      "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n0 0 1 1\n1 0 1 1\n1 1 1 1\n0 1 1 1\n"
      "Quadrilaterals\n1\n 1 2 3 4 5\nHexahedra\n1\n 1 2 3 4 5 6 7 8 3\nEnd\n";
  writeFile(dir + "/q1.mesh", linear);
  auto l = importMedit(dir + "/q1.mesh", ImportOptions{});
  ASSERT_TRUE(l.isOk()) << l.status().message();
  EXPECT_EQ(l->mesh.numTets(), 6u);
  for (const std::string& w : l->report.warnings) EXPECT_EQ(w.find("second-order"), std::string::npos) << w;
}

TEST(MeditErrors, BadHexahedra) {
  const std::string dir = tempDir("medit-hex-errors");
  const std::string p = dir + "/h.mesh";
  writeFile(p, replaced(kMeditHexes, "2 3 6 5 8 9 12 11 4", "2 3 6 5 8 9 13 11 4"));
  expectError(importMedit(p, ImportOptions{}),
              p + ":23: hexahedron 2 refers to vertex 13; vertices are numbered 1 to 12");
  writeFile(p, replaced(kMeditHexes, "2 3 6 5 8 9 12 11 4\n", ""));
  expectError(importMedit(p, ImportOptions{}), p + ":");
  writeFile(p, replaced(kMeditHexes, "Hexahedra\n2\n", "Hexahedra\n3000000000\n"));
  expectError(importMedit(p, ImportOptions{}), p + ":21:");
  // Only boundary quadrilaterals: not a volume mesh.
  std::string surface = kMeditHexes;
  surface = surface.substr(0, surface.find("Hexahedra")) + "End\n";
  writeFile(p, surface);
  expectError(importMedit(p, ImportOptions{}),
              "no volume elements (Tetrahedra, Hexahedra, Prisms or Pyramids, or their TetrahedraP2, HexahedraQ2, "
              "PrismsP2 and PyramidsP2 forms)");
}

// --- Tetrahedral OFF ------------------------------------------------------------------------------

std::string shortest(double v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

// OFF text of a mesh: scalars s0 = x + 2y (and s1 = -z when two), tetrahedra with vertices 2 and 3
// swapped when `reverse` (the negative orientation of the files that circulated).
std::string toOff(const TetMesh& m, bool keyword, bool one_line_counts, int scalars, bool prefix, bool reverse) {
  std::ostringstream out;
  if (keyword) out << "OFF\n";
  out << "# written by the test\n";
  if (one_line_counts) {
    out << m.numPoints() << " " << m.numTets() << "\n";
  } else {
    out << m.numPoints() << "\n" << m.numTets() << "\n";
  }
  for (size_t i = 0; i < m.numPoints(); ++i) {
    const double* p = m.point(i);
    out << shortest(p[0]) << " " << shortest(p[1]) << "\t" << shortest(p[2]);
    if (scalars >= 1) out << " " << shortest(p[0] + 2 * p[1]);
    if (scalars >= 2) out << " " << shortest(-p[2]);
    out << "\n";
  }
  for (const Tet& t : m.tets) {
    if (prefix) out << "4 ";
    out << t[0] << " " << t[1] << " " << (reverse ? t[3] : t[2]) << " " << (reverse ? t[2] : t[3]) << "\n";
  }
  return out.str();
}

TEST(OffImport, FromTetgenMesh) {
  auto src = importTetgen(dataPath("tetgen/cornellbox_orig.1"), ImportOptions{});
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const TetMesh& ref = src->mesh;
  const std::string dir = tempDir("off-import");
  struct Variant {
    bool keyword, one_line, prefix, reverse;
    int scalars;
  };
  for (const Variant v : {Variant{true, true, true, true, 2}, Variant{false, false, false, false, 1},
                          Variant{true, false, false, true, 0}}) {
    SCOPED_TRACE(testing::Message() << v.keyword << v.one_line << v.prefix << v.reverse << v.scalars);
    const std::string path = dir + "/m.off";
    writeFile(path, toOff(ref, v.keyword, v.one_line, v.scalars, v.prefix, v.reverse));
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh& m = r->mesh;
    ASSERT_EQ(m.numPoints(), 331u);
    ASSERT_EQ(m.numTets(), 1631u);
    EXPECT_EQ(r->report.flipped, v.reverse ? 1631u : 0u);
    EXPECT_EQ(computeMeshStats(m).inverted, 0u);
    EXPECT_TRUE(m.tets == ref.tets);  // flipping the reversed rows restores the source order
    EXPECT_EQ(0, std::memcmp(m.coords.data(), ref.coords.data(), ref.coords.size() * sizeof(double)));
    if (v.scalars == 0) {
      EXPECT_TRUE(m.point_fields.empty());
      continue;
    }
    ASSERT_EQ(m.point_fields.size(), 1u);
    const Field& s = m.point_fields[0];
    EXPECT_EQ(s.name, "scalar");
    EXPECT_EQ(s.type, ScalarType::kFloat64);
    ASSERT_EQ(s.components, static_cast<uint32_t>(v.scalars));
    for (size_t i = 0; i < m.numPoints(); ++i) {
      EXPECT_EQ(s.get(i, 0), ref.point(i)[0] + 2 * ref.point(i)[1]);
      if (v.scalars == 2) {
        EXPECT_EQ(s.get(i, 1), -ref.point(i)[2]);
      }
    }
    EXPECT_EQ(*m.findMetadata("source.format"), "off");
  }
}

const char* kOff = "TOFF\n5 2\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n1 1 1 5\n4 0 1 2 3\n4 1 3 2 4\n";

TEST(OffErrors, BadInputs) {
  const std::string dir = tempDir("off-errors");
  const std::string p = dir + "/b.off";
  writeFile(p, kOff);
  auto good = importOff(p, ImportOptions{});
  ASSERT_TRUE(good.isOk()) << good.status().message();
  EXPECT_EQ(good->report.flipped, 1u);
  writeFile(p, replaced(kOff, "1 0 0 2\n", "1 0 0\n"));
  expectError(importOff(p, ImportOptions{}), p + ":4:");
  writeFile(p, replaced(kOff, "4 1 3 2 4", "4 1 3 2 5"));
  expectError(importOff(p, ImportOptions{}), p + ":9:");
  writeFile(p, replaced(kOff, "4 1 3 2 4", "3 1 3 2 4"));
  expectError(importOff(p, ImportOptions{}), p + ":9:");
  writeFile(p, replaced(kOff, "0 1 0 3", "0 one 0 3"));
  expectError(importOff(p, ImportOptions{}), p + ":5:");
  writeFile(p, replaced(kOff, "4 1 3 2 4\n", ""));
  expectError(importOff(p, ImportOptions{}),
              p + ":2: the header announces 2 tetrahedra, rows of 5 values like the first (line 8)");
  writeFile(p, replaced(kOff, "5 2", "5000000000000 2"));
  expectError(importOff(p, ImportOptions{}), p + ":2:");
  writeFile(p, replaced(kOff, "5 2", "500000 2"));
  expectError(importOff(p, ImportOptions{}), p + ":2:");
  writeFile(p, "");
  expectError(importOff(p, ImportOptions{}), p + ":1:");
  writeFile(p, "hello\n");
  expectError(importOff(p, ImportOptions{}), p + ":1:");
  writeFile(p, replaced(kOff, "0 1 0 3", "0 nan 0 3"));
  expectError(importOff(p, ImportOptions{}), p + ":5: point 2 has a non-finite y coordinate 'nan'");
  // More rows announced than can follow the first: the header's count, at the header's line.
  writeFile(p, replaced(kOff, "5 2", "5 40"));
  expectError(importOff(p, ImportOptions{}),
              p + ":2: the header announces 40 tetrahedra, rows of 5 values like the first (line 8)");
  writeFile(p, replaced(replaced(kOff, "5 2", "900 2"), "1 1 1 5\n4 0 1 2 3\n4 1 3 2 4\n", ""));
  expectError(importOff(p, ImportOptions{}), p + ":2: the header announces 900 points");
}

// The surface OFF of Geomview and the shape benchmarks has the same header and point rows; its faces
// must not be read as tetrahedra ("3 a b c" would start every one at point 3, "4 a b c d" would give
// flat ones).
TEST(OffErrors, SurfaceOffIsNotReadAsTetrahedra) {
  const std::string dir = tempDir("off-surface");
  const std::string tris = dir + "/tris.off";
  writeFile(tris, "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  auto r = importOff(tris, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  EXPECT_NE(r.status().message().find(tris + ":7: every one of the 4 element rows starts with 3: this is a surface "
                                             "OFF of triangles"),
            std::string::npos)
      << r.status().message();
  const std::string quads = dir + "/quads.off";
  writeFile(quads,
            "OFF\n8 6 12\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
            "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  r = importOff(quads, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find(quads + ":11: all 6 tetrahedra are flat (their 4 points are coplanar): this "
                                              "looks like a surface OFF of quadrilaterals"),
            std::string::npos)
      << r.status().message();
  const std::string mixed = dir + "/mixed.off";
  writeFile(mixed, "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n4 0 3 2 1\n3 0 1 4\n");
  r = importOff(mixed, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find(mixed + ":9: tetrahedron row has 4 values; the first one has 5 (rows of 4 and 5 "
                                              "values mixed are the faces of a surface OFF"),
            std::string::npos)
      << r.status().message();
  // Geomview's binary OFF is a surface format too; it is named, not misread as counts.
  const std::string binary = dir + "/binary.off";
  writeFile(binary, std::string("OFF BINARY\n\0\0\0\4\0\0\0\4\0\0\0\6", 23));
  r = importOff(binary, ImportOptions{});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  EXPECT_NE(r.status().message().find(binary + ":1: binary OFF ('OFF BINARY', Geomview's) holds a surface"),
            std::string::npos)
      << r.status().message();
  // A tetrahedral OFF whose rows happen to start with 3 is still read when its tetrahedra are not all so.
  const std::string tets = dir + "/tets.off";
  writeFile(tets, "5\n2\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n3 0 1 2\n1 3 2 4\n");
  r = importOff(tets, ImportOptions{});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 2u);
}

// Every prefix of a valid file imports cleanly or fails with a message naming the file.
TEST(MeditOffRobustness, Prefixes) {
  const std::string dir = tempDir("medit-off-prefixes");
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"p.mesh", kMedit}, {"p.off", kOff}}) {
    const std::string path = dir + "/" + name;
    size_t failures = 0;
    for (size_t n = 0; n < text.size(); ++n) {
      writeFile(path, text.substr(0, n));
      auto r = importMesh({path}, ImportOptions{});
      if (r.isOk()) {
        EXPECT_TRUE(r->mesh.checkConsistency(path).isOk());
      } else {
        ++failures;
        EXPECT_EQ(r.status().message().rfind(path, 0), 0u) << r.status().message();
      }
    }
    EXPECT_GT(failures, text.size() * 3 / 4) << name;
  }
}

}  // namespace
}  // namespace gtn
