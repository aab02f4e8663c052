// The mesh core: exact orientation, face adjacency, boundary surface, hexahedron splits, statistics.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <set>

#include "mesh/faces.h"
#include "mesh/fresh_memory.h"
#include "mesh/hex_split.h"
#include "mesh/mesh_stats.h"
#include "mesh/mesh_stream.h"
#include "mesh/predicates.h"
#include "mesh/tet_mesh.h"

namespace gtn {
namespace {

// A structured n x n x n grid of points (i fastest), hexahedra split with `split` (5 or 6).
TetMesh structuredGrid(int n, int split, double jitter_seed = 0.0) {
  TetMesh m;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double w = jitter_seed * 0.1 * ((i * 7 + j * 13 + k * 29) % 5 - 2);
        m.coords.insert(m.coords.end(), {i + w, j - w, k + 0.5 * w});
      }
  auto id = [n](int i, int j, int k) { return static_cast<uint32_t>(i + n * (j + n * k)); };
  for (int k = 0; k + 1 < n; ++k)
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if (split == 6) splitHexSix(h, m.tets);
        else splitHexFive(h, (i + j + k) % 2 == 1, m.tets);
      }
  return m;
}

TEST(Predicates, PositiveOrientationIsPositiveDeterminant) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {0, 0, 1};
  EXPECT_EQ(orient3d(a, b, c, d), 1);
  EXPECT_EQ(orient3d(a, c, b, d), -1);
  const double e[3] = {0.5, 0.5, 0};
  EXPECT_EQ(orient3d(a, b, c, e), 0);
  EXPECT_NEAR(signedVolume(a, b, c, d), 1.0 / 6.0, 1e-15);
}

TEST(Predicates, ExactOnNearlyFlatTetrahedron) {
  // d lies exactly on the plane through a, b, c in exact arithmetic although a naive floating-point
  // determinant of these values is not zero.
  const double a[3] = {0.1, 0.1, 0.1}, b[3] = {0.2, 0.2, 0.2}, c[3] = {0.3, 0.7, 0.1}, d[3] = {0.5, 0.5, 0.5};
  EXPECT_EQ(orient3d(a, b, c, d), 0);
}

TEST(Faces, TwoTetrahedraShareOneFace) {
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  const FaceAdjacency adj = computeFaceAdjacency(m);
  EXPECT_EQ(adj.faces, 7u);
  EXPECT_EQ(adj.boundary_faces, 6u);
  EXPECT_EQ(adj.non_manifold_faces, 0u);
  EXPECT_EQ(adj.neighbor[4 * 0 + 3], 1u);  // face opposite vertex 3 of tet 0 is (0,1,2)
  EXPECT_EQ(adj.neighbor[4 * 1 + 3], 0u);
}

TEST(Faces, BoundaryTrianglesPointOutward) {
  TetMesh m = structuredGrid(4, 6, 1.0);
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  const FaceAdjacency adj = computeFaceAdjacency(m);
  // For every boundary face of tet t, the tet's fourth vertex is on the negative side.
  for (size_t t = 0; t < m.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      if (adj.neighbor[4 * t + k] != kNoNeighbor) continue;
      const Tet& tt = m.tets[t];
      EXPECT_EQ(orient3d(m.point(tt[kTetFace[k][0]]), m.point(tt[kTetFace[k][1]]), m.point(tt[kTetFace[k][2]]),
                         m.point(tt[k])),
                -1);
    }
  EXPECT_EQ(boundaryTriangles(m, adj).size(), adj.boundary_faces);
}

TEST(Faces, ThreeTetrahedraOnOneFaceAreNonManifold) {
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0.2, 0.2, 2};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
  const FaceAdjacency adj = computeFaceAdjacency(m);
  EXPECT_EQ(adj.non_manifold_faces, 1u);
  for (uint32_t t = 0; t < 3; ++t) EXPECT_EQ(adj.neighbor[4 * t + 3], kNonManifold);  // each one's (0, 1, 2)
  EXPECT_EQ(adj.faces, 10u);
}

// A damaged mesh's vertex indices beyond its points still pair faces (they share one group).
TEST(Faces, VerticesBeyondThePointsStillPair) {
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0};
  m.tets = {{0, 7, 9, 1000000}, {9, 7, 0, 4000000000u}, {7, 9, 1000000, 5}};
  const FaceAdjacency adj = computeFaceAdjacency(m);
  EXPECT_EQ(adj.faces, 10u);
  EXPECT_EQ(adj.boundary_faces, 8u);
  EXPECT_EQ(adj.neighbor[4 * 0 + 3], 1u);  // (0, 7, 9)
  EXPECT_EQ(adj.neighbor[4 * 1 + 3], 0u);
  EXPECT_EQ(adj.neighbor[4 * 0 + 0], 2u);  // (7, 9, 1000000)
  EXPECT_EQ(adj.neighbor[4 * 2 + 3], 0u);
}

