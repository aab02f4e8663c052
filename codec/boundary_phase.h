// The boundary phase of the level codec (spec section 10.3): the boundary surface, a triangle mesh,
// coded by growing it from seed triangles across its open half-edges. Each popped half-edge (p, q)
// codes whether a triangle (q, p, x) follows, then x: new (predicted by the parallelogram), its rank
// among the open loop's neighbours next(q), prev(p), ... , or an escape with its slot; in contexts of
// the angles around the ear vertex. Every triangle becomes an open face of the peeling front.
//
// BoundaryLoop holds the phase's geometry and bookkeeping (the open loop, the corner angles, the open
// half-edges) and can be used alone; BoundaryPhase<Host> runs the phase through the level coder
// (Host) that owns the streams, the slot pool and the front.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "codec/flat_maps.h"
#include "codec/prediction.h"
#include "codec/range_coder.h"
#include "codec/symbols.h"
#include "mesh/index.h"
#include "mesh/status.h"

namespace gtn::level {

// The dot products of u = a - o and v = b - o (sums over the axes in order): u.u, v.v, u.v.
struct CornerDots {
  double uu, vv, uv;
};
inline CornerDots cornerDots(const double* o, const double* a, const double* b) {
  const double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]}, v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
  return {u[0] * u[0] + u[1] * u[1] + u[2] * u[2], v[0] * v[0] + v[1] * v[1] + v[2] * v[2],
          u[0] * v[0] + u[1] * v[1] + u[2] * v[2]};
}
// The angle at o of the triangle (o, a, b) in radians, from the polynomial arccosine of
// Abramowitz and Stegun 4.4.45 (error below 1e-4): basic operations only, so that every platform
// gets the same bits. 0 for a degenerate or non-finite corner (section 10.3).
inline double cornerAngle(const double* o, const double* a, const double* b) {
  const CornerDots c = cornerDots(o, a, b);
  const double n = std::sqrt(c.uu * c.vv);
  if (!(n > 0 && n <= kMaxKey)) return 0.0;
  double x = c.uv / n;
  const bool obtuse = x < 0;
  if (obtuse) x = -x;
  if (x > 1) x = 1;
  const double acute = std::sqrt(1 - x) * (1.5707288 + x * (-0.2121144 + x * (0.0742610 + x * -0.0187293)));
  return obtuse ? 3.141592653589793 - acute : acute;
}
// The angle at o between a and b: 0 below 60 degrees, 1 below 90, 2 otherwise, 3 degenerate.
inline uint32_t openingClass(const double* o, const double* a, const double* b) {
  const CornerDots c = cornerDots(o, a, b);
  if (!(c.uu > 0 && c.vv > 0)) return 3;
  if (!(c.uv > 0)) return 2;
  return 4 * c.uv * c.uv > c.uu * c.vv ? 0 : 1;
}
// The angle left open around a vertex whose corner angles sum to `sum`: 0 below 70 degrees
// (1.2217304763960306 radians), 1 below 130 (2.2689280275926285), 2 otherwise.
inline uint32_t roomClass(double sum) {
  const double room = 6.283185307179586 - sum;
  return room < 1.2217304763960306 ? 0 : (room < 2.2689280275926285 ? 1 : 2);
}

inline constexpr int kBoundaryContexts = 2 * 4 * 4 * 2;

// The open boundary loop and what the contexts need of it, per slot while the phase lasts.
class BoundaryLoop {
 public:
  // The candidates for the apex of a triangle on the open half-edge (p, q), and their context.
  struct Candidates {
    uint32_t slot[8];
    int n = 0;
    uint32_t context = 0;  // [loop closes] * 32 + ear context
  };

  bool done() const { return done_; }
  // Slot s now holds a new vertex: no loop neighbours, no corners.
  void addSlot(uint32_t s) {
    if (s >= nxt_.size()) {
      nxt_.push_back(kNoIndex);
      prv_.push_back(kNoIndex);
      corner_sum_.push_back(0.0);
      corner_count_.push_back(0);
    }
    nxt_[s] = kNoIndex;
    prv_[s] = kNoIndex;
    corner_sum_[s] = 0.0;
    corner_count_[s] = 0;
  }
  void reserve(size_t n) {
    nxt_.reserve(n);
    prv_.reserve(n);
    corner_sum_.reserve(n);
    corner_count_.reserve(n);
  }

  // Adds triangle v (positions pos(s)): its corner angles, and its half-edges, each closing the
  // open opposite half-edge or else opening (and queueing) itself.
  template <class Pos>
  void addTriangle(const uint32_t v[3], Pos pos) {
    for (int i = 0; i < 3; ++i) {
      corner_sum_[v[i]] += cornerAngle(pos(v[i]), pos(v[(i + 1) % 3]), pos(v[(i + 2) % 3]));
      ++corner_count_[v[i]];
    }
    for (int i = 0; i < 3; ++i) {
      const uint32_t s = v[i], t = v[(i + 1) % 3], r = v[(i + 2) % 3];
      const uint32_t w = half_.find(edgeKey(t, s), kNoIndex);
      if (w != kNoIndex) {
        closeHalf(t, s, w);
      } else {
        openHalf(s, t, r);
      }
    }
  }

