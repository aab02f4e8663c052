#include "validate/mesh_checks.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <xxhash.h>

#include "mesh/predicates.h"

namespace gtn {

namespace {

std::string tetPath(const std::string& scope, size_t t) { return scope + "/tets/" + std::to_string(t); }
std::string pointPath(const std::string& scope, size_t p) { return scope + "/points/" + std::to_string(p); }

bool allFinite(const double* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

bool itemHasNonFinite(const Field& f, size_t item) {
  const size_t base = item * f.components;
  for (uint32_t c = 0; c < f.components; ++c) {
    if (f.type == ScalarType::kFloat32) {
      float v;
      std::memcpy(&v, f.bytes.data() + 4 * (base + c), 4);
      if (!std::isfinite(v)) return true;
    } else {
      double v;
      std::memcpy(&v, f.bytes.data() + 8 * (base + c), 8);
      if (!std::isfinite(v)) return true;
    }
  }
  return false;
}

bool checkFieldSizes(const std::vector<Field>& fields, size_t items, const std::string& scope, const char* kind,
                     ValidationReport& report) {
  bool ok = true;
  for (size_t i = 0; i < fields.size(); ++i) {
    const Field& f = fields[i];
    const size_t item_bytes = static_cast<size_t>(f.components) * f.valueSize();
    if (item_bytes == 0 || f.bytes.size() != items * item_bytes) {
      report.add(IssueCode::kFieldSizeMismatch, scope, scope + "/" + kind + "/" + std::to_string(i),
                 std::string(kind) + " field '" + f.name + "' holds " + std::to_string(f.bytes.size()) +
                     " bytes, expected " + std::to_string(items) + " items of " + std::to_string(item_bytes));
      ok = false;
    }
  }
  return ok;
}

// Rotates a triangle so that its smallest vertex comes first (orientation kept).
Triangle canonicalTriangle(Triangle t) {
  while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  return t;
}

// One use of an undirected boundary edge by a boundary triangle: forward when the triangle runs from
// the smaller vertex to the larger; exempt when orientation cannot be checked there (flat tetrahedra).
struct DirEdge {
  uint64_t key;
  bool forward;
  bool exempt;
  bool operator<(const DirEdge& o) const { return key != o.key ? key < o.key : forward < o.forward; }
};

void addTriangleEdges(const Triangle& tri, bool exempt, std::vector<DirEdge>& out) {
  for (int e = 0; e < 3; ++e) {
    const uint32_t a = tri[e], b = tri[(e + 1) % 3];
    const uint64_t lo = std::min(a, b), hi = std::max(a, b);
    out.push_back({(lo << 32) | hi, a < b, exempt});
  }
}

// A closed surface uses each edge an even number of times: twice where it is a manifold, four or more
// times where two parts of the volume touch along an edge (real meshes have such edges, Ossicles.vtu
// does). It is consistently oriented when each edge is used as often in one direction as in the other.
// Returns false when some edge is in an odd number of triangles (BOUNDARY_NOT_CLOSED).
bool checkBoundaryEdges(std::vector<DirEdge>& dir_edges, const std::string& scope, bool check_orientation,
                        ValidationReport& report) {
  std::sort(dir_edges.begin(), dir_edges.end());
  uint64_t boundary_edges = 0;
  bool closed = true;
  for (size_t i = 0; i < dir_edges.size();) {
    size_t j = i + 1;
    size_t forward = dir_edges[i].forward, exempt = dir_edges[i].exempt;
    while (j < dir_edges.size() && dir_edges[j].key == dir_edges[i].key) {
      forward += dir_edges[j].forward;
      exempt += dir_edges[j].exempt;
      ++j;
    }
    ++boundary_edges;
    const std::string edge =
        std::to_string(dir_edges[i].key >> 32) + "-" + std::to_string(dir_edges[i].key & 0xFFFFFFFFu);
    const std::string path = scope + "/boundary/edges/" + edge;
    if ((j - i) % 2 != 0) {
      closed = false;
      report.add(IssueCode::kBoundaryNotClosed, scope, path,
                 "boundary edge " + edge + " is in " + std::to_string(j - i) + " boundary triangles");
    } else if (check_orientation && exempt == 0 && 2 * forward != j - i) {
      report.add(IssueCode::kBoundaryOrientation, scope, path);
    }
    i = j;
  }
  report.setTotal(IssueCode::kBoundaryNotClosed, scope, boundary_edges);
  report.setTotal(IssueCode::kBoundaryOrientation, scope, boundary_edges);
  return closed;
}

// A boundary triangle as a tetrahedron's face: its outward corners and where it is.
struct BoundaryFace {
  Triangle tri;
  uint32_t tet;
  uint8_t face;
};

// Boundary triangles in more than this many are not examined as diagonals of a non-conforming
// quadrilateral (the pairs on one edge grow as the square of their number).
constexpr size_t kMaxEdgeTriangles = 16;

// A non-conforming interface: four coplanar points (a, b, c, d) of a convex quadrilateral whose two
// triangles along the diagonal a-c are boundary faces facing one way and whose two along b-d are
// boundary faces facing the other way. Two parts of the volume then meet there with shared points
// but no shared face: what welding two blocks that cut their common face along different diagonals
// leaves inside the volume. (Four points that are not coplanar would bound a tetrahedral cavity,
// which a valid mesh may have.) Each pair of triangles on one boundary edge, facing the same way, is
// a candidate: its other diagonal's two triangles are looked up by vertex set, so the cost is linear
// in the boundary. Signs are exact (orient3d, orient2dProjected). Returns the triangles found.
uint64_t checkInterfaces(const TetMesh& mesh, const std::vector<BoundaryFace>& faces,
                         const std::vector<uint8_t>& finite, const std::string& scope, ValidationReport& report) {
  auto sorted3 = [](Triangle t) {
    std::sort(t.begin(), t.end());
    return t;
  };
  std::vector<std::pair<Triangle, uint32_t>> by_set(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) by_set[f] = {sorted3(faces[f].tri), static_cast<uint32_t>(f)};
  std::sort(by_set.begin(), by_set.end());
  auto lookup = [&](uint32_t x, uint32_t y, uint32_t z) -> int64_t {
    const Triangle key = sorted3({x, y, z});
    auto it = std::lower_bound(by_set.begin(), by_set.end(), std::make_pair(key, uint32_t{0}));
    return it == by_set.end() || it->first != key ? -1 : int64_t{it->second};
  };
  std::vector<std::pair<uint64_t, uint32_t>> edges;
  edges.reserve(3 * faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int e = 0; e < 3; ++e) {
      const uint64_t a = faces[f].tri[e], b = faces[f].tri[(e + 1) % 3];
      edges.push_back({(std::min(a, b) << 32) | std::max(a, b), static_cast<uint32_t>(f)});
    }
  }
  std::sort(edges.begin(), edges.end());
  // The corner of triangle `t` that is neither x nor y, and whether t runs from x to y.
  auto other = [](const Triangle& t, uint32_t x, uint32_t y) {
    for (int e = 0; e < 3; ++e)
      if (t[e] != x && t[e] != y) return t[e];
    return t[0];
  };
  auto runs = [](const Triangle& t, uint32_t x, uint32_t y) {
    for (int e = 0; e < 3; ++e)
      if (t[e] == x) return t[(e + 1) % 3] == y;
    return false;
  };
  std::vector<uint8_t> flagged(faces.size(), 0);
  uint64_t count = 0;
  std::vector<std::string> paths;
  auto flag = [&](uint32_t f) {
    if (flagged[f]) return;
    flagged[f] = 1;
    ++count;
    if (paths.size() < ValidationReport::kMaxPaths)
      paths.push_back(tetPath(scope, faces[f].tet) + "/faces/" + std::to_string(faces[f].face));
  };
  std::string detail;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    const uint32_t a = static_cast<uint32_t>(edges[i].first >> 32), c = static_cast<uint32_t>(edges[i].first);
    for (size_t p = i; j - i <= kMaxEdgeTriangles && p < j; ++p) {
      for (size_t q = p + 1; q < j; ++q) {
        const uint32_t f1 = edges[p].second, f2 = edges[q].second;
        const Triangle &t1 = faces[f1].tri, &t2 = faces[f2].tri;
        // Facing the same way: they run along a-c in opposite directions.
        if (runs(t1, a, c) == runs(t2, a, c)) continue;
        const uint32_t b = other(t1, a, c), d = other(t2, a, c);
        if (b == d) continue;
        // Each quadrilateral once: from its diagonal with the smaller key.
        if (edges[i].first > ((uint64_t{std::min(b, d)} << 32) | std::max(b, d))) continue;
        const int64_t u1 = lookup(a, b, d), u2 = lookup(c, b, d);
        if (u1 < 0 || u2 < 0) continue;
        if (!finite[a] || !finite[b] || !finite[c] || !finite[d]) continue;
        const double *pa = mesh.point(a), *pb = mesh.point(b), *pc = mesh.point(c), *pd = mesh.point(d);
        if (orient3d(pa, pb, pc, pd) != 0) continue;
        // Projected along the axis the plane faces most (its normal's largest component is not zero
        // unless the triangle is degenerate, which the signs below then show), the two triangles of
        // each diagonal must have one sign, the other diagonal's the opposite: then the quadrilateral
        // is convex and both pairs cover it, facing opposite ways.
        double n[3];
        const double e1[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
        const double e2[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        int drop = 0;
        for (int k = 1; k < 3; ++k)
          if (std::fabs(n[k]) > std::fabs(n[drop])) drop = k;
        auto sign = [&](const Triangle& t) {
          return orient2dProjected(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]), drop);
        };
        const int s1 = sign(t1);
        if (s1 == 0 || sign(t2) != s1 || sign(faces[u1].tri) != -s1 || sign(faces[u2].tri) != -s1) continue;
        if (detail.empty())
          detail = "the quadrilateral " + std::to_string(a) + "-" + std::to_string(b) + "-" + std::to_string(c) + "-" +
                   std::to_string(d) + " is covered by boundary triangles along its diagonal " + std::to_string(a) +
                   "-" + std::to_string(c) + " facing one way and along " + std::to_string(b) + "-" +
                   std::to_string(d) +
                   " facing the other: the parts of the volume on its two sides share its "
                   "points but not its faces";
        flag(f1);
        flag(f2);
        flag(static_cast<uint32_t>(u1));
        flag(static_cast<uint32_t>(u2));
      }
    }
    i = j;
  }
  if (count > 0) report.addMany(IssueCode::kNonconformingInterface, scope, count, paths, detail);
  report.setTotal(IssueCode::kNonconformingInterface, scope, faces.size());
  return count;
}

}  // namespace