// A large mesh's face slots are grouped in several passes over its tetrahedra (two by default, past 2^24
// slots): the adjacency is the same for any number of passes, non-manifold faces and vertices beyond
// the points included.
TEST(Faces, PassesGiveTheSameAdjacency) {
  TetMesh m = structuredGrid(9, 6, 1.0);
  const uint32_t np = static_cast<uint32_t>(m.numPoints());
  m.tets.push_back({0, 1, np + 5, np + 9});  // a damaged tetrahedron: two vertices past the points
  m.tets.push_back(m.tets[3]);               // its faces in three tetrahedra
  m.tets.push_back(m.tets[3]);
  const FaceAdjacency one = computeFaceAdjacency(m);
  ASSERT_GT(one.non_manifold_faces, 0u);
  for (const uint64_t pass_slots : {uint64_t{1}, uint64_t{7}, uint64_t{100}, uint64_t{2000}}) {
    SCOPED_TRACE("passes of at most " + std::to_string(pass_slots) + " slots");
    const FaceAdjacency passes = computeFaceAdjacency(m, pass_slots);
    EXPECT_EQ(passes.neighbor, one.neighbor);
    EXPECT_EQ(passes.faces, one.faces);
    EXPECT_EQ(passes.boundary_faces, one.boundary_faces);
    EXPECT_EQ(passes.non_manifold_faces, one.non_manifold_faces);
  }
}

// The groups are matched in parallel: any number of threads finds the same adjacency, on a mesh of
// many tasks' worth of groups with faces in three tetrahedra among them.
TEST(Faces, ThreadsGiveTheSameAdjacency) {
  TetMesh m = structuredGrid(24, 6, 1.0);
  ASSERT_GT(m.numPoints(), 3u * 4096);
  for (size_t t : {size_t{3}, m.tets.size() / 2, m.tets.size() - 1}) {
    m.tets.push_back(m.tets[t]);  // its faces in three tetrahedra (two where a face was on the boundary)
  }
  auto adjacencyWith = [&](int threads) {
    FaceAdjacency adj;
    tbb::task_arena(threads).execute([&] { adj = computeFaceAdjacency(m); });
    return adj;
  };
  const FaceAdjacency one = adjacencyWith(1);
  EXPECT_GT(one.non_manifold_faces, 0u);
  for (const int threads : {2, 4}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const FaceAdjacency many = adjacencyWith(threads);
    EXPECT_EQ(many.neighbor, one.neighbor);
    EXPECT_EQ(many.faces, one.faces);
    EXPECT_EQ(many.boundary_faces, one.boundary_faces);
    EXPECT_EQ(many.non_manifold_faces, one.non_manifold_faces);
  }
}

