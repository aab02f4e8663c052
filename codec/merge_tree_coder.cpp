#include "codec/merge_tree_coder.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>

#include "codec/range_coder.h"

namespace gtn {

const double kMergeErrorQuantiles[9] = {0.0, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 1.0};

void MergeTree::makeRoots(size_t n) {
  parent.assign(n, kRoot);
  rank.assign(n, 0);
  removed.assign(n, 0);
  boundary.assign(n, 0);
  merges = 0;
  batches.clear();
  checked = false;
}

uint64_t MergeTree::boundaryMergesUpTo(uint64_t n) const {
  uint64_t count = 0;
  for (size_t v = 0; v < parent.size(); ++v) {
    if (parent[v] != kRoot && rank[v] <= n && !boundary.empty() && boundary[v]) ++count;
  }
  return count;
}

uint64_t MergeTree::tetsRemovedUpTo(uint64_t n) const {
  uint64_t count = 0;
  for (size_t v = 0; v < parent.size(); ++v) {
    if (parent[v] != kRoot && rank[v] <= n && !removed.empty()) count += removed[v];
  }
  return count;
}

Status MergeTree::check(const std::string& what) const {
  const size_t n = parent.size();
  if (rank.size() != n || removed.size() != n || boundary.size() != n)
    return invalidData(what + ": merge tree arrays differ in size");
  if (merges > n) return invalidData(what + ": merge tree has more merges than vertices");
  std::vector<uint8_t> seen(merges + 1, 0);
  uint64_t merged = 0;
  for (size_t v = 0; v < n; ++v) {
    if (parent[v] == kRoot) {
      if (rank[v] != 0) return invalidData(what + ": root vertex " + std::to_string(v) + " has a rank");
      continue;
    }
    ++merged;
    if (parent[v] >= n || parent[v] == v)
      return invalidData(what + ": vertex " + std::to_string(v) + " has an invalid parent");
    if (rank[v] == 0 || rank[v] > merges || seen[rank[v]])
      return invalidData(what + ": vertex " + std::to_string(v) + " has an invalid or repeated rank");
    seen[rank[v]] = 1;
    const uint32_t p = parent[v];
    if (parent[p] != kRoot && rank[p] <= rank[v])
      return invalidData(what + ": vertex " + std::to_string(v) + " merges into a vertex merged earlier");
  }
  if (merged != merges) return invalidData(what + ": merge count disagrees with the tree");
  if (!batches.empty()) {
    uint64_t sum = 0;
    for (uint32_t b : batches) {
      if (b == 0) return invalidData(what + ": merge tree has an empty batch");
      sum += b;
    }
    if (sum != merges) return invalidData(what + ": merge tree batches hold another number of merges");
  }
  return Status::ok();
}

std::vector<uint32_t> sliceBatches(const std::vector<uint32_t>& batches, uint64_t from, uint64_t to) {
  std::vector<uint32_t> out;
  uint64_t begin = 0;
  for (uint32_t b : batches) {
    const uint64_t end = begin + b;
    const uint64_t lo = std::max(begin, from), hi = std::min(end, to);
    if (lo < hi) out.push_back(static_cast<uint32_t>(hi - lo));
    begin = end;
  }
  return out;
}

uint64_t batchKeyOfId(uint64_t z) {
  z ^= z >> 30;
  z *= 0xBF58476D1CE4E5B9ull;
  z ^= z >> 27;
  z *= 0x94D049BB133111EBull;
  z ^= z >> 31;
  return z;
}

uint64_t batchKeyOfPoint(const double* p) {
  uint64_t b[3];
  std::memcpy(b, p, sizeof b);
  return batchKeyOfId(batchKeyOfId(batchKeyOfId(b[0]) ^ b[1]) ^ b[2]);
}

MergeTree prefixTree(const MergeTree& tree, uint64_t n) {
  MergeTree out = tree;
  if (n >= tree.merges) return out;
  out.merges = n;
  out.batches = sliceBatches(tree.batches, 0, n);
  out.checked = false;
  for (size_t v = 0; v < out.points(); ++v) {
    if (out.rank[v] == 0 || out.rank[v] <= n) continue;
    out.parent[v] = MergeTree::kRoot;
    out.rank[v] = 0;
    out.removed[v] = 0;
    out.boundary[v] = 0;
    if (v < out.error.size()) out.error[v] = 0;
  }
  return out;
}

void computeErrorQuantiles(MergeTree& tree) {
  tree.error_quantiles.clear();
  if (tree.error.size() != tree.parent.size() || tree.merges == 0) return;
  std::vector<float> e;
  e.reserve(tree.merges);
  for (size_t v = 0; v < tree.parent.size(); ++v) {
    if (tree.parent[v] != MergeTree::kRoot) e.push_back(tree.error[v]);
  }
  if (e.empty()) return;
  std::sort(e.begin(), e.end());
  for (double q : kMergeErrorQuantiles) {
    const size_t i = std::min(e.size() - 1, static_cast<size_t>(std::llround(q * double(e.size() - 1))));
    tree.error_quantiles.push_back(e[i]);
  }
}

namespace {

// Adaptive models of the body (one instance per encoder or decoder).
struct Models {
  BitModel boundary;
  BitModel exact[2];  // per boundary bit: the parent delta equals one of its predictions
  BitTree<3> hit;     // which one
  BitTree<4> choice;  // otherwise: which prediction the residual is taken from (0 = none)
  BitModel sign[2];   // per context (choice == 0 or not)
  BitTree<6> len[2];
  BitTree<4> removed[2];
  BitTree<4> index[2];  // version 3: per boundary bit, the parent's place among the candidates (15 = not one)
  BitTree<6> far;       // grid places: the bit length of a place past 13, less 14
  // Version 4's batches.
  BitModel rule;          // the batch has the rule's size
  BitTree<6> size;        // otherwise the bit length of its size
  BitTree<6> gap;         // the bit lengths of the gaps between a batch's children
  BitModel pass[4];       // per run (the fourth on): another run follows
  BitModel in_run[3][2];  // per run (the third on) and the previous flag: a child is in the run
};

// Whether a run of `run` of the `left` children left is cheaper coded as flags (about left * H(run /
// left) bits) than the order of the rest outright (about log2(left) - 1.44 bits a child, for each one
// the run places). The encoder's choice; the decoder reads it.
inline bool runPays(uint32_t run, uint32_t left) {
  const double f = static_cast<double>(run) / left;
  const double flags = f >= 1 ? 0.0 : -(f * std::log2(f) + (1 - f) * std::log2(1 - f)) * left;
  return flags < run * (std::log2(static_cast<double>(left)) - 1.44);
}

// v < 2^32 as its bit length (BitTree<6>, 0..32) and the bits below its leading one (direct bits).
// Sets *bad on a length over 32 (only a corrupt stream).
template <class C>
uint32_t codeLength(C& c, BitTree<6>& t, uint32_t v, bool* bad) {
  const uint32_t len = t.code(c, static_cast<uint32_t>(bitLength(v)));
  if (len > 32) {
    *bad = true;
    return 0;
  }
  if (len == 0) return 0;
  const uint32_t top = uint32_t{1} << (len - 1);
  return top | c.direct(v & (top - 1), static_cast<int>(len) - 1);
}

// x in [0, total), 1 <= total, as a truncated binary code of direct bits.
template <class C>
uint32_t codeUniform(C& c, uint32_t x, uint32_t total) {
  if (total <= 1) return 0;
  const int b = bitLength(total - 1);
  const uint32_t u = static_cast<uint32_t>((uint64_t{1} << b) - total);  // codes one bit shorter
  uint32_t y = c.direct(x < u ? x : (x + u) >> 1, b - 1);
  if (y < u) return y;
  y = (y << 1) | c.direct((x + u) & 1, 1);
  return y - u;
}

// Predictions of a merge's parent delta (parent id - child id): the deltas of the merges already
// coded whose children are the kReach nearest ids on either side of the child in decoding order
// (c-1, c+1, c-2, c+2, ...), nearest first, skipping ids not merged yet and ids outside the level.
// Vertices decoded close together lie close together in the mesh and tend to merge in the same
// direction (on a grid, along the same grid line). Branch-free: whether a neighbour is merged yet is
// as good as random.
struct DeltaPredictions {
  static constexpr int kReach = 4;
  static constexpr int kSize = 2 * kReach;
  int64_t d[kSize];
  int count = 0;
  // parent[id] = parent of the merges coded so far, MergeTree::kRoot elsewhere.
  DeltaPredictions(const std::vector<uint32_t>& parent, uint32_t c) {
    const uint32_t n = static_cast<uint32_t>(parent.size());
    if (c >= static_cast<uint32_t>(kReach) && c + kReach < n) {
      const uint32_t* p = parent.data() + c;
      for (int k = 1; k <= kReach; ++k) {
        add(p[-k], int64_t{c} - k);
        add(p[k], int64_t{c} + k);
      }
    } else {
      for (int k = 1; k <= kReach; ++k) {
        if (static_cast<uint32_t>(k) <= c) add(parent[c - k], int64_t{c} - k);
        if (c + k < n) add(parent[c + k], int64_t{c} + k);
      }
    }
  }

