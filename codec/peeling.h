// The peeling phase of the level codec (spec section 10.4): tetrahedra are decoded behind the open
// faces of the front, one gate face at a time in queue order. Each codes its apex as new, as a rank
// among the candidates (candidates.h) or as an escape (a rank among the live vertices by distance or
// sweep key, nearest_grid.h, else a slot), then its orientation; each emitted tetrahedron codes its
// cell values (cell_values.h), the points on its edges (section 10.5) and which of its vertices
// retire. When the queue empties, a bit says whether a seed tetrahedron follows. Host is the level
// coder: it owns the streams, the slot pool, the front and the vertices' values.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "codec/candidates.h"
#include "codec/edge_points.h"
#include "codec/front.h"
#include "codec/nearest_grid.h"
#include "codec/prediction.h"
#include "codec/range_coder.h"
#include "codec/symbols.h"
#include "mesh/faces.h"
#include "mesh/index.h"
#include "mesh/predicates.h"
#include "mesh/status.h"

namespace gtn::level {

inline constexpr uint64_t kEscapeScanBudget =
    256;  // live vertices scanned per decoded element, at most, for ranked escapes
inline constexpr uint32_t kEscapeRankBits = 12;  // ranks below 2^12

template <class Host>
class Peeling {
 public:
  static constexpr bool kEncode = Host::kEncode;

  explicit Peeling(Host& host) : h_(host), cands_(host.pool_, host.front_.edges) {}
  ApexCandidates& candidates() { return cands_; }
  // The rank queries' grid over the live vertices (built at the first ranked escape).
  NearestGrid& grid() { return grid_; }
  // Whether the level codes the points on edges (section 10.5).
  void setEdgePoints(bool on) { edge_points_ = on; }

 private:
  void predictApex(const FrontFace& g, double p[3]) const {
    gtn::level::predictApex(h_.P(g.v[0]), h_.P(g.v[1]), h_.P(g.v[2]), g.d != kNoIndex ? h_.P(g.d) : nullptr, p);
  }