// classifyFaces is what a check needs of the adjacency (mesh_checks.cpp): each tetrahedron's boundary
// and non-manifold faces, and whether a face-neighbour is one `flat` marks, as computeFaceAdjacency's
// neighbours say, with its counts, for any number of passes and threads.
TEST(Faces, ClassesAreTheAdjacencys) {
  TetMesh m = structuredGrid(14, 5, 1.0);
  const uint32_t np = static_cast<uint32_t>(m.numPoints());
  m.tets.push_back({0, 1, np + 5, np + 9});  // two vertices past the points
  m.tets.push_back(m.tets[40]);              // its faces in three tetrahedra
  m.tets.push_back(m.tets[40]);
  std::swap(m.tets[100][2], m.tets[100][3]);  // listed against its neighbours: its faces alike with theirs
  const size_t nt = m.numTets();
  std::vector<uint8_t> flat(nt, 0);
  for (size_t t = 5; t < nt; t += 97) flat[t] = 1;
  const FaceAdjacency adj = computeFaceAdjacency(m);
  ASSERT_GT(adj.non_manifold_faces, 0u);
  auto expectTheAdjacencys = [&](const FaceClasses& c, bool with_flat, bool with_alike = false) {
    ASSERT_EQ(c.mask.size(), nt);
    EXPECT_EQ(c.faces, adj.faces);
    EXPECT_EQ(c.boundary_faces, adj.boundary_faces);
    EXPECT_EQ(c.non_manifold_faces, adj.non_manifold_faces);
    size_t next_to_flat = 0, alike = 0;
    for (size_t t = 0; t < nt; ++t) {
      bool near = false, same = false;
      for (int k = 0; k < 4; ++k) {
        const uint32_t n = adj.neighbor[4 * t + k];
        EXPECT_EQ((c.mask[t] >> k) & 1, n == kNoNeighbor ? 1 : 0) << "tetrahedron " << t << " face " << k;
        EXPECT_EQ((c.mask[t] >> (4 + k)) & 1, n == kNonManifold ? 1 : 0) << "tetrahedron " << t << " face " << k;
        near = near || (n < nt && flat[n]);
        same = same || (n < nt && !facesOpposite(m.tets[t], k, m.tets[n]));
      }
      EXPECT_EQ((c.mask[t] & FaceClasses::kNextToFlat) != 0, with_flat && near) << "tetrahedron " << t;
      EXPECT_EQ((c.mask[t] & FaceClasses::kAlike) != 0, with_alike && same) << "tetrahedron " << t;
      next_to_flat += near;
      alike += same;
    }
    EXPECT_GT(next_to_flat, 10u);
    EXPECT_EQ(alike, 5u);  // the swapped one and its four neighbours
  };
  expectTheAdjacencys(classifyFaces(m), false);
  expectTheAdjacencys(classifyFaces(m, &flat), true);
  expectTheAdjacencys(classifyFaces(m, &flat, 100), true);
  expectTheAdjacencys(classifyFaces(m, &flat, 100, true), true, true);
  expectTheAdjacencys(classifyFaces(m, nullptr, 0, true), false, true);
  FaceClasses one_thread;
  tbb::task_arena(1).execute([&] { one_thread = classifyFaces(m, &flat); });
  expectTheAdjacencys(one_thread, true);
}

// Every interior face of a grid is found from both sides.
TEST(Faces, GridNeighboursAreMutual) {
  const TetMesh m = structuredGrid(5, 5);
  const FaceAdjacency adj = computeFaceAdjacency(m);
  EXPECT_EQ(adj.boundary_faces, 6u * 4 * 4 * 2);
  EXPECT_EQ(adj.non_manifold_faces, 0u);
  for (size_t t = 0; t < m.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      const uint32_t u = adj.neighbor[4 * t + k];
      if (u == kNoNeighbor) continue;
      ASSERT_LT(u, m.tets.size());
      int back = 0;
      for (int j = 0; j < 4; ++j) back += adj.neighbor[4 * size_t{u} + j] == t;
      EXPECT_EQ(back, 1) << "tetrahedron " << t << " face " << k;
    }
}

class HexSplit : public ::testing::TestWithParam<int> {};

TEST_P(HexSplit, StructuredGridIsConformingAndPositive) {
  const int split = GetParam();
  const int n = 5;
  TetMesh m = structuredGrid(n, split, 1.0);
  const size_t cells = (n - 1) * (n - 1) * (n - 1);
  EXPECT_EQ(m.tets.size(), cells * split);
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  EXPECT_EQ(zero, 0u);
  const MeshStats s = computeMeshStats(m);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  // Each boundary quadrilateral becomes exactly two triangles: a crossed diagonal would give four
  // boundary triangles on one quad and break this count.
  EXPECT_EQ(s.boundary_faces, 2u * 6 * (n - 1) * (n - 1));
  TetMesh plain = structuredGrid(n, split, 0.0);
  normalizeOrientation(plain, &zero);
  EXPECT_NEAR(computeMeshStats(plain).total_volume, 64.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Splits, HexSplit, ::testing::Values(5, 6));

TEST(HexSplit, FiveSplitWithoutAlternationIsNotConforming) {
  // The 5-split with the same parity everywhere crosses diagonals on shared faces: detected by the
  // face count (crossed faces are never shared), which a vertex-only check would miss.
  TetMesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) m.coords.insert(m.coords.end(), {double(i), double(j), double(k)});
  auto id = [](int i, int j, int k) { return static_cast<uint32_t>(i + 3 * (j + 2 * k)); };
  for (int i = 0; i < 2; ++i) {
    const uint32_t h[8] = {id(i, 0, 0), id(i + 1, 0, 0), id(i + 1, 1, 0), id(i, 1, 0),
                           id(i, 0, 1), id(i + 1, 0, 1), id(i + 1, 1, 1), id(i, 1, 1)};
    splitHexFive(h, false, m.tets);
  }
  const MeshStats s = computeMeshStats(m);
  EXPECT_GT(s.boundary_faces, 2u * 10);  // 10 boundary quads; the shared quad adds 4 unshared triangles
}

