// The apex candidates of a gate face in the level codec (spec section 10.4): the front vertices on
// the fans around the gate face's edges, ranked by multiplicity and then by distance to the
// predicted apex, or by the Delaunay sweep (the spheres through the gate face, swept into the
// undecoded side). The two orders compete: the one that has ranked the true apexes better so far is
// used. A candidate's symbol is 1 + its place in the chosen order; the context of the symbol comes
// from the first candidate. The ranker reads the slot pool's positions and the front's edges.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "codec/flat_maps.h"
#include "codec/prediction.h"
#include "codec/slot_pool.h"
#include "codec/symbols.h"
#include "mesh/index.h"
#include "mesh/predicates.h"

namespace gtn::level {

inline constexpr int kMaxGather = 48;
inline constexpr int kFanSteps = 10;
inline constexpr int kTetContexts = 10 * 3 * 3;

class ApexCandidates {
 public:
  ApexCandidates(const SlotPool& pool, const EdgeMap& edges) : pool_(pool), edges_(edges) {}
  void setDelaunayFirst(bool on) { delaunay_first_ = on; }
  bool delaunayFirst() const { return delaunay_first_; }

  // After the gate's apex x (slot) is known: its side of the gate face counts in the vote that
  // decides the wrong side behind boundary faces, and the orders are scored.
  void apexFound(uint32_t x, int side) {
    apex_votes_ += side;
    scoreOrders(x);
  }
  // The gate face's wrong side (gather): candidates there are dropped, 0 if none is known.
  int wrongSide() const { return wrong_; }
  // Whether the Delaunay order is in use and ranks by key before count: escapes are then ranked by
  // the sweep key too.
  bool keyFirst() const { return by_key_chosen_ && delaunay_first_; }
  // The Delaunay sweep of the gate face (prepareSweep): its circumcentre, squared radius and key
  // scale.
  const double* sweepCentre() const { return cc0_; }
  double sweepRadius2() const { return r2_; }
  double sweepScale() const { return key_scale_; }
  void ensureSweep() {
    if (!swept_ready_) prepareSweep();
  }

  struct Candidate {
    uint32_t s;
    uint32_t w;
    double dist;  // squared distance to the predicted apex
    double key;   // sort key: Delaunay sweep parameter, else dist
  };

