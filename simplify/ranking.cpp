#include "simplify/ranking.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <queue>

#include "mesh/faces.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {

constexpr uint32_t kNil = 0xFFFFFFFFu;
constexpr uint32_t kDead = 0xFFFFFFFFu;   // tets_[t][0] of a collapsed tetrahedron
constexpr uint32_t kOmega = 0xFFFFFFFEu;  // the virtual vertex coning the boundary
constexpr double kFlipMargin = 1e-3;
constexpr double kLocalWeight = 1.0 / 16;  // see ranking.h
// A vertex in more tetrahedra than this is neither merged nor merged onto (while its star is that
// large): evaluating a vertex costs its star times its targets, and it is evaluated again after every
// merge next to it, so a star of S tetrahedra costs about S^3 (a book of 1000 tetrahedra around one
// edge ran for minutes). Real meshes stay far below: the largest star of the shared datasets is 110.
constexpr uint32_t kMaxStar = 256;

inline void cross(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
inline double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const double* a) { return std::sqrt(dot(a, a)); }
// Normal (b - a) x (c - a).
inline void triNormal(const double* a, const double* b, const double* c, double* n) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  cross(u, w, n);
}

// A tetrahedron of the star of the vertex being evaluated, reduced to what the candidate errors need:
// its volume is linear in the position of that vertex.
struct StarTet {
  uint32_t corner;  // 4 * tet + local index of the vertex
  uint32_t o[3];    // the other three vertices
  double n[3];      // inward normal of the opposite face: volume(p) = (n . p - d) / 6
  double d;
  double other_density;  // density sum of the other three vertices
  double mass;           // current mass
};

struct BoundaryFace {
  uint32_t x, y;  // the face is (v, x, y), outward
  double n[3];
  double area;
};

struct Candidate {
  double error;
  uint32_t w;
};

struct QueueEntry {
  float error;
  uint32_t v, w, version;
  bool operator>(const QueueEntry& o) const {
    if (error != o.error) return error > o.error;
    if (v != o.v) return v > o.v;
    return w > o.w;
  }
};

using Tri = std::array<uint32_t, 3>;
using Edge = std::array<uint32_t, 2>;

template <class T>
size_t countCommon(const std::vector<T>& a, const std::vector<T>& b) {
  size_t i = 0, j = 0, n = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] < b[j]) {
      ++i;
    } else if (b[j] < a[i]) {
      ++j;
    } else {
      ++n;
      ++i;
      ++j;
    }
  }
  return n;
}