TEST(Stats, CountsDegeneraciesAndUnusedPoints) {
  TetMesh m;
  // Points 0-3 a unit tet, 4 a copy of point 1 (coincident), 5 unused, 6 coplanar with 0,1,2.
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0, 5, 5, 5, 0.5, 0.5, 0};
  m.tets = {{0, 2, 1, 3}, {0, 1, 2, 6}, {4, 2, 0, 3}};
  Field f("density", 1, ScalarType::kFloat32, 7);
  for (int i = 0; i < 7; ++i) f.set<float>(i, 0, 1.5f * i);
  m.point_fields.push_back(f);
  ASSERT_TRUE(m.checkConsistency("test").isOk());
  const MeshStats s = computeMeshStats(m);
  EXPECT_EQ(s.points, 7u);
  EXPECT_EQ(s.tets, 3u);
  EXPECT_EQ(s.inverted, 1u);  // (0,2,1,3) is negative
  EXPECT_EQ(s.zero_volume, 1u);
  EXPECT_EQ(s.unreferenced_points, 1u);
  EXPECT_EQ(s.coincident_points, 1u);
  EXPECT_DOUBLE_EQ(s.bbox_max[0], 5.0);
  ASSERT_EQ(s.fields.size(), 1u);
  EXPECT_DOUBLE_EQ(s.fields[0].max, 9.0);
  size_t zero = 0;
  EXPECT_EQ(normalizeOrientation(m, &zero), 1u);
  EXPECT_EQ(zero, 1u);
  EXPECT_EQ(computeMeshStats(m).inverted, 0u);
}

TEST(TetMesh, ConsistencyCheckNamesTheProblem) {
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.tets = {{0, 1, 2, 3}};
  Status st = m.checkConsistency("mesh.x");
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("mesh.x"), std::string::npos);
  EXPECT_NE(st.message().find("point 3"), std::string::npos);
  m.coords.insert(m.coords.end(), {0, 0, 0.1});
  m.coord_type = ScalarType::kFloat32;
  st = m.checkConsistency("mesh.x");
  ASSERT_FALSE(st.isOk());  // 0.1 is not a float32 value
  EXPECT_NE(st.message().find("float32"), std::string::npos);
  m.coords.back() = static_cast<double>(0.1f);
  EXPECT_TRUE(m.checkConsistency("mesh.x").isOk());
}

TEST(Field, KeepsBitsOfEveryType) {
  Field f("v", 2, ScalarType::kFloat64, 3);
  f.set<double>(2, 1, -0.0);
  EXPECT_TRUE(std::signbit(f.get(2, 1)));
  Field g("i", 1, ScalarType::kInt64, 1);
  g.set<int64_t>(0, 0, -5);
  EXPECT_EQ(g.get(0, 0), -5.0);
  ScalarType t;
  EXPECT_TRUE(scalarTypeFromName("uint16", &t));
  EXPECT_EQ(t, ScalarType::kUInt16);
  EXPECT_FALSE(scalarTypeFromName("half", &t));
}

TEST(MeshStream, BuilderAssemblesEvents) {
  TetMeshBuilder b;
  LevelHeader h;
  h.points = 4;
  h.tets = 1;
  h.point_fields.push_back({"s", 1, ScalarType::kUInt8});
  ASSERT_TRUE(b.beginLevel(h).isOk());
  const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (uint32_t i = 0; i < 4; ++i) {
    const uint8_t v = static_cast<uint8_t>(10 + i);
    ASSERT_TRUE(b.vertex(i, p[i], &v).isOk());
  }
  const uint32_t t[4] = {0, 1, 2, 3};
  ASSERT_TRUE(b.tet(t, nullptr).isOk());
  EXPECT_FALSE(b.vertex(7, p[0], nullptr).isOk());  // ids must be consecutive
  EXPECT_EQ(b.mesh().numPoints(), 4u);
  EXPECT_EQ(b.mesh().point_fields[0].get(3, 0), 13.0);
}