  // Front vertices around the gate face, with the coding context. `side`: the orientation filter of
  // the gate face (a, b, c). The candidates are only gathered here, with their multiplicities; both
  // orders rank by multiplicity first, so a group of equal multiplicity is filtered and keyed only
  // when a rank, the context or a new vertex's list reaches it (evaluateGroups): usually only the
  // first group is. The result is the same as keying every candidate.
  uint32_t gather(const FrontFace& g, const Orient3dFilter& side, const double p[3]) {
    if (gather_mark_.size() < pool_.size()) gather_mark_.resize(pool_.size(), 0);
    RawCandidate* c = raw_;
    int n = 0;
    uint32_t across[3] = {kNoIndex, kNoIndex,
                          kNoIndex};  // the apex of the front face across each gate edge (c, a), (a, b), (b, c)
    if (++gather_epoch_ == kGatherEpochs) {
      std::fill(gather_mark_.begin(), gather_mark_.end(), 0);
      gather_epoch_ = 1;
    }
    const uint32_t tag = gather_epoch_ << kGatherIndexBits;
    for (uint32_t s : g.v) gather_mark_[s] = tag | kGateMark;
    auto add = [&](uint32_t s) {
      const uint32_t m = gather_mark_[s];
      if ((m & ~kGateMark) == tag) {
        if (m != (tag | kGateMark)) ++c[m & kGateMark].w;
        return;
      }
      if (n < kMaxGather) {
        gather_mark_[s] = tag | static_cast<uint32_t>(n);
        c[n++] = {s, 1};
        __builtin_prefetch(P(s));  // read when the candidate is evaluated
      }
    };
    for (int j = 0; j < 3; ++j) {
      const uint32_t a = g.v[j], b = g.v[(j + 1) % 3], cc = g.v[(j + 2) % 3];
      // Forward around a: across edge (c, a), then on.
      const EdgeMap::From around = edges_.from(a);
      uint32_t v = cc;
      bool closed = false;
      for (int step = 0; step < kFanSteps; ++step) {
        const uint32_t w = around.find(v, kNoIndex);
        if (step == 0) across[j] = w;
        if (w == kNoIndex) break;
        if (w == b) {
          closed = true;
          break;
        }
        add(w);
        v = w;
      }
      if (closed) continue;
      v = b;
      for (int step = 0; step < kFanSteps; ++step) {
        const uint32_t w = edges_.find(edgeKey(v, a), kNoIndex);
        if (w == kNoIndex || w == cc) break;
        add(w);
        v = w;
      }
    }
    raw_n_ = n;
    cand_n_ = 0;
    first_ = -1;
    gate_ = &g;
    side_ = &side;
    pred_ = p;
    // The apex lies on the far side of the gate face from the decoded tetrahedron (a, b, c, d),
    // whatever the mesh's orientation convention; behind a boundary face, on the side where the
    // apexes decoded so far mostly lay. Candidates on the other side are dropped (the escape still
    // reaches them). Only signs a floating-point filter proves count (near-flat cases drop nothing):
    // exact arithmetic would cost more than it saves, and the filter is reproducible everywhere.
    wrong_ = g.d != kNoIndex ? side.sign(P(g.d)) : (apex_votes_ > 0 ? -1 : (apex_votes_ < 0 ? 1 : 0));
    // Delaunay order: the spheres through a, b and c, swept into the undecoded side, meet the
    // apex of a Delaunay tetrahedron first. key = the sweep parameter at which a candidate is met.
    delaunay_ = wrong_ != 0;
    swept_ready_ = false;
    // Two orders compete: by distance to the predicted apex (right on structured grids) and by the
    // Delaunay sweep (right on Delaunay meshes). The one that has ranked the true apexes better so
    // far is used; both sides keep the same score. Both orders are total (slots differ), so a
    // candidate's place is the number of candidates before it: nothing is sorted unless the whole
    // list is needed (a new vertex's copy sources), and the list's prefix is the same either way.
    by_key_chosen_ = delaunay_ && order_score_ > 0;
    // Ranking by key first needs every candidate keyed.
    if (by_key_chosen_ && delaunay_first_) evaluateAllGroups();
    // The context: the best multiplicity, how many share it (up to 3), how close the nearest of
    // those lies to the predicted apex, and across how many gate edges (up to 2) the front face's
    // apex is the first candidate (then the tetrahedron closes that face).
    evaluateGroups(1);
    uint32_t k = 0;
    uint32_t near = 2;
    uint32_t adjacent = 0;
    if (cand_n_ > 0) {
      // Over the best multiplicity's group: the only one evaluated so far, unless the Delaunay order
      // is chosen.
      uint32_t best_w = 0, top = 0;
      double best_dist = 0;
      for (int i = 0; i < cand_n_; ++i) best_w = std::max(best_w, cand_[i].w);
      for (int i = 0; i < cand_n_; ++i) {
        if (cand_[i].w != best_w) continue;
        best_dist = top == 0 ? cand_[i].dist : std::min(best_dist, cand_[i].dist);
        ++top;
      }
      k = 1 + (std::min<uint32_t>(best_w, 3) - 1) * 3 + std::min<uint32_t>(top, 3) - 1;
      const double *a = P(g.v[0]), *b = P(g.v[1]), *cc = P(g.v[2]);
      double e2 = 0;
      for (int i = 0; i < 3; ++i)
        e2 += (a[i] - b[i]) * (a[i] - b[i]) + (b[i] - cc[i]) * (b[i] - cc[i]) + (cc[i] - a[i]) * (cc[i] - a[i]);
      e2 /= 3.0;
      near = best_dist < 0.25 * e2 ? 0 : (best_dist < e2 ? 1 : 2);
      const uint32_t first = candidateAt(0);
      for (int j = 0; j < 3; ++j) adjacent += across[j] == first ? 1 : 0;
    }
    return (k * 3 + near) * 3 + std::min<uint32_t>(adjacent, 2);
  }

