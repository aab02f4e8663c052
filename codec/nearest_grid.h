// Rank queries over a changing set of points (the live vertices of the level codec): "the r-th
// point in (key, slot) order" and "how many points come before this one", where the key is the
// distance to a query point or, more generally, any key for which the caller can say which keys
// are final once every point within some distance of a centre has been seen (the Delaunay sweep's
// key is). The answers are defined by that order alone, so they equal a scan of every point; the
// grid only finds them sooner. Points are chained per cell in arrays indexed by slot (no
// allocation per point); a query looks at rings of cells around the centre until every point that
// can still come before the answer lies inside the rings, and falls back to a scan of every point
// when the rings would visit more cells than there are points.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "mesh/index.h"

namespace gtn {

class NearestGrid {
 public:
  // A point's key: ordered by k, then by d (then by slot).
  struct Key {
    double k, d;
    bool operator<(const Key& o) const { return k != o.k ? k < o.k : d < o.d; }
    bool operator==(const Key& o) const { return k == o.k && d == o.d; }
  };

  bool built() const { return n_ > 0; }

  // A grid of about `cells_per_point` cells per point over the box [lo, hi] (points outside the box
  // go to its border cells, points with a non-finite coordinate to a separate list).
  void build(const double lo[3], const double hi[3], size_t points, double cells_per_point = 2.0) {
    double ext = 0;
    for (int i = 0; i < 3; ++i) ext = std::max(ext, hi[i] - lo[i]);
    const double want = std::cbrt(std::max(1.0, static_cast<double>(points) * cells_per_point));
    n_ = static_cast<int>(std::clamp(want, 1.0, 256.0));
    if (!(ext > 0) || !std::isfinite(ext)) n_ = 1;
    for (int i = 0; i < 3; ++i) {
      origin_[i] = std::isfinite(lo[i]) ? lo[i] : 0.0;
      const double e = hi[i] - lo[i];
      h_[i] = e > 0 && std::isfinite(e) ? e / n_ : 1.0;
      if (!(h_[i] > 0)) h_[i] = 1.0;  // an extent so small that its cells underflow
    }
    head_.assign(static_cast<size_t>(n_) * n_ * n_ + 1, kNoIndex);  // the last: non-finite points
  }

  // Room for slots below n without reallocating (insert grows by doubling otherwise).
  void reserveSlots(size_t n) {
    cell_.reserve(n);
    next_.reserve(n);
    prev_.reserve(n);
  }
  void insert(uint32_t s, const double* q) {
    if (s >= cell_.size()) {
      cell_.resize(s + 1, kNoIndex);
      next_.resize(s + 1, kNoIndex);
      prev_.resize(s + 1, kNoIndex);
    }
    const uint32_t c = cellOf(q);
    cell_[s] = c;
    prev_[s] = kNoIndex;
    next_[s] = head_[c];
    if (head_[c] != kNoIndex) prev_[head_[c]] = s;
    head_[c] = s;
    ++count_;
  }

  void erase(uint32_t s) {
    if (s >= cell_.size() || cell_[s] == kNoIndex) return;
    if (prev_[s] != kNoIndex) next_[prev_[s]] = next_[s];
    else head_[cell_[s]] = next_[s];
    if (next_[s] != kNoIndex) prev_[next_[s]] = prev_[s];
    cell_[s] = kNoIndex;
    --count_;
  }

  // The point of rank r (0 = first) in (dist(s), s) order among those with ok(s), or kNoIndex when
  // fewer qualify. `all(fn)` calls fn(s) for every point (the fallback scan).
  template <class Dist, class Ok, class All>
  uint32_t kth(const double p[3], uint64_t r, Dist dist, Ok ok, All all) {
    return kthBy(
        p, r,
        [&](uint32_t s) {
          return Key{dist(s), 0.0};
        },
        [](double safe2) { return safe2; }, ok, all);
  }
  // How many points with ok(s) come before (d, x) in (dist(s), s) order (x itself not counted).
  template <class Dist, class Ok, class All>
  uint64_t rankOf(const double p[3], double d, uint32_t x, Dist dist, Ok ok, All all) {
    return rankOfBy(
        p, Key{d, 0.0}, x,
        [&](uint32_t s) {
          return Key{dist(s), 0.0};
        },
        [](double safe2) { return safe2; }, ok, all);
  }

  // The smallest dist(s) over the points where it is below r2, else r2 or more (a squared distance
  // and its bound): the rings stop at radius sqrt(r2), or where the nearest point seen lies within
  // the rings.
  template <class Dist, class All>
  double nearestWithin(const double p[3], double r2, Dist dist, All all) {
    double best = INFINITY;
    auto each = [&](uint32_t s) {
      const double d = dist(s);
      if (d < best) best = d;
    };
    if (!visit(p, each, [&](double safe2) { return safe2 >= r2 || best <= safe2; })) {
      best = INFINITY;
      all(each);
    }
    return best;
  }

