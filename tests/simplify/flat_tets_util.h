// Generated meshes with zero-volume tetrahedra on and near the boundary, as meshers leave them: cubes
// of an integer grid split into six tetrahedra around one of two main diagonals (chosen at random per
// cube), a flat tetrahedron (the square's four corners) wherever two neighbouring cubes split their
// common square along different diagonals, and flat tetrahedra glued onto some boundary squares (their
// outer faces use the square's other diagonal). The flat tetrahedra get either orientation at random,
// as a file may list them. Coordinates are integers (interior points away from the flat tetrahedra
// are jittered), so that the flat tetrahedra are exactly flat.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "mesh/hex_split.h"
#include "mesh/index.h"
#include "mesh/mesh_stats.h"
#include "mesh/tet_mesh.h"

namespace gtn::test {

enum class FlatShape { kBox, kRing, kEll };

inline const char* flatShapeName(FlatShape s) {
  return s == FlatShape::kBox ? "box" : s == FlatShape::kRing ? "ring" : "ell";
}

// n cubes along each axis (the ring: a square torus, n x n x 2 without its middle column; the ell: a box
// without one quadrant). Fields: point "rho" (smooth), cell "region".
inline TetMesh makeFlatTetMesh(FlatShape shape, int n, uint32_t seed, size_t* flat_count = nullptr) {
  std::mt19937 rng(seed);
  const int nx = n, ny = n, nz = shape == FlatShape::kRing ? 2 : n;
  auto inside = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return false;
    if (shape == FlatShape::kRing) return !(i >= nx / 3 && i < nx - nx / 3 && j >= ny / 3 && j < ny - ny / 3);
    if (shape == FlatShape::kEll) return !(i >= nx / 2 && j >= ny / 2);
    return true;
  };
  auto node = [&](int i, int j, int k) { return static_cast<uint32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  TetMesh m;
  const size_t np = size_t(nx + 1) * (ny + 1) * (nz + 1);
  m.coords.resize(3 * np);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        double* p = m.coords.data() + 3 * size_t{node(i, j, k)};
        p[0] = i;
        p[1] = j;
        p[2] = k;
      }
  // Cubes and their split: diagonal 0-6 or (the cube's nodes turned a quarter about z) 1-7.
  std::bernoulli_distribution turn(0.3), glue(0.25), flip(0.5);
  std::map<std::array<int, 3>, std::set<std::pair<uint32_t, uint32_t>>> cube_edges;
  std::vector<uint8_t> touched(np, 0);  // points of flat tetrahedra (kept on the grid)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!inside(i, j, k)) continue;
        uint32_t h[8] = {node(i, j, k),     node(i + 1, j, k),     node(i + 1, j + 1, k),     node(i, j + 1, k),
                         node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        if (turn(rng)) {
          const uint32_t t[8] = {h[1], h[2], h[3], h[0], h[5], h[6], h[7], h[4]};
          std::copy(t, t + 8, h);
        }
        const size_t first = m.tets.size();
        splitHexSix(h, m.tets);
        auto& edges = cube_edges[{i, j, k}];
        for (size_t t = first; t < m.tets.size(); ++t)
          for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b)
              edges.insert({std::min(m.tets[t][a], m.tets[t][b]), std::max(m.tets[t][a], m.tets[t][b])});
      }
  size_t flat = 0;
  auto addFlat = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
    Tet t{a, b, c, d};
    if (flip(rng)) std::swap(t[2], t[3]);
    m.tets.push_back(t);
    for (uint32_t v : t) touched[v] = 1;
    ++flat;
  };
  // Squares perpendicular to each axis: corners in cyclic order, and the cubes on either side.
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k <= nz; ++k)
      for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
          const int c[3] = {i, j, k};
          int u = (axis + 1) % 3, w = (axis + 2) % 3;
          const int lim[3] = {nx, ny, nz};
          if (c[u] >= lim[u] || c[w] >= lim[w]) continue;
          std::array<uint32_t, 4> q;
          for (int s = 0; s < 4; ++s) {
            int p[3] = {i, j, k};
            p[u] += (s == 1 || s == 2);
            p[w] += (s >= 2);
            q[s] = node(p[0], p[1], p[2]);
          }
          int below[3] = {i, j, k};
          below[axis] -= 1;
          const bool in_a = inside(below[0], below[1], below[2]), in_b = inside(i, j, k);
          if (in_a && in_b) {
            auto diag = [&](const std::array<int, 3>& cube) {
              return cube_edges[cube].count({std::min(q[0], q[2]), std::max(q[0], q[2])}) ? 0 : 1;
            };
            if (diag({below[0], below[1], below[2]}) != diag({i, j, k})) addFlat(q[0], q[1], q[2], q[3]);
          } else if (in_a != in_b && glue(rng)) {
            addFlat(q[0], q[1], q[2], q[3]);
          }
        }
  // Jitter the interior points that no flat tetrahedron uses (the mesh stays valid: the jitter is
  // small next to the cubes).
  std::uniform_real_distribution<double> jitter(-0.12, 0.12);
  for (int k = 1; k < nz; ++k)
    for (int j = 1; j < ny; ++j)
      for (int i = 1; i < nx; ++i) {
        const uint32_t v = node(i, j, k);
        bool all_in = true;
        for (int d = 0; d < 8; ++d) all_in &= inside(i - (d & 1), j - ((d >> 1) & 1), k - ((d >> 2) & 1));
        if (!all_in || touched[v]) continue;
        for (int a = 0; a < 3; ++a) m.coords[3 * size_t{v} + a] += jitter(rng);
      }
  // Drop the grid points no cube uses (the ring's and the ell's holes).
  std::vector<uint32_t> index(np, kNoIndex);
  for (const Tet& t : m.tets)
    for (uint32_t v : t) index[v] = 0;
  std::vector<double> coords;
  uint32_t next = 0;
  for (size_t v = 0; v < np; ++v) {
    if (index[v]) continue;
    index[v] = next++;
    coords.insert(coords.end(), m.coords.begin() + 3 * v, m.coords.begin() + 3 * v + 3);
  }
  m.coords = std::move(coords);
  for (Tet& t : m.tets)
    for (uint32_t& v : t) v = index[v];
  Field rho("rho", 1, ScalarType::kFloat64, next);
  for (uint32_t v = 0; v < next; ++v) {
    const double* p = m.point(v);
    rho.set<double>(v, 0, 1.0 + std::sin(0.7 * p[0]) * std::cos(0.5 * p[1]) + 0.1 * p[2]);
  }
  m.point_fields.push_back(std::move(rho));
  Field region("region", 1, ScalarType::kInt32, m.tets.size());
  for (size_t t = 0; t < m.tets.size(); ++t) region.set<int32_t>(t, 0, int32_t(t % 5));
  m.cell_fields.push_back(std::move(region));
  // The inverted tetrahedra of the split are turned round, as the importers do; flat ones keep
  // whichever orientation they were given.
  normalizeOrientation(m, nullptr);
  if (flat_count) *flat_count = flat;
  return m;
}

}  // namespace gtn::test