bool checkMesh(const TetMesh& mesh, const std::string& scope, ValidationReport& report, MeshCheckStats* stats) {
  MeshCheckStats local;
  MeshCheckStats& st = stats ? *stats : local;
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  st.points = np;
  st.tets = nt;

  bool fields_ok = checkFieldSizes(mesh.point_fields, np, scope, "point_fields", report);
  fields_ok &= checkFieldSizes(mesh.cell_fields, nt, scope, "cell_fields", report);

  // Indices: everything else walks the tetrahedra, so stop here when they are out of range.
  bool indices_ok = true;
  std::vector<uint8_t> bad_tet(nt, 0);
  for (size_t t = 0; t < nt; ++t) {
    const Tet& tet = mesh.tets[t];
    bool in_range = true;
    for (uint32_t v : tet) in_range &= v < np;
    if (!in_range) {
      report.add(IssueCode::kIndexOutOfRange, scope, tetPath(scope, t),
                 "tetrahedron " + std::to_string(t) + " refers to a vertex >= " + std::to_string(np));
      indices_ok = false;
      bad_tet[t] = 1;
      continue;
    }
    if (tet[0] == tet[1] || tet[0] == tet[2] || tet[0] == tet[3] || tet[1] == tet[2] || tet[1] == tet[3] ||
        tet[2] == tet[3]) {
      report.add(IssueCode::kRepeatedVertex, scope, tetPath(scope, t),
                 "tetrahedron " + std::to_string(t) + " uses a vertex twice");
      bad_tet[t] = 1;
    }
  }
  report.setTotal(IssueCode::kIndexOutOfRange, scope, nt);
  report.setTotal(IssueCode::kRepeatedVertex, scope, nt);
  // A tetrahedron with a repeated vertex has no faces or orientation to speak of: stop here too.
  if (!indices_ok || std::find(bad_tet.begin(), bad_tet.end(), 1) != bad_tet.end()) return false;

  // Coordinates and values.
  std::vector<uint8_t> finite(np, 1);
  for (size_t p = 0; p < np; ++p) {
    if (!allFinite(mesh.point(p))) {
      finite[p] = 0;
      report.add(IssueCode::kNonFiniteCoordinate, scope, pointPath(scope, p),
                 "point " + std::to_string(p) + " has a NaN or infinite coordinate");
    }
  }
  report.setTotal(IssueCode::kNonFiniteCoordinate, scope, np);
  if (fields_ok) {
    auto scan = [&](const std::vector<Field>& fields, const char* kind, size_t items) {
      for (size_t i = 0; i < fields.size(); ++i) {
        const Field& f = fields[i];
        if (!isFloatType(f.type)) continue;
        const std::string fscope = scope + "/" + kind + "/" + f.name;
        for (size_t item = 0; item < items; ++item) {
          if (itemHasNonFinite(f, item)) {
            report.add(IssueCode::kNonFiniteValue, fscope, fscope + "/" + std::to_string(item),
                       "field '" + f.name + "' item " + std::to_string(item) + " is NaN or infinite");
          }
        }
        report.setTotal(IssueCode::kNonFiniteValue, fscope, items);
      }
    };
    scan(mesh.point_fields, "point_fields", np);
    scan(mesh.cell_fields, "cell_fields", nt);
  }

  // Unreferenced points.
  std::vector<uint8_t> used(np, 0);
  for (const Tet& tet : mesh.tets) {
    for (uint32_t v : tet) used[v] = 1;
  }
  for (size_t p = 0; p < np; ++p) {
    if (!used[p]) {
      ++st.unreferenced_points;
      report.add(IssueCode::kUnreferencedPoint, scope, pointPath(scope, p));
    }
  }
  report.setTotal(IssueCode::kUnreferencedPoint, scope, np);

  // Orientation by exact predicates (only where all four points are finite: the filtered predicate
  // must not see a NaN).
  std::vector<uint8_t> flat(nt, 0);
  for (size_t t = 0; t < nt; ++t) {
    if (bad_tet[t]) continue;
    const Tet& tet = mesh.tets[t];
    if (!finite[tet[0]] || !finite[tet[1]] || !finite[tet[2]] || !finite[tet[3]]) continue;
    const int s = orient3d(mesh.point(tet[0]), mesh.point(tet[1]), mesh.point(tet[2]), mesh.point(tet[3]));
    if (s < 0) {
      ++st.inverted;
      report.add(IssueCode::kInvertedTet, scope, tetPath(scope, t));
    } else if (s == 0) {
      ++st.zero_volume;
      flat[t] = 1;
      report.add(IssueCode::kZeroVolumeTet, scope, tetPath(scope, t));
    }
  }
  report.setTotal(IssueCode::kInvertedTet, scope, nt);
  report.setTotal(IssueCode::kZeroVolumeTet, scope, nt);

  // Duplicate tetrahedra (same vertex set), reported in the order of their sorted vertices, then of
  // their indices. The tetrahedra are grouped by their smallest vertex (a counting sort, 4 bytes a
  // tetrahedron; equal ones share it) and each group is sorted on its own: a sort of every
  // tetrahedron's sorted vertices and index took 20 bytes a tetrahedron, a large mesh's peak.
  {
    auto minOf = [](const Tet& q) { return std::min(std::min(q[0], q[1]), std::min(q[2], q[3])); };
    std::vector<uint32_t> end(np + 1, 0);  // group v: [end[v - 1], end[v]) once filled (end[-1] = 0)
    for (const Tet& q : mesh.tets) ++end[minOf(q) + 1];
    for (size_t v = 0; v < np; ++v) end[v + 1] += end[v];
    std::vector<uint32_t> by_min(nt);
    for (size_t t = 0; t < nt; ++t) by_min[end[minOf(mesh.tets[t])]++] = static_cast<uint32_t>(t);
    std::vector<std::pair<Tet, uint32_t>> group;
    for (size_t v = 0, begin = 0; v < np; begin = end[v++]) {
      if (end[v] - begin < 2) continue;
      group.clear();
      for (size_t i = begin; i < end[v]; ++i) {
        Tet s = mesh.tets[by_min[i]];
        std::sort(s.begin(), s.end());
        group.emplace_back(s, by_min[i]);
      }
      std::sort(group.begin(), group.end());
      for (size_t i = 1; i < group.size(); ++i) {
        if (group[i].first == group[i - 1].first) {
          report.add(IssueCode::kDuplicateTet, scope, tetPath(scope, group[i].second),
                     "tetrahedron " + std::to_string(group[i].second) + " repeats tetrahedron " +
                         std::to_string(group[i - 1].second));
        }
      }
    }
    report.setTotal(IssueCode::kDuplicateTet, scope, nt);
  }

  // Faces and the boundary surface, from what the checks need of the face adjacency (2 bytes a
  // tetrahedron: the adjacency's 16 were the peak of a large mesh's check).
  const FaceClasses adj = classifyFaces(mesh, st.zero_volume > 0 ? &flat : nullptr);
  auto faceIs = [&](size_t t, int k, uint16_t bit) { return (adj.mask[t] & (bit << k)) != 0; };
  st.faces = adj.faces;
  st.boundary_faces = adj.boundary_faces;
  if (adj.non_manifold_faces > 0) {
    std::vector<std::string> paths;
    for (size_t slot = 0; slot < 4 * nt && paths.size() < ValidationReport::kMaxPaths; ++slot) {
      if (faceIs(slot / 4, static_cast<int>(slot % 4), FaceClasses::kNonManifold))
        paths.push_back(tetPath(scope, slot / 4) + "/faces/" + std::to_string(slot % 4));
    }
    report.addMany(IssueCode::kNonManifoldFace, scope, adj.non_manifold_faces, paths);
  }
  report.setTotal(IssueCode::kNonManifoldFace, scope, adj.faces);

  // The boundary edge checks assume manifold faces (a non-manifold face makes its edges non-manifold
  // too): on a mesh with NON_MANIFOLD_FACE they are skipped, so that each defect has one code.
  if (adj.non_manifold_faces > 0) return true;
  // An inverted tetrahedron turns its faces inside out: the orientation of the boundary edges is
  // then checked only when no tetrahedron is inverted (INVERTED_TET says it all).
  const bool check_orientation = st.inverted == 0;
  // A zero-volume tetrahedron has no orientation to normalise, so the faces around one may disagree
  // with their neighbours: edges of boundary triangles of a flat tetrahedron or of a face-neighbour of
  // one are not checked for orientation (ZERO_VOLUME_TET already reports the cause).
  auto nearFlat = [&](size_t t) { return flat[t] || (adj.mask[t] & FaceClasses::kNextToFlat) != 0; };
  std::vector<DirEdge> dir_edges;
  dir_edges.reserve(3 * adj.boundary_faces);
  std::vector<BoundaryFace> boundary;
  boundary.reserve(adj.boundary_faces);
  for (size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      if (!faceIs(t, k, FaceClasses::kBoundary)) continue;
      const bool exempt = st.zero_volume > 0 && nearFlat(t);
      const Triangle tri = {mesh.tets[t][kTetFace[k][0]], mesh.tets[t][kTetFace[k][1]], mesh.tets[t][kTetFace[k][2]]};
      addTriangleEdges(tri, exempt, dir_edges);
      // A zero-volume tetrahedron alone covers a quadrilateral from both sides (ZERO_VOLUME_TET).
      if (!flat[t]) boundary.push_back({tri, static_cast<uint32_t>(t), static_cast<uint8_t>(k)});
    }
  }
  checkBoundaryEdges(dir_edges, scope, check_orientation, report);
  checkInterfaces(mesh, boundary, finite, scope, report);
  return true;
}

