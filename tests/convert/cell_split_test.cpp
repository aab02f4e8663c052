// Conforming splitting of VTK cells into tetrahedra: volumes add up exactly (no overlap, no gap),
// shared faces are cut the same way from both sides (manifold, boundary = 2 x quads), for any vertex
// numbering.
#include "convert/cell_split.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "convert/vtk_common.h"
#include "mesh/hex_split.h"
#include "mesh/mesh_stats.h"
#include "mesh/predicates.h"

namespace gtn {
namespace {

// An nx x ny x nz grid of unit hexahedra whose points are numbered by a random permutation.
struct Grid {
  TetMesh mesh;
  VtkCells cells;
  size_t boundary_quads = 0;
};

Grid makeGrid(int nx, int ny, int nz, uint32_t seed) {
  Grid g;
  const int px = nx + 1, py = ny + 1, pz = nz + 1;
  std::vector<uint32_t> perm(static_cast<size_t>(px) * py * pz);
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(perm.begin(), perm.end(), rng);
  g.mesh.coords.resize(3 * perm.size());
  auto id = [&](int i, int j, int k) { return perm[(static_cast<size_t>(k) * py + j) * px + i]; };
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i) {
        double* p = &g.mesh.coords[3 * id(i, j, k)];
        p[0] = i, p[1] = j, p[2] = k;
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        g.cells.types.push_back(kVtkHexahedron);
        g.cells.connectivity.insert(g.cells.connectivity.end(), h, h + 8);
        g.cells.offsets.push_back(static_cast<int64_t>(g.cells.connectivity.size()));
      }
  g.boundary_quads = 2 * (static_cast<size_t>(nx) * ny + static_cast<size_t>(ny) * nz + static_cast<size_t>(nx) * nz);
  return g;
}

// How many of the tetrahedra have each triangle (its vertices ascending) as a face.
std::map<std::array<uint32_t, 3>, int> faceCounts(const std::vector<Tet>& tets) {
  std::map<std::array<uint32_t, 3>, int> count;
  for (const Tet& t : tets)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<uint32_t, 3> f;
      for (int i = 0, k = 0; i < 4; ++i)
        if (i != skip) f[k++] = t[i];
      std::sort(f.begin(), f.end());
      ++count[f];
    }
  return count;
}

ImportResult splitInto(const TetMesh& points, const VtkCells& cells, int split) {
  ImportResult r;
  r.mesh = points;
  ImportOptions options;
  options.split = split;
  const Status st = finishVtkImport("grid", cells, {}, options, &r);
  EXPECT_TRUE(st.isOk()) << st.message();
  return r;
}

TEST(CellSplit, RandomlyNumberedHexGridsSplitConformingly) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    Grid g = makeGrid(4, 3, 5, seed);
    const size_t hexes = g.cells.types.size();
    for (int split : {5, 6}) {
      ImportResult r = splitInto(g.mesh, g.cells, split);
      const MeshStats s = computeMeshStats(r.mesh);
      EXPECT_EQ(s.non_manifold_faces, 0u) << "seed " << seed << " split " << split;
      EXPECT_EQ(s.boundary_faces, 2 * g.boundary_quads) << "seed " << seed << " split " << split;
      EXPECT_EQ(s.inverted, 0u);
      EXPECT_EQ(s.zero_volume, 0u);
      EXPECT_NEAR(s.total_volume, 4.0 * 3.0 * 5.0, 1e-9) << "overlap or gap; seed " << seed << " split " << split;
      EXPECT_EQ(r.report.steiner_points, 0u);
      if (split == 6) {
        EXPECT_EQ(r.mesh.numTets(), 6 * hexes);
      } else {
        EXPECT_GE(r.mesh.numTets(), 5 * hexes);
        EXPECT_LE(r.mesh.numTets(), 6 * hexes);
      }
    }
  }
}

TEST(CellSplit, FiveWhenTheDiagonalsAllowItSixOtherwise) {
  // Unit cube; the corners 0, 2, 5, 7 get the smallest numbers, so every face diagonal passes through
  // two of them: the inscribed tetrahedron {0,2,5,7} exists and --split 5 gives 5 tetrahedra.
  TetMesh cube;
  const double corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const uint32_t five_ids[8] = {0, 4, 1, 5, 6, 2, 7, 3};  // local corner -> global number
  cube.coords.resize(24);
  for (int c = 0; c < 8; ++c)
    for (int d = 0; d < 3; ++d) cube.coords[3 * five_ids[c] + d] = corner[c][d];
  VtkCells cells;
  cells.types = {kVtkHexahedron};
  cells.connectivity.assign(five_ids, five_ids + 8);
  cells.offsets.push_back(8);
  EXPECT_EQ(splitInto(cube, cells, 5).mesh.numTets(), 5u);
  EXPECT_EQ(splitInto(cube, cells, 6).mesh.numTets(), 6u);
  // Numbered 0..7 in VTK order, face (1,2,6,5) has its smallest corner 1: no 5-split.
  TetMesh plain;
  plain.coords.assign(&corner[0][0], &corner[0][0] + 24);
  VtkCells identity;
  identity.types = {kVtkHexahedron};
  identity.connectivity = {0, 1, 2, 3, 4, 5, 6, 7};
  identity.offsets.push_back(8);
  ImportResult r = splitInto(plain, identity, 5);
  EXPECT_EQ(r.mesh.numTets(), 6u);
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("1 of 1 hexahedra split into 6"), std::string::npos);
  EXPECT_DOUBLE_EQ(computeMeshStats(r.mesh).total_volume, 1.0);
}

// The points `pts` numbered by a random permutation (seeded): the mesh's coordinates, and *perm with
// perm[i] the index that pts[i] gets.
TetMesh shuffledPoints(const std::vector<std::array<double, 3>>& pts, uint32_t seed, std::vector<uint32_t>* perm) {
  perm->resize(pts.size());
  std::iota(perm->begin(), perm->end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(perm->begin(), perm->end(), rng);
  TetMesh mesh;
  mesh.coords.resize(3 * pts.size());
  for (size_t p = 0; p < pts.size(); ++p)
    for (int d = 0; d < 3; ++d) mesh.coords[3 * (*perm)[p] + d] = pts[p][d];
  return mesh;
}

TEST(CellSplit, MixedWedgesPyramidsHexesAndTetsConform) {
  // A 2x1x1 block: the left cube as two wedges, the right cube as six pyramids around its centre,
  // plus nothing else; numbering shuffled. Volume 2, manifold, boundary = 10 quads x 2.
  for (uint32_t seed = 0; seed < 20; ++seed) {
    std::vector<std::array<double, 3>> pts;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 3; ++i) pts.push_back({double(i), double(j), double(k)});
    pts.push_back({1.5, 0.5, 0.5});  // centre of the right cube, index 12
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, seed, &perm);
    auto P = [&](int i, int j, int k) { return static_cast<int64_t>(perm[(k * 2 + j) * 3 + i]); };
    const int64_t c = perm[12];
    VtkCells cells;
    auto add = [&](int type, std::vector<int64_t> ids) {
      cells.types.push_back(type);
      cells.connectivity.insert(cells.connectivity.end(), ids.begin(), ids.end());
      cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
    };
    // Left cube [0,1]: two wedges along y, cut by the plane through (0,0)-(1,1) in x/z... the prisms
    // have triangles in the xz-plane at y = 0 and y = 1.
    add(kVtkWedge, {P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 1, 0), P(1, 1, 0), P(1, 1, 1)});
    add(kVtkWedge, {P(0, 0, 0), P(1, 0, 1), P(0, 0, 1), P(0, 1, 0), P(1, 1, 1), P(0, 1, 1)});
    // Right cube [1,2]: six pyramids, one per face, apex at the centre.
    add(kVtkPyramid, {P(1, 0, 0), P(2, 0, 0), P(2, 1, 0), P(1, 1, 0), c});
    add(kVtkPyramid, {P(1, 0, 1), P(1, 1, 1), P(2, 1, 1), P(2, 0, 1), c});
    add(kVtkPyramid, {P(1, 0, 0), P(1, 0, 1), P(2, 0, 1), P(2, 0, 0), c});
    add(kVtkPyramid, {P(1, 1, 0), P(2, 1, 0), P(2, 1, 1), P(1, 1, 1), c});
    add(kVtkPyramid, {P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1), c});
    add(kVtkPyramid, {P(2, 0, 0), P(2, 0, 1), P(2, 1, 1), P(2, 1, 0), c});
    ImportResult r = splitInto(mesh, cells, 6);
    EXPECT_EQ(r.mesh.numTets(), 2u * 3 + 6u * 2);
    const MeshStats s = computeMeshStats(r.mesh);
    EXPECT_EQ(s.non_manifold_faces, 0u) << seed;
    // Boundary: 10 unit squares as 2 triangles, except the two y faces of the left cube where the
    // wedge triangles already are triangles (2 per square as well).
    EXPECT_EQ(s.boundary_faces, 20u) << seed;
    EXPECT_NEAR(s.total_volume, 2.0, 1e-12) << seed;
    EXPECT_EQ(s.zero_volume, 0u);
  }
}