  // `pred_cell`: the cell-value record of the decoded neighbour behind the gate face, or kNoIndex.
  // `gate`: the index in faces_ of the open face (e[0], e[2], e[1]) (face 3), or -1 to look it up;
  // `fresh_apex`: e[3] was just introduced, so no open face holds it.
  Status emitTet(const uint32_t e[4], uint32_t src_tet, uint32_t pred_cell, long gate = -1, bool fresh_apex = false) {
    if (e[0] == e[1] || e[0] == e[2] || e[0] == e[3] || e[1] == e[2] || e[1] == e[3] || e[2] == e[3])
      return h_.bad("tetrahedron with a repeated vertex");
    if constexpr (!kEncode) {
      if (h_.tets_done_ >= h_.header_.tets) return h_.bad("more tetrahedra than the header announces");
    }
    // The open faces the tetrahedron closes, -1 for those it opens: the answers h_.front_.faces.find gives,
    // where the caller does not know them already. Nothing below changes them before the faces are
    // closed (pool indices stay valid until their face is erased, and the faces differ).
    long closes[4];
    for (int k = 0; k < 4; ++k) {
      closes[k] = -1;
      if (k == 3 && gate >= 0) {
        closes[k] = gate;
      } else if (k == 3 || !fresh_apex) {
        const uint32_t f[3] = {e[kTetFace[k][0]], e[kTetFace[k][1]], e[kTetFace[k][2]]};
        uint32_t key[3];
        FaceMap::sortedKey(f, key);
        closes[k] = h_.front_.faces.find(key);
      }
    }
    GTN_RETURN_IF_ERROR(h_.cells_.code(closes, src_tet, pred_cell));
    if constexpr (kEncode) {
      h_.enc_->tet_order[src_tet] = h_.tets_done_;
      h_.enc_->tet_done[src_tet] = 1;
      for (uint32_t v : h_.enc_->mesh->tets[src_tet]) --h_.enc_->remaining[v];
    } else {
      const uint32_t ids[4] = {h_.pool_.ids[e[0]], h_.pool_.ids[e[1]], h_.pool_.ids[e[2]], h_.pool_.ids[e[3]]};
      GTN_RETURN_IF_ERROR(h_.sink_->tet(ids, h_.cells_.values()));
    }
    ++h_.tets_done_;
    if (edge_points_) GTN_RETURN_IF_ERROR(codeEdgePoints(e, gate, fresh_apex));
    const uint32_t rec = h_.cells_.record();
    for (int k = 0; k < 4; ++k) {
      if (closes[k] >= 0) {
        h_.closeFace(closes[k], k, e, closes);
        continue;
      }
      const uint32_t f[3] = {e[kTetFace[k][0]], e[kTetFace[k][1]], e[kTetFace[k][2]]};
      uint32_t nb = 0;
      if constexpr (kEncode) {
        const uint32_t sv = h_.enc_->slot_src[e[k]];
        const Tet& t = h_.enc_->mesh->tets[src_tet];
        int j = 0;
        while (j < 4 && t[j] != sv) ++j;
        if (j == 4) return h_.internal("tetrahedron vertex lost");
        nb = (*h_.enc_->neighbor)[4 * size_t{src_tet} + j];
        if (nb == kNoNeighbor || nb == kNonManifold || h_.enc_->tet_done[nb])
          return h_.internal("front face without a tetrahedron behind it");
      }
      h_.openFace(f, e[k], nb, rec);
    }
    if (rec != kNoIndex) h_.cells_.release(rec);
    for (int k = 0; k < 4; ++k) {
      const uint32_t s = e[k];
      if (h_.pool_.open[s] != 0 || h_.pool_.state[s] != kLive) continue;
      uint32_t done = 0;
      if constexpr (kEncode) done = h_.enc_->remaining[h_.enc_->slot_src[s]] == 0;
      done = h_.con_->bit(retire_, done);
      if (done) GTN_RETURN_IF_ERROR(h_.retire(s));
    }
    return Status::ok();
  }