  bool queueEmpty() const { return queue_.empty(); }
  // Pops the oldest queued half-edge: false if it has been closed since, else true with (p, q) and
  // the third vertex w of its triangle.
  bool popHalfEdge(uint32_t* p, uint32_t* q, uint32_t* w) {
    const uint64_t hk = queue_.front();
    queue_.pop_front();
    *p = static_cast<uint32_t>(hk >> 32), *q = static_cast<uint32_t>(hk);
    *w = half_.find(hk, kNoIndex);
    return *w != kNoIndex;
  }

  // The candidates for the apex on the open half-edge (p, q) whose triangle has third vertex w: the
  // live vertices (live(s)) met walking the open loop forward from q and backward from p, four steps
  // each. The first two (usually the two ears, prev(p) and next(q)) are ordered: the ear at the
  // vertex whose triangles so far leave the smaller angle open comes first (it is the likelier to
  // close), then the one nearer the parallelogram prediction. The context: whether the loop closes
  // (next(q) == prev(p)), the angle the first candidate's triangle would open at its ear vertex, the
  // angle left open there and whether that vertex has four triangles already.
  template <class Pos, class Live>
  Candidates candidates(uint32_t p, uint32_t q, uint32_t w, Pos pos, Live live) const {
    Candidates c;
    auto add = [&](uint32_t s) {
      if (s == kNoIndex || s == p || s == q || !live(s)) return;
      for (int i = 0; i < c.n; ++i)
        if (c.slot[i] == s) return;
      c.slot[c.n++] = s;
    };
    uint32_t fwd = nxt_[q], bwd = prv_[p];
    const uint32_t closes = (fwd != kNoIndex && fwd == bwd) ? 1 : 0;
    for (int step = 0; step < 4; ++step) {
      add(fwd);
      add(bwd);
      if (fwd != kNoIndex) fwd = nxt_[fwd];
      if (bwd != kNoIndex) bwd = prv_[bwd];
    }
    uint32_t ear_ctx = (3 * 4 + 3) * 2;  // no ear first
    if (c.n > 0) {
      double pr[3];
      for (int i = 0; i < 3; ++i) pr[i] = pos(p)[i] + pos(q)[i] - pos(w)[i];
      auto earOf = [&](uint32_t s) { return s == prv_[p] ? p : (s == nxt_[q] ? q : kNoIndex); };
      if (c.n > 1) {
        const uint32_t e0 = earOf(c.slot[0]), e1 = earOf(c.slot[1]);
        const double s0 = e0 != kNoIndex ? corner_sum_[e0] : -1.0, s1 = e1 != kNoIndex ? corner_sum_[e1] : -1.0;
        if (s1 > s0 || (!(s1 < s0) && apexDistance(pos(c.slot[1]), pr) < apexDistance(pos(c.slot[0]), pr)))
          std::swap(c.slot[0], c.slot[1]);
      }
      const uint32_t e = earOf(c.slot[0]);
      if (e != kNoIndex) {
        const uint32_t other = e == p ? q : p;
        ear_ctx = (openingClass(pos(e), pos(other), pos(c.slot[0])) * 4 + roomClass(corner_sum_[e])) * 2 +
                  (corner_count_[e] >= 4 ? 1 : 0);
      }
    }
    c.context = closes * 32 + ear_ctx;
    return c;
  }

  uint32_t next(uint32_t s) const { return nxt_[s]; }
  uint32_t prev(uint32_t s) const { return prv_[s]; }
  double cornerSum(uint32_t s) const { return corner_sum_[s]; }
  uint32_t cornerCount(uint32_t s) const { return corner_count_[s]; }

  // The phase is over: the memory is freed, not just emptied (the decoder's memory should follow the
  // peeling front from here on), and new slots no longer get loop entries.
  void release() {
    half_ = EdgeMap();
    queue_ = RingQueue<uint64_t>();
    nxt_ = std::vector<uint32_t>();
    prv_ = std::vector<uint32_t>();
    corner_sum_ = std::vector<double>();
    corner_count_ = std::vector<uint32_t>();
    done_ = true;
  }

 private:
  void openHalf(uint32_t s, uint32_t t, uint32_t r) {
    half_.put(edgeKey(s, t), r);
    nxt_[s] = t;
    prv_[t] = s;
    queue_.push_back(edgeKey(s, t));
  }
  void closeHalf(uint32_t s, uint32_t t, uint32_t r) {
    half_.eraseIf(edgeKey(s, t), r);
    if (nxt_[s] == t) nxt_[s] = kNoIndex;
    if (prv_[t] == s) prv_[t] = kNoIndex;
  }