// Pentagonal and hexagonal prisms (VTK types 15 and 16): two hexagonal prisms stacked on a regular
// hexagon and a pentagonal prism against a side of the lower one, numbered at random. The hexagon
// they share and the quadrilateral the pentagonal prism shares are cut alike from both sides, so the
// mesh is manifold, its boundary is exactly the outer faces' triangles and the volume adds up.
TEST(CellSplit, PentagonalAndHexagonalPrismsConform) {
  const double r3 = std::sqrt(3.0);
  std::vector<std::array<double, 2>> hexagon, pentagon;
  for (int i = 0; i < 6; ++i) hexagon.push_back({std::cos(i * M_PI / 3), std::sin(i * M_PI / 3)});
  // On the side (hexagon[0], hexagon[1]), outward: a rectangle of depth 0.8 with a roof of 0.5.
  const double nx = r3 / 2, ny = 0.5, mx = 0.75, my = r3 / 4;
  pentagon = {hexagon[0],
              hexagon[1],
              {hexagon[1][0] + 0.8 * nx, hexagon[1][1] + 0.8 * ny},
              {mx + 1.3 * nx, my + 1.3 * ny},
              {hexagon[0][0] + 0.8 * nx, hexagon[0][1] + 0.8 * ny}};
  for (uint32_t seed = 0; seed < 20; ++seed) {
    // Points: the hexagon at z = 0, 1, 2 (0-17), the pentagon's 3 outer points at z = 0, 1 (18-23).
    std::vector<std::array<double, 3>> pts;
    for (int z = 0; z < 3; ++z)
      for (const auto& h : hexagon) pts.push_back({h[0], h[1], double(z)});
    for (int z = 0; z < 2; ++z)
      for (int i = 2; i < 5; ++i) pts.push_back({pentagon[i][0], pentagon[i][1], double(z)});
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, seed, &perm);
    auto H = [&](int z, int i) { return static_cast<int64_t>(perm[6 * z + i]); };
    auto Q = [&](int z, int i) { return i < 2 ? H(z, i) : static_cast<int64_t>(perm[18 + 3 * z + (i - 2)]); };
    VtkCells cells;
    auto add = [&](int type, std::vector<int64_t> ids) {
      cells.types.push_back(type);
      cells.connectivity.insert(cells.connectivity.end(), ids.begin(), ids.end());
      cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
    };
    for (int z = 0; z < 2; ++z) {
      std::vector<int64_t> ids;
      for (int layer = z; layer <= z + 1; ++layer)
        for (int i = 0; i < 6; ++i) ids.push_back(H(layer, i));
      add(kVtkHexagonalPrism, ids);
    }
    std::vector<int64_t> ids;
    for (int z = 0; z < 2; ++z)
      for (int i = 0; i < 5; ++i) ids.push_back(Q(z, i));
    add(kVtkPentagonalPrism, ids);
    ImportResult r = splitInto(mesh, cells, 6);
    const MeshStats s = computeMeshStats(r.mesh);
    EXPECT_EQ(s.non_manifold_faces, 0u) << seed;
    // Lower prism: bottom hexagon 4 triangles, 5 free sides 10; upper: top 4, sides 12; pentagonal
    // prism: 3 + 3 for its pentagons, 4 free sides 8.
    EXPECT_EQ(s.boundary_faces, 44u) << seed;
    EXPECT_NEAR(s.total_volume, 2 * (3 * r3 / 2) + 1.05, 1e-12) << seed;
    EXPECT_EQ(s.zero_volume, 0u) << seed;
    EXPECT_LE(r.mesh.numTets(), 2u * 12 + 9u);
  }
}

// Polyhedra (VTK_POLYHEDRON) from their face streams, in XML's layout (faces and faceoffsets beside
// the cells) and in the legacy one (the stream as the cell's point list): a unit cube given as a
// polyhedron of 6 quadrilaterals next to a hexahedron, and a tetrahedron-capped block of 5 faces (a
// wedge as a polyhedron) on top; numbered at random. Shared faces are cut alike from both sides.
TEST(CellSplit, PolyhedraSplitFromTheirFacesAndConform) {
  for (const bool separate : {true, false}) {
    for (uint32_t seed = 0; seed < 20; ++seed) {
      std::vector<std::array<double, 3>> pts;
      for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 3; ++i) pts.push_back({double(i), double(j), double(k)});
      pts.push_back({0, 0, 2});  // 12, 13: the wedge's top edge above x = 0
      pts.push_back({0, 1, 2});
      std::vector<uint32_t> perm;
      const TetMesh mesh = shuffledPoints(pts, seed, &perm);
      auto P = [&](int i, int j, int k) { return static_cast<int64_t>(perm[(k * 2 + j) * 3 + i]); };
      VtkCells cells;
      auto add = [&](int type, const std::vector<int64_t>& points, const std::vector<std::vector<int64_t>>& faces) {
        cells.types.push_back(type);
        if (type == kVtkPolyhedron) {
          std::vector<int64_t> stream = {static_cast<int64_t>(faces.size())};
          for (const auto& f : faces) {
            stream.push_back(static_cast<int64_t>(f.size()));
            stream.insert(stream.end(), f.begin(), f.end());
          }
          if (separate) {
            cells.connectivity.insert(cells.connectivity.end(), points.begin(), points.end());
            cells.faces.insert(cells.faces.end(), stream.begin(), stream.end());
            cells.face_offsets.push_back(static_cast<int64_t>(cells.faces.size()));
          } else {
            cells.connectivity.insert(cells.connectivity.end(), stream.begin(), stream.end());
          }
        } else {
          cells.connectivity.insert(cells.connectivity.end(), points.begin(), points.end());
          if (separate) cells.face_offsets.push_back(-1);
        }
        cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
      };
      // The left cube [0,1]^3 as a polyhedron (faces in any orientation and starting corner).
      const int64_t a = P(0, 0, 0), b = P(1, 0, 0), c = P(1, 1, 0), d = P(0, 1, 0);
      const int64_t e = P(0, 0, 1), f = P(1, 0, 1), g = P(1, 1, 1), h = P(0, 1, 1);
      add(kVtkPolyhedron, {a, b, c, d, e, f, g, h},
          {{a, d, c, b}, {e, f, g, h}, {b, c, g, f}, {a, e, h, d}, {a, b, f, e}, {d, h, g, c}});
      // The right cube [1,2] x [0,1]^2 as a hexahedron.
      add(kVtkHexahedron,
          {P(1, 0, 0), P(2, 0, 0), P(2, 1, 0), P(1, 1, 0), P(1, 0, 1), P(2, 0, 1), P(2, 1, 1), P(1, 1, 1)}, {});
      // On the left cube's top: a wedge with its ridge above x = 0, as a polyhedron of 5 faces.
      const int64_t r0 = perm[12], r1 = perm[13];
      add(kVtkPolyhedron, {e, f, g, h, r0, r1}, {{e, f, g, h}, {e, r0, f}, {h, g, r1}, {e, h, r1, r0}, {f, r0, r1, g}});
      ImportResult r;
      r.mesh = mesh;
      const Status st = finishVtkImport("poly", cells, {}, ImportOptions{}, &r);
      ASSERT_TRUE(st.isOk()) << st.message();
      const MeshStats s = computeMeshStats(r.mesh);
      EXPECT_EQ(s.non_manifold_faces, 0u) << seed;
      // Two cubes: 10 squares, less the left top (covered) = 9 squares; the wedge: 2 triangles and 2
      // quadrilaterals (its square base lies on the cube).
      EXPECT_EQ(s.boundary_faces, 9u * 2 + 2 + 2 * 2) << seed;
      EXPECT_NEAR(s.total_volume, 2.0 + 0.5, 1e-12) << seed;
      EXPECT_EQ(s.zero_volume, 0u) << seed;
      EXPECT_EQ(r.report.collapsed_tets, 0u);
    }
  }
}

