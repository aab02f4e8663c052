#include "validate/merge_checks.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <CGAL/Exact_rational.h>

#include "mesh/faces.h"
#include "mesh/predicates.h"
#include "validate/mesh_checks.h"

namespace gtn {

namespace {

const char* const kScope = "/merge_tree";

std::string vertexPath(uint32_t v) { return std::string(kScope) + "/vertices/" + std::to_string(v); }

// Sign of dot((b-a) x (c-a), (e-d) x (f-d)), exact: a floating-point filter, then rationals when the
// result is too close to zero to trust.
int normalDotSign(const double* a, const double* b, const double* c, const double* d, const double* e,
                  const double* f) {
  auto cross = [](const double* p, const double* q, const double* r, double n[3], double* mag) {
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    *mag =
        (std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2])) * (std::fabs(v[0]) + std::fabs(v[1]) + std::fabs(v[2]));
  };
  double n1[3], n2[3], m1, m2;
  cross(a, b, c, n1, &m1);
  cross(d, e, f, n2, &m2);
  const double dot = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2];
  const double bound = 1e-12 * m1 * m2;
  if (dot > bound) return 1;
  if (dot < -bound) return -1;
  using Q = CGAL::Exact_rational;
  auto exactCross = [](const double* p, const double* q, const double* r, Q n[3]) {
    const Q u[3] = {Q(q[0]) - Q(p[0]), Q(q[1]) - Q(p[1]), Q(q[2]) - Q(p[2])};
    const Q v[3] = {Q(r[0]) - Q(p[0]), Q(r[1]) - Q(p[1]), Q(r[2]) - Q(p[2])};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
  };
  Q e1[3], e2[3];
  exactCross(a, b, c, e1);
  exactCross(d, e, f, e2);
  const Q exact = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
  return exact > 0 ? 1 : (exact < 0 ? -1 : 0);
}

bool contains(const Tet& t, uint32_t v) { return t[0] == v || t[1] == v || t[2] == v || t[3] == v; }
bool contains(const Triangle& t, uint32_t v) { return t[0] == v || t[1] == v || t[2] == v; }

// Checks the forest's shape and ranks; fills order[r - 1] = the vertex merged r-th.
bool checkForest(const MergeForest& forest, size_t np, ValidationReport& report, std::vector<uint32_t>* order,
                 MergeReplayStats& st) {
  if (forest.parent.size() != np || forest.rank.size() != np) {
    report.add(IssueCode::kMergeTreeSize, kScope, kScope,
               "the merge tree has " + std::to_string(forest.parent.size()) + " parents and " +
                   std::to_string(forest.rank.size()) + " ranks for " + std::to_string(np) + " points");
    return false;
  }
  bool ok = true;
  uint64_t m = 0;
  for (size_t v = 0; v < np; ++v) {
    const uint32_t p = forest.parent[v];
    if (p == kMergeRoot) continue;
    ++m;
    if (p >= np || p == v) {
      report.add(IssueCode::kMergeTreeNotForest, kScope, vertexPath(static_cast<uint32_t>(v)),
                 "vertex " + std::to_string(v) + " has parent " + std::to_string(p));
      ok = false;
    }
  }
  st.merges = m;
  st.roots = np - m;
  if (!ok) return false;
  // Cycles: walk each vertex's parent chain, marking vertices in progress.
  std::vector<uint8_t> state(np, 0);  // 0 new, 1 on the current walk, 2 reaches a root
  std::vector<uint32_t> depth(np, 0), walk;
  for (size_t start = 0; start < np; ++start) {
    if (state[start]) continue;
    walk.clear();
    uint32_t v = static_cast<uint32_t>(start);
    bool cycle = false;
    while (true) {
      if (state[v] == 2) break;
      if (state[v] == 1) {
        cycle = true;
        break;
      }
      state[v] = 1;
      walk.push_back(v);
      if (forest.parent[v] == kMergeRoot) break;
      v = forest.parent[v];
    }
    if (cycle) {
      report.add(IssueCode::kMergeTreeNotForest, kScope, vertexPath(v),
                 "vertex " + std::to_string(v) + " is its own ancestor (the parents form a cycle)");
      ok = false;
      for (uint32_t w : walk) state[w] = 2;
      continue;
    }
    for (size_t i = walk.size(); i-- > 0;) {
      const uint32_t w = walk[i];
      depth[w] = forest.parent[w] == kMergeRoot ? 0 : depth[forest.parent[w]] + 1;
      state[w] = 2;
      st.max_depth = std::max<uint64_t>(st.max_depth, depth[w]);
    }
  }
  if (!ok) return false;
  order->assign(m, kMergeRoot);
  for (size_t v = 0; v < np; ++v) {
    const uint64_t r = forest.rank[v];
    if (forest.parent[v] == kMergeRoot) {
      if (r != 0) {
        report.add(IssueCode::kMergeRanksNotPermutation, kScope, vertexPath(static_cast<uint32_t>(v)),
                   "root vertex " + std::to_string(v) + " has rank " + std::to_string(r) + " (roots have none)");
        ok = false;
      }
      continue;
    }
    if (r < 1 || r > m) {
      report.add(
          IssueCode::kMergeRanksNotPermutation, kScope, vertexPath(static_cast<uint32_t>(v)),
          "vertex " + std::to_string(v) + " has rank " + std::to_string(r) + ", outside 1.." + std::to_string(m));
      ok = false;
    } else if ((*order)[r - 1] != kMergeRoot) {
      report.add(IssueCode::kMergeRanksNotPermutation, kScope, vertexPath(static_cast<uint32_t>(v)),
                 "vertices " + std::to_string((*order)[r - 1]) + " and " + std::to_string(v) + " share rank " +
                     std::to_string(r));
      ok = false;
    } else {
      (*order)[r - 1] = static_cast<uint32_t>(v);
    }
  }
  return ok;
}