 private:
  // Moves whole groups of equal multiplicity, best first, from raw_ to cand_ (dropping those on the
  // wrong side, keying the rest) until cand_ holds at least `want` candidates or raw_ is empty.
  void evaluateGroups(int want) {
    while (cand_n_ < want && raw_n_ > 0) {
      uint32_t w = 0;
      for (int i = 0; i < raw_n_; ++i) w = std::max(w, raw_[i].w);
      for (int i = 0; i < raw_n_;) {
        if (raw_[i].w != w) {
          ++i;
          continue;
        }
        const uint32_t s = raw_[i].s;
        raw_[i] = raw_[--raw_n_];
        evaluate(s, w);
      }
    }
  }
  // The same for every group at once (ranking by key first needs every candidate keyed).
  void evaluateAllGroups() {
    for (int i = 0; i < raw_n_; ++i) evaluate(raw_[i].s, raw_[i].w);
    raw_n_ = 0;
  }
  // Drops candidate s if it is on the wrong side, else keys it into cand_.
  void evaluate(uint32_t s, uint32_t w) {
    const double* q = P(s);
    if (wrong_ != 0 && side_->sign(q) == wrong_) return;
    Candidate& x = cand_[cand_n_++];
    x.s = s;
    x.w = w;
    // Sort keys must be ordered values: overflowing coordinates (NaN or infinite distances) sort
    // last, so that the comparison stays a strict weak order.
    x.dist = apexDistance(q, pred_);
    x.key = x.dist;
    if (delaunay_) {
      if (!swept_ready_) prepareSweep();
      x.key = sweepKey(q);
    }
  }

 public:
  // The Delaunay order's key of q (prepareSweep first): the sweep parameter at which q is met, in
  // units of 1/64 of the face's circumradius, so that nearly cospherical candidates (every cell of
  // a structured grid) tie and fall back to the distance order.
  double sweepKey(const double* q) const {
    const double e[3] = {q[0] - cc0_[0], q[1] - cc0_[1], q[2] - cc0_[2]};
    const double h = nn_[0] * e[0] + nn_[1] * e[1] + nn_[2] * e[2];
    const double t = h > 0 ? (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] - r2_) / (2 * h) : 1e300;
    const double y = t * key_scale_;
    return y < 1e18 ? floorKey(y) : 1e18;  // NaN too
  }