// No flat, inverted or non-manifold piece, the boundary triangles and the volume expected.
void expectSolidSplit(const ImportResult& r, size_t boundary_faces, double volume, uint32_t seed) {
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_EQ(s.zero_volume, 0u) << seed;
  EXPECT_EQ(s.inverted, 0u) << seed;
  EXPECT_EQ(s.non_manifold_faces, 0u) << seed;
  EXPECT_EQ(s.boundary_faces, boundary_faces) << seed;
  EXPECT_NEAR(s.total_volume, volume, 1e-12) << seed;
}

// Polyhedra whose faces do not all wind the same way (writers differ, and some wind each face as it
// comes): the faces that disagree are turned before the split, the cell is coned from its smallest
// vertex as a cube wound outward is, and the faces it shares with a hexahedron beside it still match.
// Every subset of the cube's six faces turned but all six (a cell wound inward throughout, whose
// tetrahedra the import flips afterwards), numbered at random.
TEST(CellSplit, PolyhedraWhoseFacesWindBothWaysSplitAsWoundAlike) {
  std::vector<std::array<double, 3>> pts;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) pts.push_back({double(i), double(j), double(k)});
  for (uint32_t turned = 0; turned < 63; ++turned) {
    SCOPED_TRACE("faces turned " + std::to_string(turned));
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, turned, &perm);
    auto P = [&](int i, int j, int k) { return static_cast<int64_t>(perm[(k * 2 + j) * 3 + i]); };
    const int64_t a = P(0, 0, 0), b = P(1, 0, 0), c = P(1, 1, 0), d = P(0, 1, 0);
    const int64_t e = P(0, 0, 1), f = P(1, 0, 1), g = P(1, 1, 1), h = P(0, 1, 1);
    std::vector<std::vector<int64_t>> faces = {{a, d, c, b}, {e, f, g, h}, {b, c, g, f},
                                               {a, e, h, d}, {a, b, f, e}, {d, h, g, c}};
    for (size_t k = 0; k < faces.size(); ++k)
      if (turned >> k & 1) std::reverse(faces[k].begin(), faces[k].end());
    VtkCells cells;
    cells.types = {kVtkPolyhedron, kVtkHexahedron};
    cells.connectivity = {a, b, c, d, e, f, g, h};
    cells.faces = {static_cast<int64_t>(faces.size())};
    for (const auto& face : faces) {
      cells.faces.push_back(static_cast<int64_t>(face.size()));
      cells.faces.insert(cells.faces.end(), face.begin(), face.end());
    }
    cells.face_offsets = {static_cast<int64_t>(cells.faces.size()), -1};
    cells.offsets = {0, 8};
    for (const int64_t p :
         {P(1, 0, 0), P(2, 0, 0), P(2, 1, 0), P(1, 1, 0), P(1, 0, 1), P(2, 0, 1), P(2, 1, 1), P(1, 1, 1)})
      cells.connectivity.push_back(p);
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
    const ImportResult r = splitInto(mesh, cells, 6);
    // Two unit cubes: 10 free squares of 2 triangles each, nothing inverted, nothing flat.
    expectSolidSplit(r, 10 * 2, 2.0, turned);
    EXPECT_EQ(r.mesh.numTets(), 12u);
    EXPECT_EQ(r.report.steiner_points, 0u);
    // Turned are the faces against the rest: reported where the faces did not all wind alike.
    const bool mixed = turned != 0;
    const bool said = std::any_of(r.report.warnings.begin(), r.report.warnings.end(), [](const std::string& w) {
      return w.find("1 polyhedra (VTK_POLYHEDRON) whose faces do not all wind the same way") != std::string::npos;
    });
    EXPECT_EQ(said, mixed);
  }
}