class Replay {
 public:
  Replay(const TetMesh& mesh, const MergeForest& forest, ValidationReport& report, MergeReplayStats& st)
      : mesh_(mesh), forest_(forest), report_(report), st_(st), np_(mesh.numPoints()) {
    const std::vector<Tet>& tets = mesh.tets;
    alive_.assign(tets.size(), 1);
    flat_.assign(tets.size(), 0);
    geometry_ok_ = true;
    for (size_t p = 0; p < np_ && geometry_ok_; ++p) {
      const double* x = mesh.point(p);
      geometry_ok_ = std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
    }
    // Each vertex's list made to its size at once (grown by appends, it held about a third more).
    {
      std::vector<uint32_t> count(np_, 0);
      for (const Tet& q : tets)
        for (uint32_t v : q) ++count[v];
      inc_.resize(np_);
      for (size_t v = 0; v < np_; ++v) inc_[v].reserve(count[v]);
    }
    for (size_t t = 0; t < tets.size(); ++t) {
      for (uint32_t v : tets[t]) inc_[v].push_back(static_cast<uint32_t>(t));
      if (geometry_ok_) flat_[t] = orientation(tets[t]) <= 0;
    }
    // The boundary from the faces' classes (2 bytes a tetrahedron; the adjacency's 16 beside the lists
    // were the peak of a large file's check).
    btris_ = boundaryTriangles(mesh, classifyFaces(mesh));
    balive_.assign(btris_.size(), 1);
    binc_.resize(np_);
    is_boundary_.assign(np_, 0);
    for (size_t b = 0; b < btris_.size(); ++b) {
      for (uint32_t v : btris_[b]) {
        binc_[v].push_back(static_cast<uint32_t>(b));
        is_boundary_[v] = 1;
      }
    }
    rep_.resize(np_);
    for (size_t v = 0; v < np_; ++v) rep_[v] = static_cast<uint32_t>(v);
  }

  uint32_t find(uint32_t v) {
    uint32_t r = v;
    while (rep_[r] != r) r = rep_[r];
    while (rep_[v] != r) {
      const uint32_t next = rep_[v];
      rep_[v] = r;
      v = next;
    }
    return r;
  }

  // Tetrahedron x of level 0 as the merges so far have made it: its vertices' representatives (level
  // 0's tetrahedra are read through the merges, not copied: 16 bytes a tetrahedron of a large file).
  Tet tet(size_t x) {
    const Tet& m = mesh_.tets[x];
    return {find(m[0]), find(m[1]), find(m[2]), find(m[3])};
  }

