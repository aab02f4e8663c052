#include "simplify/ranking.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include "codec/edge_points.h"
#include "codec/grid_coder.h"
#include "mesh/faces.h"
#include "mesh/fresh_memory.h"
#include "mesh/index.h"
#include "mesh/longest_first.h"
#include "mesh/mesh_stats.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {

constexpr uint32_t kOmega = 0xFFFFFFFEu;  // the virtual vertex coning the boundary
constexpr double kFlipMargin = 1e-3;
constexpr double kLocalWeight = 1.0 / 16;  // see ranking.h
// A vertex in more tetrahedra than this is neither merged nor merged onto (while its star is that
// large): evaluating a vertex costs its star times its targets, and it is evaluated again after every
// merge next to it, so a star of S tetrahedra costs about S^3 (a book of 1000 tetrahedra around one
// edge ran for minutes). Real meshes stay far below: the largest star of the shared datasets is 110.
constexpr uint32_t kMaxStar = 256;

// The passes between the rounds over the tetrahedra or the vertices (the seams, the runs' live
// corners) run in parallel in blocks of kBlock items; what they find does not depend on the threads.
constexpr size_t kBlock = size_t{1} << 14;
// Partitions split the two sides of a cut at once from this many vertices.
constexpr size_t kParallelSplit = size_t{1} << 16;

// Calls f(begin, end) for the blocks [b * kBlock, (b + 1) * kBlock) of [0, n), in parallel. Like
// every parallel step of the ranking, isolated: while the ranking's thread waits for its share, it
// takes no task from outside the ranking (a level being encoded beside it, say), which would hold up
// the ranking for as long as that task runs.
template <class F>
void parallelBlocks(size_t n, F&& f) {
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(size_t{0}, (n + kBlock - 1) / kBlock,
                      [&](size_t b) { f(b * kBlock, std::min(n, (b + 1) * kBlock)); });
  });
}

// Sets a per-vertex flag that other threads may set too (never clear) at the same time.
inline void setFlag(uint8_t& flag) { std::atomic_ref<uint8_t>(flag).store(1, std::memory_order_relaxed); }

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

struct BoundaryFace {
  uint32_t x, y;  // the face is (v, x, y), outward
  double n[3];
  double area;
};

inline double norm1(const double* a, const double* b) {
  return std::fabs(b[0] - a[0]) + std::fabs(b[1] - a[1]) + std::fabs(b[2] - a[2]);
}

// Whether the boundary triangle f = (v, x, y) still faces its old way once v moves from pv to pw;
// n_new receives its new normal. The margin on the angle is not enough on its own: when the new
// triangle is flat up to rounding, n_new is rounding noise and its angle to the old normal anything,
// and the validator's exact sign (validate/merge_checks.cpp) may come out negative. So the dot
// product must also exceed a bound on its rounding error (a few ulp of the product of the edge
// lengths; 1e-12 of it, the validator's filter too, is far above) so that its sign is certain.
inline bool keepsFacing(const double* pv, const double* pw, const double* px, const double* py, const BoundaryFace& f,
                        double* n_new) {
  triNormal(pw, px, py, n_new);
  const double d = dot(f.n, n_new);
  const double rounding = 1e-12 * norm1(pv, px) * norm1(pv, py) * norm1(pw, px) * norm1(pw, py);
  return d > kFlipMargin * norm(f.n) * norm(n_new) && d > rounding;
}

struct Candidate {
  double error;
  uint32_t w;
};

struct QueueEntry {
  float error;
  uint32_t v, w;
  bool operator<(const QueueEntry& o) const {
    if (error != o.error) return error < o.error;
    if (v != o.v) return v < o.v;
    return w < o.w;
  }
};

// The candidates, one per vertex at most, in a binary min-heap by (error, v, w) that knows where each
// vertex's entry is, so that a vertex evaluated again replaces its entry in place. The order is a
// total one over distinct vertices, so the entries come out in the same order as from any other
// priority queue of the same entries; the heap holds at most one entry per vertex (12 bytes, and 4
// for its position), where a queue with stale entries grows with every evaluation.
class CandidateHeap {
 public:
  // Room for `points` vertices: every vertex, or with `local`, the vertices v whose local[v] is below
  // `points` (a part's, numbered within it), which are then the only ones it may hold.
  explicit CandidateHeap(size_t points, const uint32_t* local = nullptr) : local_(local) {
    assignPopulated(at_, points, kNoIndex);
  }
  bool empty() const { return heap_.empty(); }
  bool has(uint32_t v) const { return at(v) != kNoIndex; }
  const QueueEntry& top() const { return heap_.front(); }
  // Sets v's entry (adds it, or replaces the one it has).
  void set(const QueueEntry& e) {
    uint32_t i = at(e.v);
    if (i == kNoIndex) {
      i = static_cast<uint32_t>(heap_.size());
      heap_.push_back(e);
      at(e.v) = i;
      up(i);
      return;
    }
    const bool smaller = e < heap_[i];
    heap_[i] = e;
    if (smaller) up(i);
    else down(i);
  }
  // Removes v's entry, if it has one.
  void erase(uint32_t v) {
    const uint32_t i = at(v);
    if (i == kNoIndex) return;
    at(v) = kNoIndex;
    const QueueEntry last = heap_.back();
    heap_.pop_back();
    if (i == heap_.size()) return;
    const bool smaller = last < heap_[i];
    heap_[i] = last;
    at(last.v) = i;
    if (smaller) up(i);
    else down(i);
  }
  void pop() { erase(heap_.front().v); }

 private:
  uint32_t& at(uint32_t v) { return at_[local_ ? local_[v] : v]; }
  uint32_t at(uint32_t v) const { return at_[local_ ? local_[v] : v]; }
  void place(uint32_t i, const QueueEntry& e) {
    heap_[i] = e;
    at(e.v) = i;
  }
  void up(uint32_t i) {
    const QueueEntry e = heap_[i];
    while (i > 0) {
      const uint32_t parent = (i - 1) / 2;
      if (!(e < heap_[parent])) break;
      place(i, heap_[parent]);
      i = parent;
    }
    place(i, e);
  }
  void down(uint32_t i) {
    const QueueEntry e = heap_[i];
    const size_t n = heap_.size();
    for (;;) {
      size_t c = 2 * size_t{i} + 1;
      if (c >= n) break;
      if (c + 1 < n && heap_[c + 1] < heap_[c]) ++c;
      if (!(heap_[c] < e)) break;
      place(i, heap_[c]);
      i = static_cast<uint32_t>(c);
    }
    place(i, e);
  }
  std::vector<QueueEntry> heap_;
  std::vector<uint32_t> at_;  // per vertex: its entry's index in heap_, kNoIndex for none
  const uint32_t* local_;     // vertex -> index in at_, or null: the vertex itself
};

// A link triangle (a < b < c) and a link edge (a < b) as one integer each, a << 64 | b << 32 | c and
// a << 32 | b: the link condition only counts common elements, which integer keys sort and compare
// in far fewer instructions than arrays.
using Tri = unsigned __int128;
using Edge = uint64_t;
inline Tri triKey(uint32_t a, uint32_t b, uint32_t c) { return (Tri{a} << 64) | (Tri{b} << 32) | c; }
inline Edge edgeKey(uint32_t a, uint32_t b) { return (Edge{a} << 32) | b; }

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

// A face (v, x, y) of the star of v: key (min(x, y) << 32 | max(x, y)), then its tetrahedron and
// local face. Every face holds v, so ordering by the other two orders the sorted triples alike.
struct StarFace {
  uint64_t key;
  uint32_t i, j;  // the tetrahedron's place in the star, the face's local index
  bool operator<(const StarFace& o) const { return key != o.key ? key < o.key : (i != o.i ? i < o.i : j < o.j); }
};

// What evaluating one vertex needs besides the mesh: scratch buffers reused from one vertex to the
// next, one set per thread (the vertices around a merge are evaluated in parallel).
struct Workspace {
  explicit Workspace(size_t points) {
    assignPopulated(mark, points, 0u);
    assignPopulated(target_index, points, 0u);
  }

  // n stamps no mark holds yet, the first returned (mark is cleared when the count would wrap).
  uint32_t freshStamps(uint32_t n) {
    if (stamp > UINT32_MAX - n) {
      std::fill(mark.begin(), mark.end(), 0);
      stamp = 0;
    }
    const uint32_t first = stamp + 1;
    stamp += n;
    return first;
  }
  // Deduplicates small vertex lists without sorting: mark[x] == stamp means x is already listed.
  void uniqueByMark(std::vector<uint32_t>& list) {
    freshStamps(1);
    size_t n = 0;
    for (uint32_t x : list) {
      if (mark[x] == stamp) continue;
      mark[x] = stamp;
      list[n++] = x;
    }
    list.resize(n);
  }
  std::vector<uint32_t> mark;
  uint32_t stamp = 0;
  // The storage of the pools of the lanes this thread runs one after another (Ranker::withPartPool):
  // kept for the next lane rather than freed, which the allocator would not give back to the system
  // (pools of a few MB each, of sizes that differ, fragment its free memory).
  std::vector<uint32_t> spare_pool;

  std::vector<uint32_t> corners, targets;
  std::vector<Tet> star_tets;  // the tetrahedra of `corners`, as the merges have made them
  // The star of the vertex being evaluated, one array per quantity so that the volumes after a merge
  // are computed for all its tetrahedra at once. Per tetrahedron: the other three vertices, the
  // inward normal n of their face and d, with volume(p) = (n . p - d) / 6, the density sum of the
  // other three vertices, the current volume and mass, and the volume with v moved to the target.
  std::vector<std::array<uint32_t, 3>> star_o;
  std::vector<double> nx, ny, nz, d, od, vol, mass, vol_w;
  // Per target (its index in targets): the star tetrahedra that hold it, ascending.
  std::vector<uint32_t> target_index, holds_start, holds;
  std::vector<BoundaryFace> faces;
  std::vector<StarFace> face_keys;
  std::vector<Candidate> cands;
  uint64_t evaluations = 0;  // candidate errors computed
};

// The star pool's room beyond the corners, at least (Ranker::star_pool_).
constexpr size_t kMinStarSlack = 4096;

// Below this many vertices to evaluate, the evaluations run on the calling thread. A merge's own
// handful (lazy evaluation: its target and the vertices left with no candidate) costs less than
// waking another thread for it: at 8, the generated 64^3 grid's convert with 2 threads took the same
// wall time and a tenth more CPU. The first evaluation of a lane's vertices is parallel.
constexpr size_t kParallelEvaluations = 64;