 private:
  void add(uint32_t p, int64_t id) {
    d[count] = int64_t{p} - id;
    count += p != MergeTree::kRoot;
  }
};

// The vertex x has been merged into, recursively (x itself if it is a root): up[v] is v's parent for the
// merges made so far, v for a root. Path halving shortens the chains as it goes.
inline uint32_t rootOf(std::vector<uint32_t>& up, uint32_t x) {
  while (up[x] != x) {
    up[x] = up[up[x]];
    x = up[x];
  }
  return x;
}

// Each vertex's tetrahedra: incident[at[v] .. at[v + 1]) are the tetrahedra of vertex v, in order.
struct VertexTets {
  std::vector<uint64_t> at;
  std::vector<uint32_t> incident;
};
// `tets`: 4 vertex ids per tetrahedron, all below n.
VertexTets vertexTets(size_t n, std::span<const uint32_t> tets) {
  VertexTets out;
  out.at.assign(n + 1, 0);
  for (uint32_t v : tets) ++out.at[v + 1];
  for (size_t v = 0; v < n; ++v) out.at[v + 1] += out.at[v];
  out.incident.resize(tets.size());
  std::vector<uint64_t> fill(out.at.begin(), out.at.end() - 1);
  for (size_t i = 0; i < tets.size(); ++i) out.incident[fill[tets[i]]++] = static_cast<uint32_t>(i / 4);
  return out;
}

// The classes of the merges made so far (a root and the vertices merged into it, recursively) as
// chains of vertices. A walk of a class drops the vertices that have nothing left to give, so that
// it costs about what the rest give, however large the class.
class ClassChains {
 public:
  explicit ClassChains(size_t n) : up_(n), next_(n, kNone), last_(n) {
    for (uint32_t v = 0; v < n; ++v) up_[v] = last_[v] = v;
  }
  uint32_t root(uint32_t x) { return rootOf(up_, x); }
  // Calls keep(y) for every vertex y of the class of root c, c first; a y other than c for which it
  // returns false leaves the chain.
  template <class Keep>
  void walk(uint32_t c, Keep keep) {
    uint32_t prev = kNone;
    for (uint32_t y = c; y != kNone;) {
      const bool kept = keep(y);
      const uint32_t after = next_[y];
      if (!kept && y != c) {
        next_[prev] = after;
        if (last_[c] == y) last_[c] = prev;
      } else {
        prev = y;
      }
      y = after;
    }
  }
  // Root c merges into root p: c's class joins p's.
  void merge(uint32_t c, uint32_t p) {
    up_[c] = p;
    next_[last_[p]] = c;
    last_[p] = last_[c];
  }

 private:
  static constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> up_, next_, last_;
};

// Version 3: the parent as a place among the child's neighbours at the time of its merge, in the
// mesh the earlier merges left (the vertices that share a tetrahedron of the level with the child or
// with a vertex merged into it, each replaced by its root: the vertex it has been merged into,
// recursively), nearest first: by the squared distance ((dx*dx + dy*dy) + dz*dz) in double, ties to
// the smaller decoding id. The encoder works in the tree's own numbering and breaks ties by `key` (the
// decoding ids); the decoder in decoding order with no key.
class ParentCandidates {
 public:
  // `tets`: 4 vertex ids per tetrahedron, all below n (the caller checks), `vt` their vertexTets;
  // `coords`: 3 per vertex.
  ParentCandidates(size_t n, std::span<const uint32_t> tets, const VertexTets& vt, const double* coords,
                   const uint32_t* key)
      : coords_(coords), key_(key), chains_(n), mark_(n, kNone), live_(n) {
    // Each vertex's neighbours once.
    const std::vector<uint64_t>& at = vt.at;
    const std::vector<uint32_t>& incident = vt.incident;
    start_.assign(n + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      uint64_t out = 0;
      for (uint32_t v = 0; v < n; ++v) {
        start_[v] = out;
        for (uint64_t k = at[v]; k < at[v + 1]; ++k) {
          const uint32_t* t = tets.data() + 4 * size_t{incident[k]};
          for (int j = 0; j < 4; ++j) {
            const uint32_t w = t[j];
            if (w == v || mark_[w] == v) continue;
            mark_[w] = v;
            if (pass) neighbours_[out] = w;
            ++out;
          }
        }
        if (pass) live_[v] = static_cast<uint32_t>(out - start_[v]);
      }
      start_[n] = out;
      if (!pass) neighbours_.resize(out);
      std::fill(mark_.begin(), mark_.end(), kNone);
    }
  }

  // Gathers the candidates of child c (a vertex not merged yet); returns their number. A neighbour
  // whose root is c stays in c's class (roots only merge): it leaves its vertex's list when met, and
  // a vertex with no other neighbour left leaves the class's list (c itself stays), so that a gather
  // costs about the child's neighbours, however many vertices were merged into it.
  uint32_t gather(uint32_t c) {
    ++stamp_;
    keyed_.clear();
    const double* pc = coords_ + 3 * size_t{c};
    chains_.walk(c, [&](uint32_t y) {
      const uint64_t begin = start_[y];
      uint64_t end = begin + live_[y];
      for (uint64_t k = begin; k < end;) {
        const uint32_t q = chains_.root(neighbours_[k]);
        if (q == c) {
          neighbours_[k] = neighbours_[--end];
          continue;
        }
        ++k;
        if (mark_[q] == stamp_) continue;
        mark_[q] = stamp_;
        const double* pq = coords_ + 3 * size_t{q};
        const double dx = pq[0] - pc[0], dy = pq[1] - pc[1], dz = pq[2] - pc[2];
        keyed_.push_back({(dx * dx + dy * dy) + dz * dz, key_ ? key_[q] : q, q});
      }
      live_[y] = static_cast<uint32_t>(end - begin);
      return end != begin;
    });
    return static_cast<uint32_t>(keyed_.size());
  }
  // The place of p among the gathered candidates in their order (the count when p is none of them).
  uint32_t placeOf(uint32_t p) const {
    const Keyed* at = nullptr;
    for (const Keyed& k : keyed_) at = k.v == p ? &k : at;
    if (!at) return static_cast<uint32_t>(keyed_.size());
    uint32_t place = 0;
    for (const Keyed& k : keyed_) place += before(k, *at);
    return place;
  }
  // The candidate at place i (i below the count) in their order.
  uint32_t at(uint32_t i) {
    std::nth_element(keyed_.begin(), keyed_.begin() + i, keyed_.end(),
                     [](const Keyed& a, const Keyed& b) { return before(a, b); });
    return keyed_[i].v;
  }

  // Child c merges into parent p: c's vertices become p's.
  void merge(uint32_t c, uint32_t p) { chains_.merge(c, p); }

 private:
  static constexpr uint32_t kNone = UINT32_MAX;
  struct Keyed {
    double d2;
    uint32_t id, v;
  };
  static bool before(const Keyed& a, const Keyed& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.id < b.id); }
  const double* coords_;
  const uint32_t* key_;
  std::vector<uint64_t> start_;       // per vertex: its first entry in neighbours_
  std::vector<uint32_t> neighbours_;  // each vertex's neighbours in the level, those outside its class first
  ClassChains chains_;
  std::vector<uint32_t> mark_;
  std::vector<uint32_t> live_;  // per vertex: its neighbours that may still lie outside its class
  uint32_t stamp_ = 0;
  std::vector<Keyed> keyed_;
};

// Version 5's inferred values (parent_form 3): a merge's child's boundary bit and the tetrahedra the
// merge removes, read off the mesh the earlier merges made of the level. A tetrahedron of the level is
// alive while the roots of its four vertices differ; a merge c -> p kills the alive ones whose roots
// include c and p. The child's star is the alive tetrahedra with a vertex whose root is c (exactly one
// such vertex each); c is a boundary vertex when an edge of its link (the other three roots of each
// tetrahedron of its star, in pairs) lies in exactly one of them. Each vertex keeps its tetrahedra,
// the dead ones dropped when met, and a class (the vertices merged into a root) drops a vertex whose
// tetrahedra are all dead, so that a star costs about its tetrahedra, however large the class.
class StarCounter {
 public:
  // `vt`: vertexTets of `tets` (taken over: the walks reorder each vertex's list).
  StarCounter(size_t n, std::span<const uint32_t> tets, VertexTets vt)
      : tets_(tets),
        chains_(n),
        at_(std::move(vt.at)),
        incident_(std::move(vt.incident)),
        live_(n),
        dead_(tets.size() / 4, 0) {
    for (size_t v = 0; v < n; ++v) live_[v] = static_cast<uint32_t>(at_[v + 1] - at_[v]);
  }