  void apply(uint64_t rank, uint32_t c, uint32_t target_parent) {
    const uint32_t t = find(target_parent);
    const std::string what =
        "merge " + std::to_string(rank) + " (vertex " + std::to_string(c) + " into " + std::to_string(t) + ")";
    // Tetrahedra around c: those with t collapse, the others move to t.
    std::vector<uint32_t>& list = inc_[c];
    list.erase(std::remove_if(list.begin(), list.end(), [&](uint32_t x) { return !alive_[x]; }), list.end());
    moved_.clear();
    bool adjacent = false;
    uint64_t removed = 0;
    for (uint32_t x : list) {
      if (contains(tet(x), t)) {
        adjacent = true;
        ++removed;
        alive_[x] = 0;
      } else {
        moved_.push_back(x);
      }
    }
    // A merge across no edge is reported once; its other effects follow from it and are not. A vertex
    // no tetrahedron uses (the mid-edge point of a quadratic cell) may merge into any vertex: that
    // changes nothing but the vertex count.
    const bool free = list.empty();
    const bool check = adjacent || free;
    if (!adjacent && !free)
      report_.add(IssueCode::kMergeNotAdjacent, kScope, vertexPath(c), what + ": no edge joins them");
    if (check && c < forest_.removed.size() && forest_.removed[c] != removed) {
      report_.add(IssueCode::kMergeAnnotationMismatch, kScope, vertexPath(c),
                  what + " removes " + std::to_string(removed) + " tetrahedra; the tree says " +
                      std::to_string(forest_.removed[c]));
    }
    if (check && c < forest_.boundary.size() && (forest_.boundary[c] != 0) != (is_boundary_[c] != 0)) {
      report_.add(IssueCode::kMergeAnnotationMismatch, kScope, vertexPath(c),
                  what + ": the tree's boundary flag is " + std::to_string(forest_.boundary[c]) + ", the vertex is " +
                      (is_boundary_[c] ? "on the boundary" : "interior"));
    }
    if (is_boundary_[c]) ++st_.boundary_merges;
    if (check && is_boundary_[c]) {
      bool boundary_edge = false;
      for (uint32_t b : binc_[c]) boundary_edge |= balive_[b] && contains(btris_[b], t);
      if (!is_boundary_[t] || !boundary_edge) {
        report_.add(IssueCode::kMergeBoundaryIntoInterior, kScope, vertexPath(c),
                    what + (is_boundary_[t] ? ": not along a boundary edge" : ": the target is interior"));
      }
    }
    // From here on c stands for t in every tetrahedron.
    rep_[c] = t;
    for (uint32_t x : moved_) {
      const Tet tet = this->tet(x);
      inc_[t].push_back(x);
      if (!geometry_ok_ || !check) {
        if (geometry_ok_) flat_[x] = orientation(tet) <= 0;
        continue;
      }
      ++st_.tets_checked;
      const int s = orientation(tet);
      if (s < 0) {
        report_.add(IssueCode::kMergeInvertsTet, kScope, vertexPath(c),
                    what + " inverts tetrahedron " + std::to_string(x) + " of level 0");
      } else if (s == 0 && !flat_[x]) {
        report_.add(IssueCode::kMergeFlattensTet, kScope, vertexPath(c),
                    what + " flattens tetrahedron " + std::to_string(x) + " of level 0");
      }
      flat_[x] = s <= 0;
    }
    if (check && !moved_.empty()) checkManifoldAround(t, c, what);
    // Boundary triangles around c.
    if (is_boundary_[c]) {
      uint64_t boundary_removed = 0;
      for (uint32_t b : binc_[c]) {
        if (!balive_[b]) continue;
        Triangle& tri = btris_[b];
        if (contains(tri, t)) {
          balive_[b] = 0;
          ++boundary_removed;
          continue;
        }
        Triangle before = tri;
        for (uint32_t& v : tri) {
          if (v == c) v = t;
        }
        binc_[t].push_back(b);
        if (check && geometry_ok_ &&
            normalDotSign(mesh_.point(before[0]), mesh_.point(before[1]), mesh_.point(before[2]), mesh_.point(tri[0]),
                          mesh_.point(tri[1]), mesh_.point(tri[2])) < 0) {
          report_.add(IssueCode::kMergeFlipsBoundary, kScope, vertexPath(c),
                      what + " flips boundary triangle " + std::to_string(b));
        }
      }
      binc_[c].clear();
      // Readers know only the boundary flag: the stream simplifier takes a boundary merge to remove
      // exactly the two boundary triangles of a manifold boundary edge. One across an edge in more
      // (a non-manifold boundary) makes every simplification past it disagree with its header. (None
      // removed: not along a boundary edge, reported above.)
      if (check && is_boundary_[t] && boundary_removed != 0 && boundary_removed != 2) {
        report_.add(
            IssueCode::kMergeAnnotationMismatch, kScope, vertexPath(c),
            what + " removes " + std::to_string(boundary_removed) + " boundary triangles; a boundary merge removes 2");
      }
    }
    list.clear();
    list.shrink_to_fit();
    rep_[c] = t;
  }

