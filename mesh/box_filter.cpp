#include "mesh/box_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mesh/index.h"

namespace gtn {

namespace {
void cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// True when `axis` separates the tetrahedron from the box.
bool separates(const double axis[3], const double* const p[4], const double center[3], const double half[3]) {
  if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0) return false;
  double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
  for (int i = 0; i < 4; ++i) {
    const double t = dot(axis, p[i]);
    tmin = std::min(tmin, t);
    tmax = std::max(tmax, t);
  }
  const double c = dot(axis, center);
  const double r = std::abs(axis[0]) * half[0] + std::abs(axis[1]) * half[1] + std::abs(axis[2]) * half[2];
  return tmax < c - r || tmin > c + r;
}
}  // namespace

bool tetMeetsBox(const double* const p[4], const double lo[3], const double hi[3]) {
  // The box's axes first: the bounding boxes overlap.
  for (int k = 0; k < 3; ++k) {
    double tmin = p[0][k], tmax = p[0][k];
    for (int i = 1; i < 4; ++i) {
      tmin = std::min(tmin, p[i][k]);
      tmax = std::max(tmax, p[i][k]);
    }
    if (tmax < lo[k] || tmin > hi[k]) return false;
  }
  const double center[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
  const double half[3] = {0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1]), 0.5 * (hi[2] - lo[2])};
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  double edge[6][3];
  for (int e = 0; e < 6; ++e)
    for (int k = 0; k < 3; ++k) edge[e][k] = p[kEdges[e][1]][k] - p[kEdges[e][0]][k];
  // Face normals: faces (0,1,2), (0,1,3), (0,2,3) from edges at vertex 0, (1,2,3) from edges at 1.
  static constexpr int kFaceEdges[4][2] = {{0, 1}, {0, 2}, {1, 2}, {3, 4}};
  for (const auto& f : kFaceEdges) {
    double n[3];
    cross(edge[f[0]], edge[f[1]], n);
    if (separates(n, p, center, half)) return false;
  }
  for (int e = 0; e < 6; ++e)
    for (int k = 0; k < 3; ++k) {
      const double axis[3] = {double(k == 0), double(k == 1), double(k == 2)};
      double n[3];
      cross(edge[e], axis, n);
      if (separates(n, p, center, half)) return false;
    }
  return true;
}

TetMesh cropToBox(const TetMesh& mesh, const double lo[3], const double hi[3], std::vector<size_t>* kept_points_out,
                  std::vector<size_t>* kept_tets_out) {
  TetMesh out;
  out.coord_type = mesh.coord_type;
  out.metadata = mesh.metadata;
  std::vector<uint32_t> index(mesh.numPoints(), kNoIndex);
  std::vector<size_t> kept_tets;
  for (size_t t = 0; t < mesh.numTets(); ++t) {
    const Tet& tet = mesh.tets[t];
    const double* p[4] = {mesh.point(tet[0]), mesh.point(tet[1]), mesh.point(tet[2]), mesh.point(tet[3])};
    if (!tetMeetsBox(p, lo, hi)) continue;
    kept_tets.push_back(t);
    for (uint32_t v : tet) index[v] = 0;
  }
  std::vector<size_t> kept_points;
  for (size_t v = 0; v < index.size(); ++v) {
    if (index[v] == kNoIndex) continue;
    index[v] = static_cast<uint32_t>(kept_points.size());
    kept_points.push_back(v);
  }
  out.coords.reserve(3 * kept_points.size());
  for (size_t v : kept_points) out.coords.insert(out.coords.end(), mesh.point(v), mesh.point(v) + 3);
  out.tets.reserve(kept_tets.size());
  for (size_t t : kept_tets) {
    const Tet& tet = mesh.tets[t];
    out.tets.push_back({index[tet[0]], index[tet[1]], index[tet[2]], index[tet[3]]});
  }
  auto keep = [](const std::vector<Field>& fields, const std::vector<size_t>& items, std::vector<Field>& dst) {
    for (const Field& f : fields) {
      Field g(f.name, f.components, f.type, items.size());
      for (size_t i = 0; i < items.size(); ++i) g.copyItem(f, items[i], i);
      dst.push_back(std::move(g));
    }
  };
  keep(mesh.point_fields, kept_points, out.point_fields);
  keep(mesh.cell_fields, kept_tets, out.cell_fields);
  if (kept_points_out) *kept_points_out = std::move(kept_points);
  if (kept_tets_out) *kept_tets_out = std::move(kept_tets);
  return out;
}

}  // namespace gtn