// One queue of candidates and the pool of star lists it works on: the whole mesh's, or, while the
// ranking runs in parts (RankingOptions::parts), one part's, whose merges touch no other part.
struct Lane {
  explicit Lane(size_t points) : heap(points) {}
  CandidateHeap heap;
  // The corners (4 * tet + local index) of the vertices whose lists this pool holds: a vertex's list
  // is a contiguous run, so that gathering a star reads independent words instead of chasing a
  // linked list. Corners of collapsed tetrahedra are dropped lazily, by gatherStar (each evaluation
  // rewrites only its own vertex's run). A merge writes the target's new list after the used part of
  // the pool (the source's corners, then its own: the order every sum over a star follows). The pool
  // keeps room for an eighth more than its corners, and when a new list does not fit, the runs are
  // moved down over the abandoned ones, in place, in the order they lie (compactStars).
  std::vector<uint32_t> pool;
  uint64_t used = 0;  // pool[0, used) holds the runs, live and abandoned
  uint64_t peak = 0, compactions = 0;
  std::vector<uint32_t> members;   // the vertices whose runs the pool holds, ascending; empty: every vertex
  bool restricted = false;         // merges only between vertices with no neighbour in another part
  bool parallel = true;            // a merge's vertices are evaluated in parallel
  float error_limit = INFINITY;    // stop before a merge of a larger error
  std::vector<uint32_t> sequence;  // the vertices merged away, in order
  uint64_t popped = 0, rejected = 0, stale = 0;
  Workspace* ws = nullptr;        // the thread's that runs the lane
  std::vector<Candidate> best;    // recompute's results, per listed vertex
  std::vector<Candidate> sorted;  // a rejected vertex's candidates
  // Scratch buffers of validate and merge.
  std::vector<uint32_t> corners, corners_w, recompute, now;
  std::vector<Tet> star_tets, star_tets_w;  // the tetrahedra of corners and corners_w
  std::vector<BoundaryFace> faces, faces_w;
  std::vector<Tri> tris_a, tris_b, whole_a, whole_b;
  std::vector<Edge> edges_a, edges_b;
  std::vector<uint32_t> lk_verts;
};

// The rounds of parts come in series of at most kMaxRounds rounds, in P, P - 1, ... parts (at least
// 2); see nextRankingSeries. Each round's bound on the error of its merges is the kRoundQuantile
// quantile of the errors of its vertices' best candidates as the round starts.
constexpr uint32_t kMaxRounds = 6;
constexpr double kRoundQuantile = 0.6;
// RankingOptions::parts = 0 ranks meshes of kAutoPartTets tetrahedra or more in parts of about
// kPartTets tetrahedra (kAutoParts at least). A part's queue jumps about its part of the mesh: with
// parts of a fixed size, what it touches stays about as near the processor as on a small mesh, and
// the time per tetrahedron stays about the same as the mesh grows (8 parts of the 128^3 grid took
// 1.4 times as long per merge as on the 64^3 grid). Meshes of fewer than 9 kPartTets tetrahedra
// keep kAutoParts parts: their parts fit the cache, and more, smaller parts made coarser views
// worse for little time.
constexpr uint32_t kAutoParts = 8;
constexpr size_t kAutoPartTets = size_t{1} << 20;
constexpr size_t kPartTets = size_t{1} << 18;
// The fine rounds' cuts, shifted by these fractions of a part (Ranker::partition): one part fewer
// moves the cuts of many parts little (the 128^3 grid's middle cut by 1.4 nodes from 46 to 45
// parts), and a vertex by a cut in every fine round would wait for a later series, which left
// the coarse views further from the source.
constexpr double kFineShift[kMaxRounds] = {0, 1.0 / 3, -1.0 / 3, 1.0 / 6, -1.0 / 6, 0.5};
constexpr uint32_t kMaxParts = 256;  // part_ is a byte

uint32_t autoParts(size_t tets) {
  if (tets < kAutoPartTets) return 1;
  return static_cast<uint32_t>(std::clamp<size_t>(tets / kPartTets, kAutoParts, kMaxParts));
}

class Ranker {
 public:
  Ranker(const TetMesh& mesh, std::vector<double> density, const RankingOptions& options)
      : mesh_(mesh),
        grid_(options.grid_tets),
        nt_(options.grid_tets ? options.grid_tets->size() : mesh.numTets()),
        density_(std::move(density)),
        options_(options),
        thread_ws_([points = mesh.numPoints()] { return Workspace(points); }) {}

  MergeTree run(RankingStats* stats, const ProgressFn& progress);
  // batchMerges (ranking.h) on a Ranker of the same mesh.
  MergeTree batch(const MergeTree& ranked, const BatchKeys& keys, uint32_t divisor,
                  const std::vector<RankingRound>& rounds, const RankingFaces* faces, BatchStats* stats);

 private:
  const double* pos(uint32_t v) const { return mesh_.coords.data() + 3 * size_t{v}; }
  bool samePosition(uint32_t a, uint32_t b) const {
    const double* p = pos(a);
    const double* q = pos(b);
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
  }
  // The ranking's state for the mesh as given; the face flags from `faces` where given (batch()).
  void init(const RankingFaces* faces = nullptr);
  // Parts of about equal numbers of vertices, by recursive bisection of their positions along the
  // longest side: part_ and seam_.
  void partition(uint32_t parts, double shift);
  // The tetrahedra not collapsed yet.
  size_t liveTets() const;
  // seam_: the vertices of the live tetrahedra whose vertices lie in more than one part of part_.
  void markSeams();
  // Places each member's run in L's pool, as long as its live tetrahedra (star_size_), with an eighth
  // more room (at least kMinStarSlack) for the merges' appends; the runs are empty.
  void sizePool(Lane& L);
  // Fills the pool of L, a lane of every vertex, with every vertex's list, its live corners in
  // ascending order, from the tetrahedra.
  void buildWholePool(Lane& L);
  // The live tetrahedra around the vertices of each part of part_ (`parts` parts), ascending: a
  // tetrahedron is listed for every part one of its vertices is in. Lanes that make their pools as
  // they start (buildPoolOfPart) read them, so that only the running lanes' pools are held.
  struct PartTets {
    std::vector<uint64_t> begin;  // part p's tetrahedra are tets[begin[p], begin[p + 1])
    std::vector<uint32_t> tets;
  };
  PartTets partTets(uint32_t parts) const;
  // Fills the pool of L, the lane of part p of part_, with its members' lists, each vertex's live
  // corners in ascending order, from the part's tetrahedra.
  void buildPoolOfPart(Lane& L, uint32_t p, const PartTets& around);
  // Calls f() with L's pool made (buildPoolOfPart) in the storage the calling thread keeps for its
  // lanes (Workspace::spare_pool), which gets it back after: a lane of a round of parts holds its
  // pool only while it runs. A part's merges touch no tetrahedron of another part's lists, so a
  // pool made while other parts merge is the one made before they started.
  template <class F>
  void withPartPool(Lane& L, uint32_t p, const PartTets& around, F&& f) {
    Workspace& ws = thread_ws_.local();
    L.pool.swap(ws.spare_pool);
    buildPoolOfPart(L, p, around);
    f();
    L.pool.swap(ws.spare_pool);
  }
  // Evaluates the lane's live vertices and queues their best candidates (their results stay in
  // L.best until the lane's next evaluation).
  void startLane(Lane& L);
  // Merges until the lane's queue is empty or its error limit is reached (startLane first).
  void runLane(Lane& L, uint64_t merged_before, const ProgressFn* progress);
  // v's live corners, and their tetrahedra as the merges have made them (each read once here: the
  // evaluations read them many times).
  void gatherStar(Lane& L, uint32_t v, std::vector<uint32_t>& corners, std::vector<Tet>& tets);
  // Moves run[0, n)'s corners of live tetrahedra to its front, in order; returns how many.
  uint32_t keepLive(uint32_t* run, uint32_t n) const {
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = run[i];
      run[m] = c;
      m += !dead_[c >> 2];
    }
    return m;
  }
  // Calls f(v) for each vertex whose run the lane's pool holds, ascending.
  template <class F>
  void forMembers(const Lane& L, F&& f) const {
    if (L.members.empty()) {
      for (uint32_t v = 0; v < star_len_.size(); ++v) f(v);
    } else {
      for (uint32_t v : L.members) f(v);
    }
  }
  void gatherBoundaryFaces(uint32_t v, const std::vector<uint32_t>& corners, const std::vector<Tet>& tets,
                           std::vector<BoundaryFace>& faces, Workspace& ws) const;
  void candidates(Lane& L, uint32_t v, std::vector<Candidate>& out, Workspace& ws);
  bool validate(Lane& L, uint32_t v, uint32_t w);
  // The triangles of Lk(u) in the complex with the boundary coned to kOmega (each one's vertices
  // ascending; a triangle twice only where the mesh is not a manifold).
  void linkTriangles(const std::vector<uint32_t>& corners, const std::vector<Tet>& tets,
                     const std::vector<BoundaryFace>& faces, bool boundary, std::vector<Tri>& tris) const;
  void merge(Lane& L, uint32_t v, uint32_t w, float error);
  // Evaluates the vertices of `list` again (distinct) and queues each one's best target.
  void recompute(Lane& L, const std::vector<uint32_t>& list);
  void push(Lane& L, uint32_t v, const Candidate& c) { L.heap.set(QueueEntry{static_cast<float>(c.error), v, c.w}); }
  void compactStars(Lane& L);

  const TetMesh& mesh_;
  // The source's tetrahedra: the mesh's, or made from their indices (RankingOptions::grid_tets).
  const RuleGridTets* grid_;
  size_t nt_;
  Tet srcTet(size_t t) const { return grid_ ? (*grid_)[t] : mesh_.tets[t]; }
  // The density at each point; empty: 1 everywhere (volume only, and the batches, which never rank),
  // without an array of ones (8 bytes a point).
  std::vector<double> density_;
  double density(uint32_t x) const { return density_.empty() ? 1.0 : density_[x]; }
  RankingOptions options_;
  double mass_scale_ = 1, area_scale_ = 1;

  // The tetrahedra as the merges so far have made them, read through the mesh's rather than copied
  // (16 bytes a tetrahedron, a fifth of a large convert's peak of memory): vertex k of tetrahedron t
  // is up_[srcTet(t)[k]] (tet(t)), and dead_[t] marks the collapsed ones. A merge v -> w points
  // the vertex that each tetrahedron of v's star names at v's place to w, so that every vertex a live
  // tetrahedron names is one step from the vertex it stands for now.
  std::vector<uint32_t> up_;
  std::vector<uint8_t> dead_;
  Tet tet(size_t t) const {
    const Tet m = srcTet(t);
    return {up_[m[0]], up_[m[1]], up_[m[2]], up_[m[3]]};
  }
  // Per vertex: where its list of corners begins in its lane's pool, and its length.
  std::vector<uint64_t> star_begin_;
  std::vector<uint32_t> star_len_;
  // The face flags (RankingFaces): the caller's where it gave them, else made by init (own_faces_).
  RankingFaces own_faces_;
  const uint8_t *boundary_ = nullptr, *frozen_ = nullptr, *pinned_ = nullptr;
  std::vector<uint8_t> alive_;
  // Lazy evaluation (RankingOptions::lazy): per vertex, whether its queued candidate was computed
  // before a merge changed its star, and is recomputed when it comes to the top.
  std::vector<uint8_t> stale_;
  std::vector<uint32_t> star_size_;  // live tetrahedra around each vertex (kMaxStar)
  bool crowded(uint32_t v) const { return star_size_[v] > kMaxStar; }
  // Ranking in parts: each vertex's part, and whether it shares a tetrahedron with another part's.
  std::vector<uint8_t> part_, seam_;
  std::vector<uint32_t> part_index_;  // each vertex's place among its part's members (the parts' heaps)
  MergeTree tree_;
  bool replaying_ = false;  // batch(): merges are applied as given, nothing is evaluated

  tbb::enumerable_thread_specific<Workspace> thread_ws_;
};