  // Compares the current state with a stored level.
  void compare(const StoredLevel& level, const std::vector<uint64_t>& keys0) {
    const std::string scope = "/levels/" + std::to_string(level.level);
    std::vector<uint64_t> replay_points;
    for (size_t v = 0; v < np_; ++v) {
      if (rep_[v] == v) replay_points.push_back(keys0[v]);
    }
    std::vector<std::array<uint64_t, 2>> replay_tets;
    std::vector<uint8_t> cells;
    for (size_t x = 0; x < alive_.size(); ++x) {
      if (!alive_[x]) continue;
      const Tet q = tet(x);
      const uint64_t vk[4] = {keys0[q[0]], keys0[q[1]], keys0[q[2]], keys0[q[3]]};
      cellBytes(mesh_, x, cells);
      replay_tets.push_back(tetKey(vk, !geometry_ok_ || flat_[x], cells.data(), cells.size()));
    }
    std::sort(replay_points.begin(), replay_points.end());
    std::sort(replay_tets.begin(), replay_tets.end());
    std::vector<uint64_t> level_points = pointKeys(*level.mesh);
    std::sort(level_points.begin(), level_points.end());
    const std::vector<std::array<uint64_t, 2>> level_tets = sortedTetKeys(*level.mesh, pointKeys(*level.mesh));
    const auto [extra_p, missing_p] = multisetDifference(level_points, replay_points);
    const auto [extra_t, missing_t] = multisetDifference(level_tets, replay_tets);
    if (extra_p || missing_p || extra_t || missing_t) {
      report_.add(IssueCode::kLevelMismatch, scope, scope,
                  "level " + std::to_string(level.level) + " (" + std::to_string(level.mesh->numPoints()) +
                      " points, " + std::to_string(level.mesh->numTets()) + " tetrahedra) differs from level 0 after " +
                      std::to_string(level.merges) + " merges (" + std::to_string(replay_points.size()) + " points, " +
                      std::to_string(replay_tets.size()) + " tetrahedra): " + std::to_string(extra_t) +
                      " tetrahedra and " + std::to_string(extra_p) + " points not in the replay, " +
                      std::to_string(missing_t) + " tetrahedra and " + std::to_string(missing_p) + " points missing");
    }
  }

 private:
  int orientation(const Tet& t) const {
    return orient3d(mesh_.point(t[0]), mesh_.point(t[1]), mesh_.point(t[2]), mesh_.point(t[3]));
  }