// A straight angle in a face (three corners in a line: a pentagonal prism whose base has a point on
// an edge, a cube whose faces carry the hanging nodes of a refined neighbour) would make the fan from
// the face's smallest corner hold a flat triangle, and the cell's cone flat tetrahedra, overlapping
// their neighbours'. The face is fanned from the first corner whose fan has none, alike from both
// cells that share it, and the cell is coned from an apex or an added point that makes no flat
// tetrahedron: the volumes add up, nothing is flat, and shared faces match (numbered at random).
TEST(CellSplit, StraightAnglesInFacesMakeNoFlatTetrahedra) {
  for (uint32_t seed = 0; seed < 12; ++seed) {
    // Two pentagonal prisms, z in [0, 1], on either side of y = 0, each with (0.5, 0) on its base.
    const std::array<double, 2> base[7] = {{0, 0}, {0.5, 0}, {1, 0}, {1, 1}, {0, 1}, {0, -1}, {1, -1}};
    std::vector<std::array<double, 3>> pts;
    for (int z = 0; z < 2; ++z)
      for (const auto& b : base) pts.push_back({b[0], b[1], double(z)});
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, seed, &perm);
    auto P = [&](int z, int i) { return static_cast<int64_t>(perm[7 * z + i]); };
    VtkCells cells;
    for (const std::array<int, 5>& ring : {std::array<int, 5>{0, 1, 2, 3, 4}, std::array<int, 5>{0, 5, 6, 2, 1}}) {
      cells.types.push_back(kVtkPentagonalPrism);
      for (int z = 0; z < 2; ++z)
        for (int i : ring) cells.connectivity.push_back(P(z, i));
      cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
    }
    // Each prism: its two pentagons of 3 triangles and three free sides of 2.
    expectSolidSplit(splitInto(mesh, cells, 6), 2u * (6 + 6), 2.0, seed);
  }
  for (uint32_t seed = 0; seed < 12; ++seed) {
    // A unit cube as a polyhedron whose x = 1 face is four quadrilaterals (its centre and the middles
    // of its edges, a refined neighbour's nodes), so that its four faces around it are pentagons.
    std::vector<std::array<double, 3>> pts;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) pts.push_back({double(i), double(j), double(k)});
    for (const std::array<double, 3>& q :
         std::vector<std::array<double, 3>>{{1, 0.5, 0}, {1, 1, 0.5}, {1, 0.5, 1}, {1, 0, 0.5}, {1, 0.5, 0.5}})
      pts.push_back(q);
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, seed, &perm);
    auto C = [&](int i, int j, int k) { return static_cast<int64_t>(perm[(k * 2 + j) * 2 + i]); };
    auto M = [&](int i) { return static_cast<int64_t>(perm[8 + i]); };
    const int64_t a = C(0, 0, 0), b = C(1, 0, 0), c = C(1, 1, 0), d = C(0, 1, 0);
    const int64_t e = C(0, 0, 1), f = C(1, 0, 1), g = C(1, 1, 1), h = C(0, 1, 1);
    const int64_t z0 = M(0), y1 = M(1), z1 = M(2), y0 = M(3), mid = M(4);
    // Each face wound with its normal outward.
    const std::vector<std::vector<int64_t>> faces = {{a, e, h, d},  // x = 0
                                                     {b, z0, mid, y0}, {z0, c, y1, mid},
                                                     {mid, y1, g, z1}, {y0, mid, z1, f},   // x = 1
                                                     {a, d, c, z0, b}, {e, f, z1, g, h},   // z = 0, z = 1
                                                     {a, b, y0, f, e}, {d, h, g, y1, c}};  // y = 0, y = 1
    VtkCells cells;
    cells.types = {kVtkPolyhedron};
    cells.connectivity = {static_cast<int64_t>(faces.size())};
    for (const auto& face : faces) {
      cells.connectivity.push_back(static_cast<int64_t>(face.size()));
      cells.connectivity.insert(cells.connectivity.end(), face.begin(), face.end());
    }
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
    // x = 0: 2 triangles; x = 1: 4 quadrilaterals of 2; four pentagons of 3.
    expectSolidSplit(splitInto(mesh, cells, 6), 2u + 8 + 12, 1.0, seed);
  }
  // A hexahedron whose x = 0 face is collapsed onto a segment by its coordinates (distinct indices: a
  // wedge written as a hexahedron, as at the axis of an O-grid) has flat pieces however it is split:
  // it is split as before, with no point added, and said to be.
  for (uint32_t seed = 0; seed < 6; ++seed) {
    std::vector<std::array<double, 3>> pts;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) pts.push_back({double(i), i == 0 ? 0.0 : double(j), double(k)});
    std::vector<uint32_t> perm;
    const TetMesh mesh = shuffledPoints(pts, seed, &perm);
    auto C = [&](int i, int j, int k) { return static_cast<int64_t>(perm[(k * 2 + j) * 2 + i]); };
    VtkCells cells;
    cells.types = {kVtkHexahedron};
    cells.connectivity = {C(0, 0, 0), C(1, 0, 0), C(1, 1, 0), C(0, 1, 0),
                          C(0, 0, 1), C(1, 0, 1), C(1, 1, 1), C(0, 1, 1)};
    cells.offsets.push_back(8);
    const ImportResult r = splitInto(mesh, cells, 6);
    EXPECT_EQ(r.mesh.numPoints(), 8u) << seed;
    EXPECT_EQ(r.report.steiner_points, 0u) << seed;
    EXPECT_EQ(r.mesh.numTets(), 6u) << seed;
    EXPECT_NEAR(computeMeshStats(r.mesh).total_volume, 0.5, 1e-12) << seed;
    const auto& w = r.report.warnings;
    EXPECT_TRUE(std::any_of(w.begin(), w.end(), [](const std::string& m) {
      return m.find("1 cells have flat tetrahedra however they are split") != std::string::npos;
    })) << seed;
  }
}

TEST(CellSplit, MalformedFaceStreamsAreRejected) {
  auto attempt = [](const std::vector<int64_t>& stream) {
    VtkCells cells;
    cells.types = {kVtkPolyhedron};
    cells.connectivity = {0, 1, 2, 3};
    cells.offsets = {0, 4};
    cells.faces = stream;
    cells.face_offsets = {static_cast<int64_t>(stream.size())};
    std::vector<Tet> tets;
    std::vector<uint32_t> tet_cell;
    ImportReport report;
    return splitVtkCells("p.vtu", cells, 4, nullptr, 6, &tets, &tet_cell, &report);
  };
  const std::vector<int64_t> tet = {4, 3, 0, 1, 2, 3, 0, 3, 1, 3, 1, 3, 2, 3, 2, 3, 0};
  EXPECT_TRUE(attempt(tet).isOk());
  struct Case {
    std::vector<int64_t> stream;
    const char* part;
  };
  std::vector<int64_t> far = tet, extra = tet, two = tet, three = tet;
  far[2] = 9;
  extra.push_back(7);
  two[1] = 2;
  three[0] = 3;
  const std::vector<Case> cases = {{far, "refers to point 9 but there are 4 points"},
                                   {extra, "1 entries left after its 4 faces"},
                                   {two, "face 0 has 2 points"},
                                   {three, "face count of at least 4"},
                                   {{}, "face count of at least 4"}};
  for (const Case& k : cases) {
    const Status st = attempt(k.stream);
    ASSERT_FALSE(st.isOk()) << k.part;
    EXPECT_NE(st.message().find("p.vtu: cell 0 (VTK_POLYHEDRON)"), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(k.part), std::string::npos) << st.message() << " lacks " << k.part;
  }
}

TEST(CellSplit, CellFieldsSpreadOverTheTetrahedraOfTheirCell) {
  Grid g = makeGrid(2, 1, 1, 7);
  Field per_cell("region", 1, ScalarType::kInt32, 2);
  per_cell.set<int32_t>(0, 0, 11);
  per_cell.set<int32_t>(1, 0, 22);
  ImportResult r;
  r.mesh = g.mesh;
  ASSERT_TRUE(finishVtkImport("grid", g.cells, {per_cell}, ImportOptions{}, &r).isOk());
  ASSERT_EQ(r.mesh.cell_fields.size(), 1u);
  const Field& f = r.mesh.cell_fields[0];
  ASSERT_EQ(f.itemCount(), 12u);
  for (size_t t = 0; t < 12; ++t) {
    // The tet lies in cell 0 (x < 1) or cell 1 (x > 1): its centroid says which.
    double cx = 0;
    for (uint32_t v : r.mesh.tets[t]) cx += r.mesh.point(v)[0] / 4;
    EXPECT_EQ(f.data<int32_t>()[t], cx < 1 ? 11 : 22);
  }
}

TEST(CellSplit, QuadraticTetraKeepsCornersAndWarns) {
  TetMesh mesh;
  for (int i = 0; i < 10; ++i) mesh.coords.insert(mesh.coords.end(), {double(i % 2), double(i / 2 % 2), double(i / 4)});
  mesh.coords[0] = 0, mesh.coords[1] = 0, mesh.coords[2] = 0;
  mesh.coords[3] = 1, mesh.coords[4] = 0, mesh.coords[5] = 0;
  mesh.coords[6] = 0, mesh.coords[7] = 1, mesh.coords[8] = 0;
  mesh.coords[9] = 0, mesh.coords[10] = 0, mesh.coords[11] = 1;
  VtkCells cells;
  cells.types = {kVtkQuadraticTetra};
  for (int i = 0; i < 10; ++i) cells.connectivity.push_back(i);
  cells.offsets.push_back(10);
  ImportResult r = splitInto(mesh, cells, 6);
  ASSERT_EQ(r.mesh.numTets(), 1u);
  std::set<uint32_t> corners(r.mesh.tets[0].begin(), r.mesh.tets[0].end());
  EXPECT_EQ(corners, (std::set<uint32_t>{0, 1, 2, 3}));
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("1 quadratic tetrahedra"), std::string::npos);
  EXPECT_EQ(computeMeshStats(r.mesh).unreferenced_points, 6u);
}