void Ranker::init(const RankingFaces* faces) {
  const size_t np = mesh_.numPoints();
  const size_t nt = nt_;
  alive_.assign(np, 1);
  if (!faces || faces->boundary.size() != np || faces->frozen.size() != np || faces->pinned.size() != np) {
    // Made first, and their face matching gone before the ranking's star lists are made: the peak
    // memory is the larger of the two, not their sum.
    own_faces_ = rankingFaces(mesh_);
    faces = &own_faces_;
  }
  // Read where they are (pinned: never merged away, but may be merged onto; see ranking.h).
  boundary_ = faces->boundary.data();
  frozen_ = faces->frozen.data();
  pinned_ = faces->pinned.data();
  area_scale_ = faces->area_scale;
  resizePopulated(up_, np);
  std::iota(up_.begin(), up_.end(), 0u);
  assignPopulated(dead_, nt, uint8_t{0});
  star_size_.assign(np, 0);
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t v : srcTet(t)) ++star_size_[v];
  star_begin_.assign(np, 0);
  star_len_.assign(np, 0);
  double mass = 0, volume = 0;
  for (size_t t = 0; t < nt; ++t) {
    const Tet q = srcTet(t);
    const double vol = signedVolume(pos(q[0]), pos(q[1]), pos(q[2]), pos(q[3]));
    const double rho = 0.25 * (density(q[0]) + density(q[1]) + density(q[2]) + density(q[3]));
    mass += std::fabs(rho * vol);
    volume += std::fabs(vol);
  }
  mass_scale_ = mass > 0 && std::isfinite(mass) ? mass : (volume > 0 && std::isfinite(volume) ? volume : 1.0);
  tree_.makeRoots(np);
  tree_.error.assign(np, 0.0f);
}

void Ranker::partition(uint32_t parts, double shift) {
  const size_t np = mesh_.numPoints();
  part_.assign(np, 0);
  seam_.assign(np, 0);
  std::vector<uint32_t> ids(np);
  for (uint32_t v = 0; v < np; ++v) ids[v] = v;
  // Splits ids[lo, hi) into k parts numbered from `first`: the longer share of the bounding box's
  // longest side first, at the vertex whose place matches the parts' shares (ties by index), moved by
  // `shift` parts' counts (the parts then differ in size: by (1 + shift) to (1 - shift) where k is 2).
  auto split = [&](auto&& self, size_t lo, size_t hi, uint32_t k, uint32_t first) -> void {
    if (k <= 1 || hi - lo < 2) {
      for (size_t i = lo; i < hi; ++i) part_[ids[i]] = static_cast<uint8_t>(first);
      return;
    }
    double mn[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, mx[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = lo; i < hi; ++i)
      for (int a = 0; a < 3; ++a) {
        mn[a] = std::min(mn[a], pos(ids[i])[a]);
        mx[a] = std::max(mx[a], pos(ids[i])[a]);
      }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (mx[a] - mn[a] > mx[axis] - mn[axis]) axis = a;
    const uint32_t k0 = k / 2;
    // Unshifted, in integers: the exact shares.
    const size_t mid = shift == 0 ? lo + (hi - lo) * k0 / k
                                  : lo + static_cast<size_t>(static_cast<double>(hi - lo) * (k0 + shift) / k);
    std::nth_element(ids.begin() + lo, ids.begin() + mid, ids.begin() + hi, [&](uint32_t x, uint32_t y) {
      const double px = pos(x)[axis], py = pos(y)[axis];
      return px < py || (px == py && x < y);  // NaN coordinates compare by index alone
    });
    // The two sides are apart (ids and part_ at distinct places): split at once when large.
    if (hi - lo >= kParallelSplit)
      tbb::parallel_invoke([&] { self(self, lo, mid, k0, first); }, [&] { self(self, mid, hi, k - k0, first + k0); });
    else {
      self(self, lo, mid, k0, first);
      self(self, mid, hi, k - k0, first + k0);
    }
  };
  tbb::this_task_arena::isolate([&] { split(split, 0, np, parts, 0); });
  markSeams();
}

size_t Ranker::liveTets() const {
  std::atomic<size_t> live{0};
  parallelBlocks(dead_.size(), [&](size_t t0, size_t t1) {
    size_t n = 0;
    for (size_t t = t0; t < t1; ++t) n += !dead_[t];
    live.fetch_add(n, std::memory_order_relaxed);
  });
  return live.load();
}

void Ranker::markSeams() {
  seam_.assign(mesh_.numPoints(), 0);
  parallelBlocks(dead_.size(), [&](size_t t0, size_t t1) {
    for (size_t t = t0; t < t1; ++t) {
      if (dead_[t]) continue;
      const Tet q = tet(t);
      const uint8_t p = part_[q[0]];
      if (part_[q[1]] != p || part_[q[2]] != p || part_[q[3]] != p)
        for (uint32_t v : q) setFlag(seam_[v]);
    }
  });
}

void Ranker::sizePool(Lane& L) {
  uint64_t total = 0;
  forMembers(L, [&](uint32_t v) {
    star_begin_[v] = total;
    star_len_[v] = 0;
    total += star_size_[v];
  });
  assignPopulated(L.pool, total + std::max<uint64_t>(total / 8, kMinStarSlack), 0u);
  L.peak = L.pool.size();
  L.used = total;
}

void Ranker::buildWholePool(Lane& L) {
  sizePool(L);
  // The corners in groups of vertices of equal ranges, one group a thread: each reads every
  // tetrahedron and writes its own vertices' runs, in the tetrahedra's order (the same runs for any
  // number of groups).
  const uint64_t np = mesh_.numPoints();
  const uint32_t groups = static_cast<uint32_t>(std::clamp<int>(tbb::this_task_arena::max_concurrency(), 1, 64));
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(uint32_t{0}, groups, [&](uint32_t g) {
      const uint64_t lo = np * g / groups, hi = np * (g + 1) / groups;
      for (size_t t = 0; t < dead_.size(); ++t) {
        if (dead_[t]) continue;
        const Tet q = tet(t);
        for (int k = 0; k < 4; ++k) {
          const uint32_t v = q[k];
          if (v >= lo && v < hi) L.pool[star_begin_[v] + star_len_[v]++] = static_cast<uint32_t>(4 * t + k);
        }
      }
    });
  });
}

Ranker::PartTets Ranker::partTets(uint32_t parts) const {
  // In blocks of tetrahedra: each block counts its tetrahedra of every part, then writes them at its
  // place within each part's list, so that every list is in ascending order whatever the threads.
  constexpr size_t kPartBlock = size_t{1} << 16;
  const size_t nt = dead_.size();
  const size_t blocks = (nt + kPartBlock - 1) / kPartBlock;
  auto eachPart = [&](size_t t, auto&& f) {  // f(p) once for each part of t's vertices
    const Tet q = tet(t);
    uint8_t seen[4];
    int n = 0;
    for (int k = 0; k < 4; ++k) {
      const uint8_t p = part_[q[k]];
      if (std::find(seen, seen + n, p) != seen + n) continue;
      seen[n++] = p;
      f(p);
    }
  };
  std::vector<uint64_t> at(blocks * parts, 0);  // per block and part: its count, then its first place
  auto eachBlock = [&](auto&& f) {
    tbb::this_task_arena::isolate([&] {
      tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
        uint64_t* mine = at.data() + b * parts;
        for (size_t t = b * kPartBlock, end = std::min(nt, t + kPartBlock); t < end; ++t)
          if (!dead_[t]) eachPart(t, [&](uint8_t p) { f(mine[p], t); });
      });
    });
  };
  eachBlock([](uint64_t& count, size_t) { ++count; });
  PartTets out;
  out.begin.assign(parts + 1, 0);
  uint64_t total = 0;
  for (uint32_t p = 0; p < parts; ++p) {
    out.begin[p] = total;
    for (size_t b = 0; b < blocks; ++b) {
      const uint64_t count = at[b * parts + p];
      at[b * parts + p] = total;
      total += count;
    }
  }
  out.begin[parts] = total;
  resizePopulated(out.tets, total);
  eachBlock([&](uint64_t& place, size_t t) { out.tets[place++] = static_cast<uint32_t>(t); });
  return out;
}

void Ranker::buildPoolOfPart(Lane& L, uint32_t p, const PartTets& around) {
  sizePool(L);
  for (uint64_t i = around.begin[p]; i < around.begin[p + 1]; ++i) {
    const uint32_t t = around.tets[i];
    const Tet q = tet(t);
    for (int k = 0; k < 4; ++k)
      if (part_[q[k]] == p) L.pool[star_begin_[q[k]] + star_len_[q[k]]++] = 4 * t + static_cast<uint32_t>(k);
  }
}

void Ranker::startLane(Lane& L) {
  L.ws = &thread_ws_.local();
  std::vector<uint32_t> all;
  forMembers(L, [&](uint32_t v) {
    if (alive_[v]) all.push_back(v);
  });
  recompute(L, all);
}

void Ranker::runLane(Lane& L, uint64_t merged_before, const ProgressFn* progress) {
  L.ws = &thread_ws_.local();  // the thread that runs it, perhaps not startLane's
  const uint64_t np = mesh_.numPoints();
  while (!L.heap.empty() && merged_before + L.sequence.size() < options_.max_merges &&
         !(L.heap.top().error > L.error_limit)) {
    const QueueEntry e = L.heap.top();
    L.heap.pop();
    ++L.popped;
    if (options_.lazy && stale_[e.v]) {
      // Computed before its star changed: computed again, and queued by its new error.
      stale_[e.v] = 0;
      L.now.assign(1, e.v);
      recompute(L, L.now);
      ++L.stale;
      continue;
    }
    if (validate(L, e.v, e.w)) {
      merge(L, e.v, e.w, e.error);
      const uint64_t merged = merged_before + L.sequence.size();
      if (progress && merged % 16384 == 0)
        reportProgress(*progress, "rank merges", static_cast<double>(merged) / static_cast<double>(np));
      continue;
    }
    ++L.rejected;
    // The cheap filter let an invalid target through: take the best target that passes every check.
    candidates(L, e.v, L.sorted, *L.ws);
    std::sort(L.sorted.begin(), L.sorted.end(), [](const Candidate& a, const Candidate& b) {
      return a.error < b.error || (a.error == b.error && a.w < b.w);
    });
    for (const Candidate& c : L.sorted) {
      if (validate(L, e.v, c.w)) {
        push(L, e.v, c);
        break;
      }
    }
  }
}

