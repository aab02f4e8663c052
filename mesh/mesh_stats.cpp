#include "mesh/mesh_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "mesh/faces.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {
FieldStats fieldStats(const Field& f, bool per_cell) {
  FieldStats s;
  s.name = f.name;
  s.components = f.components;
  s.type = f.type;
  s.per_cell = per_cell;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const size_t n = f.itemCount();
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t c = 0; c < f.components; ++c) {
      const double v = f.get(i, c);
      if (!std::isfinite(v)) {
        ++s.non_finite;
        continue;
      }
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (lo <= hi) {
    s.has_range = true;
    s.min = lo;
    s.max = hi;
  }
  return s;
}
}  // namespace

MeshStats computeMeshStats(const TetMesh& mesh) {
  MeshStats s;
  s.points = mesh.numPoints();
  s.tets = mesh.numTets();
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  s.faces = adj.faces;
  s.boundary_faces = adj.boundary_faces;
  s.non_manifold_faces = adj.non_manifold_faces;

  if (s.points > 0) {
    for (int a = 0; a < 3; ++a) {
      s.bbox_min[a] = std::numeric_limits<double>::infinity();
      s.bbox_max[a] = -std::numeric_limits<double>::infinity();
    }
    for (size_t i = 0; i < s.points; ++i) {
      for (int a = 0; a < 3; ++a) {
        s.bbox_min[a] = std::min(s.bbox_min[a], mesh.coords[3 * i + a]);
        s.bbox_max[a] = std::max(s.bbox_max[a], mesh.coords[3 * i + a]);
      }
    }
  }

  std::vector<uint8_t> used(s.points, 0);
  s.min_volume = std::numeric_limits<double>::infinity();
  s.max_volume = -std::numeric_limits<double>::infinity();
  for (const Tet& t : mesh.tets) {
    const double *a = mesh.point(t[0]), *b = mesh.point(t[1]), *c = mesh.point(t[2]), *d = mesh.point(t[3]);
    const int o = orient3d(a, b, c, d);
    if (o < 0) ++s.inverted;
    if (o == 0) ++s.zero_volume;
    const double vol = o == 0 ? 0.0 : signedVolume(a, b, c, d);
    s.min_volume = std::min(s.min_volume, vol);
    s.max_volume = std::max(s.max_volume, vol);
    s.total_volume += vol;
    for (uint32_t v : t) used[v] = 1;
  }
  if (mesh.tets.empty()) s.min_volume = s.max_volume = 0;
  s.unreferenced_points = static_cast<uint64_t>(std::count(used.begin(), used.end(), 0));

  std::vector<uint32_t> order(s.points);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](uint32_t x, uint32_t y) {
    const double *p = mesh.point(x), *q = mesh.point(y);
    if (p[0] != q[0]) return p[0] < q[0];
    if (p[1] != q[1]) return p[1] < q[1];
    return p[2] < q[2];
  };
  std::sort(order.begin(), order.end(), less);
  for (size_t i = 1; i < order.size(); ++i)
    if (!less(order[i - 1], order[i])) ++s.coincident_points;

  for (const Field& f : mesh.point_fields) s.fields.push_back(fieldStats(f, false));
  for (const Field& f : mesh.cell_fields) s.fields.push_back(fieldStats(f, true));
  return s;
}

size_t defaultPointField(const std::vector<bool>& varies) {
  for (size_t i = 0; i < varies.size(); ++i)
    if (varies[i]) return i;
  return SIZE_MAX;
}

bool firstComponentVaries(const Field& field) {
  bool seen = false;
  double first = 0;
  for (size_t i = 0, n = field.itemCount(); i < n; ++i) {
    const double v = field.get(i, 0);
    if (!std::isfinite(v)) continue;
    if (!seen) {
      seen = true;
      first = v;
    } else if (v != first) {
      return true;
    }
  }
  return false;
}

size_t normalizeOrientation(TetMesh& mesh, size_t* zero_volume) {
  size_t flipped = 0, flat = 0;
  for (Tet& t : mesh.tets) {
    const int o = orient3d(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]), mesh.point(t[3]));
    if (o < 0) {
      std::swap(t[2], t[3]);
      ++flipped;
    } else if (o == 0) {
      ++flat;
    }
  }
  if (zero_volume) *zero_volume = flat;
  return flipped;
}

size_t orientFlatTets(TetMesh& mesh) {
  const size_t n = mesh.tets.size();
  std::vector<char> flat(n, 0);
  bool any = false;
  for (size_t t = 0; t < n; ++t) {
    const Tet& v = mesh.tets[t];
    flat[t] = orient3d(mesh.point(v[0]), mesh.point(v[1]), mesh.point(v[2]), mesh.point(v[3])) == 0;
    any |= flat[t] != 0;
  }
  if (!any) return 0;
  FaceAdjacency adj = computeFaceAdjacency(mesh);
  // Breadth first from the oriented (solid) tetrahedra into the flat ones.
  std::vector<uint32_t> queue;
  for (size_t t = 0; t < n; ++t)
    if (!flat[t]) queue.push_back(static_cast<uint32_t>(t));
  size_t swapped = 0;
  for (size_t head = 0; head < queue.size(); ++head) {
    const uint32_t t = queue[head];
    for (int k = 0; k < 4; ++k) {
      const uint32_t f = adj.neighbor[4 * static_cast<size_t>(t) + k];
      if (f == kNoNeighbor || f == kNonManifold || !flat[f]) continue;
      int j = 0;
      while (j < 4 && adj.neighbor[4 * static_cast<size_t>(f) + j] != t) ++j;
      if (j == 4) continue;
      flat[f] = 0;  // oriented from here on
      if (!facesOpposite(mesh.tets[t], k, mesh.tets[f])) {
        // Swapping corners 2 and 3 reverses every face and exchanges local faces 2 and 3.
        std::swap(mesh.tets[f][2], mesh.tets[f][3]);
        std::swap(adj.neighbor[4 * static_cast<size_t>(f) + 2], adj.neighbor[4 * static_cast<size_t>(f) + 3]);
        ++swapped;
      }
      queue.push_back(f);
    }
  }
  return swapped;
}

}  // namespace gtn