  // After c moved into t: every face through t of a moved tetrahedron must lie in at most two live
  // tetrahedra.
  void checkManifoldAround(uint32_t t, uint32_t c, const std::string& what) {
    std::unordered_map<uint64_t, uint32_t> count;  // face (two other vertices) -> live tetrahedra
    auto faceKey = [](uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a); };
    for (uint32_t x : moved_) {
      const Tet tet = this->tet(x);
      uint32_t others[3], n = 0;
      for (uint32_t v : tet) {
        if (v != t) others[n++] = v;
      }
      for (int i = 0; i < 3; ++i) count.emplace(faceKey(others[i], others[(i + 1) % 3]), 0);
    }
    std::vector<uint32_t>& list = inc_[t];
    list.erase(std::remove_if(list.begin(), list.end(), [&](uint32_t x) { return !alive_[x]; }), list.end());
    for (uint32_t x : list) {
      const Tet tet = this->tet(x);
      uint32_t others[3], n = 0;
      for (uint32_t v : tet) {
        if (v != t && n < 3) others[n++] = v;
      }
      if (n != 3) continue;
      for (int i = 0; i < 3; ++i) {
        auto it = count.find(faceKey(others[i], others[(i + 1) % 3]));
        if (it != count.end()) ++it->second;
      }
    }
    for (const auto& [key, n] : count) {
      if (n > 2) {
        report_.add(IssueCode::kMergeBreaksManifold, kScope, vertexPath(c),
                    what + " leaves face (" + std::to_string(t) + ", " + std::to_string(key >> 32) + ", " +
                        std::to_string(key & 0xFFFFFFFFu) + ") in " + std::to_string(n) + " tetrahedra");
        break;
      }
    }
  }

  const TetMesh& mesh_;
  const MergeForest& forest_;
  ValidationReport& report_;
  MergeReplayStats& st_;
  size_t np_;
  bool geometry_ok_ = true;
  std::vector<uint8_t> alive_, flat_;
  std::vector<std::vector<uint32_t>> inc_;
  std::vector<Triangle> btris_;
  std::vector<uint8_t> balive_, is_boundary_;
  std::vector<std::vector<uint32_t>> binc_;
  std::vector<uint32_t> rep_, moved_;
};

}  // namespace

MergeForest forestFromTree(const MergeTree& tree) {
  MergeForest f;
  f.parent = tree.parent;
  f.rank.assign(tree.rank.begin(), tree.rank.end());
  f.boundary = tree.boundary;
  f.removed = tree.removed;
  return f;
}

void checkMergeTree(const TetMesh& level0, const MergeForest& forest, const std::vector<StoredLevel>& levels,
                    ValidationReport& report, MergeReplayStats* stats) {
  MergeReplayStats local;
  MergeReplayStats& st = stats ? *stats : local;
  const size_t np = level0.numPoints();
  std::vector<uint32_t> order;
  if (!checkForest(forest, np, report, &order, st)) return;
  const uint64_t m = order.size();
  // The leading merges of points no tetrahedron of level 0 uses.
  uint64_t free = 0;
  {
    std::vector<uint8_t> used(np, 0);
    for (const Tet& t : level0.tets)
      for (uint32_t v : t)
        if (v < np) used[v] = 1;
    while (free < m && !used[order[free]]) ++free;
  }

  std::vector<StoredLevel> sorted;
  for (const StoredLevel& level : levels) {
    const std::string scope = "/levels/" + std::to_string(level.level);
    if (level.merges > m) {
      report.add(IssueCode::kLevelMergesOutOfRange, scope, scope,
                 "level " + std::to_string(level.level) + " declares " + std::to_string(level.merges) +
                     " merges; the merge tree holds " + std::to_string(m));
      continue;
    }
    // The ratio counts the vertices tetrahedra use: the first `free` merges, of points no tetrahedron
    // of level 0 uses, are left out of both sides (spec section 7.1).
    const double counted = static_cast<double>(np - free), merged = static_cast<double>(level.merges) - free;
    if (level.ratio >= 0 && np > free && level.merges >= free &&
        !(std::fabs(level.ratio * counted - merged) <= 1.0 + 1e-9 * counted)) {
      report.add(IssueCode::kLevelRatioMismatch, scope, scope,
                 "level " + std::to_string(level.level) + " declares ratio " + std::to_string(level.ratio) + " but " +
                     std::to_string(level.merges - free) + " merges of " + std::to_string(np - free) +
                     " referenced points is " + std::to_string(merged / counted));
    }
    if (level.mesh) sorted.push_back(level);
  }
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const StoredLevel& a, const StoredLevel& b) { return a.merges < b.merges; });

  Replay replay(level0, forest, report, st);
  const std::vector<uint64_t> keys0 = sorted.empty() ? std::vector<uint64_t>() : pointKeys(level0);
  size_t next = 0;
  for (uint64_t r = 0;; ++r) {
    while (next < sorted.size() && sorted[next].merges == r) replay.compare(sorted[next++], keys0);
    if (r == m) break;
    const uint32_t c = order[r];
    replay.apply(r + 1, c, forest.parent[c]);
  }
}

}  // namespace gtn