  // The points on the edges of the tetrahedron (e, closing `gate`, -1 for a seed) that are coded now,
  // while both ends are live (section 10.5): per edge, a bit per point and a final clear bit. An
  // edge's points are coded with the first tetrahedron that has the edge, so the edges of a gate face
  // rarely have any left (only behind a boundary face), and those to a new apex always do on a
  // quadratic mesh: the bits' contexts tell these apart.
  Status codeEdgePoints(const uint32_t e[4], long gate, bool fresh_apex) {
    const bool boundary_gate = gate >= 0 && h_.front_.faces.at(gate).d == kNoIndex;
    for (int k = 0; k < 6; ++k) {
      const uint32_t a = e[kTetEdge[k][0]], b = e[kTetEdge[k][1]];
      const uint32_t kind = gate < 0 || (k >= 3 && fresh_apex) ? 0 : (k >= 3 ? 1 : (boundary_gate ? 2 : 3));
      EdgePoint *next = nullptr, *end = nullptr;  // the encoder's entries of the edge
      uint32_t hi = 0;
      if constexpr (kEncode) {
        const uint32_t sa = h_.enc_->slot_src[a], sb = h_.enc_->slot_src[b], lo = std::min(sa, sb);
        hi = std::max(sa, sb);
        next = h_.enc_->edge_points.data() + h_.enc_->edge_point_start[lo];
        end = h_.enc_->edge_points.data() + h_.enc_->edge_point_start[lo + 1];
        while (next != end && next->b < hi) ++next;
      }
      for (uint32_t more = 0;; more = 1) {
        uint32_t bit = 0;
        if constexpr (kEncode) bit = next != end && next->b == hi && next->point != kNoIndex;
        bit = h_.geo_->bit(edge_point_[kind][more], bit);
        if (!bit) break;
        if constexpr (!kEncode) {
          if (!h_.geo_->ok()) return h_.bad("geometry stream is truncated or corrupt");
        }
        uint32_t src = 0;
        if constexpr (kEncode) {
          src = next->point;
          next->point = kNoIndex;
          ++next;
        }
        FieldPrediction fp;
        fp.kind = FieldPrediction::kEdge;
        fp.s[0] = a;
        fp.s[1] = b;
        const double *pa = h_.P(a), *pb = h_.P(b);
        const double mid[3] = {(pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5, (pa[2] + pb[2]) * 0.5};
        uint32_t s;
        GTN_RETURN_IF_ERROR(h_.introduceVertex(src, mid, fp, &s));
        GTN_RETURN_IF_ERROR(h_.retire(s));
      }
    }
    return Status::ok();
  }

  // A seed tetrahedron: its four vertices, existing or new.
  Status seedTet() {
    uint32_t src_tet = 0;
    Tet src{};
    if constexpr (kEncode) {
      src_tet = static_cast<uint32_t>(h_.enc_->next_seed_tet);
      src = h_.enc_->mesh->tets[src_tet];
    }
    uint32_t e[4];
    for (int i = 0; i < 4; ++i) GTN_RETURN_IF_ERROR(h_.codeSeedVertex(*h_.con_, src[i], &e[i]));
    return emitTet(e, src_tet, kNoIndex);
  }

  // An apex outside the candidate list: its rank among the live vertices not on the wrong side of
  // the gate face, or its slot. The rank is by sweep key (then distance to the predicted apex) in a
  // "Delaunay first" level while the Delaunay order is in use, else by distance: the apex of a
  // Delaunay tetrahedron is the first vertex the sweep meets, whichever fan it lies on, and in a
  // thin shell the apex lies across the shell, near the prediction but far along the front. A rank
  // may cost a scan of every live vertex, so it is allowed only while the live counts of the ranked
  // escapes so far stay within kEscapeScanBudget per tetrahedron and boundary triangle decoded so
  // far: the decoder's work stays linear in what it outputs, whatever the stream (or the header's
  // counts) says.
  Status codeEscape(const FrontFace& g, const Orient3dFilter& side, const double p[3], uint32_t xs, uint32_t* x) {
    const bool allowed = escape_scan_ + h_.live_ <= kEscapeScanBudget * (h_.tets_done_ + h_.btris_done_ + 1);
    uint32_t by_rank = 0;
    const int wrong = cands_.wrongSide();
    uint64_t rank = 0;
    auto eligible = [&](uint32_t t) {
      return h_.pool_.state[t] == kLive && t != g.v[0] && t != g.v[1] && t != g.v[2] &&
             !(wrong != 0 && side.sign(h_.P(t)) == wrong);
    };
    auto dist = [&](uint32_t t) { return apexDistance(h_.P(t), p); };
    auto all = [&](auto fn) {
      for (uint32_t t = 0; t < h_.pool_.state.size(); ++t)
        if (h_.pool_.state[t] == kLive) fn(t);
    };
    const bool by_key = cands_.keyFirst();
    if (by_key) cands_.ensureSweep();
    const double* cc0 = cands_.sweepCentre();
    const double r2 = cands_.sweepRadius2(), key_scale = cands_.sweepScale();
    const bool swept = by_key && key_scale > 0 && std::isfinite(key_scale) && std::isfinite(r2) &&
                       std::isfinite(cc0[0]) && std::isfinite(cc0[1]) && std::isfinite(cc0[2]);
    auto key = [&](uint32_t t) { return NearestGrid::Key{cands_.sweepKey(h_.P(t)), apexDistance(h_.P(t), p)}; };
    // Every vertex with a key below the bound lies within sqrt(safe2) of the circumcentre C: one
    // at sweep parameter tau (a length along the normal) lies in the sphere of centre C + tau n
    // through a, b and c, so within |tau| + sqrt(R^2 + tau^2) of C when tau >= 0, and within R of C
    // when tau < 0. Margins keep rounding on the safe side.
    auto bound = [&](double safe2) {
      const double s = std::sqrt(safe2) * (1 - 1e-9), r = std::sqrt(r2);
      if (!(s > r * (1 + 1e-6))) return -std::numeric_limits<double>::infinity();
      const double tau = (s - r) * (s + r) / (2 * s) - 1e-9 * (s + r);
      const double y = 64.0 * tau / r;
      return y < 1e18 ? floorKey(y) - 1 : 1e18;
    };
    if (allowed && !grid_.built()) buildGrid();
    if constexpr (kEncode) {
      if (allowed && h_.isLive(xs) && eligible(xs)) {
        rank = swept ? grid_.rankOfBy(cc0, key(xs), xs, key, bound, eligible, all)
                     : grid_.rankOf(p, dist(xs), xs, dist, eligible, all);
        by_rank = rank < (uint64_t{1} << kEscapeRankBits);
      }
    }
    if (allowed) by_rank = h_.con_->bit(esc_by_rank_, by_rank);
    if (!by_rank) {
      *x = h_.codeSlot(*h_.con_, xs);
      if (!h_.isLive(*x)) return h_.bad("tetrahedron refers to a vertex that is not live");
      return Status::ok();
    }
    escape_scan_ += h_.live_;
    // Rank: its bit length b (BitTree<4>), then the b - 1 bits below the leading one.
    const uint32_t b = esc_bits_.code(*h_.con_, kEncode ? static_cast<uint32_t>(bitLength(rank)) : 0);
    if (b > kEscapeRankBits) return h_.bad("escape rank out of range");
    if (b > 1)
      rank =
          (uint64_t{1} << (b - 1)) |
          h_.con_->direct(kEncode ? static_cast<uint32_t>(rank) & ((1u << (b - 1)) - 1) : 0, static_cast<int>(b) - 1);
    else rank = b;
    if constexpr (kEncode) {
      *x = xs;
      return Status::ok();
    }
    // The rank-th eligible live vertex in that order.
    *x = swept ? grid_.kthBy(cc0, rank, key, bound, eligible, all) : grid_.kth(p, rank, dist, eligible, all);
    if (*x == kNoIndex) return h_.bad("escape rank beyond the live vertices");
    return Status::ok();
  }

  // The rank queries' grid over the live vertices, built at the first ranked escape and kept up
  // to date from then on (it changes no answer, only how soon it is found).
  void buildGrid() {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t t = 0; t < h_.pool_.state.size(); ++t) {
      if (h_.pool_.state[t] != kLive) continue;
      for (int i = 0; i < 3; ++i) {
        const double v = h_.P(t)[i];
        if (!std::isfinite(v)) continue;
        lo[i] = std::min(lo[i], v);
        hi[i] = std::max(hi[i], v);
      }
    }
    grid_.build(lo, hi, h_.live_);
    grid_.reserveSlots(h_.pool_.state.capacity());
    for (uint32_t t = 0; t < h_.pool_.state.size(); ++t)
      if (h_.pool_.state[t] == kLive) grid_.insert(t, h_.P(t));
  }