  // Gathers the star of c (a root): call before boundary() and merge().
  void gather(uint32_t c) {
    star_.clear();
    chains_.walk(c, [&](uint32_t y) {
      const uint64_t begin = at_[y];
      uint64_t end = begin + live_[y];
      for (uint64_t k = begin; k < end;) {
        const uint32_t t = incident_[k];
        if (dead_[t]) {
          incident_[k] = incident_[--end];
          continue;
        }
        ++k;
        Entry e{t, {0, 0, 0}};
        int m = 0;
        for (int j = 0; j < 4; ++j) {
          const uint32_t w = chains_.root(tets_[4 * size_t{t} + j]);
          if (w != c && m < 3) e.other[m++] = w;
        }
        if (m == 3) star_.push_back(e);  // always, as a merge kills every tetrahedron it folds
      }
      live_[y] = static_cast<uint32_t>(end - begin);
      return end != begin;
    });
  }
  // Whether the gathered child is a boundary vertex.
  bool boundary() {
    edges_.clear();
    for (const Entry& e : star_) {
      const uint32_t a = e.other[0], b = e.other[1], d = e.other[2];
      edges_.push_back(edgeKey(a, b));
      edges_.push_back(edgeKey(a, d));
      edges_.push_back(edgeKey(b, d));
    }
    std::sort(edges_.begin(), edges_.end());
    for (size_t i = 0; i < edges_.size();) {
      size_t j = i + 1;
      while (j < edges_.size() && edges_[j] == edges_[i]) ++j;
      if (j - i == 1) return true;
      i = j;
    }
    return false;
  }
  // The gathered child c merges into p: returns the tetrahedra the merge removes.
  uint32_t merge(uint32_t c, uint32_t p) {
    uint32_t removed = 0;
    for (const Entry& e : star_) {
      if (e.other[0] == p || e.other[1] == p || e.other[2] == p) {
        dead_[e.tet] = 1;
        ++removed;
      }
    }
    chains_.merge(c, p);
    return removed;
  }

 private:
  struct Entry {
    uint32_t tet;
    uint32_t other[3];  // the roots of its other three vertices
  };
  static uint64_t edgeKey(uint32_t a, uint32_t b) { return a < b ? (uint64_t{a} << 32) | b : (uint64_t{b} << 32) | a; }
  std::span<const uint32_t> tets_;
  ClassChains chains_;
  std::vector<uint64_t> at_;        // per vertex: its first entry in incident_
  std::vector<uint32_t> incident_;  // each vertex's tetrahedra, those still alive first
  std::vector<uint32_t> live_;      // per vertex: its tetrahedra that may still be alive
  std::vector<uint8_t> dead_;       // per tetrahedron
  std::vector<Entry> star_;
  std::vector<uint64_t> edges_;
};

// Version 4's grid places (parent_form 4): the parent as a place among the roots of the grid nodes
// next to the child, where decoding id g < ni * nj * nk is node (g mod ni, (g / ni) mod nj, g / (ni *
// nj)) of an ni x nj x nk block and the nodes next to a node are the up to 26 others of its 3 x 3 x 3
// neighbourhood: each root once, the child left out, nearest the child first, by the squared
// difference of the grid indices, ties to the smaller id. Nothing of the level is read: the ids and
// the dims decide. A root within the neighbourhood is a neighbour itself, so the order is: the
// neighbours that are roots, the 6 face neighbours, then the 12 edge and the 8 corner ones, each
// group in id order, then the roots farther away that neighbours were merged into; the decoder
// gathers groups only as far as the place it reads (most parents are face neighbours). The roots of
// the rest of the child's class (the vertices merged into it) are not gathered: on a grid that walk
// cost four times the rest of a merge's decode for about 5% of the parents.
class GridCandidates {
 public:
  GridCandidates(size_t n, const std::array<uint32_t, 3>& dims)
      : ni_(dims[0]), nj_(dims[1]), nk_(dims[2]), nodes_(uint64_t{dims[0]} * dims[1] * dims[2]), up_(n), mark_(n, 0) {
    for (uint32_t v = 0; v < n; ++v) up_[v] = v;
    int o = 0;
    for (int len = 1; len <= 3; ++len)
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if (di * di + dj * dj + dk * dk != len) continue;
            offsets_[o++] = {di, dj, dk, di + int64_t{ni_} * (dj + int64_t{nj_} * dk)};
          }
  }

  // Starts the candidates of child c (a vertex not merged yet).
  void begin(uint32_t c) {
    ++stamp_;
    list_.clear();
    c_ = c;
    group_ = c < nodes_ ? 0 : kGroups;  // an id past the nodes has no candidate
    if (c < nodes_) {
      node(c, g_);
      for (int a = 0; a < 3; ++a) {
        lo_[a] = g_[a] == 0;
        hi_[a] = g_[a] + 1 == dim(a);
      }
    }
  }
  // Whether there is a candidate at place i (gathering the groups up to it).
  bool has(uint32_t i) {
    while (list_.size() <= i && group_ < kGroups) gatherGroup();
    return list_.size() > i;
  }
  // The place of p among all the candidates (kNoPlace when p is none of them). The groups are gathered
  // only up to p's: a group only appends to the list, and a candidate is listed once, so its place is
  // the same in the whole list (the farther roots, the costliest group, are mostly never needed).
  uint32_t placeOf(uint32_t p) {
    for (size_t i = 0;; ++i) {
      while (i == list_.size() && group_ < kGroups) gatherGroup();
      if (i == list_.size()) return kNoPlace;
      if (list_[i].v == p) return static_cast<uint32_t>(i);
    }
  }
  // The candidate at place i (has(i) true).
  uint32_t at(uint32_t i) const { return list_[i].v; }
  // Child c merges into parent p.
  void merge(uint32_t c, uint32_t p) { up_[c] = p; }
  // Starts loading what begin(c) and the groups read: the neighbours' parents, in c's row and the
  // rows around it (an id's neighbours lie in 9 runs of 3 ids).
  void prefetch(uint32_t c) const {
    if (c >= nodes_) return;
    for (int64_t dk = -1; dk <= 1; ++dk)
      for (int64_t dj = -1; dj <= 1; ++dj) {
        const int64_t x = int64_t{c} + int64_t{ni_} * (dj + int64_t{nj_} * dk);
        if (x >= 0 && static_cast<uint64_t>(x) < up_.size()) __builtin_prefetch(&up_[static_cast<size_t>(x)]);
      }
  }

  static constexpr uint32_t kNoPlace = UINT32_MAX;

 private:
  static constexpr int kGroups = 4;  // faces, edges, corners, the roots farther away
  struct Offset {
    int di, dj, dk;
    int64_t step;  // the id difference
  };
  struct Keyed {
    uint64_t d2;
    uint32_t v;
  };
  uint32_t dim(int a) const { return a == 0 ? ni_ : a == 1 ? nj_ : nk_; }
  bool inside(const Offset& o) const {
    return !((o.di < 0 && lo_[0]) || (o.di > 0 && hi_[0]) || (o.dj < 0 && lo_[1]) || (o.dj > 0 && hi_[1]) ||
             (o.dk < 0 && lo_[2]) || (o.dk > 0 && hi_[2]));
  }
  void gatherGroup() {
    static constexpr int kFirst[4] = {0, 6, 18, 26};
    if (group_ < 3) {
      // The neighbours of the group that are roots, in id order (the offsets are in it).
      for (int k = kFirst[group_]; k < kFirst[group_ + 1]; ++k) {
        const Offset& o = offsets_[k];
        if (!inside(o)) continue;
        const uint32_t x = static_cast<uint32_t>(int64_t{c_} + o.step);
        if (up_[x] != x) continue;
        mark_[x] = stamp_;
        list_.push_back({static_cast<uint64_t>(group_ + 1), x});
      }
    } else {
      // The roots that merged neighbours lead to, outside the neighbourhood (every root within it is
      // listed already), by squared distance, then id.
      const size_t first = list_.size();
      for (const Offset& o : offsets_) {
        if (!inside(o)) continue;
        const uint32_t x = static_cast<uint32_t>(int64_t{c_} + o.step);
        if (up_[x] == x) continue;
        const uint32_t q = root(x);
        if (q == c_ || mark_[q] == stamp_) continue;
        mark_[q] = stamp_;
        uint64_t d2 = 0;
        if (q < nodes_) {
          uint32_t gq[3];
          node(q, gq);
          for (int a = 0; a < 3; ++a) {
            const uint64_t d = gq[a] > g_[a] ? gq[a] - g_[a] : g_[a] - gq[a];
            d2 += d * d;  // no overflow: the dims' product is below 2^32
          }
        }
        list_.push_back({d2, q});
      }
      std::sort(list_.begin() + static_cast<std::ptrdiff_t>(first), list_.end(),
                [](const Keyed& a, const Keyed& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.v < b.v); });
    }
    ++group_;
  }
  void node(uint32_t g, uint32_t out[3]) const {
    const uint32_t jk = g / ni_;
    out[0] = g - jk * ni_;
    out[2] = jk / nj_;
    out[1] = jk - out[2] * nj_;
  }
  uint32_t root(uint32_t x) { return rootOf(up_, x); }
  uint32_t ni_, nj_, nk_;
  uint64_t nodes_;
  Offset offsets_[26];
  std::vector<uint32_t> up_, mark_;
  uint32_t stamp_ = 0;
  uint32_t c_ = 0;
  uint32_t g_[3] = {0, 0, 0};
  bool lo_[3] = {false, false, false}, hi_[3] = {false, false, false};
  int group_ = kGroups;
  std::vector<Keyed> list_;
};