namespace {
ValidationReport errorsOf(const TetMesh& mesh, const std::string& scope) {
  ValidationReport report(16);
  checkMesh(mesh, scope, report);
  return report;
}
}  // namespace

void LevelStructureCheck::checkLevel0() {
  std::call_once(level0_once_, [&] { level0_report_.emplace(errorsOf(*level0_, "/levels/0")); });
}

std::string LevelStructureCheck::level0Errors() {
  checkLevel0();
  std::string errors;
  for (const ReportedIssue& issue : level0_report_->issues()) {
    const IssueInfo& info = issueInfo(issue.code);
    if (info.severity == Severity::kError)
      errors += std::string(errors.empty() ? "" : "; ") + info.code + ": " + issue.message();
  }
  return errors;
}

Status LevelStructureCheck::check(const TetMesh& level, size_t index) {
  checkLevel0();
  const ValidationReport report = errorsOf(level, "/levels/" + std::to_string(index));
  std::string errors;
  for (const ReportedIssue& issue : report.issues()) {
    const IssueInfo& info = issueInfo(issue.code);
    if (info.severity != Severity::kError || level0_report_->count(issue.code) > 0) continue;
    errors += std::string(errors.empty() ? "" : "; ") + info.code + ": " + issue.message();
  }
  if (errors.empty()) return Status::ok();
  return invalidData(what_ + ": mip level " + std::to_string(index) + " is not a valid mesh (" + errors +
                     "), so the file was not written; this is a bug in gtn's simplifier, please report it "
                     "with the input");
}