  EdgeMap half_;  // open boundary half-edge -> third vertex of its triangle
  RingQueue<uint64_t> queue_;
  // Per slot: the open boundary loop and, over the boundary triangles added so far, the sum of
  // their corner angles at the vertex (cornerAngle) and their count (section 10.3).
  std::vector<uint32_t> nxt_, prv_;
  std::vector<double> corner_sum_;
  std::vector<uint32_t> corner_count_;
  bool done_ = false;
};

// The phase itself. Host is the level coder: it provides the boundary stream (bnd()), the slot pool
// (P, isLive, codeSlot), new vertices (introduceVertex, codeSeedVertex), the emitted triangle
// (emitBoundaryTriangle: the encoder's bookkeeping or the decoder's sink), the front (openFace) and
// the encoder's side (enc()).
template <class Host>
class BoundaryPhase {
 public:
  static constexpr bool kEncode = Host::kEncode;

  explicit BoundaryPhase(Host& host) : h_(host) {}
  BoundaryLoop& loop() { return loop_; }

  Status run() {
    auto& bnd = h_.bnd();
    while (true) {
      if (loop_.queueEmpty()) {
        bool more = false;
        uint32_t tri = 0;
        GTN_RETURN_IF_ERROR(codeSeedTriangle(&more, &tri));
        if (!more) break;
        continue;
      }
      if constexpr (!kEncode) {
        if (!bnd.ok()) return h_.bad("boundary stream is truncated or corrupt");
      }
      uint32_t p, q, w;
      if (!loop_.popHalfEdge(&p, &q, &w)) continue;
      uint32_t has = 0, tri = 0, x_src = 0;
      if constexpr (kEncode) has = h_.enc()->partnerTriangle(p, q, &tri, &x_src);
      has = bnd.bit(partner_, has);
      if (!has) continue;
      const BoundaryLoop::Candidates c = loop_.candidates(
          p, q, w, [&](uint32_t s) { return h_.P(s); }, [&](uint32_t s) { return h_.isLive(s); });
      uint32_t sym = 0;
      if constexpr (kEncode) sym = candidateSymbol(h_.enc()->src_slot[x_src], c.slot, c.n);
      sym = sym_[c.context].code(bnd, sym);
      uint32_t x;
      if (sym == kSymNew) {
        double pred[3];
        for (int i = 0; i < 3; ++i) pred[i] = h_.P(p)[i] + h_.P(q)[i] - h_.P(w)[i];
        FieldPrediction fp;
        fp.kind = FieldPrediction::kParallelogram;
        fp.s[0] = p;
        fp.s[1] = q;
        fp.s[2] = w;
        GTN_RETURN_IF_ERROR(h_.introduceVertex(x_src, pred, fp, &x));
      } else if (sym == kSymEscape) {
        x = h_.codeSlot(bnd, kEncode ? h_.enc()->src_slot[x_src] : 0);
        if (!h_.isLive(x)) return h_.bad("boundary triangle refers to a vertex that is not live");
      } else {
        if (sym > static_cast<uint32_t>(c.n)) return h_.bad("boundary candidate rank out of range");
        x = c.slot[sym - 1];
      }
      const uint32_t v[3] = {q, p, x};
      GTN_RETURN_IF_ERROR(addTriangle(v, tri));
    }
    loop_.release();
    return Status::ok();
  }

 private:
  // When the half-edge queue empties: whether another component follows, and its seed triangle.
  Status codeSeedTriangle(bool* more, uint32_t* tri) {
    uint32_t bit = 0;
    if constexpr (kEncode) bit = h_.enc()->nextSeedTriangle(tri);
    *more = h_.bnd().bit(seed_more_, bit);
    if (!*more) return Status::ok();
    uint32_t v[3];
    for (int i = 0; i < 3; ++i)
      GTN_RETURN_IF_ERROR(h_.codeSeedVertex(h_.bnd(), kEncode ? h_.enc()->btris[*tri].v[i] : 0, &v[i]));
    return addTriangle(v, *tri);
  }

  // Emits triangle v (the encoder's boundary triangle `tri`), adds it to the loop and opens it, as
  // seen from inside, on the front.
  Status addTriangle(const uint32_t v[3], uint32_t tri) {
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return h_.bad("boundary triangle with a repeated vertex");
    GTN_RETURN_IF_ERROR(h_.emitBoundaryTriangle(v, tri));
    loop_.addTriangle(v, [&](uint32_t s) { return h_.P(s); });
    const uint32_t inward[3] = {v[0], v[2], v[1]};
    if (h_.front().find(inward) >= 0) return h_.bad("boundary triangle repeated");
    h_.openFace(inward, kNoIndex, kEncode ? h_.enc()->btris[tri].tet : 0);
    return Status::ok();
  }

  Host& h_;
  BoundaryLoop loop_;
  BitTree<4> sym_[kBoundaryContexts];
  BitModel seed_more_, partner_;
};

}  // namespace gtn::level