// Version 3's parent index: the place i of the parent among `count` candidates, or count when it is
// not one of them (then the version 2 delta code follows). BitTree<4> s per boundary bit: s = i for
// i < 14, 14 and then i - 14 uniform in [0, count - 14) for i >= 14, 15 = not a candidate. Nothing is
// coded when there is no candidate.
constexpr uint32_t kIndexEscape = 15, kIndexLong = 14;

template <class C>
uint32_t codeParentIndex(C& c, BitTree<4>& model, uint32_t index, uint32_t count) {
  if (count == 0) return 0;
  const uint32_t s = model.code(c, index >= count ? kIndexEscape : std::min(index, kIndexLong));
  if (s == kIndexEscape) return count;
  if (s < kIndexLong) return s;               // the decoder checks s < count
  if (count <= kIndexLong) return count + 1;  // corrupt: rejected by the decoder
  return kIndexLong + codeUniform(c, index - kIndexLong, count - kIndexLong);
}

// The per-merge body of the payload (rank order), shared by the encoder (values in, returned
// unchanged) and the decoder (values out).
struct MergeCode {
  uint32_t child_index, boundary, exact, hit, choice, sign, len, low_bits, removed;
  uint32_t index;  // version 3: the parent's place among the candidates (= their count: not one)
};

template <class C>
void codeDelta(C& c, Models& m, MergeCode& v);

// Grid places' parent place, coded whatever the number of candidates (which the decoder learns only
// as far as the place): BitTree<4> s per boundary bit, s = i for i < 14, 14 and then i - 14 as a
// length code for i >= 14, 15 = not a candidate (kNoPlace). Sets *bad on a corrupt length.
template <class C>
uint32_t codeGridPlace(C& c, Models& m, uint32_t boundary, uint32_t place, bool* bad) {
  const bool none = place == GridCandidates::kNoPlace;
  const uint32_t s = m.index[boundary].code(c, none ? kIndexEscape : std::min(place, kIndexLong));
  if (s == kIndexEscape) return GridCandidates::kNoPlace;
  if (s < kIndexLong) return s;
  return kIndexLong + codeLength(c, m.far, none ? 0 : place - kIndexLong, bad);
}

// How a merge's parent is coded: version 3's candidates, version 4's grid places, or deltas only.
enum class ParentCode { kCandidates, kGridPlaces, kDeltas };

// Version 5's `inferred` bits: what the body leaves out because the decoder knows it.
constexpr uint8_t kInferRemoved = 1;   // the tetrahedra a merge removes (parent_form 3: StarCounter)
constexpr uint8_t kInferBoundary = 2;  // the child's boundary bit (parent_form 3: StarCounter)
constexpr uint8_t kOwnChildren = 4;    // the children are the level's vertices the next level lacks

// What follows the child's index (codeUniform over the vertices not merged yet), once the child and
// so its parent-delta predictions are known; `candidates` is the number of the child's parent
// candidates for ParentCode::kCandidates. v.index: the parent's place (kCandidates: the count when
// none; kGridPlaces: kNoPlace when none). Sets *bad on a corrupt code.
template <class C>
void codeMerge(C& c, Models& m, MergeCode& v, int predictions, ParentCode form, uint32_t candidates, bool* bad,
               uint8_t inferred) {
  if (!(inferred & kInferBoundary)) v.boundary = c.bit(m.boundary, v.boundary);
  bool delta = true;
  if (form == ParentCode::kCandidates) {
    v.index = codeParentIndex(c, m.index[v.boundary], v.index, candidates);
    delta = v.index == candidates;  // otherwise a candidate, or corrupt (the decoder rejects it)
  } else if (form == ParentCode::kGridPlaces) {
    v.index = codeGridPlace(c, m, v.boundary, v.index, bad);
    delta = v.index == GridCandidates::kNoPlace;
  }
  if (delta) {
    if (predictions > 0) v.exact = c.bit(m.exact[v.boundary], v.exact);
    if (v.exact) {
      v.hit = m.hit.code(c, v.hit);
    } else {
      codeDelta(c, m, v);
    }
  }
  if (inferred & kInferRemoved) return;
  const uint32_t k = m.removed[v.boundary].code(c, std::min<uint32_t>(v.removed, 15));
  v.removed = k == 15 ? c.direct(v.removed, 32) : k;
}

template <class C>
void codeDelta(C& c, Models& m, MergeCode& v) {
  v.choice = m.choice.code(c, v.choice);
  const int ctx = v.choice ? 1 : 0;
  v.len = m.len[ctx].code(c, v.len);
  if (v.len > 33) return;  // only a corrupt stream gets here; the decoder rejects it
  if (v.len > 0) {
    v.sign = c.bit(m.sign[ctx], v.sign);
    v.low_bits = c.direct(v.low_bits, static_cast<int>(v.len) - 1);
  }
}