Status checkLevelStructure(const std::vector<const TetMesh*>& levels, const std::string& what) {
  if (levels.size() < 2) return Status::ok();
  LevelStructureCheck check(*levels[0], what);
  for (size_t i = 1; i < levels.size(); ++i) GTN_RETURN_IF_ERROR(check.check(*levels[i], i));
  return Status::ok();
}

void checkStoredBoundary(const TetMesh& mesh, const std::vector<Triangle>& stored, const std::string& scope,
                         ValidationReport& report) {
  // Where a face is in three or more tetrahedra the boundary is not defined (NON_MANIFOLD_FACE says
  // why), so the stored one is not checked against it: one code per defect.
  const FaceClasses adj = classifyFaces(mesh);
  if (adj.non_manifold_faces > 0) return;
  // A stored surface with a hole is reported as such rather than as a mismatch (one code per defect).
  std::vector<DirEdge> stored_edges;
  stored_edges.reserve(3 * stored.size());
  for (const Triangle& t : stored) addTriangleEdges(t, false, stored_edges);
  if (!checkBoundaryEdges(stored_edges, scope, false, report)) return;
  std::vector<Triangle> expected = boundaryTriangles(mesh, adj);
  std::vector<Triangle> got = stored;
  for (Triangle& t : expected) t = canonicalTriangle(t);
  for (Triangle& t : got) t = canonicalTriangle(t);
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  const auto [extra, missing] = multisetDifference(got, expected);
  if (extra || missing) {
    report.add(IssueCode::kBoundaryMismatch, scope, scope + "/boundary",
               "the stored boundary surface has " + std::to_string(got.size()) + " triangles, " +
                   std::to_string(extra) + " of them not boundary faces of the tetrahedra; " + std::to_string(missing) +
                   " of the " + std::to_string(expected.size()) + " boundary faces are missing");
  }
}

