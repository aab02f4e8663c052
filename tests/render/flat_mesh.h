// A test mesh with tetrahedra of zero volume: a solid torus of square cross-section whose hexahedra
// are split into six tetrahedra each (Kuhn), where some hexahedra are split the mirrored way and the
// quads where the two splits meet are bridged by flat tetrahedra (the four corners of the quad),
// some boundary quads carry a flat tetrahedron of their own (two of its faces on the boundary), and
// some triangles in planes z = const are split on one side at a point inside them, bridged by a flat
// tetrahedron (the triangle and the point). Every flat tetrahedron is exactly flat (orient3d is 0)
// and oriented consistently with its neighbours, as a mesher writes them. The point field "f" is
// linear in the position, so that every tetrahedralization of the torus renders the same image.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "mesh/faces.h"
#include "mesh/predicates.h"
#include "mesh/tet_mesh.h"

namespace gtn::test {

struct FlatTorus {
  TetMesh mesh;
  size_t flat = 0;           // tetrahedra of zero volume
  size_t flat_boundary = 0;  // of which with faces on the boundary
};

// `with_flats` false: the same torus, every hexahedron split the same way, no flat tetrahedra.
inline FlatTorus makeFlatTorus(uint32_t seed, bool with_flats = true, int nu = 24, int nx = 4, int nz = 4) {
  constexpr double kMajor = 3.0, kHalf = 1.0;
  FlatTorus out;
  TetMesh& m = out.mesh;
  auto vid = [&](int i, int j, int k) { return static_cast<uint32_t>(((i % nu) * (nx + 1) + j) * (nz + 1) + k); };
  for (int i = 0; i < nu; ++i) {
    const double u = 2.0 * M_PI * i / nu;
    for (int j = 0; j <= nx; ++j) {
      const double r = kMajor - kHalf + 2.0 * kHalf * j / nx;
      // The x and y of a column are computed once: the quads of constant j are exactly planar.
      const double x = r * std::cos(u), y = r * std::sin(u);
      for (int k = 0; k <= nz; ++k) {
        m.coords.push_back(x);
        m.coords.push_back(y);
        m.coords.push_back(-kHalf + 2.0 * kHalf * k / nz);
      }
    }
  }
  auto P = [&](uint32_t v) { return m.coords.data() + 3 * v; };
  std::mt19937 rng(seed);
  auto chance = [&](double p) { return std::uniform_real_distribution<double>(0, 1)(rng) < p; };
  // Mirrored hexahedra (split about the other main diagonal in i): never two neighbours along j or k.
  std::vector<char> mirrored(static_cast<size_t>(nu) * nx * nz, 0);
  auto hex = [&](int i, int j, int k) -> char& { return mirrored[(static_cast<size_t>(i % nu) * nx + j) * nz + k]; };
  if (with_flats)
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nx; ++j)
        for (int k = 0; k < nz; ++k)
          if (chance(0.12) && !(j > 0 && hex(i, j - 1, k)) && !(k > 0 && hex(i, j, k - 1))) hex(i, j, k) = 1;
  auto positive = [&](Tet t) {
    if (orient3d(P(t[0]), P(t[1]), P(t[2]), P(t[3])) < 0) std::swap(t[2], t[3]);
    return t;
  };
  std::vector<Tet> solid, flats;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nx; ++j)
      for (int k = 0; k < nz; ++k) {
        const bool mir = hex(i, j, k);
        auto corner = [&](int dx, int dy, int dz) { return vid(i + (mir ? 1 - dx : dx), j + dy, k + dz); };
        const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        for (const auto& p : perms) {
          int d[3] = {0, 0, 0};
          Tet t;
          t[0] = corner(0, 0, 0);
          for (int s = 0; s < 3; ++s) {
            d[p[s]] = 1;
            t[s + 1] = corner(d[0], d[1], d[2]);
          }
          solid.push_back(positive(t));
        }
        if (!with_flats) continue;
        // Quads between a mirrored and a plain hexahedron (their diagonals cross): bridged.
        if (j + 1 < nx && hex(i, j + 1, k) != mir)
          flats.push_back({vid(i, j + 1, k), vid(i + 1, j + 1, k), vid(i + 1, j + 1, k + 1), vid(i, j + 1, k + 1)});
        if (k + 1 < nz && hex(i, j, k + 1) != mir)
          flats.push_back({vid(i, j, k + 1), vid(i + 1, j, k + 1), vid(i + 1, j + 1, k + 1), vid(i, j + 1, k + 1)});
        // Boundary quads with a flat tetrahedron on top.
        if (j == 0 && chance(0.15))
          flats.push_back({vid(i, 0, k), vid(i + 1, 0, k), vid(i + 1, 0, k + 1), vid(i, 0, k + 1)});
        if (k == nz - 1 && chance(0.15))
          flats.push_back({vid(i, j, nz), vid(i + 1, j, nz), vid(i + 1, j + 1, nz), vid(i, j + 1, nz)});
      }
  // Faces of the solid tetrahedra: sorted triple -> (tetrahedron, local face).
  auto key = [](uint32_t a, uint32_t b, uint32_t c) {
    std::array<uint32_t, 3> s = {a, b, c};
    std::sort(s.begin(), s.end());
    return s;
  };
  if (with_flats) {
    // Triangles in planes z = const between two solid tetrahedra, or on the boundary z = +-1: split
    // on one side at a point inside (its z copied, so that it lies in the plane exactly).
    std::map<std::array<uint32_t, 3>, std::vector<std::pair<size_t, int>>> faces;
    for (size_t t = 0; t < solid.size(); ++t)
      for (int f = 0; f < 4; ++f)
        faces[key(solid[t][kTetFace[f][0]], solid[t][kTetFace[f][1]], solid[t][kTetFace[f][2]])].push_back({t, f});
    std::set<size_t> split;
    for (const auto& [tri, users] : faces) {
      const double z = P(tri[0])[2];
      if (P(tri[1])[2] != z || P(tri[2])[2] != z || !chance(users.size() == 1 ? 0.2 : 0.1)) continue;
      const size_t t = users[0].first;
      if (split.count(t)) continue;
      split.insert(t);
      const uint32_t mid = static_cast<uint32_t>(m.numPoints());
      for (int c = 0; c < 2; ++c) m.coords.push_back((P(tri[0])[c] + 2 * P(tri[1])[c] + P(tri[2])[c]) / 4);
      m.coords.push_back(z);
      const Tet old = solid[t];
      const int apex = users[0].second;  // face f is opposite vertex f
      const int* f = kTetFace[apex];
      solid[t] = positive({old[f[0]], old[f[1]], mid, old[apex]});
      solid.push_back(positive({old[f[1]], old[f[2]], mid, old[apex]}));
      solid.push_back(positive({old[f[2]], old[f[0]], mid, old[apex]}));
      flats.push_back({tri[0], tri[1], tri[2], mid});
    }
  }
  // Flat tetrahedra oriented as their neighbours: a shared face is listed in opposite cyclic orders.
  std::map<std::array<uint32_t, 3>, std::array<uint32_t, 3>> listed;
  for (const Tet& t : solid)
    for (int f = 0; f < 4; ++f) {
      const std::array<uint32_t, 3> tri = {t[kTetFace[f][0]], t[kTetFace[f][1]], t[kTetFace[f][2]]};
      listed[key(tri[0], tri[1], tri[2])] = tri;
    }
  auto sameCycle = [](const std::array<uint32_t, 3>& a, const std::array<uint32_t, 3>& b) {
    for (int r = 0; r < 3; ++r)
      if (a[0] == b[r] && a[1] == b[(r + 1) % 3] && a[2] == b[(r + 2) % 3]) return true;
    return false;
  };
  // Passes until every flat one is oriented: one whose faces are all flat ones' or on the boundary
  // (a boundary quad over triangles both split) follows the flat ones oriented before it.
  std::vector<char> oriented(flats.size(), 0);
  for (bool progress = true; progress;) {
    progress = false;
    for (size_t i = 0; i < flats.size(); ++i) {
      Tet& t = flats[i];
      for (int f = 0; f < 4 && !oriented[i]; ++f) {
        const std::array<uint32_t, 3> tri = {t[kTetFace[f][0]], t[kTetFace[f][1]], t[kTetFace[f][2]]};
        const auto it = listed.find(key(tri[0], tri[1], tri[2]));
        if (it == listed.end()) continue;
        if (sameCycle(tri, it->second)) std::swap(t[2], t[3]);
        oriented[i] = progress = true;
        for (int g = 0; g < 4; ++g) {
          const std::array<uint32_t, 3> own = {t[kTetFace[g][0]], t[kTetFace[g][1]], t[kTetFace[g][2]]};
          listed.emplace(key(own[0], own[1], own[2]), own);
        }
      }
    }
  }
  // How many flat tetrahedra have a face that no other tetrahedron has.
  std::map<std::array<uint32_t, 3>, int> uses;
  std::vector<Tet> all = solid;
  all.insert(all.end(), flats.begin(), flats.end());
  for (const Tet& t : all)
    for (int f = 0; f < 4; ++f) ++uses[key(t[kTetFace[f][0]], t[kTetFace[f][1]], t[kTetFace[f][2]])];
  for (const Tet& t : flats) {
    bool boundary = false;
    for (int f = 0; f < 4; ++f) boundary |= uses[key(t[kTetFace[f][0]], t[kTetFace[f][1]], t[kTetFace[f][2]])] == 1;
    out.flat_boundary += boundary;
  }
  out.flat = flats.size();
  // Flat tetrahedra spread through the stream, not all at its end.
  std::shuffle(all.begin(), all.end(), rng);
  m.tets = all;
  Field f("f", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) f.set<double>(v, 0, P(v)[0] + 0.5 * P(v)[1] + 0.25 * P(v)[2]);
  m.point_fields.push_back(std::move(f));
  return out;
}

}  // namespace gtn::test