// The numbers 1..M still free (here: decoding ids + 1 of the vertices not merged yet): one bit per
// number, and a Fenwick tree over the free counts of 64-number blocks, small enough to stay in cache.
class FreeRanks {
 public:
  explicit FreeRanks(uint32_t m) : bits_((size_t{m} + 63) / 64, ~uint64_t{0}), blocks_(bits_.size()) {
    if (m % 64) bits_.back() = (uint64_t{1} << (m % 64)) - 1;
    top_ = 1;
    while (top_ * 2 <= blocks_) top_ *= 2;
    // Padded to 2 * top_ with counts no search ever goes past, so that kth needs no bounds test.
    tree_.assign(2 * top_, UINT32_MAX);
    for (size_t b = 1; b <= blocks_; ++b) tree_[b] = 0;
    for (size_t b = 1; b <= blocks_; ++b) {
      tree_[b] += static_cast<uint32_t>(std::popcount(bits_[b - 1]));
      const size_t j = b + (b & (0 - b));
      if (j <= blocks_) tree_[j] += tree_[b];
    }
  }
  // Free ranks smaller than r.
  uint32_t countBelow(uint32_t r) const {
    const uint32_t i = r - 1;
    uint32_t s = 0;
    for (size_t b = i >> 6; b > 0; b -= b & (0 - b)) s += tree_[b];
    return s + static_cast<uint32_t>(std::popcount(bits_[i >> 6] & ((uint64_t{1} << (i & 63)) - 1)));
  }
  void take(uint32_t r) {
    const uint32_t i = r - 1;
    bits_[i >> 6] &= ~(uint64_t{1} << (i & 63));
    for (size_t b = (i >> 6) + 1; b <= blocks_; b += b & (0 - b)) tree_[b] -= 1;
  }
  // The (k+1)-th smallest free rank (k < free count). Without branches on the counts, which are
  // as good as random.
  uint32_t kth(uint32_t k) const {
    size_t pos = 0;
    uint32_t rem = k;  // free ranks still to skip
    for (size_t step = top_; step > 0; step >>= 1) {
      const uint32_t t = tree_[pos + step];
      const bool right = t <= rem;
      pos = right ? pos + step : pos;
      rem = right ? rem - t : rem;
    }
    // Block `pos` holds it: the rem-th set bit (from 0) of its word. Byte counts, their running
    // sums (each below 128), and the number of bytes whose running sum is at most rem.
    const uint64_t w = bits_[pos];
    constexpr uint64_t kOnes = 0x0101010101010101ull, kHigh = 0x8080808080808080ull;
    uint64_t c = w - ((w >> 1) & 0x5555555555555555ull);
    c = (c & 0x3333333333333333ull) + ((c >> 2) & 0x3333333333333333ull);
    c = (c + (c >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    const uint64_t sums = c * kOnes;
    const uint64_t le = (((rem * kOnes) | kHigh) - sums) & kHigh;
    const uint32_t byte = static_cast<uint32_t>(((le >> 7) * kOnes) >> 56);
    const uint32_t before = byte ? static_cast<uint32_t>(sums >> (8 * byte - 8)) & 0xFF : 0;
    uint32_t b = static_cast<uint32_t>(w >> (8 * byte)) & 0xFF;
    for (uint32_t j = before; j < rem; ++j) b &= b - 1;
    return static_cast<uint32_t>(pos * 64 + 8 * byte + std::countr_zero(b)) + 1;
  }

 private:
  std::vector<uint64_t> bits_;
  size_t blocks_;
  std::vector<uint32_t> tree_;
  size_t top_ = 1;
};

// Version 4's batches: a batch's size (the rule's, or coded), its children as a set (ascending ids,
// each as its gap among the vertices not merged yet after the previous one), and their order: runs,
// each a flag per child left in key order (ties to the smaller id), then the rest, each as its place
// among those left in key order.
struct BatchScratch {
  std::vector<uint32_t> ids;
  std::vector<std::pair<uint64_t, uint32_t>> keyed;
  std::vector<uint32_t> deferred;
  std::vector<uint8_t> flags;
};

uint32_t batchRule(uint64_t unmerged, uint64_t left, uint32_t divisor) {
  return static_cast<uint32_t>(std::min<uint64_t>((unmerged + divisor - 1) / divisor, left));
}

template <class Key>
void sortByKey(BatchScratch& w, const Key& key) {
  w.keyed.clear();
  for (uint32_t id : w.ids) w.keyed.emplace_back(key(id), id);
  std::sort(w.keyed.begin(), w.keyed.end());
}

// `seq`: the batch's children (decoding ids) in rank order; `place`: scratch of P entries.
// `all_left`: the batch's children are known to be every vertex left in `unmerged` (version 5's own
// children, last batch): no gap is coded.
template <class Key>
void encodeBatch(EntropyCoder<true>& rc, Models& m, FreeRanks& unmerged, uint32_t rule, std::span<const uint32_t> seq,
                 bool all_left, const Key& key, BatchScratch& w, std::vector<uint32_t>& place) {
  const uint32_t size = static_cast<uint32_t>(seq.size());
  bool bad = false;
  rc.bit(m.rule, size == rule);
  if (size != rule) codeLength(rc, m.size, size, &bad);
  w.ids.assign(seq.begin(), seq.end());
  std::sort(w.ids.begin(), w.ids.end());
  uint32_t pos = 0;
  for (uint32_t id : w.ids) {
    const uint32_t at = unmerged.countBelow(id + 1);
    if (!all_left) codeLength(rc, m.gap, at - pos, &bad);
    unmerged.take(id + 1);
    pos = at;
  }
  if (size == 1) return;
  sortByKey(w, key);
  for (uint32_t k = 0; k < size; ++k) place[w.keyed[k].second] = k;
  // The rank order as runs, each in key order (each the longest that is): a run is coded as a flag per
  // child left, in key order, while that is cheaper than coding the rest's order outright.
  w.deferred.clear();  // the children left, in key order
  for (const auto& [k, id] : w.keyed) w.deferred.push_back(id);
  std::vector<uint8_t>& in_run = w.flags;
  uint32_t done = 0;
  for (uint32_t pass = 0; w.deferred.size() > 1; ++pass) {
    const uint32_t left = static_cast<uint32_t>(w.deferred.size());
    uint32_t run = 1;
    while (done + run < size && place[seq[done + run]] > place[seq[done + run - 1]]) ++run;
    if (!runPays(run, left)) {
      rc.bit(m.pass[std::min(pass, 3u)], 0);
      break;
    }
    rc.bit(m.pass[std::min(pass, 3u)], 1);
    in_run.assign(size, 0);
    for (uint32_t j = done; j < done + run; ++j) in_run[place[seq[j]]] = 1;
    uint32_t prev = 0, kept = 0;
    for (uint32_t id : w.deferred) {
      const uint32_t flag = in_run[place[id]];
      rc.bit(m.in_run[std::min(pass, 2u)][prev], flag);
      prev = flag;
      if (!flag) w.deferred[kept++] = id;
    }
    w.deferred.resize(kept);
    done += run;
  }
  // The rest in rank order, each as its place among those left, in key order.
  const uint32_t left = static_cast<uint32_t>(w.deferred.size());
  if (left <= 1) return;
  for (uint32_t k = 0; k < left; ++k) place[w.deferred[k]] = k;
  FreeRanks rest(left);
  for (uint32_t j = done; j < size; ++j) {
    const uint32_t d = place[seq[j]];
    codeUniform(rc, rest.countBelow(d + 1), left - (j - done));
    rest.take(d + 1);
  }
}

// Decodes a batch of at most `most` children into `seq`, in their merge order; false on a corrupt
// batch. `own`: the children are drawn from `unmerged` (unmerged_count of them) as version 5's own
// children, and a batch of all of them codes no gap.
template <class Key>
bool decodeBatch(EntropyCoder<false>& rc, Models& m, FreeRanks& unmerged, uint64_t unmerged_count, uint32_t rule,
                 uint64_t most, bool own, const Key& key, BatchScratch& w, std::vector<uint32_t>& seq) {
  bool bad = false;
  uint64_t size = rule;
  if (!rc.bit(m.rule, 0)) size = codeLength(rc, m.size, 0, &bad);
  if (bad || size == 0 || size > most || !rc.ok()) return false;
  const bool all_left = own && size == unmerged_count;
  w.ids.clear();
  uint64_t pos = 0;
  for (uint64_t j = 0; j < size; ++j) {
    const uint64_t at = all_left ? 0 : pos + codeLength(rc, m.gap, 0, &bad);
    if (bad || at >= unmerged_count - j || !rc.ok()) return false;
    const uint32_t id = unmerged.kth(static_cast<uint32_t>(at)) - 1;
    unmerged.take(id + 1);
    w.ids.push_back(id);
    pos = at;
  }
  seq.clear();
  if (size == 1) {
    seq.push_back(w.ids[0]);
    return true;
  }
  sortByKey(w, key);
  w.deferred.clear();
  for (const auto& [k, id] : w.keyed) w.deferred.push_back(id);
  for (uint32_t pass = 0; w.deferred.size() > 1; ++pass) {
    if (!rc.bit(m.pass[std::min(pass, 3u)], 0)) break;
    uint32_t prev = 0, kept = 0;
    const size_t first = seq.size();
    for (uint32_t id : w.deferred) {
      prev = rc.bit(m.in_run[std::min(pass, 2u)][prev], 0);
      if (prev) seq.push_back(id);
      else w.deferred[kept++] = id;
    }
    if (seq.size() == first || !rc.ok()) return false;  // an empty run: corrupt
    w.deferred.resize(kept);
  }
  const uint32_t left = static_cast<uint32_t>(w.deferred.size());
  if (left == 1) seq.push_back(w.deferred[0]);
  if (left <= 1) return rc.ok();
  FreeRanks rest(left);
  for (uint32_t j = 0; j < left; ++j) {
    const uint32_t x = codeUniform(rc, 0, left - j);
    if (x >= left - j) return false;
    const uint32_t d = rest.kth(x) - 1;
    rest.take(d + 1);
    seq.push_back(w.deferred[d]);
  }
  return rc.ok();
}

void putVarint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}

void putF64(std::vector<uint8_t>& out, double d) {
  uint8_t b[8];
  std::memcpy(b, &d, 8);  // the project assumes a little-endian host
  out.insert(out.end(), b, b + 8);
}

void putF32(std::vector<uint8_t>& out, float f) {
  uint8_t b[4];
  std::memcpy(b, &f, 4);
  out.insert(out.end(), b, b + 4);
}

class Reader {
 public:
  Reader(std::span<const uint8_t> in, const std::string& what) : in_(in), what_(what) {}
  Status varint(uint64_t* v, const char* field) {
    uint64_t result = 0;
    for (int shift = 0; shift < 70; shift += 7) {
      if (pos_ >= in_.size()) return error(field, "truncated");
      const uint8_t b = in_[pos_++];
      if (shift == 63 && (b & 0x7E)) return error(field, "varint overflows 64 bits");
      result |= uint64_t{b & 0x7Fu} << shift;
      if (!(b & 0x80)) {
        *v = result;
        return Status::ok();
      }
    }
    return error(field, "varint longer than 10 bytes");
  }
  Status u8(uint8_t* v, const char* field) {
    if (pos_ >= in_.size()) return error(field, "truncated");
    *v = in_[pos_++];
    return Status::ok();
  }
  Status f64(double* v, const char* field) {
    if (in_.size() - pos_ < 8) return error(field, "truncated");
    std::memcpy(v, in_.data() + pos_, 8);
    pos_ += 8;
    return Status::ok();
  }
  Status f32(double* v, const char* field) {
    if (in_.size() - pos_ < 4) return error(field, "truncated");
    float f;
    std::memcpy(&f, in_.data() + pos_, 4);
    pos_ += 4;
    *v = f;
    return Status::ok();
  }
  Status bytes(uint64_t n, std::span<const uint8_t>* out, const char* field) {
    if (n > in_.size() - pos_) return error(field, "length exceeds the payload");
    *out = in_.subspan(pos_, n);
    pos_ += n;
    return Status::ok();
  }
  Status error(const char* field, const std::string& why) const {
    return invalidData(what_ + ": merge tree payload, byte " + std::to_string(pos_) + " (" + field + "): " + why);
  }
  size_t pos() const { return pos_; }
  size_t size() const { return in_.size(); }