 private:
  // The circumcentre and radius of the gate face and its normal into the undecoded side.
  void prepareSweep() {
    const FrontFace& g = *gate_;
    const double *a = P(g.v[0]), *b = P(g.v[1]), *c3 = P(g.v[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c3[0] - a[0], c3[1] - a[1], c3[2] - a[2]};
    const double N[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    const double NN = N[0] * N[0] + N[1] * N[1] + N[2] * N[2];
    const double w[3] = {uu * v[0] - vv * u[0], uu * v[1] - vv * u[1], uu * v[2] - vv * u[2]};
    const double wx[3] = {w[1] * N[2] - w[2] * N[1], w[2] * N[0] - w[0] * N[2], w[0] * N[1] - w[1] * N[0]};
    r2_ = 0;
    for (int i = 0; i < 3; ++i) {
      cc0_[i] = NN > 0 ? a[i] + wx[i] / (2 * NN) : a[i];
      nn_[i] = -wrong_ * N[i];
      r2_ += (cc0_[i] - a[i]) * (cc0_[i] - a[i]);
    }
    const double nl = std::sqrt(NN);
    key_scale_ = r2_ > 0 && nl > 0 ? 64.0 * nl / std::sqrt(r2_) : 0.0;
    swept_ready_ = true;
  }

  static bool beforeByDistance(const Candidate& x, const Candidate& y) {
    if (x.w != y.w) return x.w > y.w;
    if (x.dist != y.dist) return x.dist < y.dist;
    return x.s < y.s;
  }
  // The Delaunay order: by key, then count, in a level that sets "Delaunay first"; by count, then
  // key, in others.
  static bool beforeByKey(const Candidate& x, const Candidate& y, bool key_first) {
    if (key_first && x.key != y.key) return x.key < y.key;
    if (x.w != y.w) return x.w > y.w;
    if (x.key != y.key) return x.key < y.key;
    if (x.dist != y.dist) return x.dist < y.dist;
    return x.s < y.s;
  }
  // The two orders as function objects, so that the sorts inline them.
  struct ByDistance {
    bool operator()(const Candidate& x, const Candidate& y) const { return beforeByDistance(x, y); }
  };
  struct ByKey {
    bool key_first;
    bool operator()(const Candidate& x, const Candidate& y) const { return beforeByKey(x, y, key_first); }
  };
  // Place of the candidate at index i in one order (0 = first).
  int placeOf(int i, bool by_key) const {
    int place = 0;
    const Candidate& x = cand_[i];
    if (by_key) {
      for (int j = 0; j < cand_n_; ++j) place += beforeByKey(cand_[j], x, delaunay_first_);
    } else {
      for (int j = 0; j < cand_n_; ++j) place += beforeByDistance(cand_[j], x);
    }
    return place;
  }
  // Index of `slot` in cand_, evaluating groups until it is there; -1 if it is no candidate (or was
  // dropped).
  int candidateIndex(uint32_t slot) {
    for (;;) {
      for (int i = 0; i < cand_n_; ++i)
        if (cand_[i].s == slot) return i;
      bool pending = false;
      for (int i = 0; i < raw_n_; ++i) pending |= raw_[i].s == slot;
      if (!pending) return -1;
      evaluateGroups(cand_n_ + 1);
    }
  }

 public:
  // The coded symbol of `slot` (kNoIndex: a new vertex): new, 1 + its place in the chosen order among
  // the first kMaxCandidates, or escape.
  uint32_t candidateSymbolOf(uint32_t slot) {
    if (slot == kNoIndex) return kSymNew;
    const int i = candidateIndex(slot);
    if (i < 0) return kSymEscape;
    const int place = placeOf(i, by_key_chosen_);
    return place < kMaxCandidates ? static_cast<uint32_t>(place + 1) : kSymEscape;
  }
  // The slot at `place` of the chosen order, kNoIndex if there are not that many candidates.
  uint32_t candidateAt(int place) {
    evaluateGroups(place + 1);
    if (place >= cand_n_) return kNoIndex;
    if (place == 0) return cand_[firstIndex()].s;
    return by_key_chosen_ ? candidateAt(place, ByKey{delaunay_first_}) : candidateAt(place, ByDistance());
  }

 private:
  // Index in cand_ of the first candidate of the chosen order (cand_ not empty), found once per
  // gate: the groups evaluated later have smaller multiplicities and come after it in both orders.
  int firstIndex() {
    if (first_ < 0) first_ = by_key_chosen_ ? firstIndex(ByKey{delaunay_first_}) : firstIndex(ByDistance());
    return first_;
  }
  template <class Before>
  int firstIndex(Before before) const {
    int best = 0;
    for (int i = 1; i < cand_n_; ++i)
      if (before(cand_[i], cand_[best])) best = i;
    return best;
  }
  template <class Before>
  uint32_t candidateAt(int place, Before before) const {
    Candidate tmp[kMaxGather];
    std::copy(cand_, cand_ + cand_n_, tmp);
    std::nth_element(tmp, tmp + place, tmp + cand_n_, before);
    return tmp[place].s;
  }

 public:
  // The first kMaxCandidates candidates in the chosen order; returns their count.
  int orderedCandidates(uint32_t* out) {
    evaluateAllGroups();
    if (by_key_chosen_) return orderedCandidates(out, ByKey{delaunay_first_});
    return orderedCandidates(out, ByDistance());
  }

 private:
  template <class Before>
  int orderedCandidates(uint32_t* out, Before before) const {
    Candidate tmp[kMaxGather];
    std::copy(cand_, cand_ + cand_n_, tmp);
    std::sort(tmp, tmp + cand_n_, before);
    const int m = std::min(cand_n_, kMaxCandidates);
    for (int i = 0; i < m; ++i) out[i] = tmp[i].s;
    return m;
  }
  // After a tetrahedron's apex x is known: the order that placed it earlier (among the first
  // kMaxCandidates; later or absent counts as kMaxCandidates) scores a point. Without the Delaunay
  // order (no side to sweep into) both orders are the same.
  void scoreOrders(uint32_t x) {
    if (!delaunay_) return;
    // The usual apex is the first candidate, whose place in the chosen order is 0.
    const bool first = first_ >= 0 && cand_[first_].s == x;
    const int i = first ? first_ : candidateIndex(x);
    if (i < 0) return;
    const int rk = first && by_key_chosen_ ? 0 : std::min(placeOf(i, true), kMaxCandidates);
    const int rd = first && !by_key_chosen_ ? 0 : std::min(placeOf(i, false), kMaxCandidates);
    if (rk < rd && order_score_ < kOrderScoreLimit) ++order_score_;
    if (rd < rk && order_score_ > -kOrderScoreLimit) --order_score_;
  }

  const double* P(uint32_t s) const { return pool_.position(s); }

  const SlotPool& pool_;
  const EdgeMap& edges_;
  bool delaunay_first_ = false;  // the level's "Delaunay first" bit: rank by key before count
  int wrong_ = 0;                // the gate's wrong side (gather)
  int64_t apex_votes_ = 0;       // sum of orient3dCertain(a, b, c, apex) over the tetrahedra decoded so far
  // Apex candidates in both orders (section 10.4 of the spec) and which order has ranked better.
  static constexpr int kOrderScoreLimit = 32;
  struct RawCandidate {
    uint32_t s;
    uint32_t w;  // how many fan walks reached it
  };
  RawCandidate raw_[kMaxGather];  // the gate's candidates not evaluated yet, unordered
  // Per slot, while gatherCandidates runs: gather_epoch_ above kGatherIndexBits bits that hold the
  // slot's index in raw_, or kGateMark for the gate's own vertices (an older epoch: neither). Finding
  // a fan vertex among the candidates so far is then one load, not a scan of them all.
  static constexpr uint32_t kGatherIndexBits = 6;
  static constexpr uint32_t kGateMark = (1u << kGatherIndexBits) - 1;
  static constexpr uint32_t kGatherEpochs = 1u << (32 - kGatherIndexBits);
  static_assert(kMaxGather < kGateMark);
  std::vector<uint32_t> gather_mark_;  // grown to the pool's size as it grows
  uint32_t gather_epoch_ = 0;
  int raw_n_ = 0;
  Candidate cand_[kMaxGather];  // the evaluated ones (whole groups, best multiplicities), unordered
  int cand_n_ = 0;
  int first_ = -1;                        // firstIndex(), -1 until found
  const FrontFace* gate_ = nullptr;       // the gate face, its side filter and predicted apex, while
  const Orient3dFilter* side_ = nullptr;  // its candidates are evaluated
  const double* pred_ = nullptr;
  bool delaunay_ = false, swept_ready_ = false, by_key_chosen_ = false;
  double cc0_[3] = {0, 0, 0}, nn_[3] = {0, 0, 0}, r2_ = 0, key_scale_ = 0;  // prepareSweep
  int order_score_ = 0;
};

}  // namespace gtn::level