TEST(CellSplit, RejectsUnsupportedTypesWithNameAndCount) {
  VtkCells cells;
  auto add = [&](int type, int n) {
    cells.types.push_back(type);
    for (int i = 0; i < n; ++i) cells.connectivity.push_back(i);
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  };
  add(41, 12), add(41, 12), add(38, 18), add(10, 4), add(66, 9), add(5, 3);
  std::vector<Tet> tets;
  std::vector<uint32_t> tet_cell;
  ImportReport report;
  const Status st = splitVtkCells("in.vtu", cells, 20, nullptr, 6, &tets, &tet_cell, &report);
  ASSERT_FALSE(st.isOk());
  EXPECT_EQ(st.code(), StatusCode::kUnsupported);
  for (const char* part : {"in.vtu", "2 cells of type 41 (VTK_CONVEX_POINT_SET)", "1 cell of type 38 (unknown)",
                           "1 cell of type 66 (unknown)"})
    EXPECT_NE(st.message().find(part), std::string::npos) << st.message() << " lacks " << part;
  // The triangle is not a reason to reject: cells of lower dimension are skipped.
  EXPECT_EQ(st.message().find("VTK_TRIANGLE"), std::string::npos) << st.message();
}

// Volume meshes written by Gmsh, MMG or meshio list their boundary triangles and feature edges
// beside the tetrahedra: those are skipped (with a warning) and the cell fields still line up.
TEST(CellSplit, SkipsCellsOfLowerDimensionWithAWarning) {
  TetMesh mesh;
  mesh.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  VtkCells cells;
  auto add = [&](int type, std::vector<int64_t> ids) {
    cells.types.push_back(type);
    cells.connectivity.insert(cells.connectivity.end(), ids.begin(), ids.end());
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  };
  add(1, {4}), add(3, {0, 1}), add(5, {0, 1, 2}), add(kVtkTetra, {0, 1, 2, 3}), add(9, {0, 1, 4, 3}),
      add(7, {0, 1, 2, 3, 4}), add(kVtkTetra, {1, 2, 3, 4}), add(22, {0, 1, 2, 3, 4, 0});
  Field id("id", 1, ScalarType::kInt32, cells.types.size());
  for (size_t c = 0; c < cells.types.size(); ++c) id.set<int32_t>(c, 0, static_cast<int32_t>(10 * c));
  ImportResult r;
  r.mesh = mesh;
  const Status st = finishVtkImport("mixed.vtk", cells, {id}, ImportOptions{}, &r);
  ASSERT_TRUE(st.isOk()) << st.message();
  ASSERT_EQ(r.mesh.numTets(), 2u);
  ASSERT_EQ(r.mesh.cell_fields.size(), 1u);
  EXPECT_EQ(r.mesh.cell_fields[0].data<int32_t>()[0], 30);
  EXPECT_EQ(r.mesh.cell_fields[0].data<int32_t>()[1], 60);
  ASSERT_EQ(r.report.warnings.size(), 1u);
  for (const char* part : {"skipped 6 cells", "1 cell of type 1 (VTK_VERTEX)", "1 cell of type 3 (VTK_LINE)",
                           "1 cell of type 5 (VTK_TRIANGLE)", "1 cell of type 7 (VTK_POLYGON)",
                           "1 cell of type 9 (VTK_QUAD)", "1 cell of type 22 (VTK_QUADRATIC_TRIANGLE)"})
    EXPECT_NE(r.report.warnings[0].find(part), std::string::npos) << r.report.warnings[0] << " lacks " << part;

  // Nothing but surface cells: not a volume mesh.
  VtkCells surface;
  surface.types = {5, 5};
  surface.connectivity = {0, 1, 2, 0, 2, 3};
  surface.offsets = {0, 3, 6};
  ImportResult s;
  s.mesh = mesh;
  const Status none = finishVtkImport("surface.vtk", surface, {}, ImportOptions{}, &s);
  ASSERT_FALSE(none.isOk());
  EXPECT_NE(none.message().find("surface.vtk: no volume cells, only 2 cells of type 5 (VTK_TRIANGLE)"),
            std::string::npos)
      << none.message();
}

TEST(CellSplit, VoxelSplitsLikeItsHexahedron) {
  // A unit voxel, corners numbered x fastest, then y, then z.
  TetMesh mesh;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) mesh.coords.insert(mesh.coords.end(), {double(i), double(j), double(k)});
  VtkCells cells;
  cells.types = {kVtkVoxel};
  cells.connectivity = {0, 1, 2, 3, 4, 5, 6, 7};
  cells.offsets.push_back(8);
  for (int split : {5, 6}) {
    ImportResult r = splitInto(mesh, cells, split);
    const MeshStats s = computeMeshStats(r.mesh);
    EXPECT_NEAR(s.total_volume, 1.0, 1e-12) << "split " << split;
    EXPECT_EQ(s.zero_volume, 0u);
    EXPECT_EQ(s.boundary_faces, 12u);
    EXPECT_EQ(s.non_manifold_faces, 0u);
  }
}

// A cell that vtkCellValidator accepts gives only positively oriented tetrahedra, whatever the
// numbering of its points, so the import reports no flips; its mirror image is all flips.
TEST(CellSplit, ValidCellsNeedNoFlipsAndMirroredOnesAllDo) {
  struct Case {
    int type;
    std::vector<std::array<double, 3>> corners;
  };
  std::vector<Case> cases = {
      {kVtkHexahedron, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}},
      {kVtkVoxel, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}},
      // vtkWedge: the first triangle's normal points away from the second (VTK's parametric
      // coordinates for the wedge are the mirror image, which the validator rejects).
      {kVtkWedge, {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 1}}},
      {kVtkPyramid, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}}},
  };
  for (int sides : {5, 6}) {
    Case c{sides == 5 ? kVtkPentagonalPrism : kVtkHexagonalPrism, {}};
    for (double z : {0.0, 1.0})
      for (int i = 0; i < sides; ++i)
        c.corners.push_back({std::cos(2 * M_PI * i / sides), std::sin(2 * M_PI * i / sides), z});
    cases.push_back(c);
  }
  for (const Case& c : cases) {
    const size_t n = c.corners.size();
    for (uint32_t seed = 0; seed < 12; ++seed) {
      std::vector<uint32_t> at(n);
      std::iota(at.begin(), at.end(), 0u);
      std::shuffle(at.begin(), at.end(), std::mt19937(seed));
      for (const double mirror : {1.0, -1.0}) {
        TetMesh mesh;
        mesh.coords.resize(3 * n);
        VtkCells cells;
        cells.types = {c.type};
        for (size_t i = 0; i < n; ++i) {
          for (int d = 0; d < 3; ++d) mesh.coords[3 * at[i] + d] = c.corners[i][d] * (d == 2 ? mirror : 1.0);
          cells.connectivity.push_back(at[i]);
        }
        cells.offsets.push_back(static_cast<int64_t>(n));
        const ImportResult r = splitInto(mesh, cells, 6);
        EXPECT_EQ(r.report.flipped, mirror > 0 ? 0u : r.mesh.numTets()) << "type " << c.type << " seed " << seed;
      }
    }
  }
}