 private:
  std::span<const uint8_t> in_;
  size_t pos_ = 0;
  const std::string& what_;
};

constexpr uint8_t kVersion2 = 2, kVersion3 = 3, kVersion4 = 4, kVersion5 = 5;

// The header fields of every version (free_merges is version 3's and 4's; parent_form and divisor
// version 4's, and parent_form is 3 in version 3; grid is parent_form 4's).
constexpr uint8_t kParentDeltas = 2, kParentCandidates = 3, kParentGrid = 4;
struct Header {
  uint8_t version = 0, parent_form = kParentDeltas, inferred = 0;
  uint64_t points = 0, merges = 0, boundary_merges = 0, tets_removed = 0, free_merges = 0, divisor = 0;
  std::array<uint32_t, 3> grid = {0, 0, 0};
  bool candidates() const { return parent_form == kParentCandidates; }
  std::span<const uint8_t> body;
};

// The tetrahedra of `mesh` as 4 ids each, after checking that they name its points.
StatusOr<std::span<const uint32_t>> tetIds(const TetMesh& mesh, const std::string& what) {
  std::span<const uint32_t> ids(mesh.tets.empty() ? nullptr : mesh.tets.front().data(), 4 * mesh.tets.size());
  const size_t n = mesh.numPoints();
  for (size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] >= n)
      return invalidData(what + ": tetrahedron " + std::to_string(i / 4) + " names a vertex out of range");
  }
  return ids;
}

}  // namespace

uint64_t leadingFreeMerges(const MergeTree& tree) {
  std::vector<uint8_t> free(tree.merges, 0);
  for (size_t v = 0; v < tree.points(); ++v) {
    if (tree.rank[v] == 0 || tree.rank[v] > tree.merges) continue;
    free[tree.rank[v] - 1] = tree.removed[v] == 0 && !tree.boundary[v];
  }
  uint64_t u = 0;
  while (u < free.size() && free[u]) ++u;
  return u;
}

StatusOr<std::vector<uint8_t>> encodeMergeTree(const MergeTree& tree, const std::vector<uint32_t>& vertex_order,
                                               const TetMesh* mesh) {
  return encodeMergeTree(tree, vertex_order, mesh, MergeTreeForm{mesh ? kVersion3 : kVersion2, mesh != nullptr});
}