std::vector<uint64_t> pointKeys(const TetMesh& mesh) {
  const size_t np = mesh.numPoints();
  std::vector<uint64_t> keys(np);
  std::vector<uint8_t> buf;
  for (size_t p = 0; p < np; ++p) {
    buf.assign(reinterpret_cast<const uint8_t*>(mesh.point(p)), reinterpret_cast<const uint8_t*>(mesh.point(p) + 3));
    for (const Field& f : mesh.point_fields) {
      const size_t item = static_cast<size_t>(f.components) * f.valueSize();
      if ((p + 1) * item <= f.bytes.size())
        buf.insert(buf.end(), f.bytes.begin() + p * item, f.bytes.begin() + (p + 1) * item);
    }
    keys[p] = XXH3_64bits(buf.data(), buf.size());
  }
  return keys;
}

std::array<uint64_t, 2> tetKey(const uint64_t vertex_keys[4], bool flat, const uint8_t* cell_bytes, size_t cell_size) {
  uint64_t k[5];
  if (flat) {
    std::copy(vertex_keys, vertex_keys + 4, k);
    std::sort(k, k + 4);
    k[4] = 1;
  } else {
    // Bring the smallest key first with an even permutation, then rotate the other three (a cyclic
    // rotation of three is even too).
    static const int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
    const int m = static_cast<int>(std::min_element(vertex_keys, vertex_keys + 4) - vertex_keys);
    for (int i = 0; i < 4; ++i) k[i] = vertex_keys[kEven[m][i]];
    while (k[1] > k[2] || k[1] > k[3]) {
      const uint64_t t = k[1];
      k[1] = k[2];
      k[2] = k[3];
      k[3] = t;
    }
    k[4] = 0;
  }
  const uint64_t seed = cell_size ? XXH3_64bits(cell_bytes, cell_size) : 0;
  const XXH128_hash_t h = XXH3_128bits_withSeed(k, sizeof(k), seed);
  return {h.high64, h.low64};
}