// A hexahedron that is not convex (one corner pushed in): the cone from its smallest vertex mixes an
// inverted tetrahedron with positive ones, and flipping it would overlap the others. The split is
// taken from global point 4 (local corner 7) instead, which the face rule allows (every face through
// it is cut through it), and its tetrahedra tile the cell. With no coordinates it is the plain cone.
TEST(CellSplit, NonConvexHexahedronIsConedFromAnAllowedVertexWithoutInversions) {
  // Global point g at corners[g]; the cell lists its local corners 0..7 as these global indices.
  const uint32_t local_to_global[8] = {0, 5, 1, 7, 6, 2, 3, 4};
  const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  TetMesh mesh;
  mesh.coords.resize(24);
  VtkCells cells;
  cells.types = {kVtkHexahedron};
  for (int l = 0; l < 8; ++l) {
    for (int d = 0; d < 3; ++d) mesh.coords[3 * local_to_global[l] + d] = cube[l][d];
    cells.connectivity.push_back(local_to_global[l]);
  }
  cells.offsets.push_back(8);
  const double dent[3] = {0.75, 0.5, 0.5};  // local corner 1, global point 5
  std::copy(dent, dent + 3, &mesh.coords[3 * 5]);
  auto volume = [&](const Tet& t) {
    return signedVolume(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]), mesh.point(t[3]));
  };
  double hex_volume = 0;
  for (const bool with_coords : {false, true}) {
    std::vector<Tet> tets;
    std::vector<uint32_t> tet_cell;
    ImportReport report;
    ASSERT_TRUE(
        splitVtkCells("h.vtu", cells, 8, with_coords ? mesh.coords.data() : nullptr, 6, &tets, &tet_cell, &report)
            .isOk());
    // Asked for 5 (its diagonals allow it only when they form an inscribed tetrahedron), the split
    // never inverts a piece either.
    std::vector<Tet> five;
    std::vector<uint32_t> five_cell;
    ImportReport five_report;
    ASSERT_TRUE(splitVtkCells("h.vtu", cells, 8, mesh.coords.data(), 5, &five, &five_cell, &five_report).isOk());
    for (const Tet& t : five) EXPECT_GT(volume(t), 0.0);
    ASSERT_EQ(tets.size(), 6u);
    size_t negative = 0;
    for (const Tet& t : tets) negative += volume(t) < 0;
    if (!with_coords) {
      EXPECT_EQ(negative, 1u);  // the plain cone from global 0 inverts one piece
      for (const Tet& t : tets) EXPECT_TRUE(std::find(t.begin(), t.end(), 0u) != t.end());
      continue;
    }
    EXPECT_EQ(negative, 0u);
    for (const Tet& t : tets) hex_volume += volume(t);
    for (const Tet& t : tets)
      EXPECT_TRUE(std::find(t.begin(), t.end(), 4u) != t.end()) << "coned from global 4 (local 7)";
    ASSERT_EQ(report.warnings.size(), 1u);
    EXPECT_NE(report.warnings[0].find("1 cells that are not convex split from another vertex"), std::string::npos)
        << report.warnings[0];
    // The pieces tile the cell: their boundary is the cell's 12 face triangles, each once.
    const std::map<std::array<uint32_t, 3>, int> faces = faceCounts(tets);
    size_t once = 0;
    for (const auto& [f, n] : faces) {
      EXPECT_LE(n, 2);
      once += n == 1;
    }
    EXPECT_EQ(once, 12u);
  }
  // The same cell as a VTK_POLYHEDRON (its faces in a face stream) is coned from global 4 too.
  const int hex_faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  VtkCells poly;
  poly.types = {kVtkPolyhedron};
  poly.connectivity = {6};
  for (const auto& f : hex_faces) {
    poly.connectivity.push_back(4);
    for (int l : f) poly.connectivity.push_back(local_to_global[l]);
  }
  poly.offsets = {0, static_cast<int64_t>(poly.connectivity.size())};
  for (const bool with_coords : {false, true}) {
    std::vector<Tet> tets;
    std::vector<uint32_t> tet_cell;
    ImportReport report;
    ASSERT_TRUE(
        splitVtkCells("p.vtk", poly, 8, with_coords ? mesh.coords.data() : nullptr, 6, &tets, &tet_cell, &report)
            .isOk());
    ASSERT_EQ(tets.size(), 6u);
    size_t negative = 0;
    double total = 0;
    for (const Tet& t : tets) negative += volume(t) < 0, total += std::fabs(volume(t));
    if (!with_coords) {
      EXPECT_EQ(negative, 1u);  // the plain cone from global 0
      continue;
    }
    EXPECT_EQ(negative, 0u);
    EXPECT_NEAR(total, hex_volume, 1e-12);  // the same faces, cut by the same rule: the same cell
    for (const Tet& t : tets) EXPECT_TRUE(std::find(t.begin(), t.end(), 4u) != t.end()) << "coned from global 4";
    ASSERT_EQ(report.warnings.size(), 1u);
    EXPECT_NE(report.warnings[0].find("1 cells that are not convex split from another vertex"), std::string::npos)
        << report.warnings[0];
  }
}