StatusOr<std::vector<uint8_t>> encodeMergeTree(const MergeTree& tree, const std::vector<uint32_t>& vertex_order,
                                               const TetMesh* mesh, const MergeTreeForm& form) {
  GTN_RETURN_IF_ERROR(tree.check("merge tree"));
  const size_t n = tree.points();
  if (vertex_order.size() != n) return invalidData("merge tree: vertex order has the wrong size");
  if (n > 0xFFFFFFF0u) return unsupported("merge tree: more than 2^32 - 16 vertices");
  if (form.version < kVersion2 || form.version > kVersion5) return usageError("merge tree: no such payload version");
  const uint8_t version = form.version;
  const bool batched = version >= kVersion4;
  const bool with_candidates = version == kVersion3 || (batched && form.candidates);
  if (with_candidates && !mesh) return usageError("merge tree: parent candidates are coded against the level's mesh");
  const uint64_t grid_nodes = uint64_t{form.grid[0]} * form.grid[1] * form.grid[2];
  const bool with_grid = batched && !with_candidates && grid_nodes > 0;
  if (with_grid && grid_nodes > n) return usageError("merge tree: a grid of more nodes than the tree has vertices");
  if (mesh && mesh->numPoints() != n) return invalidData("merge tree: the mesh and the tree differ in vertices");
  // inverse[id] = source vertex with decoding id `id`.
  std::vector<uint32_t> inverse(n, MergeTree::kRoot);
  for (size_t v = 0; v < n; ++v) {
    const uint32_t id = vertex_order[v];
    if (id >= n || inverse[id] != MergeTree::kRoot) return invalidData("merge tree: vertex order is not a permutation");
    inverse[id] = static_cast<uint32_t>(v);
  }
  // Version 5: the children among the level's own vertices where it names the next level's (they are
  // then exactly the tree's children), and with candidates, the removed counts and boundary bits left
  // to the decoder where the level's mesh gives them (tried, and dropped if a merge disagrees).
  uint8_t inferred = 0;
  if (version == kVersion5 && form.next_index) {
    if (form.next_index->size() != n) return invalidData("merge tree: the next level's ids have the wrong size");
    for (size_t v = 0; v < n; ++v)
      if ((tree.parent[v] == MergeTree::kRoot) == ((*form.next_index)[v] == kNoIndex))
        return invalidData("merge tree: vertex " + std::to_string(v) +
                           (tree.parent[v] == MergeTree::kRoot ? " is neither merged nor a vertex of the next level"
                                                               : " is merged but also a vertex of the next level"));
    inferred |= kOwnChildren;
  }
  if (version == kVersion5 && with_candidates) inferred |= kInferRemoved | kInferBoundary;
  const uint32_t divisor = tree.batch_divisor ? tree.batch_divisor : kDefaultBatchDivisor;
  std::span<const uint32_t> tets;
  if (with_candidates) {
    GTN_ASSIGN_OR_RETURN(tets, tetIds(*mesh, "merge tree"));
  }
  // by_rank[r - 1] = decoding id of the vertex merged at rank r.
  std::vector<uint32_t> by_rank(tree.merges);
  for (size_t v = 0; v < n; ++v) {
    if (tree.parent[v] != MergeTree::kRoot) by_rank[tree.rank[v] - 1] = vertex_order[v];
  }
  auto key = [&](uint32_t id) {
    return with_candidates ? batchKeyOfPoint(mesh->coords.data() + 3 * size_t{inverse[id]}) : batchKeyOfId(id);
  };
  // The body with the given inferred bits; false where a merge's removed count or boundary bit is not
  // what the level gives (the caller then codes them).
  std::vector<uint8_t> body;
  auto codeBody = [&](uint8_t inferring) -> bool {
    body.clear();
    EntropyCoder<true> rc(&body);
    Models m;
    std::optional<ParentCandidates> candidates;
    std::optional<StarCounter> stars;
    if (with_candidates) {
      VertexTets vt = vertexTets(n, tets);
      candidates.emplace(n, tets, vt, mesh->coords.data(), vertex_order.data());
      if (inferring & (kInferRemoved | kInferBoundary)) stars.emplace(n, tets, std::move(vt));
    }
    std::optional<GridCandidates> grid;
    if (with_grid) grid.emplace(n, form.grid);
    const ParentCode parent_code = with_candidates ? ParentCode::kCandidates
                                   : with_grid     ? ParentCode::kGridPlaces
                                                   : ParentCode::kDeltas;
    FreeRanks unmerged(static_cast<uint32_t>(n));  // decoding ids + 1 of the vertices not merged yet
    uint64_t own_left = n;                         // of them, those the batches draw from
    if (inferring & kOwnChildren) {
      for (size_t v = 0; v < n; ++v)
        if (tree.parent[v] == MergeTree::kRoot) unmerged.take(vertex_order[v] + 1);
      own_left = tree.merges;
    }
    std::vector<uint32_t> coded_parent(n, MergeTree::kRoot);  // decoding ids, merges coded so far
    BatchScratch scratch;
    std::vector<uint32_t> place(batched ? n : 0);
    uint64_t batch_end = 0;
    size_t batch = 0;
    // What a merge reads lies anywhere in arrays of a vertex each: on a large grid their loads are
    // started a few merges ahead, in the order they depend on each other (the child's id, then its
    // vertex, then its parent's id).
    constexpr uint64_t kAhead = 16;
    for (uint64_t r = 0; r < tree.merges; ++r) {
      if (r + kAhead < tree.merges) __builtin_prefetch(&inverse[by_rank[r + kAhead]]);
      if (r + kAhead / 2 < tree.merges) {
        const uint32_t id2 = by_rank[r + kAhead / 2], v2 = inverse[id2];
        __builtin_prefetch(&tree.parent[v2]);
        __builtin_prefetch(&tree.boundary[v2]);
        __builtin_prefetch(&tree.removed[v2]);
        __builtin_prefetch(&coded_parent[id2]);
        if (grid) grid->prefetch(id2);
      }
      if (r + kAhead / 4 < tree.merges)
        __builtin_prefetch(&vertex_order[tree.parent[inverse[by_rank[r + kAhead / 4]]]]);
      if (batched && r == batch_end) {
        const uint32_t rule = batchRule(n - r, tree.merges - r, divisor);
        const uint32_t size = tree.batches.empty() ? rule : tree.batches[batch++];
        encodeBatch(rc, m, unmerged, rule, std::span<const uint32_t>(by_rank.data() + r, size),
                    (inferring & kOwnChildren) && size == own_left, key, scratch, place);
        own_left -= size;
        batch_end = r + size;
      }
      const uint32_t id = by_rank[r];
      const uint32_t v = inverse[id];
      MergeCode code{};
      uint32_t count = 0;
      const uint32_t pid = vertex_order[tree.parent[v]];
      if (stars) {
        stars->gather(v);
        if ((inferring & kInferBoundary) && stars->boundary() != (tree.boundary[v] != 0)) return false;
        if (stars->merge(v, tree.parent[v]) != tree.removed[v] && (inferring & kInferRemoved)) return false;
      }
      if (candidates) {
        count = candidates->gather(v);
        code.index = candidates->placeOf(tree.parent[v]);
        candidates->merge(v, tree.parent[v]);
      } else if (grid) {
        grid->begin(id);
        code.index = grid->placeOf(pid);
        grid->merge(id, pid);
      }
      const int64_t delta = int64_t{pid} - int64_t{id};
      int64_t residual = delta;
      const DeltaPredictions pred(coded_parent, id);
      for (int k = 0; k < pred.count; ++k) {
        const int64_t d = delta - pred.d[k];
        if (d == 0 && !code.exact) {
          code.exact = 1;
          code.hit = static_cast<uint32_t>(k);
        }
        if (std::llabs(d) < std::llabs(residual)) {
          residual = d;
          code.choice = static_cast<uint32_t>(k + 1);
        }
      }
      coded_parent[id] = pid;
      const uint64_t mag = static_cast<uint64_t>(std::llabs(residual));
      code.len = static_cast<uint32_t>(bitLength(mag));
      code.sign = residual < 0 ? 1 : 0;
      code.low_bits = code.len > 1 ? static_cast<uint32_t>(mag & ((uint64_t{1} << (code.len - 1)) - 1)) : 0;
      code.boundary = tree.boundary[v] ? 1 : 0;
      code.removed = tree.removed[v];
      if (!batched) {
        code.child_index = unmerged.countBelow(id + 1);
        codeUniform(rc, code.child_index, static_cast<uint32_t>(n - r));
        unmerged.take(id + 1);
      }
      bool bad = false;
      codeMerge(rc, m, code, pred.count, parent_code, count, &bad, inferring);
    }
    rc.finish();
    return true;
  };
  if (!codeBody(inferred)) {
    inferred &= kOwnChildren;
    codeBody(inferred);
  }

  std::vector<uint8_t> out;
  out.push_back(version);
  putVarint(out, n);
  putVarint(out, tree.merges);
  putVarint(out, tree.boundaryMergesUpTo(tree.merges));
  putVarint(out, tree.tetsRemovedUpTo(tree.merges));
  if (version >= kVersion3) putVarint(out, leadingFreeMerges(tree));
  if (batched) {
    out.push_back(with_candidates ? kParentCandidates : with_grid ? kParentGrid : kParentDeltas);
    if (with_grid)
      for (uint32_t d : form.grid) putVarint(out, d);
    putVarint(out, divisor);
    if (version == kVersion5) out.push_back(inferred);
  }
  putF64(out, tree.w_density);
  putF64(out, tree.w_geometry);
  putVarint(out, tree.field.size());
  out.insert(out.end(), tree.field.begin(), tree.field.end());
  const size_t q = tree.error_quantiles.size() == 9 ? 9 : 0;
  out.push_back(static_cast<uint8_t>(q));
  // Version 5 stores the quantiles as f32: they are merges' errors, which the ranking keeps as float.
  for (size_t i = 0; i < q; ++i) {
    if (version == kVersion5) putF32(out, static_cast<float>(tree.error_quantiles[i]));
    else putF64(out, tree.error_quantiles[i]);
  }
  putVarint(out, body.size());
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

namespace {

StatusOr<Header> readHeader(Reader& r, uint64_t expected_points, MergeTree* tree) {
  Header h;
  GTN_RETURN_IF_ERROR(r.u8(&h.version, "version"));
  if (h.version < kVersion2 || h.version > kVersion5)
    return r.error("version", "unsupported version " + std::to_string(h.version));
  GTN_RETURN_IF_ERROR(r.varint(&h.points, "points"));
  if (h.points != expected_points)
    return r.error("points", std::to_string(h.points) + " vertices, the level has " + std::to_string(expected_points));
  if (h.points > 0xFFFFFFF0u) return r.error("points", "more than 2^32 - 16 vertices");
  GTN_RETURN_IF_ERROR(r.varint(&h.merges, "merges"));
  if (h.merges > h.points) return r.error("merges", "more merges than vertices");
  GTN_RETURN_IF_ERROR(r.varint(&h.boundary_merges, "boundary_merges"));
  if (h.boundary_merges > h.merges) return r.error("boundary_merges", "more boundary merges than merges");
  GTN_RETURN_IF_ERROR(r.varint(&h.tets_removed, "tets_removed"));
  if (h.version >= kVersion3) {
    GTN_RETURN_IF_ERROR(r.varint(&h.free_merges, "free_merges"));
    if (h.free_merges > h.merges - h.boundary_merges) return r.error("free_merges", "more than the interior merges");
    h.parent_form = 3;
  }
  if (h.version >= kVersion4) {
    GTN_RETURN_IF_ERROR(r.u8(&h.parent_form, "parent_form"));
    if (h.parent_form < kParentDeltas || h.parent_form > kParentGrid)
      return r.error("parent_form", "must be 2, 3 or 4");
    if (h.parent_form == kParentGrid) {
      uint64_t nodes = 1;
      for (uint32_t& d : h.grid) {
        uint64_t v = 0;
        GTN_RETURN_IF_ERROR(r.varint(&v, "grid dims"));
        if (v == 0 || v > h.points) return r.error("grid dims", "must be 1 to the vertex count");
        nodes *= v;  // both factors below 2^32: no overflow
        if (nodes > h.points) return r.error("grid dims", "more grid nodes than vertices");
        d = static_cast<uint32_t>(v);
      }
    }
    GTN_RETURN_IF_ERROR(r.varint(&h.divisor, "batch_divisor"));
    if (h.divisor == 0 || h.divisor > 0xFFFFFFFFu) return r.error("batch_divisor", "must be 1 to 2^32 - 1");
  }
  if (h.version == kVersion5) {
    GTN_RETURN_IF_ERROR(r.u8(&h.inferred, "inferred"));
    if (h.inferred & ~(kInferRemoved | kInferBoundary | kOwnChildren))
      return r.error("inferred", "unknown bits " + std::to_string(h.inferred));
    if ((h.inferred & (kInferRemoved | kInferBoundary)) && h.parent_form != kParentCandidates)
      return r.error("inferred", "removed counts and boundary bits are inferred only with parents as candidates");
  }
  GTN_RETURN_IF_ERROR(r.f64(&tree->w_density, "w_density"));
  GTN_RETURN_IF_ERROR(r.f64(&tree->w_geometry, "w_geometry"));
  uint64_t name_len = 0;
  GTN_RETURN_IF_ERROR(r.varint(&name_len, "field name length"));
  std::span<const uint8_t> name;
  GTN_RETURN_IF_ERROR(r.bytes(name_len, &name, "field name"));
  tree->field.assign(name.begin(), name.end());
  uint8_t q = 0;
  GTN_RETURN_IF_ERROR(r.u8(&q, "quantile count"));
  if (q != 0 && q != 9) return r.error("quantile count", "must be 0 or 9");
  for (int i = 0; i < q; ++i) {
    double d = 0;
    GTN_RETURN_IF_ERROR(h.version == kVersion5 ? r.f32(&d, "quantile") : r.f64(&d, "quantile"));
    tree->error_quantiles.push_back(d);
  }
  uint64_t body_len = 0;
  GTN_RETURN_IF_ERROR(r.varint(&body_len, "body length"));
  GTN_RETURN_IF_ERROR(r.bytes(body_len, &h.body, "body"));
  if (r.pos() != r.size()) return r.error("end", "trailing bytes after the body");
  return h;
}

}  // namespace

StatusOr<MergeTreeHeader> readMergeTreeHeader(std::span<const uint8_t> payload, uint64_t expected_points,
                                              const std::string& what) {
  Reader r(payload, what);
  MergeTree scratch;
  GTN_ASSIGN_OR_RETURN(Header h, readHeader(r, expected_points, &scratch));
  MergeTreeHeader out;
  out.version = h.version;
  out.merges = h.merges;
  out.boundary_merges = h.boundary_merges;
  out.tets_removed = h.tets_removed;
  out.free_merges = h.free_merges;
  out.candidates = h.candidates();
  out.needs_mesh = h.candidates();
  out.needs_next_ids = (h.inferred & kOwnChildren) != 0;
  out.inferred = h.inferred;
  out.grid = h.grid;
  return out;
}

// How many merges ahead decodeMergeTree starts loading what a merge reads.
constexpr size_t kDecodeAhead = 8;

StatusOr<MergeTree> decodeMergeTree(std::span<const uint8_t> payload, uint64_t expected_points, const std::string& what,
                                    const TetMesh* mesh, uint64_t max_merges, const std::vector<uint32_t>* next_ids) {
  Reader r(payload, what);
  MergeTree tree;
  GTN_ASSIGN_OR_RETURN(Header h, readHeader(r, expected_points, &tree));
  const size_t n = h.points;
  const uint64_t decode = std::min(h.merges, max_merges);
  std::optional<GridCandidates> grid;
  if (h.parent_form == kParentGrid && decode > 0) grid.emplace(n, h.grid);
  const ParentCode parent_code = h.candidates()                 ? ParentCode::kCandidates
                                 : h.parent_form == kParentGrid ? ParentCode::kGridPlaces
                                                                : ParentCode::kDeltas;
  std::optional<ParentCandidates> candidates;
  std::optional<StarCounter> stars;
  if (h.candidates() && decode > 0) {
    if (!mesh)
      return usageError(what + ": the merge tree (version " + std::to_string(h.version) +
                        ") is decoded against its level, which was not decoded");
    if (mesh->numPoints() != n)
      return invalidData(what + ": the merge tree has " + std::to_string(n) + " vertices, its level's mesh " +
                         std::to_string(mesh->numPoints()));
    GTN_ASSIGN_OR_RETURN(std::span<const uint32_t> tets, tetIds(*mesh, what));
    VertexTets vt = vertexTets(n, tets);
    candidates.emplace(n, tets, vt, mesh->coords.data(), nullptr);
    if (h.inferred & (kInferRemoved | kInferBoundary)) stars.emplace(n, tets, std::move(vt));
  }
  tree.makeRoots(n);
  tree.merges = decode;
  if (h.version >= kVersion4) tree.batch_divisor = static_cast<uint32_t>(h.divisor);
  EntropyCoder<false> rc(h.body);
  Models m;
  FreeRanks unmerged(static_cast<uint32_t>(n));
  uint64_t own_left = n;  // the vertices the batches draw their children from, not merged yet
  const bool own = (h.inferred & kOwnChildren) != 0;
  if (own && decode > 0) {
    if (!next_ids)
      return usageError(what +
                        ": the merge tree (version 5) is decoded knowing which of its level's vertices the "
                        "next level has (the level names none, or they were not given)");
    if (next_ids->size() != n)
      return invalidData(what + ": the merge tree has " + std::to_string(n) + " vertices, the next level's ids " +
                         std::to_string(next_ids->size()));
    own_left = 0;
    for (uint32_t v = 0; v < n; ++v) {
      if ((*next_ids)[v] != kNoIndex) unmerged.take(v + 1);
      else ++own_left;
    }
    if (own_left != h.merges)
      return invalidData(what + ": the merge tree has " + std::to_string(h.merges) + " merges, its level " +
                         std::to_string(own_left) + " vertices the next level lacks");
  }
  uint64_t got_boundary = 0, got_removed = 0;
  auto bodyError = [&](uint64_t r, const std::string& why) {
    return invalidData(what + ": merge tree payload body, merge " + std::to_string(r + 1) + ": " + why);
  };
  BatchScratch scratch;
  std::vector<uint32_t> seq;
  size_t next = 0;
  auto key = [&](uint32_t id) {
    return h.candidates() ? batchKeyOfPoint(mesh->coords.data() + 3 * size_t{id}) : batchKeyOfId(id);
  };
  for (uint64_t r = 0; r < decode; ++r) {
    MergeCode code{};
    uint32_t id = 0;
    if (h.version >= kVersion4) {
      if (next == seq.size()) {
        const uint32_t rule = batchRule(n - r, h.merges - r, static_cast<uint32_t>(h.divisor));
        if (!decodeBatch(rc, m, unmerged, own ? own_left : n - r, rule, h.merges - r, own, key, scratch, seq))
          return bodyError(r, "batch corrupt or out of range");
        if (own) own_left -= seq.size();
        next = 0;
        tree.batches.push_back(static_cast<uint32_t>(std::min<uint64_t>(seq.size(), decode - r)));
      }
      id = seq[next++];
      // The batch's children are known: what a merge reads around one (its neighbours' parents and,
      // on a grid, their union-find entries) is loaded a few merges ahead (encodeMergeTree does so).
      if (next + kDecodeAhead <= seq.size()) {
        const uint32_t ahead = seq[next + kDecodeAhead - 1];
        __builtin_prefetch(&tree.parent[ahead]);
        __builtin_prefetch(&tree.rank[ahead]);
        if (grid) grid->prefetch(ahead);
      }
    } else {
      code.child_index = codeUniform(rc, 0, static_cast<uint32_t>(n - r));
      if (code.child_index >= n - r) return bodyError(r, "child out of range");
      id = unmerged.kth(code.child_index) - 1;
      unmerged.take(id + 1);
    }
    const DeltaPredictions pred(tree.parent, id);
    const uint32_t count = candidates ? candidates->gather(id) : 0;
    if (grid) grid->begin(id);
    if (stars) {
      stars->gather(id);
      if (h.inferred & kInferBoundary) code.boundary = stars->boundary() ? 1 : 0;
    }
    bool bad = false;
    codeMerge(rc, m, code, pred.count, parent_code, count, &bad, h.inferred);
    if (!rc.ok() || bad) return bodyError(r, "body truncated or corrupt");
    uint32_t pid = 0;
    if (candidates && code.index < count) {
      pid = candidates->at(code.index);
    } else if (grid && code.index != GridCandidates::kNoPlace) {
      if (!grid->has(code.index)) return bodyError(r, "parent candidate out of range");
      pid = grid->at(code.index);
    } else {
      if (candidates && code.index > count) return bodyError(r, "parent candidate out of range");
      int64_t delta;
      if (code.exact) {
        if (code.hit >= static_cast<uint32_t>(pred.count)) return bodyError(r, "parent prediction out of range");
        delta = pred.d[code.hit];
      } else {
        if (code.len > 33) return bodyError(r, "parent delta too long");
        if (code.choice > static_cast<uint32_t>(pred.count)) return bodyError(r, "parent predictor out of range");
        const int64_t mag = code.len == 0 ? 0 : static_cast<int64_t>((uint64_t{1} << (code.len - 1)) | code.low_bits);
        delta = (code.choice ? pred.d[code.choice - 1] : 0) + (code.sign ? -mag : mag);
      }
      const int64_t pid64 = int64_t{id} + delta;
      if (delta == 0 || pid64 < 0 || pid64 >= static_cast<int64_t>(n)) return bodyError(r, "parent id out of range");
      pid = static_cast<uint32_t>(pid64);
    }
    // The parent must still be alive: merged later (a larger rank) or never.
    if (tree.parent[pid] != MergeTree::kRoot) return bodyError(r, "merges into a vertex merged earlier");
    if (candidates) candidates->merge(id, pid);
    if (grid) grid->merge(id, pid);
    if (stars) {
      const uint32_t removed = stars->merge(id, pid);
      if (h.inferred & kInferRemoved) code.removed = removed;
    }
    tree.parent[id] = pid;
    tree.rank[id] = static_cast<uint32_t>(r + 1);
    tree.boundary[id] = static_cast<uint8_t>(code.boundary);
    tree.removed[id] = code.removed;
    got_boundary += code.boundary;
    got_removed += code.removed;
  }
  tree.checked = true;                 // every record was checked as it was decoded
  if (decode < h.merges) return tree;  // a prefix: the rest of the body is not read
  if (!rc.finishedCleanly())
    return invalidData(what + ": merge tree payload body truncated, corrupt or followed by trailing bytes");
  if (got_boundary != h.boundary_merges || got_removed != h.tets_removed)
    return invalidData(what + ": merge tree payload counts disagree with its header");
  if (h.version >= kVersion3 && leadingFreeMerges(tree) != h.free_merges)
    return invalidData(what + ": merge tree payload's free_merges disagrees with its records");
  return tree;
}

}  // namespace gtn