// The builder grows its storage, reserved from the header's counts, with the pages mapped a step
// ahead: a header that declares more than the stream holds, or less, still builds what arrives.
TEST(MeshStream, BuilderKeepsWhatArrivesWhateverTheHeaderDeclares) {
  for (uint64_t declared : {uint64_t{0}, uint64_t{10}, uint64_t{200000}, uint64_t{1} << 24}) {
    SCOPED_TRACE(declared);
    TetMeshBuilder b;
    LevelHeader h;
    h.points = declared;
    h.tets = declared;
    h.point_fields.push_back({"id", 1, ScalarType::kUInt32});
    h.cell_fields.push_back({"w", 1, ScalarType::kFloat64});
    ASSERT_TRUE(b.beginLevel(h).isOk());
    const uint32_t n = 100000;
    for (uint32_t i = 0; i < n; ++i) {
      const double p[3] = {double(i), 0.5 * i, -1.0 * i};
      ASSERT_TRUE(b.vertex(i, p, reinterpret_cast<const uint8_t*>(&i)).isOk());
    }
    for (uint32_t i = 0; i + 3 < n; ++i) {
      const uint32_t t[4] = {i, i + 1, i + 2, i + 3};
      const double w = 0.25 * i;
      ASSERT_TRUE(b.tet(t, reinterpret_cast<const uint8_t*>(&w)).isOk());
    }
    const TetMesh& m = b.mesh();
    ASSERT_EQ(m.numPoints(), n);
    ASSERT_EQ(m.numTets(), n - 3);
    for (uint32_t i = 0; i < n; i += 997) {
      EXPECT_EQ(m.point(i)[2], -1.0 * i);
      EXPECT_EQ(m.point_fields[0].get(i, 0), double(i));
    }
    for (uint32_t i = 0; i + 3 < n; i += 997) {
      EXPECT_EQ(m.tets[i][3], i + 3);
      EXPECT_EQ(m.cell_fields[0].get(i, 0), 0.25 * i);
    }
  }
}

// TetMeshBuilder takes a level whole (a decoder that holds it so skips the events); a sink that
// takes events refuses it, and so does a subclass of the builder (it may be watching the events).
TEST(MeshStream, WholeLevelGoesToTheBuilderOnly) {
  class Watching : public TetMeshBuilder {};
  TetMeshBuilder b;
  Watching w;
  CountingSink c;
  EXPECT_TRUE(b.takesWholeLevel());
  EXPECT_FALSE(w.takesWholeLevel());
  EXPECT_FALSE(c.takesWholeLevel());
  LevelHeader h;
  h.points = 4;
  h.tets = 1;
  h.coord_type = ScalarType::kFloat32;
  h.metadata = {{"source.format", "test"}};
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.tets = {{0, 1, 2, 3}};
  m.blocks.push_back({});
  const Status refused = c.wholeLevel(h, TetMesh(m), {});
  EXPECT_FALSE(refused.isOk());
  EXPECT_EQ(refused.code(), StatusCode::kUsage);
  ASSERT_TRUE(b.wholeLevel(h, TetMesh(m), {{0, 2, 1}}).isOk());
  EXPECT_TRUE(b.mesh().coords == m.coords);
  EXPECT_TRUE(b.mesh().tets == m.tets);
  EXPECT_EQ(b.mesh().coord_type, ScalarType::kFloat32);  // the header's, as beginLevel sets it
  EXPECT_TRUE(b.mesh().metadata == h.metadata);
  EXPECT_TRUE(b.mesh().blocks.empty());  // as the events build it
  ASSERT_EQ(b.boundary().size(), 1u);
  EXPECT_EQ(b.boundary()[0][1], 2u);
  EXPECT_EQ(b.header().tets, 1u);
}

// Mapping a buffer's pages ahead changes none of its contents, whatever its size and alignment.
TEST(FreshMemory, PopulatingKeepsTheContents) {
  for (size_t n : {size_t{1}, size_t{5000}, size_t{1} << 16, (size_t{1} << 20) + 3}) {
    std::vector<uint8_t> v(n + 7);
    for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<uint8_t>(i * 7 + 1);
    populateForWrite(v.data() + 3, n);
    for (size_t i = 0; i < v.size(); ++i) ASSERT_EQ(v[i], static_cast<uint8_t>(i * 7 + 1)) << i;
    std::vector<uint32_t> w = {5, 6};
    resizePopulated(w, n);
    ASSERT_EQ(w.size(), n);
    EXPECT_EQ(w[0], 5u);
    if (n > 2) {
      EXPECT_EQ(w[1], 6u);
      EXPECT_EQ(w[n - 1], 0u);  // new elements value-initialized
    }
    std::vector<double> r;
    reservePopulated(r, n);
    EXPECT_GE(r.capacity(), n);
    EXPECT_TRUE(r.empty());
  }
}

}  // namespace
}  // namespace gtn