// A hexahedron with a warped face (pyvista's qualityEx.vtk: a frustum whose bottom corner 4 is lifted
// out of its face's plane) mixes orientations however it is coned from a vertex. It is split around a
// Steiner point instead, over its 12 face triangles (the face rule's, so a neighbour would agree):
// none inverted, the tetrahedra fill the cell exactly once, and the point carries the mean of its
// corners' floating-point fields and its smallest corner's integer ones. With float32 points the
// added point is a float32 value too (the check that caught GCC 12's dropped rounding).
TEST(CellSplit, WarpedHexahedronIsSplitAroundASteinerPoint) {
  const double corner[8][3] = {{0, 0, -1},       {1, 0, -1},       {1, 1, -1},       {0, 1, -1},
                               {0.3, 0.3, -1.3}, {0.7, 0.3, -2.0}, {0.7, 0.7, -2.0}, {0.3, 0.7, -2.0}};
  const int local_to_global[8] = {4, 5, 6, 7, 0, 1, 2, 3};  // the file's "8 12 13 14 15 8 9 10 11", renumbered
  for (const bool float32 : {false, true}) {
    TetMesh points;
    points.coord_type = float32 ? ScalarType::kFloat32 : ScalarType::kFloat64;
    // Moved off the origin so that no coordinate of the corners' mean is a float32 value by chance.
    for (const auto& c : corner)
      for (int d = 0; d < 3; ++d) {
        const double x = c[d] + 0.1 * (d + 1);
        points.coords.push_back(float32 ? static_cast<double>(static_cast<float>(x)) : x);
      }
    Field temperature("temperature", 2, ScalarType::kFloat64, 8), id("id", 1, ScalarType::kInt32, 8);
    for (size_t i = 0; i < 8; ++i) {
      temperature.set<double>(i, 0, 10.0 + static_cast<double>(i));
      temperature.set<double>(i, 1, 0.5 * static_cast<double>(i * i));
      id.set<int32_t>(i, 0, 100 + static_cast<int32_t>(i));
    }
    points.point_fields = {temperature, id};
    VtkCells cells;
    cells.types = {kVtkHexahedron};
    for (int l = 0; l < 8; ++l) cells.connectivity.push_back(local_to_global[l]);
    cells.offsets.push_back(8);
    const ImportResult r = splitInto(points, cells, 6);
    const std::string where = float32 ? "float32" : "float64";
    ASSERT_EQ(r.report.steiner_points, 1u) << where;
    ASSERT_EQ(r.mesh.numPoints(), 9u);
    ASSERT_EQ(r.mesh.numTets(), 12u) << "the cone from the added point over 6 faces of 2 triangles";
    const double* s = r.mesh.point(8);
    for (int d = 0; d < 3; ++d) {
      if (float32) {
        EXPECT_EQ(static_cast<double>(static_cast<float>(s[d])), s[d]) << "coordinate " << d;
      }
      double lo = 1e300, hi = -1e300;
      for (size_t i = 0; i < 8; ++i) lo = std::min(lo, r.mesh.point(i)[d]), hi = std::max(hi, r.mesh.point(i)[d]);
      EXPECT_GT(s[d], lo);
      EXPECT_LT(s[d], hi);
    }
    // Every tetrahedron has the added point and none is inverted; their volumes add up to the
    // cell's, taken from its six faces (each cut along the diagonal through its smallest global
    // index) by the divergence theorem: a mixed split, flipped, would add up to more.
    double split_volume = 0;
    for (const Tet& t : r.mesh.tets) {
      EXPECT_TRUE(std::find(t.begin(), t.end(), 8u) != t.end());
      const double v = signedVolume(r.mesh.point(t[0]), r.mesh.point(t[1]), r.mesh.point(t[2]), r.mesh.point(t[3]));
      EXPECT_GT(v, 0.0) << where;
      split_volume += v;
    }
    const int hex_faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    const double origin[3] = {0, 0, 0};
    double cell_volume = 0;
    for (const auto& f : hex_faces) {
      int m = 0;
      for (int k = 1; k < 4; ++k)
        if (local_to_global[f[k]] < local_to_global[f[m]]) m = k;
      auto p = [&](int k) { return r.mesh.point(local_to_global[f[(m + k) % 4]]); };
      cell_volume += signedVolume(origin, p(0), p(1), p(2)) + signedVolume(origin, p(0), p(2), p(3));
    }
    EXPECT_NEAR(split_volume, std::fabs(cell_volume), 1e-12) << where;
    const MeshStats stats = computeMeshStats(r.mesh);
    EXPECT_EQ(stats.boundary_faces, 12u);
    EXPECT_EQ(stats.non_manifold_faces, 0u);
    EXPECT_EQ(stats.inverted, 0u);
    // Fields: the mean of the 8 corners, and for integers the smallest corner's (global 0, value 100).
    ASSERT_EQ(r.mesh.point_fields.size(), 2u);
    EXPECT_EQ(r.mesh.point_fields[0].get(8, 0), 13.5);
    EXPECT_EQ(r.mesh.point_fields[0].get(8, 1), 0.5 * 140.0 / 8.0);
    EXPECT_EQ(r.mesh.point_fields[1].get(8, 0), 100.0);
    bool warned = false;
    for (const std::string& w : r.report.warnings)
      warned |= w.find("1 cells that are not convex split around a point added") != std::string::npos;
    EXPECT_TRUE(warned) << where;
  }
}

// The same warped cell in a structured grid (PLOT3D, VTK structured datasets): where a grid split (5,
// either parity, or 6) mixes its pieces' orientations, it is split around an added point over its faces cut
// along the diagonals those pieces use; every piece then turns the same way and the faces keep
// their diagonals (the 12 face triangles are those of the 5- or 6-split).
TEST(CellSplit, WarpedStructuredCellIsSplitAroundASteinerPointAlongItsGridDiagonals) {
  const double corner[8][3] = {{0.3, 0.3, -1.3}, {0.7, 0.3, -2.0}, {0.7, 0.7, -2.0}, {0.3, 0.7, -2.0},
                               {0, 0, -1},       {1, 0, -1},       {1, 1, -1},       {0, 1, -1}};
  const uint32_t h[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  int mixed_splits = 0;
  for (const auto& [split, odd] : {std::pair{6, false}, std::pair{5, false}, std::pair{5, true}}) {
    const std::string where = "split " + std::to_string(split) + (odd ? " odd" : "");
    TetMesh mesh;
    for (const auto& c : corner) mesh.coords.insert(mesh.coords.end(), c, c + 3);
    mesh.point_fields = {Field("f", 1, ScalarType::kFloat64, 8)};
    for (size_t i = 0; i < 8; ++i) mesh.point_fields[0].set<double>(i, 0, static_cast<double>(i));
    std::vector<Tet> plain;
    if (split == 5) splitHexFive(h, odd, plain);
    else splitHexSix(h, plain);
    auto signs = [&](const std::vector<Tet>& tets) {
      std::set<int> s;
      for (const Tet& t : tets)
        s.insert(orient3d(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]), mesh.point(t[3])));
      return s;
    };
    const bool mixed = signs(plain).count(1) && signs(plain).count(-1);
    mixed_splits += mixed;
    std::vector<uint32_t> tet_cell;
    ImportReport report;
    GridHexSplitter grid(&mesh, &tet_cell);
    grid.split(h, split, odd, 7);
    grid.finish(&report);
    if (!mixed) {  // kept as it is
      EXPECT_EQ(report.steiner_points, 0u) << where;
      EXPECT_EQ(mesh.tets, plain) << where;
      EXPECT_TRUE(report.warnings.empty()) << where;
      continue;
    }
    EXPECT_EQ(report.steiner_points, 1u) << where;
    ASSERT_EQ(mesh.numPoints(), 9u);
    ASSERT_EQ(mesh.tets.size(), 12u);
    EXPECT_EQ(tet_cell, std::vector<uint32_t>(12, 7));
    EXPECT_EQ(signs(mesh.tets), std::set<int>{1}) << where;
    EXPECT_EQ(mesh.point_fields[0].get(8, 0), 3.5);
    // The cell's surface: the faces of the plain split seen once, and of the new one without point 8.
    auto surface = [](const std::vector<Tet>& tets, bool drop_apex) {
      std::set<std::array<uint32_t, 3>> once;
      for (const auto& [f, n] : faceCounts(tets))
        if (n == 1 && (!drop_apex || f[2] != 8)) once.insert(f);
      return once;
    };
    EXPECT_EQ(surface(mesh.tets, true), surface(plain, false)) << where;
  }
  EXPECT_GE(mixed_splits, 1) << "the warped cell mixes orientations under some grid split";
}