void Ranker::gatherStar(Lane& L, uint32_t v, std::vector<uint32_t>& corners, std::vector<Tet>& tets) {
  uint32_t* run = L.pool.data() + star_begin_[v];
  const uint32_t m = keepLive(run, star_len_[v]);
  star_len_[v] = m;
  corners.assign(run, run + m);
  tets.resize(m);
  for (uint32_t i = 0; i < m; ++i) tets[i] = tet(run[i] >> 2);
}

void Ranker::compactStars(Lane& L) {
  // The runs in the order they lie; each moves down (never up: the runs before it are at most as
  // long as the space they took), without the corners of collapsed tetrahedra, as gatherStar would.
  std::vector<std::pair<uint64_t, uint32_t>> runs;
  forMembers(L, [&](uint32_t v) {
    if (star_len_[v] > 0) runs.emplace_back(star_begin_[v], v);
  });
  std::sort(runs.begin(), runs.end());
  uint32_t* pool = L.pool.data();
  uint64_t used = 0;
  for (const auto& [begin, v] : runs) {
    const uint32_t n = star_len_[v];
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = pool[begin + i];
      pool[used + m] = c;
      m += !dead_[c >> 2];
    }
    star_begin_[v] = used;
    star_len_[v] = m;
    used += m;
  }
  L.used = used;
  ++L.compactions;
}