void cellBytes(const TetMesh& mesh, size_t t, std::vector<uint8_t>& out) {
  out.clear();
  for (const Field& f : mesh.cell_fields) {
    const size_t item = static_cast<size_t>(f.components) * f.valueSize();
    if ((t + 1) * item <= f.bytes.size())
      out.insert(out.end(), f.bytes.begin() + t * item, f.bytes.begin() + (t + 1) * item);
  }
}

std::vector<std::array<uint64_t, 2>> sortedTetKeys(const TetMesh& mesh, const std::vector<uint64_t>& point_keys) {
  std::vector<std::array<uint64_t, 2>> keys;
  keys.reserve(mesh.numTets());
  std::vector<uint8_t> cells;
  const size_t np = mesh.numPoints();
  for (size_t t = 0; t < mesh.numTets(); ++t) {
    const Tet& tet = mesh.tets[t];
    if (tet[0] >= np || tet[1] >= np || tet[2] >= np || tet[3] >= np) continue;
    const double *a = mesh.point(tet[0]), *b = mesh.point(tet[1]), *c = mesh.point(tet[2]), *d = mesh.point(tet[3]);
    const bool finite = allFinite(a) && allFinite(b) && allFinite(c) && allFinite(d);
    const bool flat = !finite || orient3d(a, b, c, d) == 0;
    const uint64_t vk[4] = {point_keys[tet[0]], point_keys[tet[1]], point_keys[tet[2]], point_keys[tet[3]]};
    cellBytes(mesh, t, cells);
    keys.push_back(tetKey(vk, flat, cells.data(), cells.size()));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

}  // namespace gtn