TEST(CellSplit, QuadraticHexWedgePyramidKeepTheirCorners) {
  // A unit cube as a 20-point quadratic hexahedron, and a wedge and a pyramid beside it; the extra
  // points sit anywhere (they are dropped): only the corners (listed first) shape the tetrahedra.
  TetMesh mesh;
  const double corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (const auto& c : corner) mesh.coords.insert(mesh.coords.end(), {c[0], c[1], c[2]});
  for (int i = 0; i < 19; ++i) mesh.coords.insert(mesh.coords.end(), {0.5, 0.5, 0.5});  // points 8..26
  VtkCells cells;
  auto add = [&](int type, std::vector<int64_t> ids, int extra) {
    cells.types.push_back(type);
    cells.connectivity.insert(cells.connectivity.end(), ids.begin(), ids.end());
    for (int i = 0; i < extra; ++i) cells.connectivity.push_back(8 + i);
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  };
  add(kVtkQuadraticHexahedron, {0, 1, 2, 3, 4, 5, 6, 7}, 12);
  add(kVtkTriquadraticHexahedron, {0, 1, 2, 3, 4, 5, 6, 7}, 19);
  add(kVtkQuadraticWedge, {0, 1, 2, 4, 5, 6}, 9);
  add(kVtkQuadraticPyramid, {0, 1, 2, 3, 6}, 8);
  // VTK_QUADRATIC_LINEAR_WEDGE, VTK_BIQUADRATIC_QUADRATIC_WEDGE, VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON
  // and VTK_TRIQUADRATIC_PYRAMID.
  add(31, {0, 1, 2, 4, 5, 6}, 6);
  add(32, {0, 1, 2, 4, 5, 6}, 12);
  add(33, {0, 1, 2, 3, 4, 5, 6, 7}, 16);
  add(37, {0, 1, 2, 3, 6}, 14);
  ImportResult r = splitInto(mesh, cells, 6);
  EXPECT_EQ(r.mesh.numTets(), 6u + 6u + 3u + 2u + 3u + 3u + 6u + 2u);
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_NEAR(s.total_volume, 1.0 + 1.0 + 0.5 + 1.0 / 3.0 + 0.5 + 0.5 + 1.0 + 1.0 / 3.0, 1e-12);
  EXPECT_EQ(s.zero_volume, 0u);
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("8 higher-order cells (quadratic hexahedra, wedges or pyramids"),
            std::string::npos)
      << r.report.warnings[0];
  // A quadratic hexahedron with the point count of a linear one is malformed.
  VtkCells bad;
  bad.types = {kVtkQuadraticHexahedron};
  bad.connectivity = {0, 1, 2, 3, 4, 5, 6, 7};
  bad.offsets.push_back(8);
  std::vector<Tet> tets;
  std::vector<uint32_t> tet_cell;
  ImportReport report;
  const Status st = splitVtkCells("q.vtu", bad, 27, nullptr, 6, &tets, &tet_cell, &report);
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("q.vtu: cell 0 (VTK_QUADRATIC_HEXAHEDRON) has 8 points, expected 20"), std::string::npos)
      << st.message();
}

TEST(CellSplit, RejectsBadIndicesAndPointCounts) {
  VtkCells cells;
  cells.types = {kVtkTetra};
  cells.connectivity = {0, 1, 2, 7};
  cells.offsets.push_back(4);
  std::vector<Tet> tets;
  std::vector<uint32_t> tet_cell;
  ImportReport report;
  Status st = splitVtkCells("m.vtk", cells, 4, nullptr, 6, &tets, &tet_cell, &report);
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("m.vtk: cell 0 refers to point 7 but there are 4 points"), std::string::npos)
      << st.message();
  cells.types = {kVtkHexahedron};
  cells.connectivity = {0, 1, 2, 3};
  st = splitVtkCells("m.vtk", cells, 4, nullptr, 6, &tets, &tet_cell, &report);
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("has 4 points, expected 8"), std::string::npos) << st.message();
}

TEST(CellSplit, DegenerateHexahedronDropsFlatPieces) {
  // A wedge written as a hexahedron with repeated points (common in VTK files): the pieces made flat
  // by repetition are dropped and counted; what remains fills the wedge.
  TetMesh mesh;
  mesh.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  VtkCells cells;
  cells.types = {kVtkHexahedron};
  cells.connectivity = {0, 1, 2, 2, 3, 4, 5, 5};
  cells.offsets.push_back(8);
  ImportResult r = splitInto(mesh, cells, 6);
  EXPECT_GT(r.report.collapsed_tets, 0u);
  EXPECT_EQ(r.mesh.numTets() + r.report.collapsed_tets, 6u);
  const MeshStats s = computeMeshStats(r.mesh);
  EXPECT_DOUBLE_EQ(s.total_volume, 0.5);
  EXPECT_EQ(s.non_manifold_faces, 0u);
}

// Lagrange and Bezier volume cells of any order (VTK 9): their corners come first and are kept; a
// cubic Lagrange hexahedron has 64 points, more than any fixed-size cell.
TEST(CellSplit, LagrangeAndBezierCellsKeepTheirCorners) {
  TetMesh mesh;
  // A unit cube's corners in VTK order, then 56 further points (their positions do not matter).
  const double corners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (const auto& c : corners) mesh.coords.insert(mesh.coords.end(), {c[0], c[1], c[2]});
  for (int k = 8; k < 64; ++k) mesh.coords.insert(mesh.coords.end(), {0.5, 0.5, 0.01 * k});
  VtkCells cells;
  auto add = [&](int type, int n) {
    cells.types.push_back(type);
    for (int k = 0; k < n; ++k) cells.connectivity.push_back(k);
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  };
  add(72, 64);  // VTK_LAGRANGE_HEXAHEDRON, order 3
  add(79, 27);  // VTK_BEZIER_HEXAHEDRON, order 2
  // VTK_LAGRANGE_TETRAHEDRON, order 2: the cube's corners 0 1 3 4, then six edge points.
  cells.types.push_back(71);
  for (int64_t k : {0, 1, 3, 4, 8, 9, 10, 11, 12, 13}) cells.connectivity.push_back(k);
  cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  ImportResult r;
  r.mesh = mesh;
  const Status st = finishVtkImport("lagrange.vtu", cells, {}, ImportOptions{}, &r);
  ASSERT_TRUE(st.isOk()) << st.message();
  EXPECT_EQ(r.mesh.numTets(), 13u);
  EXPECT_NEAR(computeMeshStats(r.mesh).total_volume, 2.0 + 1.0 / 6.0, 1e-12);
  ASSERT_FALSE(r.report.warnings.empty());
  EXPECT_NE(r.report.warnings[0].find("3 higher-order cells"), std::string::npos) << r.report.warnings[0];
  // Fewer points than corners is an error.
  VtkCells short_cell;
  short_cell.types = {72};
  short_cell.connectivity = {0, 1, 2, 3, 4, 5, 6};
  short_cell.offsets = {0, 7};
  ImportResult s2;
  s2.mesh = mesh;
  const Status bad = finishVtkImport("short.vtu", short_cell, {}, ImportOptions{}, &s2);
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.message().find("VTK_LAGRANGE_HEXAHEDRON) has 7 points, fewer than its 8 corners"), std::string::npos)
      << bad.message();
}

// An unstructured cell blanked by VTK (vtkGhostType HIDDENCELL = 32) is dropped with its values.
TEST(CellSplit, HiddenCellsAreDropped) {
  TetMesh mesh;
  mesh.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 3, 2, 2, 2, 3, 2, 2, 2, 3};
  VtkCells cells;
  auto add = [&](int type, std::vector<int64_t> ids) {
    cells.types.push_back(type);
    cells.connectivity.insert(cells.connectivity.end(), ids.begin(), ids.end());
    cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
  };
  add(kVtkTetra, {0, 1, 2, 3}), add(kVtkTetra, {1, 2, 3, 4}), add(kVtkTetra, {5, 6, 7, 8});
  Field ghost("vtkGhostType", 1, ScalarType::kUInt8, 3);
  ghost.bytes = {1, 32, 0};  // a duplicate (kept in a single file) and a hidden cell
  Field id("id", 1, ScalarType::kInt32, 3);
  for (int c = 0; c < 3; ++c) id.set<int32_t>(c, 0, 10 * c);
  ImportResult r;
  r.mesh = mesh;
  const Status st = finishVtkImport("hidden.vtu", cells, {ghost, id}, ImportOptions{}, &r);
  ASSERT_TRUE(st.isOk()) << st.message();
  ASSERT_EQ(r.mesh.numTets(), 2u);
  EXPECT_EQ(r.report.dropped_cells, 1u);
  ASSERT_EQ(r.mesh.cell_fields.size(), 2u);
  EXPECT_EQ(r.mesh.cell_fields[1].data<int32_t>()[0], 0);
  EXPECT_EQ(r.mesh.cell_fields[1].data<int32_t>()[1], 20);
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("1 cells blanked by VTK"), std::string::npos) << r.report.warnings[0];
}

}  // namespace
}  // namespace gtn