template <class T>
void sortUnique(std::vector<T>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

class Ranker {
 public:
  Ranker(const TetMesh& mesh, std::vector<double> density, const RankingOptions& options)
      : mesh_(mesh), density_(std::move(density)), options_(options) {}

  MergeTree run(RankingStats* stats);

 private:
  const double* pos(uint32_t v) const { return mesh_.coords.data() + 3 * size_t{v}; }
  bool samePosition(uint32_t a, uint32_t b) const {
    const double* p = pos(a);
    const double* q = pos(b);
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
  }
  void init();
  void gatherStar(uint32_t v, std::vector<uint32_t>& corners);
  void gatherBoundaryFaces(uint32_t v, const std::vector<uint32_t>& corners, std::vector<BoundaryFace>& faces);
  void candidates(uint32_t v, std::vector<Candidate>& out);
  bool validate(uint32_t v, uint32_t w);
  void linkOf(uint32_t u, const std::vector<uint32_t>& corners, const std::vector<BoundaryFace>& faces,
              std::vector<Tri>& tris, std::vector<Edge>& edges, std::vector<uint32_t>& verts);
  void merge(uint32_t v, uint32_t w, float error);
  void recompute(uint32_t v);
  void push(uint32_t v, const Candidate& c) {
    heap_.push(QueueEntry{static_cast<float>(c.error), v, c.w, version_[v]});
  }

  const TetMesh& mesh_;
  std::vector<double> density_;
  RankingOptions options_;
  double mass_scale_ = 1, area_scale_ = 1;

  std::vector<Tet> tets_;
  std::vector<uint32_t> next_;  // per corner: next corner of the same vertex
  std::vector<uint32_t> head_;  // per vertex: first corner
  std::vector<uint8_t> boundary_, frozen_, alive_;
  std::vector<uint32_t> star_size_;  // live tetrahedra around each vertex (kMaxStar)
  bool crowded(uint32_t v) const { return star_size_[v] > kMaxStar; }
  std::vector<uint32_t> version_;
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, std::greater<QueueEntry>> heap_;
  MergeTree tree_;
  uint64_t evaluations_ = 0;

  // Deduplicates small vertex lists without sorting: mark_[x] == stamp_ means x is already listed.
  void uniqueByMark(std::vector<uint32_t>& list) {
    if (++stamp_ == 0) {
      std::fill(mark_.begin(), mark_.end(), 0);
      stamp_ = 1;
    }
    size_t n = 0;
    for (uint32_t x : list) {
      if (mark_[x] == stamp_) continue;
      mark_[x] = stamp_;
      list[n++] = x;
    }
    list.resize(n);
  }
  std::vector<uint32_t> mark_;
  uint32_t stamp_ = 0;

  // Scratch buffers reused across calls.
  std::vector<uint32_t> corners_, corners_w_, targets_, recompute_;
  std::vector<StarTet> star_;
  std::vector<BoundaryFace> faces_, faces_w_;
  std::vector<Candidate> cands_;
  // A face (v, x, y) of the star of v: key (min(x, y) << 32 | max(x, y)), then its tetrahedron and
  // local face. Every face holds v, so ordering by the other two orders the sorted triples alike.
  struct StarFace {
    uint64_t key;
    uint32_t t, j;
    bool operator<(const StarFace& o) const {
      return key != o.key ? key < o.key : (t != o.t ? t < o.t : j < o.j);
    }
  };
  std::vector<StarFace> face_keys_;
  std::vector<Tri> tris_a_, tris_b_;
  std::vector<Edge> edges_a_, edges_b_;
  std::vector<uint32_t> verts_a_, verts_b_, lk_verts_;
};

void Ranker::init() {
  const size_t np = mesh_.numPoints();
  const size_t nt = mesh_.numTets();
  tets_ = mesh_.tets;
  next_.assign(4 * nt, kNil);
  head_.assign(np, kNil);
  for (size_t t = nt; t-- > 0;) {
    for (int k = 3; k >= 0; --k) {
      const uint32_t v = tets_[t][k];
      const uint32_t c = static_cast<uint32_t>(4 * t + k);
      next_[c] = head_[v];
      head_[v] = c;
    }
  }
  star_size_.assign(np, 0);
  for (const Tet& q : tets_)
    for (uint32_t v : q) ++star_size_[v];
  boundary_.assign(np, 0);
  frozen_.assign(np, 0);
  alive_.assign(np, 1);
  version_.assign(np, 0);
  mark_.assign(np, 0);
  {
    const FaceAdjacency adj = computeFaceAdjacency(mesh_);
    double area = 0;
    for (size_t t = 0; t < nt; ++t) {
      for (int k = 0; k < 4; ++k) {
        const uint32_t nb = adj.neighbor[4 * t + k];
        if (nb != kNoNeighbor && nb != kNonManifold) continue;
        const uint32_t a = tets_[t][kTetFace[k][0]], b = tets_[t][kTetFace[k][1]], c = tets_[t][kTetFace[k][2]];
        if (nb == kNonManifold) {
          frozen_[a] = frozen_[b] = frozen_[c] = 1;
          continue;
        }
        boundary_[a] = boundary_[b] = boundary_[c] = 1;
        double n[3];
        triNormal(pos(a), pos(b), pos(c), n);
        area += 0.5 * norm(n);
      }
    }
    area_scale_ = area > 0 && std::isfinite(area) ? area : 1.0;
  }
  double mass = 0, volume = 0;
  for (size_t t = 0; t < nt; ++t) {
    const Tet& q = tets_[t];
    const double vol = signedVolume(pos(q[0]), pos(q[1]), pos(q[2]), pos(q[3]));
    const double rho = 0.25 * (density_[q[0]] + density_[q[1]] + density_[q[2]] + density_[q[3]]);
    mass += std::fabs(rho * vol);
    volume += std::fabs(vol);
  }
  mass_scale_ = mass > 0 && std::isfinite(mass) ? mass : (volume > 0 && std::isfinite(volume) ? volume : 1.0);
  tree_.parent.assign(np, MergeTree::kRoot);
  tree_.rank.assign(np, 0);
  tree_.removed.assign(np, 0);
  tree_.boundary.assign(np, 0);
  tree_.error.assign(np, 0.0f);
}

void Ranker::gatherStar(uint32_t v, std::vector<uint32_t>& corners) {
  corners.clear();
  uint32_t prev = kNil;
  uint32_t c = head_[v];
  while (c != kNil) {
    const uint32_t nx = next_[c];
    if (tets_[c >> 2][0] == kDead) {
      if (prev == kNil) {
        head_[v] = nx;
      } else {
        next_[prev] = nx;
      }
    } else {
      corners.push_back(c);
      prev = c;
    }
    c = nx;
  }
}

void Ranker::gatherBoundaryFaces(uint32_t v, const std::vector<uint32_t>& corners, std::vector<BoundaryFace>& faces) {
  faces.clear();
  if (!boundary_[v]) return;
  // Faces containing v: three per tetrahedron; those seen once are on the boundary.
  face_keys_.clear();
  for (uint32_t c : corners) {
    const uint32_t t = c >> 2;
    const int k = c & 3;
    for (int j = 0; j < 4; ++j) {
      if (j == k) continue;
      uint32_t other[2];
      int n = 0;
      for (int m = 0; m < 3; ++m) {
        const uint32_t u = tets_[t][kTetFace[j][m]];
        if (u != v && n < 2) other[n++] = u;
      }
      const uint32_t x = std::min(other[0], other[1]), y = std::max(other[0], other[1]);
      face_keys_.push_back({(uint64_t{x} << 32) | y, t, static_cast<uint32_t>(j)});
    }
  }
  std::sort(face_keys_.begin(), face_keys_.end());
  for (size_t i = 0; i < face_keys_.size();) {
    size_t j = i + 1;
    while (j < face_keys_.size() && face_keys_[j].key == face_keys_[i].key) ++j;
    if (j - i == 1) {
      const uint32_t t = face_keys_[i].t;
      const int f = static_cast<int>(face_keys_[i].j);
      uint32_t tri[3] = {tets_[t][kTetFace[f][0]], tets_[t][kTetFace[f][1]], tets_[t][kTetFace[f][2]]};
      while (tri[0] != v) std::rotate(tri, tri + 1, tri + 3);
      BoundaryFace bf;
      bf.x = tri[1];
      bf.y = tri[2];
      triNormal(pos(v), pos(bf.x), pos(bf.y), bf.n);
      bf.area = 0.5 * norm(bf.n);
      faces.push_back(bf);
    }
    i = j;
  }
}

void Ranker::candidates(uint32_t v, std::vector<Candidate>& out) {
  out.clear();
  if (!alive_[v] || frozen_[v] || crowded(v)) return;
  gatherStar(v, corners_);
  if (corners_.empty()) return;
  const double* pv = pos(v);
  const double rho_v = density_[v];
  star_.clear();
  targets_.clear();
  for (uint32_t c : corners_) {
    const uint32_t t = c >> 2;
    const int k = c & 3;
    StarTet s;
    s.corner = c;
    const uint32_t a = tets_[t][kTetFace[k][0]], b = tets_[t][kTetFace[k][1]], d = tets_[t][kTetFace[k][2]];
    s.o[0] = a;
    s.o[1] = b;
    s.o[2] = d;
    double nout[3];
    triNormal(pos(a), pos(b), pos(d), nout);
    s.n[0] = -nout[0];
    s.n[1] = -nout[1];
    s.n[2] = -nout[2];
    s.d = dot(s.n, pos(a));
    s.other_density = density_[a] + density_[b] + density_[d];
    const double vol = (dot(s.n, pv) - s.d) / 6.0;
    s.mass = 0.25 * (rho_v + s.other_density) * vol;
    star_.push_back(s);
    if (!boundary_[v]) targets_.insert(targets_.end(), {a, b, d});
  }
  gatherBoundaryFaces(v, corners_, faces_);
  double face_area = 0;
  if (boundary_[v]) {
    for (const BoundaryFace& f : faces_) {
      targets_.push_back(f.x);
      targets_.push_back(f.y);
      face_area += f.area;
    }
  }
  uniqueByMark(targets_);
  for (uint32_t w : targets_) {
    if (frozen_[w] || crowded(w)) continue;
    ++evaluations_;
    const bool same = samePosition(v, w);
    const double* pw = pos(w);
    const double rho_w = density_[w];
    double net = 0, local = 0;
    bool ok = true;
    for (const StarTet& s : star_) {
      if (s.o[0] == w || s.o[1] == w || s.o[2] == w) {
        net -= s.mass;
        local += std::fabs(s.mass);
        continue;
      }
      double vol;
      if (same) {
        vol = (dot(s.n, pv) - s.d) / 6.0;
      } else {
        vol = (dot(s.n, pw) - s.d) / 6.0;
        if (!(vol > 0)) {
          ok = false;
          break;
        }
      }
      const double change = 0.25 * (rho_w + s.other_density) * vol - s.mass;
      net += change;
      local += std::fabs(change);
    }
    if (!ok) continue;
    const double ed = std::fabs(net) + kLocalWeight * local;
    double eg = 0;
    if (boundary_[v] && face_area > 0) {
      for (const BoundaryFace& f : faces_) {
        if (f.x == w || f.y == w) continue;
        double nn[3];
        triNormal(pw, pos(f.x), pos(f.y), nn);
        const double new_area = 0.5 * norm(nn);
        if (!same && !(dot(f.n, nn) > kFlipMargin * norm(f.n) * norm(nn))) {
          ok = false;
          break;
        }
        eg += std::fabs(new_area - f.area) * f.area;
        for (const BoundaryFace& g : faces_) {
          if (&g == &f) continue;
          const bool has_w = g.x == w || g.y == w;
          const bool shares = g.x == f.x || g.y == f.x || g.x == f.y || g.y == f.y;
          if (has_w && shares) eg += std::fabs(new_area - g.area) * g.area;
        }
      }
      eg /= face_area;
    }
    if (!ok) continue;
    const double e = options_.w_density * ed / mass_scale_ + options_.w_geometry * eg / area_scale_;
    out.push_back({std::isfinite(e) ? e : 1e30, w});
  }
}

void Ranker::linkOf(uint32_t u, const std::vector<uint32_t>& corners, const std::vector<BoundaryFace>& faces,
                    std::vector<Tri>& tris, std::vector<Edge>& edges, std::vector<uint32_t>& verts) {
  tris.clear();
  for (uint32_t c : corners) {
    const uint32_t t = c >> 2;
    const int k = c & 3;
    Tri tri{tets_[t][(k + 1) & 3], tets_[t][(k + 2) & 3], tets_[t][(k + 3) & 3]};
    std::sort(tri.begin(), tri.end());
    tris.push_back(tri);
  }
  if (boundary_[u]) {
    for (const BoundaryFace& f : faces) tris.push_back({std::min(f.x, f.y), std::max(f.x, f.y), kOmega});
  }
  sortUnique(tris);
  edges.clear();
  verts.clear();
  for (const Tri& t : tris) {
    edges.push_back({t[0], t[1]});
    edges.push_back({t[0], t[2]});
    edges.push_back({t[1], t[2]});
    verts.insert(verts.end(), t.begin(), t.end());
  }
  sortUnique(edges);
  sortUnique(verts);
}

bool Ranker::validate(uint32_t v, uint32_t w) {
  if (v == w || !alive_[v] || !alive_[w] || frozen_[v] || frozen_[w] || crowded(v) || crowded(w)) return false;
  if (boundary_[v] && !boundary_[w]) return false;
  gatherStar(v, corners_);
  gatherStar(w, corners_w_);
  gatherBoundaryFaces(v, corners_, faces_);
  gatherBoundaryFaces(w, corners_w_, faces_w_);
  // Tetrahedra around the edge vw and the vertices of Lk(vw).
  size_t edge_tets = 0;
  lk_verts_.clear();
  const bool same = samePosition(v, w);
  for (uint32_t c : corners_) {
    const Tet& q = tets_[c >> 2];
    const int k = c & 3;
    if (q[0] == w || q[1] == w || q[2] == w || q[3] == w) {
      ++edge_tets;
      for (uint32_t x : q) {
        if (x != v && x != w) lk_verts_.push_back(x);
      }
      continue;
    }
    if (!same) {
      const double* p[4] = {pos(q[0]), pos(q[1]), pos(q[2]), pos(q[3])};
      p[k] = pos(w);
      if (orient3d(p[0], p[1], p[2], p[3]) <= 0) return false;
    }
  }
  if (edge_tets == 0) return false;
  size_t edge_faces = 0;
  for (const BoundaryFace& f : faces_) {
    if (f.x == w || f.y == w) {
      ++edge_faces;
      continue;
    }
    if (!same) {
      double nn[3];
      triNormal(pos(w), pos(f.x), pos(f.y), nn);
      if (!(dot(f.n, nn) > kFlipMargin * norm(f.n) * norm(nn))) return false;
    }
  }
  if (boundary_[v] && edge_faces == 0) return false;  // not a boundary edge
  // A collapsing tetrahedron T = (v, w, x, y) glues its faces (v, x, y) and (w, x, y). When one of them
  // is on the boundary, the tetrahedron across the other one inherits the boundary triangle: the
  // streamed triangle keeps T's orientation, the mesh's takes the neighbour's. They agree when both
  // are positively oriented (a flat tetrahedron's orientation is arbitrary), so require that.
  for (uint32_t c : corners_) {
    const uint32_t t = c >> 2;
    const Tet& q = tets_[t];
    if (q[0] != w && q[1] != w && q[2] != w && q[3] != w) continue;
    uint32_t xy[2], m = 0;
    for (uint32_t z : q) {
      if (z != v && z != w) xy[m++] = z;
    }
    auto across = [&](const std::vector<uint32_t>& star) -> uint32_t {
      for (uint32_t cc : star) {
        const uint32_t r = cc >> 2;
        if (r == t) continue;
        const Tet& p = tets_[r];
        bool has_x = false, has_y = false;
        for (uint32_t z : p) {
          has_x |= z == xy[0];
          has_y |= z == xy[1];
        }
        if (has_x && has_y) return r;
      }
      return kNil;
    };
    const uint32_t nv = across(corners_), nw = across(corners_w_);
    if (nv != kNil && nw != kNil) continue;
    if (orient3d(pos(q[0]), pos(q[1]), pos(q[2]), pos(q[3])) <= 0) return false;
    const uint32_t n = nv != kNil ? nv : nw;
    if (n != kNil) {
      const Tet& p = tets_[n];
      if (orient3d(pos(p[0]), pos(p[1]), pos(p[2]), pos(p[3])) <= 0) return false;
    }
  }
  // Link condition: Lk(v) ∩ Lk(w) = Lk(vw), counted per dimension (Lk(vw) is always contained).
  sortUnique(lk_verts_);
  const size_t lk_v = lk_verts_.size() + (edge_faces > 0 ? 1 : 0);
  const size_t lk_e = edge_tets + edge_faces;
  linkOf(v, corners_, faces_, tris_a_, edges_a_, verts_a_);
  linkOf(w, corners_w_, faces_w_, tris_b_, edges_b_, verts_b_);
  if (countCommon(tris_a_, tris_b_) != 0) return false;
  if (countCommon(edges_a_, edges_b_) != lk_e) return false;
  if (countCommon(verts_a_, verts_b_) != lk_v) return false;
  return true;
}

void Ranker::merge(uint32_t v, uint32_t w, float error) {
  gatherStar(v, corners_);
  recompute_.clear();
  recompute_.push_back(w);
  uint32_t removed = 0;
  for (uint32_t c : corners_) {
    Tet& q = tets_[c >> 2];
    for (uint32_t x : q) {
      if (x != v) recompute_.push_back(x);
    }
    if (q[0] == w || q[1] == w || q[2] == w || q[3] == w) {
      for (uint32_t x : q) --star_size_[x];
      q[0] = kDead;
      ++removed;
    } else {
      q[c & 3] = w;
      ++star_size_[w];
    }
  }
  if (!corners_.empty()) {
    next_[corners_.back()] = head_[w];
    head_[w] = head_[v];
    head_[v] = kNil;
  }
  alive_[v] = 0;
  ++version_[v];
  tree_.parent[v] = w;
  tree_.rank[v] = static_cast<uint32_t>(++tree_.merges);
  tree_.removed[v] = removed;
  tree_.boundary[v] = boundary_[v];
  tree_.error[v] = error;
  uniqueByMark(recompute_);
  for (uint32_t x : recompute_) recompute(x);
}

void Ranker::recompute(uint32_t v) {
  ++version_[v];
  candidates(v, cands_);
  if (cands_.empty()) return;
  const Candidate* best = &cands_[0];
  for (const Candidate& c : cands_) {
    if (c.error < best->error || (c.error == best->error && c.w < best->w)) best = &c;
  }
  push(v, *best);
}

MergeTree Ranker::run(RankingStats* stats) {
  init();
  const uint32_t np = static_cast<uint32_t>(mesh_.numPoints());
  for (uint32_t v = 0; v < np; ++v) recompute(v);
  uint64_t popped = 0, rejected = 0;
  std::vector<Candidate> sorted;
  while (!heap_.empty() && tree_.merges < options_.max_merges) {
    const QueueEntry e = heap_.top();
    heap_.pop();
    if (!alive_[e.v] || version_[e.v] != e.version) continue;
    ++popped;
    if (validate(e.v, e.w)) {
      merge(e.v, e.w, e.error);
      continue;
    }
    ++rejected;
    // The cheap filter let an invalid target through: take the best target that passes every check.
    ++version_[e.v];
    candidates(e.v, sorted);
    std::sort(sorted.begin(), sorted.end(), [](const Candidate& a, const Candidate& b) {
      return a.error < b.error || (a.error == b.error && a.w < b.w);
    });
    for (const Candidate& c : sorted) {
      if (validate(e.v, c.w)) {
        push(e.v, c);
        break;
      }
    }
  }
  if (stats) {
    stats->popped = popped;
    stats->rejected = rejected;
    stats->evaluations = evaluations_;
  }
  return std::move(tree_);
}

}  // namespace