 public:
  // The phase: gate faces until the queue empties, then seed tetrahedra until a bit says no more.
  Status run() {
    while (true) {
      const long idx = h_.front_.nextGate();
      h_.front_.prefetchNext(h_.pool_);
      if constexpr (!kEncode) {
        if (!h_.con_->ok()) return h_.bad("connectivity stream is truncated or corrupt");
        if (!h_.geo_->ok()) return h_.bad("geometry stream is truncated or corrupt");
      }
      if (idx < 0) {
        uint32_t more = 0;
        if constexpr (kEncode) {
          while (h_.enc_->next_seed_tet < h_.enc_->tet_done.size() && h_.enc_->tet_done[h_.enc_->next_seed_tet])
            ++h_.enc_->next_seed_tet;
          more = h_.enc_->next_seed_tet < h_.enc_->tet_done.size();
        }
        more = h_.con_->bit(seed_more_, more);
        if (!more) break;
        GTN_RETURN_IF_ERROR(seedTet());
        continue;
      }
      const FrontFace g = h_.front_.faces.at(idx);
      double p[3];
      predictApex(g, p);
      const Orient3dFilter side(h_.P(g.v[0]), h_.P(g.v[1]), h_.P(g.v[2]));
      const uint32_t ctx = cands_.gather(g, side, p);
      uint32_t sym = 0, x_src = 0, flip = 0;
      if constexpr (kEncode) {
        const Tet& t = h_.enc_->mesh->tets[h_.enc_->face_tet[idx]];
        const uint32_t ga = h_.enc_->slot_src[g.v[0]], gb = h_.enc_->slot_src[g.v[1]], gcv = h_.enc_->slot_src[g.v[2]];
        int xi = -1;
        for (int i = 0; i < 4; ++i)
          if (t[i] != ga && t[i] != gb && t[i] != gcv) xi = i;
        if (xi < 0) return h_.internal("gate face does not belong to its tetrahedron");
        x_src = t[xi];
        h_.enc_->prefetchCoding(h_.enc_->face_tet[idx], t, x_src);
        // Parity of (a, b, c, x) as a permutation of the stored order: its inversions are the 3 - xi
        // stored vertices after x's place and those among the places of a, b and c.
        auto place = [&](uint32_t v) { return int{t[1] == v} + 2 * int{t[2] == v} + 3 * int{t[3] == v}; };
        const int pa = place(ga), pb = place(gb), pc = place(gcv);
        flip = (3 - xi + (pa > pb) + (pa > pc) + (pb > pc)) & 1;
        sym = cands_.candidateSymbolOf(h_.enc_->src_slot[x_src]);
      }
      sym = tsym_[ctx].code(*h_.con_, sym);
      uint32_t x;
      if (sym == kSymNew) {
        FieldPrediction fp;
        fp.kind = g.d != kNoIndex ? FieldPrediction::kInterpolate : FieldPrediction::kAverage;
        fp.s[0] = g.v[0];
        fp.s[1] = g.v[1];
        fp.s[2] = g.v[2];
        fp.s[3] = g.d;
        uint32_t cands[kMaxCandidates];
        h_.near_ = cands;
        h_.n_near_ = cands_.orderedCandidates(cands);
        GTN_RETURN_IF_ERROR(h_.introduceVertex(x_src, p, fp, &x));
        h_.n_near_ = 0;
      } else if (sym == kSymEscape) {
        GTN_RETURN_IF_ERROR(codeEscape(g, side, p, kEncode ? h_.enc_->src_slot[x_src] : 0, &x));
      } else {
        x = cands_.candidateAt(static_cast<int>(sym) - 1);
        if (x == kNoIndex) return h_.bad("candidate rank out of range");
      }
      cands_.apexFound(x, side.sign(h_.P(x)));
      flip = h_.con_->bit(flip_, flip);
      if constexpr (kEncode) {
        // The next gate's face record was prefetched at the start of this one.
        if (const long next = h_.front_.peekGate(); next >= 0) h_.enc_->prefetchTet(h_.enc_->face_tet[next]);
      }
      const uint32_t e[4] = {g.v[0], flip ? g.v[2] : g.v[1], flip ? g.v[1] : g.v[2], x};
      GTN_RETURN_IF_ERROR(emitTet(e, kEncode ? h_.enc_->face_tet[idx] : 0, g.cell, idx, sym == kSymNew));
    }
    return Status::ok();
  }

 private:
  Host& h_;
  ApexCandidates cands_;
  NearestGrid grid_;
  BitTree<4> tsym_[kTetContexts];
  BitModel esc_by_rank_;
  BitTree<4> esc_bits_;
  uint64_t escape_scan_ = 0;  // live counts of the ranked escapes so far
  BitModel flip_, retire_, seed_more_;
  bool edge_points_ = false;
  BitModel edge_point_[4][2];  // [edge kind (codeEdgePoints)][after a point on the same edge]
};

}  // namespace gtn::level