  // The same in (key(s), s) order. `bound(safe2)`: a b such that every point with key.k < b
  // lies within sqrt(safe2) of `centre` (-infinity when none surely does; infinite safe2 means
  // every point has been seen).
  template <class KeyOf, class Bound, class Ok, class All>
  uint32_t kthBy(const double centre[3], uint64_t r, KeyOf key, Bound bound, Ok ok, All all) {
    // The r + 1 first points seen so far, in a heap whose top is the last of them: a point after the
    // top is not asked ok(s), and the answer is the top once every point before it has been seen.
    buf_.clear();
    auto each = [&](uint32_t s) {
      const Ranked x{key(s), s};
      if (buf_.size() > r && !(x < buf_.front())) return;
      if (!ok(s)) return;
      buf_.push_back(x);
      std::push_heap(buf_.begin(), buf_.end());
      if (buf_.size() > r + 1) {
        std::pop_heap(buf_.begin(), buf_.end());
        buf_.pop_back();
      }
    };
    const bool done = visit(centre, each, [&](double safe2) {
      // Every point whose key is below the bound has been seen.
      return buf_.size() > r && (safe2 == INFINITY || buf_.front().key.k < bound(safe2));
    });
    if (!done) {  // the fallback: every point
      buf_.clear();
      all(each);
    }
    return buf_.size() > r ? buf_.front().slot : kNoIndex;
  }
  template <class KeyOf, class Bound, class Ok, class All>
  uint64_t rankOfBy(const double centre[3], Key kx, uint32_t x, KeyOf key, Bound bound, Ok ok, All all) {
    uint64_t rank = 0;
    auto before = [&](uint32_t s) {
      if (s == x) return;
      const Key e = key(s);
      if ((e < kx || (e == kx && s < x)) && ok(s)) ++rank;
    };
    // Done once the rings hold every point whose key is kx.k or less.
    const bool done = visit(centre, before, [&](double safe2) { return safe2 == INFINITY || bound(safe2) > kx.k; });
    if (!done) {
      rank = 0;
      all(before);
    }
    return rank;
  }

 private:
  uint32_t cellIndex(int i, double v) const {
    const double f = std::floor((v - origin_[i]) / h_[i]);
    if (!(f > 0)) return 0;  // also NaN (0 / 0 when the cell size underflowed)
    return f >= n_ - 1 ? static_cast<uint32_t>(n_ - 1) : static_cast<uint32_t>(f);
  }
  uint32_t cellOf(const double* q) const {
    if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2]))
      return static_cast<uint32_t>(head_.size() - 1);
    return (cellIndex(2, q[2]) * n_ + cellIndex(1, q[1])) * n_ + cellIndex(0, q[0]);
  }

  struct Ranked {
    Key key;
    uint32_t slot;
    bool operator<(const Ranked& o) const { return key < o.key || (key == o.key && slot < o.slot); }
  };

  // Calls each(s) for the points of growing rings of cells around p, and stop(safe2) after each
  // ring, safe2 being a squared radius within which every point has been visited (infinite once
  // the rings cover the grid). Returns true when stop said so or every point was visited; false
  // when the rings grew too costly (the caller then scans every point itself).
  template <class Each, class Stop>
  bool visit(const double p[3], Each each, Stop stop) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return false;
    for (uint32_t s = head_.back(); s != kNoIndex; s = next_[s]) each(s);
    int c[3];
    for (int i = 0; i < 3; ++i) c[i] = static_cast<int>(cellIndex(i, p[i]));
    const uint64_t max_cells = 4 * count_ + 64;
    uint64_t cells = 0;
    for (int k = 0;; ++k) {
      int lo[3], hi[3];
      for (int i = 0; i < 3; ++i) lo[i] = std::max(0, c[i] - k), hi[i] = std::min(n_ - 1, c[i] + k);
      for (int z = lo[2]; z <= hi[2]; ++z) {
        for (int y = lo[1]; y <= hi[1]; ++y) {
          const bool inner_zy = std::abs(z - c[2]) < k && std::abs(y - c[1]) < k;
          for (int x = lo[0]; x <= hi[0]; ++x) {
            if (inner_zy && std::abs(x - c[0]) < k) {  // visited in an earlier ring: jump across
              x = c[0] + k - 1;
              continue;
            }
            ++cells;
            for (uint32_t s = head_[(static_cast<uint32_t>(z) * n_ + y) * n_ + x]; s != kNoIndex; s = next_[s]) each(s);
          }
        }
      }
      // The distance from p to the nearest face of the visited box that has cells beyond it, less
      // a margin for the rounding of the cell boundaries. Infinite only when no face has cells
      // beyond it: over a box near the double range a distance or its square can overflow, and
      // then the largest double stands for it (a lower bound, so no point is taken as final too
      // soon; an infinite one claimed the whole grid seen, and the encoder ranked an escape among
      // the points of the first rings only, which the decoder could not find).
      constexpr double kLargest = std::numeric_limits<double>::max();
      double safe = INFINITY;
      auto bound = [&](double gap, double a, double b) {
        const double d = gap - 1e-9 * (std::fabs(a) + std::fabs(b));
        safe = std::min(safe, std::isnan(d) ? 0.0 : std::min(d, kLargest));  // NaN: inf - inf
      };
      for (int i = 0; i < 3; ++i) {
        if (lo[i] > 0) {
          const double edge = origin_[i] + lo[i] * h_[i];
          bound(p[i] - edge, p[i], edge);
        }
        if (hi[i] < n_ - 1) {
          const double edge = origin_[i] + (hi[i] + 1) * h_[i];
          bound(edge - p[i], p[i], edge);
        }
      }
      const double safe2 = safe == INFINITY ? INFINITY : (safe > 0 ? std::min(safe * safe, kLargest) : 0.0);
      if (stop(safe2) || safe2 == INFINITY) return true;
      if (cells > max_cells) return false;
    }
  }

  int n_ = 0;
  double origin_[3] = {0, 0, 0}, h_[3] = {1, 1, 1};
  uint64_t count_ = 0;
  std::vector<uint32_t> head_, cell_, next_, prev_;
  std::vector<Ranked> buf_;
};

}  // namespace gtn