StatusOr<MergeTree> rankMerges(const TetMesh& mesh, const RankingOptions& options, RankingStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  GTN_RETURN_IF_ERROR(mesh.checkConsistency("simplification input"));
  if (mesh.numPoints() >= 0xFFFFFFF0u || mesh.numTets() >= 0x3FFFFFFFu)
    return unsupported("simplification: mesh too large for 32-bit vertex and corner ids");
  const Field* field = nullptr;
  if (options.field.empty()) {
    if (!mesh.point_fields.empty()) field = &mesh.point_fields[0];
  } else if (options.field != "none") {
    field = mesh.findPointField(options.field);
    if (!field) {
      std::string names;
      for (const Field& f : mesh.point_fields) names += (names.empty() ? "" : ", ") + f.name;
      return usageError("simplification field '" + options.field + "' not found (point fields: " +
                        (names.empty() ? "none" : names) + ")");
    }
  }
  if (!(options.w_density >= 0) || !(options.w_geometry >= 0) || !std::isfinite(options.w_density) ||
      !std::isfinite(options.w_geometry))
    return usageError("simplification weights must be finite and non-negative");
  std::vector<double> density(mesh.numPoints(), 1.0);
  if (field && field->components > 0) {
    for (size_t i = 0; i < density.size(); ++i) {
      const double d = field->get(i, 0);
      density[i] = std::isfinite(d) ? d : 0.0;
    }
  }
  Ranker ranker(mesh, std::move(density), options);
  RankingStats local;
  MergeTree tree = ranker.run(&local);
  tree.field = field ? field->name : "";
  tree.w_density = options.w_density;
  tree.w_geometry = options.w_geometry;
  computeErrorQuantiles(tree);
  if (stats) {
    *stats = local;
    stats->merges = tree.merges;
    stats->boundary_merges = tree.boundaryMergesUpTo(tree.merges);
    stats->field = tree.field;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return tree;
}

}  // namespace gtn