void Ranker::gatherBoundaryFaces(uint32_t v, const std::vector<uint32_t>& corners, const std::vector<Tet>& tets,
                                 std::vector<BoundaryFace>& faces, Workspace& ws) const {
  faces.clear();
  if (!boundary_[v]) return;
  // Faces containing v: three per tetrahedron; those seen once are on the boundary.
  std::vector<StarFace>& keys = ws.face_keys;
  keys.clear();
  for (uint32_t i = 0; i < corners.size(); ++i) {
    const int k = corners[i] & 3;
    const Tet& q = tets[i];
    for (int j = 0; j < 4; ++j) {
      if (j == k) continue;
      uint32_t other[2];
      int n = 0;
      for (int m = 0; m < 3; ++m) {
        const uint32_t u = q[kTetFace[j][m]];
        if (u != v && n < 2) other[n++] = u;
      }
      const uint32_t x = std::min(other[0], other[1]), y = std::max(other[0], other[1]);
      keys.push_back({(uint64_t{x} << 32) | y, i, static_cast<uint32_t>(j)});
    }
  }
  std::sort(keys.begin(), keys.end());
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j].key == keys[i].key) ++j;
    if (j - i == 1) {
      const int f = static_cast<int>(keys[i].j);
      const Tet& q = tets[keys[i].i];
      uint32_t tri[3] = {q[kTetFace[f][0]], q[kTetFace[f][1]], q[kTetFace[f][2]]};
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

void Ranker::candidates(Lane& L, uint32_t v, std::vector<Candidate>& out, Workspace& ws) {
  out.clear();
  if (!alive_[v] || frozen_[v] || pinned_[v] || crowded(v) || (L.restricted && seam_[v])) return;
  gatherStar(L, v, ws.corners, ws.star_tets);
  if (ws.corners.empty()) return;
  const double* pv = pos(v);
  const double rho_v = density(v);
  const size_t ns = ws.corners.size();
  ws.star_o.resize(ns);
  for (auto* a : {&ws.nx, &ws.ny, &ws.nz, &ws.d, &ws.od, &ws.vol, &ws.mass, &ws.vol_w}) a->resize(ns);
  ws.targets.clear();
  for (size_t i = 0; i < ns; ++i) {
    const int k = ws.corners[i] & 3;
    const Tet& q = ws.star_tets[i];
    const uint32_t a = q[kTetFace[k][0]], b = q[kTetFace[k][1]], d = q[kTetFace[k][2]];
    ws.star_o[i] = {a, b, d};
    double nout[3];
    triNormal(pos(a), pos(b), pos(d), nout);
    const double n[3] = {-nout[0], -nout[1], -nout[2]};
    ws.nx[i] = n[0];
    ws.ny[i] = n[1];
    ws.nz[i] = n[2];
    ws.d[i] = dot(n, pos(a));
    ws.od[i] = density(a) + density(b) + density(d);
    ws.vol[i] = (dot(n, pv) - ws.d[i]) / 6.0;
    ws.mass[i] = 0.25 * (rho_v + ws.od[i]) * ws.vol[i];
    if (!boundary_[v]) ws.targets.insert(ws.targets.end(), {a, b, d});
  }
  gatherBoundaryFaces(v, ws.corners, ws.star_tets, ws.faces, ws);
  double face_area = 0;
  if (boundary_[v]) {
    for (const BoundaryFace& f : ws.faces) {
      ws.targets.push_back(f.x);
      ws.targets.push_back(f.y);
      face_area += f.area;
    }
  }
  ws.uniqueByMark(ws.targets);
  // Which star tetrahedra hold each target (mark == stamp marks the targets), ascending.
  const size_t num_targets = ws.targets.size();
  for (size_t j = 0; j < num_targets; ++j) ws.target_index[ws.targets[j]] = static_cast<uint32_t>(j);
  ws.holds_start.assign(num_targets + 1, 0);
  for (size_t i = 0; i < ns; ++i)
    for (uint32_t x : ws.star_o[i])
      if (ws.mark[x] == ws.stamp) ++ws.holds_start[ws.target_index[x] + 1];
  for (size_t j = 0; j < num_targets; ++j) ws.holds_start[j + 1] += ws.holds_start[j];
  ws.holds.resize(ws.holds_start[num_targets]);
  for (size_t i = 0; i < ns; ++i)
    for (uint32_t x : ws.star_o[i])
      if (ws.mark[x] == ws.stamp) ws.holds[ws.holds_start[ws.target_index[x]]++] = static_cast<uint32_t>(i);
  // holds_start[j] now ends target j's list; target 0's begins at 0, target j's at the end of j - 1.
  const double *nx = ws.nx.data(), *ny = ws.ny.data(), *nz = ws.nz.data(), *sd = ws.d.data(), *od = ws.od.data(),
               *mass = ws.mass.data(), *vol_v = ws.vol.data();
  double* vol_w = ws.vol_w.data();
  for (size_t j = 0; j < num_targets; ++j) {
    const uint32_t w = ws.targets[j];
    if (frozen_[w] || crowded(w) || (L.restricted && seam_[w])) continue;
    ++ws.evaluations;
    const bool same = samePosition(v, w);
    const double* pw = pos(w);
    const double rho_w = density(w);
    // The volume of every star tetrahedron with v moved to w, in one pass that the compiler
    // vectorizes (the same arithmetic, element by element); then the sums, in the star's order.
    const double p0 = pw[0], p1 = pw[1], p2 = pw[2];
    if (!same)
      for (size_t i = 0; i < ns; ++i) vol_w[i] = (nx[i] * p0 + ny[i] * p1 + nz[i] * p2 - sd[i]) / 6.0;
    const double* vols = same ? vol_v : vol_w;
    const uint32_t* hold = ws.holds.data() + (j == 0 ? 0 : ws.holds_start[j - 1]);
    const uint32_t* hold_end = ws.holds.data() + ws.holds_start[j];
    double net = 0, local = 0;
    bool ok = true;
    for (size_t i = 0; i < ns; ++i) {
      if (hold != hold_end && *hold == i) {
        ++hold;
        net -= mass[i];
        local += std::fabs(mass[i]);
        continue;
      }
      const double vi = vols[i];
      if (!same && !(vi > 0)) {
        ok = false;
        break;
      }
      const double ch = 0.25 * (rho_w + od[i]) * vi - mass[i];
      net += ch;
      local += std::fabs(ch);
    }
    if (!ok) continue;
    const double ed = std::fabs(net) + kLocalWeight * local;
    double eg = 0;
    if (boundary_[v] && face_area > 0) {
      for (const BoundaryFace& f : ws.faces) {
        if (f.x == w || f.y == w) continue;
        double nn[3];
        const bool facing = keepsFacing(pv, pw, pos(f.x), pos(f.y), f, nn);
        const double new_area = 0.5 * norm(nn);
        if (!same && !facing) {
          ok = false;
          break;
        }
        eg += std::fabs(new_area - f.area) * f.area;
        for (const BoundaryFace& g : ws.faces) {
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

void Ranker::linkTriangles(const std::vector<uint32_t>& corners, const std::vector<Tet>& tets,
                           const std::vector<BoundaryFace>& faces, bool boundary, std::vector<Tri>& tris) const {
  tris.clear();
  for (size_t i = 0; i < corners.size(); ++i) {
    const int k = corners[i] & 3;
    const Tet& q = tets[i];
    uint32_t a = q[(k + 1) & 3], b = q[(k + 2) & 3], d = q[(k + 3) & 3];
    if (a > b) std::swap(a, b);
    if (b > d) std::swap(b, d);
    if (a > b) std::swap(a, b);
    tris.push_back(triKey(a, b, d));
  }
  if (boundary) {
    for (const BoundaryFace& f : faces) tris.push_back(triKey(std::min(f.x, f.y), std::max(f.x, f.y), kOmega));
  }
}

bool Ranker::validate(Lane& L, uint32_t v, uint32_t w) {
  if (v == w || !alive_[v] || !alive_[w] || frozen_[v] || frozen_[w] || pinned_[v] || crowded(v) || crowded(w))
    return false;
  if (boundary_[v] && !boundary_[w]) return false;
  if (L.restricted && (seam_[v] || seam_[w])) return false;
  gatherStar(L, v, L.corners, L.star_tets);
  gatherStar(L, w, L.corners_w, L.star_tets_w);
  gatherBoundaryFaces(v, L.corners, L.star_tets, L.faces, *L.ws);
  gatherBoundaryFaces(w, L.corners_w, L.star_tets_w, L.faces_w, *L.ws);
  // Tetrahedra around the edge vw and the vertices of Lk(vw).
  size_t edge_tets = 0;
  L.lk_verts.clear();
  const bool same = samePosition(v, w);
  for (size_t i = 0; i < L.corners.size(); ++i) {
    const Tet& q = L.star_tets[i];
    const int k = L.corners[i] & 3;
    if (q[0] == w || q[1] == w || q[2] == w || q[3] == w) {
      ++edge_tets;
      for (uint32_t x : q) {
        if (x != v && x != w) L.lk_verts.push_back(x);
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
  for (const BoundaryFace& f : L.faces) {
    if (f.x == w || f.y == w) {
      ++edge_faces;
      continue;
    }
    if (!same) {
      double nn[3];
      if (!keepsFacing(pos(v), pos(w), pos(f.x), pos(f.y), f, nn)) return false;
    }
  }
  // A boundary merge runs along a boundary edge, and one in exactly two boundary triangles: readers
  // store only the merge's boundary flag and take it to remove two (stream_simplifier.cpp). An edge
  // in four or more (a non-manifold boundary: two parts of the surface touching along it) passes the
  // link condition of the coned complex, which is no manifold there, yet removes them all.
  if (boundary_[v] && edge_faces != 2) return false;
  // A collapsing tetrahedron T = (v, w, x, y) glues its faces (v, x, y) and (w, x, y). When one of them
  // is on the boundary, the tetrahedron across the other one inherits the boundary triangle: the
  // streamed triangle keeps T's orientation, the mesh's takes the neighbour's. They agree when both
  // are positively oriented (a flat tetrahedron's orientation is arbitrary), so require that.
  for (size_t i = 0; i < L.corners.size(); ++i) {
    const uint32_t t = L.corners[i] >> 2;
    const Tet& q = L.star_tets[i];
    if (q[0] != w && q[1] != w && q[2] != w && q[3] != w) continue;
    uint32_t xy[2], m = 0;
    for (uint32_t z : q) {
      if (z != v && z != w) xy[m++] = z;
    }
    // The tetrahedron of a star (corners and their tetrahedra) across (x, y) from t, and where it is.
    auto across = [&](const std::vector<uint32_t>& star, const std::vector<Tet>& star_tets) -> const Tet* {
      for (size_t j = 0; j < star.size(); ++j) {
        if (star[j] >> 2 == t) continue;
        const Tet& p = star_tets[j];
        bool has_x = false, has_y = false;
        for (uint32_t z : p) {
          has_x |= z == xy[0];
          has_y |= z == xy[1];
        }
        if (has_x && has_y) return &p;
      }
      return nullptr;
    };
    const Tet* nv = across(L.corners, L.star_tets);
    const Tet* nw = across(L.corners_w, L.star_tets_w);
    if (nv && nw) continue;
    if (orient3d(pos(q[0]), pos(q[1]), pos(q[2]), pos(q[3])) <= 0) return false;
    if (const Tet* n = nv ? nv : nw) {
      const Tet& p = *n;
      if (orient3d(pos(p[0]), pos(p[1]), pos(p[2]), pos(p[3])) <= 0) return false;
    }
  }
  // Link condition: Lk(v) ∩ Lk(w) = Lk(vw), counted per dimension (Lk(vw) is always contained).
  sortUnique(L.lk_verts);
  const size_t lk_v = L.lk_verts.size() + (edge_faces > 0 ? 1 : 0);
  const size_t lk_e = edge_tets + edge_faces;
  linkTriangles(L.corners, L.star_tets, L.faces, boundary_[v], L.tris_a);
  linkTriangles(L.corners_w, L.star_tets_w, L.faces_w, boundary_[w], L.tris_b);
  // Common vertices first, by marks (Lk(v)'s at `s`, those Lk(w) has too at s + 1): a common edge or
  // triangle has only common vertices, so the edges and triangles compared are those few, sorted.
  Workspace& ws = *L.ws;
  const uint32_t s = ws.freshStamps(2);
  bool omega_v = false, omega_w = false;
  auto corners3 = [](Tri t) {
    return std::array<uint32_t, 3>{static_cast<uint32_t>(t >> 64), static_cast<uint32_t>(t >> 32),
                                   static_cast<uint32_t>(t)};
  };
  for (Tri t : L.tris_a)
    for (uint32_t x : corners3(t)) {
      if (x == kOmega) omega_v = true;
      else ws.mark[x] = s;
    }
  size_t common = 0;
  for (Tri t : L.tris_b)
    for (uint32_t x : corners3(t)) {
      if (x == kOmega) {
        omega_w = true;
      } else if (ws.mark[x] == s) {
        ws.mark[x] = s + 1;
        ++common;
      }
    }
  const bool omega = omega_v && omega_w;
  if (common + (omega ? 1 : 0) != lk_v) return false;
  auto shared = [&](uint32_t x) { return x == kOmega ? omega : ws.mark[x] == s + 1; };
  // The edges and triangles of a link whose vertices are all common.
  auto sharedParts = [&](const std::vector<Tri>& tris, std::vector<Edge>& edges, std::vector<Tri>& whole) {
    edges.clear();
    whole.clear();
    for (Tri t : tris) {
      const auto [a, b, c] = corners3(t);
      const bool sa = shared(a), sb = shared(b), sc = shared(c);
      if (sa && sb) edges.push_back(edgeKey(a, b));
      if (sa && sc) edges.push_back(edgeKey(a, c));
      if (sb && sc) edges.push_back(edgeKey(b, c));
      if (sa && sb && sc) whole.push_back(t);
    }
    sortUnique(edges);
    sortUnique(whole);
  };
  sharedParts(L.tris_a, L.edges_a, L.whole_a);
  sharedParts(L.tris_b, L.edges_b, L.whole_b);
  if (countCommon(L.whole_a, L.whole_b) != 0) return false;
  return countCommon(L.edges_a, L.edges_b) == lk_e;
}

void Ranker::merge(Lane& L, uint32_t v, uint32_t w, float error) {
  gatherStar(L, v, L.corners, L.star_tets);
  L.recompute.clear();
  L.recompute.push_back(w);
  uint32_t removed = 0;
  for (size_t i = 0; i < L.corners.size(); ++i) {
    const uint32_t c = L.corners[i];
    const Tet& q = L.star_tets[i];
    for (uint32_t x : q) {
      if (x != v) L.recompute.push_back(x);
    }
    if (q[0] == w || q[1] == w || q[2] == w || q[3] == w) {
      for (uint32_t x : q) --star_size_[x];
      dead_[c >> 2] = 1;
      ++removed;
    }
  }
  // Then v's place in the tetrahedra that stay names w (after the loop above, which reads v there:
  // tetrahedra of the star may name v by the same vertex).
  for (uint32_t c : L.corners) {
    if (dead_[c >> 2]) continue;
    up_[srcTet(c >> 2)[c & 3]] = w;
    ++star_size_[w];
  }
  up_[v] = w;
  star_size_[v] = 0;  // its tetrahedra are w's now, or gone: lists built from the tetrahedra size by it
  // w's list becomes v's corners, then its own (the killed ones are dropped when next gathered).
  {
    star_len_[v] = 0;
    if (L.pool.size() - L.used < L.corners.size() + star_len_[w]) compactStars(L);
    const uint32_t nw = star_len_[w];
    // After compaction the runs hold at most every corner, and a list at most two crowded stars.
    if (L.pool.size() - L.used < L.corners.size() + nw) {
      L.pool.resize(L.used + L.corners.size() + nw);
      L.peak = std::max<uint64_t>(L.peak, L.pool.size());
    }
    const uint64_t b = L.used;
    uint32_t* pool = L.pool.data();
    std::copy(L.corners.begin(), L.corners.end(), pool + b);
    std::copy_n(pool + star_begin_[w], nw, pool + b + L.corners.size());
    star_begin_[w] = b;
    star_len_[w] = static_cast<uint32_t>(L.corners.size()) + nw;
    L.used = b + L.corners.size() + nw;
  }
  alive_[v] = 0;
  if (!replaying_) L.heap.erase(v);
  tree_.parent[v] = w;
  L.sequence.push_back(v);
  tree_.removed[v] = removed;
  tree_.boundary[v] = boundary_[v];
  tree_.error[v] = error;
  if (replaying_) return;
  L.ws->uniqueByMark(L.recompute);
  if (!options_.lazy) {
    recompute(L, L.recompute);
    return;
  }
  // w, whose star is now v's and its own, is evaluated at once, and so is a vertex with no queued
  // candidate (nothing would bring it back); the others are only marked stale.
  L.now.clear();
  for (uint32_t u : L.recompute) {
    const bool at_once = u == w || !L.heap.has(u);
    stale_[u] = !at_once;
    if (at_once) L.now.push_back(u);
  }
  recompute(L, L.now);
}

void Ranker::recompute(Lane& L, const std::vector<uint32_t>& list) {
  // The evaluations read the mesh and each rewrites only its own vertex's star run, so they run in
  // parallel; the results are queued afterwards in the list's order, as one thread would.
  const size_t n = list.size();
  L.best.resize(n);
  auto evaluate = [&](size_t i, Workspace& ws) {
    candidates(L, list[i], ws.cands, ws);
    Candidate best{0, kNoIndex};
    for (const Candidate& c : ws.cands)
      if (best.w == kNoIndex || c.error < best.error || (c.error == best.error && c.w < best.w)) best = c;
    L.best[i] = best;
  };
  if (!L.parallel || n < kParallelEvaluations) {
    for (size_t i = 0; i < n; ++i) evaluate(i, *L.ws);
  } else {
    // Isolated: while it waits for its share, this thread takes no task from outside the ranking (a
    // level being encoded beside it, say), which would hold up every merge after this one.
    tbb::this_task_arena::isolate([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2), [&](const tbb::blocked_range<size_t>& r) {
        Workspace& ws = thread_ws_.local();
        for (size_t i = r.begin(); i < r.end(); ++i) evaluate(i, ws);
      });
    });
  }
  for (size_t i = 0; i < n; ++i) {
    if (L.best[i].w != kNoIndex) push(L, list[i], L.best[i]);
    else L.heap.erase(list[i]);
  }
}

// The kRoundQuantile quantile of the errors of the best candidates the lanes' vertices had when they
// started (startLane's L.best; infinite when none has one; errors that are not finite are left out).
float roundErrorBound(const std::vector<std::unique_ptr<Lane>>& lanes) {
  std::vector<float> errors;
  for (const auto& L : lanes)
    for (const Candidate& c : L->best)
      if (c.w != kNoIndex && std::isfinite(static_cast<float>(c.error))) errors.push_back(static_cast<float>(c.error));
  if (errors.empty()) return INFINITY;
  const size_t k =
      std::min(errors.size() - 1, static_cast<size_t>(kRoundQuantile * static_cast<double>(errors.size())));
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(k), errors.end());
  return errors[k];
}

MergeTree Ranker::run(RankingStats* stats, const ProgressFn& progress) {
  init(options_.faces);
  const size_t np = mesh_.numPoints();
  stale_.assign(options_.lazy ? np : 0, 0);
  const uint32_t parts = std::min<uint32_t>(options_.parts != 0 ? options_.parts : autoParts(nt_), kMaxParts);
  // In parts: each part merges vertices that have no neighbour in another part, which touches
  // nothing another part reads or writes, so the parts run in parallel, up to the round's bound on
  // the error; their merges are then interleaved by error (each part's in its own order). Further
  // rounds do the same with other parts, and the whole mesh's queue goes on from there with every
  // vertex, the seams between the parts included.
  std::vector<uint32_t> order;
  std::vector<RankingRound> made_rounds;
  uint64_t popped = 0, rejected = 0, restaled = 0, pool_peak = 0, compactions = 0;
  auto count = [&](const Lane& L) {
    popped += L.popped;
    rejected += L.rejected;
    restaled += L.stale;
    pool_peak = std::max(pool_peak, L.peak);
    compactions += L.compactions;
  };
  // One round in `round_parts` parts, their cuts shifted by `shift` (partition).
  auto runRound = [&](uint32_t round_parts, double shift) {
    partition(round_parts, shift);
    const size_t round_begin = order.size();
    std::vector<std::unique_ptr<Lane>> lanes;
    for (uint32_t p = 0; p < round_parts; ++p) {
      lanes.push_back(std::make_unique<Lane>(0));
      lanes.back()->restricted = true;
      lanes.back()->parallel = false;
    }
    // A part's heap holds only its own vertices (a merge in a round of parts touches no other part's),
    // numbered within the part: one array of the vertices' numbers for every part, not one of every
    // vertex per part.
    part_index_.assign(np, 0);
    for (uint32_t v = 0; v < np; ++v) {
      if (!alive_[v]) continue;
      std::vector<uint32_t>& members = lanes[part_[v]]->members;
      part_index_[v] = static_cast<uint32_t>(members.size());
      members.push_back(v);
    }
    for (auto& L : lanes) L->heap = CandidateHeap(L->members.size(), part_index_.data());
    // Per part, an estimate of the work at hand: its vertices, then (below) its likely merges.
    std::vector<uint64_t> cost(round_parts);
    for (uint32_t p = 0; p < round_parts; ++p) cost[p] = lanes[p]->members.size();
    // Each lane's pool, made from the tetrahedra around its part as the lane starts, twice (to
    // evaluate its vertices, then to merge), in ascending order of the corners: the pools of the
    // lanes running, not of every part, are held at once.
    const PartTets around = partTets(round_parts);
    // The parts on the threads, the costliest first, each with its pool.
    auto eachPart = [&](const std::vector<uint64_t>& cost, auto&& fn) {
      tbb::this_task_arena::isolate([&] {
        forEachLongestFirst(cost, [&](size_t p) {
          Lane& L = *lanes[p];
          withPartPool(L, static_cast<uint32_t>(p), around, [&] { fn(L); });
        });
      });
    };
    // Every part's vertices evaluated first: the round's bound on the error is a quantile of their
    // best candidates' errors (the same whatever the threads), so that the parts stop at about the
    // same error, and merges a part would make at errors where other parts stop wait for the next
    // round or the whole mesh's queue.
    eachPart(cost, [&](Lane& L) { startLane(L); });
    const float bound = roundErrorBound(lanes);
    for (auto& L : lanes) L->error_limit = bound;
    // A part makes about as many merges as it has vertices whose best candidate is within the bound.
    for (uint32_t p = 0; p < round_parts; ++p)
      cost[p] =
          static_cast<uint64_t>(std::count_if(lanes[p]->best.begin(), lanes[p]->best.end(), [&](const Candidate& c) {
            return c.w != kNoIndex && !(c.error > bound);
          }));
    eachPart(cost, [&](Lane& L) { runLane(L, 0, nullptr); });
    // The parts' merges by error, each part's in its order (ties: the lower part first): the parts'
    // next merges in a heap, the least error (then the lower part) on top.
    std::vector<size_t> next(round_parts, 0);
    using Head = std::pair<float, uint32_t>;  // the error of a part's next merge, the part
    std::vector<Head> heads;
    for (uint32_t p = 0; p < round_parts; ++p)
      if (!lanes[p]->sequence.empty()) heads.emplace_back(tree_.error[lanes[p]->sequence[0]], p);
    // A total order (a NaN error, which no merge should have, after every other).
    const auto later = [](const Head& a, const Head& b) {
      const bool an = std::isnan(a.first), bn = std::isnan(b.first);
      if (an != bn) return an;
      if (!an && a.first != b.first) return b.first < a.first;
      return b.second < a.second;
    };
    std::make_heap(heads.begin(), heads.end(), later);
    while (!heads.empty()) {
      std::pop_heap(heads.begin(), heads.end(), later);
      const uint32_t p = heads.back().second;
      heads.pop_back();
      const std::vector<uint32_t>& seq = lanes[p]->sequence;
      order.push_back(seq[next[p]++]);
      if (next[p] < seq.size()) {
        heads.emplace_back(tree_.error[seq[next[p]]], p);
        std::push_heap(heads.begin(), heads.end(), later);
      }
    }
    made_rounds.push_back(RankingRound{order.size() - round_begin, round_parts, part_, bound});
    for (const auto& L : lanes) count(*L);
    std::fill(stale_.begin(), stale_.end(), 0);
    reportProgress(progress, "rank merges", static_cast<double>(order.size()) / static_cast<double>(np));
  };
  // Series of rounds of parts, each round with one part fewer than the one before, so that its cuts
  // fall elsewhere and most of the last round's seams are inside its parts (nextRankingSeries). The
  // tail starts after the first series where another follows, else with the whole mesh's queue.
  bool tail_started = false;
  auto startTail = [&] {
    if (!tail_started && options_.beside_ranking_tail) options_.beside_ranking_tail();
    tail_started = true;
  };
  uint32_t series = parts > 1 ? parts : 0;
  for (bool first = true; series != 0; first = false) {
    if (!first) startTail();
    const bool fine = series >= 2 * kAutoParts;
    for (uint32_t r = 0; r < kMaxRounds && series >= r + 2; ++r) {
      const uint32_t round_parts = series - r;
      runRound(round_parts, fine ? kFineShift[r] : 0.0);
    }
    series = nextRankingSeries(series, liveTets());
  }
  // The whole mesh's queue, its pool from the tetrahedra left.
  const uint64_t part_merges = order.size();
  for (Workspace& ws : thread_ws_) ws.spare_pool = {};
  part_ = seam_ = {};
  Lane whole(np);
  buildWholePool(whole);
  startTail();
  startLane(whole);
  runLane(whole, part_merges, &progress);
  order.insert(order.end(), whole.sequence.begin(), whole.sequence.end());
  count(whole);
  for (size_t i = 0; i < order.size(); ++i) tree_.rank[order[i]] = static_cast<uint32_t>(i + 1);
  tree_.merges = order.size();
  if (stats) {
    stats->popped = popped;
    stats->rejected = rejected;
    stats->stale = restaled;
    stats->evaluations = 0;
    for (const Workspace& ws : thread_ws_) stats->evaluations += ws.evaluations;
    stats->star_pool_corners = pool_peak;
    stats->star_compactions = compactions;
    stats->parts = parts;
    stats->part_merges = part_merges;
    stats->rounds = std::move(made_rounds);
    stats->faces = std::move(own_faces_);  // empty where the caller gave them
  }
  return std::move(tree_);
}

// The most passes in key order a batch makes (batchMerges).
constexpr uint32_t kBatchPasses = 8;

MergeTree Ranker::batch(const MergeTree& ranked, const BatchKeys& keys, uint32_t divisor,
                        const std::vector<RankingRound>& rounds, const RankingFaces* faces, BatchStats* stats) {
  init(faces);
  replaying_ = true;
  const size_t np = mesh_.numPoints();
  std::vector<uint32_t> by_rank(ranked.merges);
  for (uint32_t v = 0; v < np; ++v)
    if (ranked.rank[v]) by_rank[ranked.rank[v] - 1] = v;
  // The vertex each one has been merged into, recursively (path halving). A part's chains stay in
  // the part: its merges' parents are its own vertices, alive when its round began.
  std::vector<uint32_t> up(np);
  for (uint32_t v = 0; v < np; ++v) up[v] = v;
  auto root = [&](uint32_t x) {
    while (up[x] != x) {
      up[x] = up[up[x]];
      x = up[x];
    }
    return x;
  };
  auto byKey = [&](uint32_t a, uint32_t b) {
    const uint64_t ka = keys[a], kb = keys[b];
    return ka < kb || (ka == kb && a < b);
  };
  std::vector<uint32_t> order;
  order.reserve(ranked.merges);
  BatchStats st;
  // The unused points' merges first, as one batch (they remove nothing and change no tetrahedron).
  const uint64_t free = leadingFreeMerges(ranked);
  if (free) {
    std::vector<uint32_t> first(by_rank.begin(), by_rank.begin() + static_cast<std::ptrdiff_t>(free));
    std::sort(first.begin(), first.end(), byKey);
    for (uint32_t v : first) {
      alive_[v] = 0;
      up[v] = ranked.parent[v];
      tree_.parent[v] = ranked.parent[v];
      tree_.error[v] = ranked.error.empty() ? 0.0f : ranked.error[v];
      order.push_back(v);
    }
    tree_.batches.push_back(static_cast<uint32_t>(free));
  }
  const uint32_t d = divisor ? divisor : kDefaultBatchDivisor;
  uint64_t unmerged = np - free;
  // Each lane's vertices' places in its list of vertices (batchLane's `verts`), written by the lane
  // as it starts (a vertex is in one lane at a time).
  std::vector<uint32_t> place;
  assignPopulated(place, np, kNoIndex);
  // A merge made by a lane: its place in the batch's order (the pass, or the sweep after the passes,
  // then the key, or the rank), and its child.
  struct Made {
    uint32_t stage;
    uint64_t key;
    uint32_t v;
    bool operator<(const Made& o) const {
      return stage != o.stage ? stage < o.stage : (key != o.key ? key < o.key : v < o.v);
    }
  };
  constexpr uint32_t kSweeps = kBatchPasses + 1;  // the sweeps by rank after the passes
  constexpr uint32_t kOther = UINT32_MAX;         // the merges into another target
  // Batches the merges `merges` (by rank) of lane L, whose vertices not merged yet number `left`,
  // into `out` (each batch's merges as made): see ranking.h. `clean` = every batch before them ended
  // where the ranking's prefix does.
  auto batchLane = [&](Lane& L, const std::vector<uint32_t>& verts, const std::vector<uint32_t>& merges, uint64_t left,
                       bool clean, std::vector<std::vector<Made>>& out, BatchStats& bs) {
    L.ws = &thread_ws_.local();
    // Per vertex of the lane (`verts`, ascending: the vertices its merges and their stars hold), at
    // its place: its rank while it is the child of a merge of the lane's batch not made yet, else
    // kNoIndex; the largest rank of the batch's merges tried so far whose child's star held it
    // (late); the vertex a merge of the batch waits for, and the count of the lane's merges made when
    // its checks last failed with the parent it then had (kNoIndex: none); the count of the lane's
    // merges made when one last changed a tetrahedron around it (stamp: a check that failed is not
    // made again while nothing around it changed). Held by the running lanes only, not for every
    // vertex. A vertex of another lane (a star across a part's cut, where the batches' mesh differs
    // from the ranking's) has the last place, shared, whose marks only make the checks run again.
    const uint32_t n = static_cast<uint32_t>(verts.size());
    for (uint32_t i = 0; i < n; ++i) std::atomic_ref<uint32_t>(place[verts[i]]).store(i, std::memory_order_relaxed);
    auto at = [&](uint32_t y) {
      const uint32_t i = std::atomic_ref<uint32_t>(place[y]).load(std::memory_order_relaxed);
      return i < n && verts[i] == y ? i : n;
    };
    std::vector<uint32_t> pending(n + 1, kNoIndex), late(n + 1, 0), blocker(n + 1, kNoIndex), failed(n + 1, kNoIndex),
        failed_root(n + 1, kNoIndex), stamp(n + 1, 0);
    std::vector<uint32_t> carry, batch, deferred, still, touched;
    std::vector<Made>* made_into = nullptr;
    uint32_t clock = 0;
    size_t next = 0;
    // The first vertex y of the tetrahedra around x with stop(y) (kNoIndex: none).
    auto inStar = [&](uint32_t x, auto&& stop) {
      gatherStar(L, x, L.corners, L.star_tets);
      for (const Tet& q : L.star_tets)
        for (uint32_t y : q)
          if (stop(y)) return y;
      return kNoIndex;
    };
    auto apply = [&](uint32_t v, uint32_t w, uint32_t stage, uint64_t key) {
      ++clock;
      inStar(v, [&](uint32_t y) { return stamp[at(y)] = clock, false; });
      merge(L, v, w, ranked.error.empty() ? 0.0f : ranked.error[v]);
      up[v] = w;
      made_into->push_back(Made{stage, key, v});
    };
    auto tryMerge = [&](uint32_t v, uint32_t stage, uint64_t key) {
      const uint32_t w = root(ranked.parent[v]);
      if (w == v || !validate(L, v, w)) return false;
      apply(v, w, stage, key);
      return true;
    };
    // Into the target the ranking's error prefers among those the checks allow now.
    auto tryOther = [&](uint32_t v) {
      candidates(L, v, L.sorted, *L.ws);
      std::sort(L.sorted.begin(), L.sorted.end(), [](const Candidate& a, const Candidate& b) {
        return a.error < b.error || (a.error == b.error && a.w < b.w);
      });
      for (const Candidate& c : L.sorted) {
        if (validate(L, v, c.w)) {
          apply(v, c.w, kOther, ranked.rank[v]);
          ++bs.retargeted;
          return true;
        }
      }
      return false;
    };
    // A merge waits for the merges of the batch ranked before it whose child is in its child's star:
    // one of them would change the other's neighbourhood, and the ranking made them in rank order.
    // The vertex it waits for goes to blocker[v], so that v is not looked at again before that merge
    // is made.
    auto waitsFor = [&](uint32_t v) {
      const uint32_t r = ranked.rank[v];
      return inStar(v, [&](uint32_t y) { return pending[at(y)] < r; });
    };
    auto changedSince = [&](uint32_t v, uint32_t w, uint32_t t) {
      auto changed = [&](uint32_t y) { return stamp[at(y)] > t; };
      return inStar(v, changed) != kNoIndex || inStar(w, changed) != kNoIndex;
    };
    // A merge in the very neighbourhood the ranking made it in is allowed as it was then, and is made
    // without the checks: while every batch so far ended at the ranking's prefix (ranked_so_far), when
    // its parent is still a root, no merge of the batch ranked before it is left with its child in the
    // star of the child or of the parent, and none ranked after it has been made with its child in
    // those stars (late[y]: the largest rank of the batch's merges tried so far whose child's star held
    // y). In a part, the child and the parent are away from the other parts, as in the ranking.
    bool ranked_so_far = clean;
    auto asRanked = [&](uint32_t v) {
      const uint32_t r = ranked.rank[v];
      const uint32_t w = ranked.parent[v];
      if (!ranked_so_far || root(w) != w || (L.restricted && (seam_[v] || seam_[w]))) return false;
      auto differs = [&](uint32_t y) { return pending[at(y)] < r || late[at(y)] > r; };
      return inStar(v, differs) == kNoIndex && inStar(w, differs) == kNoIndex;
    };
    auto markLate = [&](uint32_t v) {
      const uint32_t r = ranked.rank[v];
      inStar(v, [&](uint32_t y) {
        uint32_t& l = late[at(y)];
        if (l == 0) touched.push_back(y);
        l = std::max(l, r);
        return false;
      });
    };
    while (next < merges.size() || !carry.empty()) {
      const uint64_t want = (left + d - 1) / d;
      // The merges left over from the last batch first (their ranks are the smallest), then the next
      // ones by rank.
      batch = carry;
      while (batch.size() < want && next < merges.size()) batch.push_back(merges[next++]);
      out.emplace_back();
      made_into = &out.back();
      for (uint32_t v : batch) pending[at(v)] = ranked.rank[v];
      ranked_so_far = clean && bs.carried == 0 && bs.retargeted == 0 && bs.dropped == 0;
      // Passes in key order, each making the merges that need not wait and are allowed, while one does.
      deferred = batch;
      std::sort(deferred.begin(), deferred.end(), byKey);
      // At most kBatchPasses: where the ranking made long chains of neighbouring merges (on a smooth
      // grid, whose errors tie), each pass makes few of them, and the rest go by rank.
      uint32_t passes = 0;
      for (size_t made = 1; made && !deferred.empty() && passes++ < kBatchPasses;) {
        made = 0;
        still.clear();
        for (uint32_t v : deferred) {
          const uint32_t r = ranked.rank[v];
          const uint32_t i = at(v);
          if (blocker[i] != kNoIndex && pending[at(blocker[i])] < r) {
            still.push_back(v);
            continue;
          }
          const uint32_t w = root(ranked.parent[v]);
          if (failed[i] != kNoIndex && failed_root[i] == w && !changedSince(v, w, failed[i])) {
            still.push_back(v);
            continue;
          }
          blocker[i] = waitsFor(v);
          if (blocker[i] != kNoIndex) {
            still.push_back(v);
            continue;
          }
          markLate(v);
          if (asRanked(v)) {
            apply(v, ranked.parent[v], passes, keys[v]);
            ++bs.unchecked;
          } else if (!tryMerge(v, passes, keys[v])) {
            failed[i] = clock;
            failed_root[i] = w;
            still.push_back(v);
            continue;
          }
          ++made;
          pending[i] = kNoIndex;
        }
        deferred.swap(still);
        ++bs.passes;
      }
      bs.deferred += deferred.size();
      // The deferred ones by rank, as long as one of them can merge (the first time through, those
      // in the neighbourhood the ranking made them in without the checks).
      std::sort(deferred.begin(), deferred.end(),
                [&](uint32_t a, uint32_t b) { return ranked.rank[a] < ranked.rank[b]; });
      uint32_t sweep = kSweeps;
      for (bool progress = true, first = true; progress && !deferred.empty(); first = false, ++sweep) {
        progress = false;
        still.clear();
        for (uint32_t v : deferred) {
          if (first) markLate(v);
          if (first && asRanked(v)) {
            apply(v, ranked.parent[v], sweep, ranked.rank[v]);
            ++bs.unchecked;
          } else if (!tryMerge(v, sweep, ranked.rank[v])) {
            still.push_back(v);
            continue;
          }
          progress = true;
          pending[at(v)] = kNoIndex;
        }
        deferred.swap(still);
      }
      for (uint32_t v : batch) {
        const uint32_t i = at(v);
        pending[i] = blocker[i] = failed[i] = kNoIndex;
      }
      for (uint32_t y : touched) late[at(y)] = 0;
      touched.clear();
      // Those whose parent the new order made invalid: another target, where one is allowed.
      still.clear();
      for (uint32_t v : deferred)
        if (!tryOther(v)) still.push_back(v);
      deferred.swap(still);
      carry = deferred;
      bs.carried += carry.size();
      if (made_into->empty()) {
        // None of them can merge in this order: the first one stays a root.
        out.pop_back();
        carry.erase(carry.begin());
        ++bs.dropped;
        continue;
      }
      left -= made_into->size();
    }
  };
  auto add = [](BatchStats& to, const BatchStats& from) {
    to.deferred += from.deferred;
    to.carried += from.carried;
    to.passes += from.passes;
    to.unchecked += from.unchecked;
    to.retargeted += from.retargeted;
    to.dropped += from.dropped;
  };
  auto clean = [](const BatchStats& s) { return s.carried == 0 && s.retargeted == 0 && s.dropped == 0; };
  // The i-th batches of the lanes, together: one batch of the tree each.
  auto appendBatches = [&](std::vector<std::vector<std::vector<Made>>>& lane_batches) {
    for (size_t i = 0;; ++i) {
      std::vector<Made> all;
      bool any = false;
      for (auto& lb : lane_batches) {
        if (i >= lb.size()) continue;
        any = true;
        all.insert(all.end(), lb[i].begin(), lb[i].end());
        lb[i] = {};
      }
      if (!any) break;
      std::sort(all.begin(), all.end());
      for (const Made& m : all) order.push_back(m.v);
      tree_.batches.push_back(static_cast<uint32_t>(all.size()));
      unmerged -= all.size();
    }
  };
  // The rounds of parts, when they are the ranking's (their merges follow the unused points').
  bool use_rounds = !rounds.empty();
  uint64_t round_merges = 0;
  for (const RankingRound& rr : rounds) {
    round_merges += rr.merges;
    use_rounds = use_rounds && rr.parts > 1 && rr.parts <= kMaxParts && rr.part.size() == np &&
                 std::all_of(rr.part.begin(), rr.part.end(), [&](uint8_t p) { return p < rr.parts; });
  }
  use_rounds = use_rounds && free + round_merges <= ranked.merges;
  size_t next = free;
  bool all_clean = true;
  // Each round's lanes (and then the whole mesh's) hold their vertices' lists from the tetrahedra
  // left, the last round's lanes gone first (one set of lists at a time).
  std::vector<std::unique_ptr<Lane>> lanes;
  for (const RankingRound& rr : use_rounds ? rounds : std::vector<RankingRound>{}) {
    lanes.clear();
    part_ = rr.part;
    markSeams();
    std::vector<std::vector<uint32_t>> lane_merges(rr.parts);
    for (uint32_t p = 0; p < rr.parts; ++p) {
      lanes.push_back(std::make_unique<Lane>(0));
      lanes.back()->restricted = true;
      lanes.back()->parallel = false;
    }
    for (uint32_t v = 0; v < np; ++v)
      if (alive_[v]) lanes[part_[v]]->members.push_back(v);
    for (uint64_t i = 0; i < rr.merges; ++i, ++next) lane_merges[part_[by_rank[next]]].push_back(by_rank[next]);
    // Each lane makes its pool as it starts, from its part's tetrahedra, and drops it when done: the
    // pools of the lanes running, not of every part, are held at once.
    const PartTets around = partTets(rr.parts);
    std::vector<std::vector<std::vector<Made>>> lane_batches(rr.parts);
    std::vector<BatchStats> lane_stats(rr.parts);
    // The parts on the threads, those of the most merges first.
    std::vector<uint64_t> cost(rr.parts);
    for (uint32_t p = 0; p < rr.parts; ++p) cost[p] = lane_merges[p].size();
    tbb::this_task_arena::isolate([&] {
      forEachLongestFirst(cost, [&](size_t p) {
        Lane& L = *lanes[p];
        withPartPool(L, static_cast<uint32_t>(p), around, [&] {
          batchLane(L, L.members, lane_merges[p], L.members.size(), all_clean, lane_batches[p], lane_stats[p]);
        });
      });
    });
    for (const BatchStats& s : lane_stats) {
      add(st, s);
      all_clean = all_clean && clean(s);
    }
    appendBatches(lane_batches);
  }
  // The merges after the rounds, on the whole mesh.
  for (Workspace& ws : thread_ws_) ws.spare_pool = {};
  lanes.clear();
  part_ = seam_ = {};
  Lane whole(0);
  buildWholePool(whole);
  {
    std::vector<std::vector<std::vector<Made>>> whole_batches(1);
    BatchStats s;
    const std::vector<uint32_t> rest(by_rank.begin() + static_cast<std::ptrdiff_t>(next), by_rank.end());
    std::vector<uint32_t> alive;
    for (uint32_t v = 0; v < np; ++v)
      if (alive_[v]) alive.push_back(v);
    batchLane(whole, alive, rest, unmerged, all_clean, whole_batches[0], s);
    add(st, s);
    appendBatches(whole_batches);
  }
  for (size_t i = 0; i < order.size(); ++i) tree_.rank[order[i]] = static_cast<uint32_t>(i + 1);
  tree_.merges = order.size();
  tree_.batch_divisor = d;
  tree_.field = ranked.field;
  tree_.w_density = ranked.w_density;
  tree_.w_geometry = ranked.w_geometry;
  tree_.error_quantiles = ranked.error_quantiles;
  st.batches = tree_.batches.size();
  if (stats) *stats = st;
  return std::move(tree_);
}

// The mid-edge points (codec/edge_points.h) merge into their edge's first end as merges 1..U, before
// the ranked ones (see ranking.h).
void mergeEdgePointsFirst(const TetMesh& mesh, MergeTree& tree) {
  const std::vector<EdgePoint> points = findEdgePoints(mesh);
  if (points.empty()) return;
  const uint32_t u = static_cast<uint32_t>(points.size());
  for (uint32_t& r : tree.rank)
    if (r) r += u;
  uint32_t rank = 0;
  for (const EdgePoint& e : points) {
    tree.parent[e.point] = e.a;
    tree.rank[e.point] = ++rank;
    tree.removed[e.point] = 0;
    tree.boundary[e.point] = 0;
    if (!tree.error.empty()) tree.error[e.point] = 0.0f;
  }
  tree.merges += u;
}

}  // namespace

RankingFaces rankingFaces(const TetMesh& mesh) {
  const size_t np = mesh.numPoints();
  RankingFaces out;
  out.boundary.assign(np, 0);
  out.frozen.assign(np, 0);
  out.pinned.assign(np, 0);
  const FaceClasses classes = classifyFaces(mesh, nullptr, 0, true);
  double area = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const uint16_t m = classes.mask[t];
    if (m == 0) continue;
    const Tet& q = mesh.tets[t];
    // A face listed in the same direction by both its tetrahedra (a flat one whose orientation the
    // file chose against its neighbours'): neither may change, see ranking.h.
    if (m & FaceClasses::kAlike)
      for (uint32_t x : q) out.pinned[x] = 1;
    for (int k = 0; k < 4; ++k) {
      const uint32_t a = q[kTetFace[k][0]], b = q[kTetFace[k][1]], c = q[kTetFace[k][2]];
      if (m & (FaceClasses::kNonManifold << k)) out.frozen[a] = out.frozen[b] = out.frozen[c] = 1;
      if (!(m & (FaceClasses::kBoundary << k))) continue;
      out.boundary[a] = out.boundary[b] = out.boundary[c] = 1;
      double n[3];
      triNormal(mesh.point(a), mesh.point(b), mesh.point(c), n);
      area += 0.5 * norm(n);
    }
  }
  out.area_scale = area > 0 && std::isfinite(area) ? area : 1.0;
  return out;
}

// The series of rounds (ranking.h): P, P - 1, ... parts (kMaxRounds rounds at most, 2 parts at
// least). Many small parts (a fine series, P >= 2 kAutoParts) leave many seams, and one part fewer
// moves the cuts of a large P little: the vertices along them would be left to the whole mesh's
// queue, one thread's work (46 parts of the 128^3 grid left it 270 thousand merges, 8 parts 150
// thousand). So a fine series (its cuts shifted, kFineShift) is followed by another, in one part per
// kPartTets of the tetrahedra left (at most half as many parts), or, below 2 kAutoParts such parts,
// by the last series in kAutoParts, kAutoParts - 1, ... parts, which takes most of the seams left on
// a mesh the fine series have made much smaller (the 200^3 grid: 180 parts, then 22, then 8). A
// series of fewer than 2 kAutoParts parts is the last. Returns the part count of the series after
// one of `parts` parts, 0 where it was the last.
uint32_t nextRankingSeries(uint32_t parts, size_t live_tets) {
  if (parts < 2 * kAutoParts) return 0;
  const size_t next = std::min<size_t>(live_tets / kPartTets, parts / 2);
  return next >= 2 * kAutoParts ? static_cast<uint32_t>(next) : kAutoParts;
}

std::string defaultFieldNote(const RankingStats& stats) {
  if (stats.constant_fields.empty()) return "";
  std::string names;
  for (const std::string& n : stats.constant_fields) names += (names.empty() ? "'" : ", '") + n + "'";
  const std::string on = stats.field.empty() ? "volume only" : "field '" + stats.field + "'";
  return "the simplification ranks on " + on + " (constant: " + names + "; --simplify-field chooses another)";
}

Status checkRankingOptions(const TetMesh& mesh, const RankingOptions& options) {
  const size_t tets = options.grid_tets ? options.grid_tets->size() : mesh.numTets();
  if (mesh.numPoints() >= 0xFFFFFFF0u || tets >= 0x3FFFFFFFu)
    return unsupported("simplification: mesh too large for 32-bit vertex and corner ids");
  if (options.grid_tets) {
    const size_t np = mesh.numPoints();
    if ((!mesh.tets.empty() && mesh.tets.size() != tets) || options.grid_tets->points() != np)
      return usageError("simplification: a grid's tetrahedra given for a mesh of other points or tetrahedra");
    if (!options.faces || options.faces->boundary.size() != np || options.faces->frozen.size() != np ||
        options.faces->pinned.size() != np)
      return usageError("simplification: a grid's tetrahedra given without the mesh's face flags");
  }
  if (!options.field.empty() && options.field != "none" && !mesh.findPointField(options.field)) {
    std::string names;
    for (const Field& f : mesh.point_fields) names += (names.empty() ? "" : ", ") + f.name;
    return usageError("simplification field '" + options.field +
                      "' not found (point fields: " + (names.empty() ? "none" : names) + ")");
  }
  if (!(options.w_density >= 0) || !(options.w_geometry >= 0) || !std::isfinite(options.w_density) ||
      !std::isfinite(options.w_geometry))
    return usageError("simplification weights must be finite and non-negative");
  return Status::ok();
}

StatusOr<MergeTree> rankMerges(const TetMesh& mesh, const RankingOptions& options, RankingStats* stats,
                               const ProgressFn& progress) {
  const auto start = std::chrono::steady_clock::now();
  // A mesh whose tetrahedra were released (RankingOptions::grid_tets) was checked with them; its cell
  // fields no longer match a count of tetrahedra.
  if (!options.grid_tets) GTN_RETURN_IF_ERROR(mesh.checkConsistency("simplification input"));
  GTN_RETURN_IF_ERROR(checkRankingOptions(mesh, options));
  const Field* field = nullptr;
  std::vector<std::string> constant_fields;
  if (options.field.empty()) {
    // A constant density makes the mass the volume times a constant: rank on a field that varies.
    std::vector<bool> varies;
    for (const Field& f : mesh.point_fields) {
      varies.push_back(f.components > 0 && firstComponentVaries(f));
      if (varies.back()) break;  // the first that varies is the one
      constant_fields.push_back(f.name);
    }
    const size_t chosen = defaultPointField(varies);
    if (chosen != SIZE_MAX) field = &mesh.point_fields[chosen];
  } else if (options.field != "none") {
    field = mesh.findPointField(options.field);
  }
  std::vector<double> density;
  if (field && field->components > 0) {
    density.resize(mesh.numPoints());
    for (size_t i = 0; i < density.size(); ++i) {
      const double d = field->get(i, 0);
      density[i] = std::isfinite(d) ? d : 0.0;
    }
  }
  Ranker ranker(mesh, std::move(density), options);
  RankingStats local;
  MergeTree tree = ranker.run(&local, progress);
  tree.field = field ? field->name : "";
  tree.w_density = options.w_density;
  tree.w_geometry = options.w_geometry;
  computeErrorQuantiles(tree);
  // A grid of rule cells (RankingOptions::grid_tets) uses every point.
  if (options.max_merges > tree.merges && !options.grid_tets) mergeEdgePointsFirst(mesh, tree);
  if (stats) {
    *stats = std::move(local);
    stats->merges = tree.merges;
    stats->boundary_merges = tree.boundaryMergesUpTo(tree.merges);
    stats->field = tree.field;
    stats->constant_fields = std::move(constant_fields);
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return tree;
}

StatusOr<MergeTree> batchMerges(const TetMesh& mesh, const MergeTree& ranked, const BatchKeys& keys, uint32_t divisor,
                                BatchStats* stats, const std::vector<RankingRound>& rounds, const RankingFaces* faces,
                                const RuleGridTets* grid_tets) {
  const auto start = std::chrono::steady_clock::now();
  GTN_RETURN_IF_ERROR(ranked.check("merge tree"));
  if (ranked.points() != mesh.numPoints() || keys.size() != mesh.numPoints())
    return invalidData("batchMerges: the tree, the keys and the mesh differ in vertices");
  RankingOptions options;
  options.w_density = ranked.w_density;
  options.w_geometry = ranked.w_geometry;
  options.faces = faces;
  options.grid_tets = grid_tets;
  GTN_RETURN_IF_ERROR(checkRankingOptions(mesh, options));
  Ranker ranker(mesh, {}, options);
  BatchStats local;
  MergeTree tree = ranker.batch(ranked, keys, divisor, rounds, faces, &local);
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return tree;
}

}  // namespace gtn
