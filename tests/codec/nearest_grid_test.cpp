// NearestGrid's answers (kth, rankOf, nearestWithin) are defined by the (distance, slot) order alone:
// they must equal a scan of every point, whatever the grid's cells, for points inside and outside the box it was built for,
// coincident points, non-finite coordinates, and points inserted and erased as the front moves.
#include "codec/nearest_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace gtn {
namespace {

constexpr double kMaxKey = 1.7976931348623157e308;

struct Model {
  std::vector<double> pos;  // 3 per slot
  std::vector<uint8_t> live;
  const double* P(uint32_t s) const { return &pos[3 * size_t{s}]; }
};

double dist(const Model& m, uint32_t s, const double p[3]) {
  const double* q = m.P(s);
  const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
  const double d = dx * dx + dy * dy + dz * dz;
  return d <= kMaxKey ? d : kMaxKey;
}

void runScenario(uint32_t seed, bool clustered) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Model m;
  const uint32_t slots = 600;
  m.pos.resize(3 * slots);
  m.live.assign(slots, 0);
  auto place = [&](uint32_t s) {
    const uint32_t kind = rng() % 40;
    for (int i = 0; i < 3; ++i) m.pos[3 * s + i] = clustered ? 0.01 * std::round(u(rng) * 20) : u(rng);
    if (kind == 0) m.pos[3 * s] = std::numeric_limits<double>::quiet_NaN();
    if (kind == 1) m.pos[3 * s + 1] = std::numeric_limits<double>::infinity();
    if (kind == 2) m.pos[3 * s + 2] = 1e200;  // far outside the box, squared distance overflows
    if (kind == 3) m.pos[3 * s] = 5.0;        // outside the box the grid was built for
    if (kind == 4 && s > 0) std::copy_n(&m.pos[3 * (s - 1)], 3, &m.pos[3 * s]);  // coincident
  };
  for (uint32_t s = 0; s < slots / 2; ++s) {
    place(s);
    m.live[s] = 1;
  }
  NearestGrid grid;
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  grid.build(lo, hi, slots / 2);
  for (uint32_t s = 0; s < slots; ++s)
    if (m.live[s]) grid.insert(s, m.P(s));
  for (int step = 0; step < 3000; ++step) {
    // Move the set: erase one live slot, revive one dead slot at a new place.
    const uint32_t a = rng() % slots, b = rng() % slots;
    if (m.live[a]) {
      grid.erase(a);
      m.live[a] = 0;
    }
    if (!m.live[b]) {
      place(b);
      m.live[b] = 1;
      grid.insert(b, m.P(b));
    }
    double p[3];
    for (int i = 0; i < 3; ++i) p[i] = u(rng) * (step % 5 == 0 ? 3.0 : 1.0);
    if (step % 97 == 0) p[1] = std::numeric_limits<double>::quiet_NaN();
    const uint32_t parity = rng() % 3;
    auto ok = [&](uint32_t s) { return parity == 0 || s % 3 != parity; };
    auto d = [&](uint32_t s) { return dist(m, s, p); };
    auto all = [&](auto fn) {
      for (uint32_t s = 0; s < slots; ++s)
        if (m.live[s]) fn(s);
    };
    std::vector<std::pair<double, uint32_t>> order;
    for (uint32_t s = 0; s < slots; ++s)
      if (m.live[s] && ok(s)) order.push_back({d(s), s});
    std::sort(order.begin(), order.end());
    const uint64_t r = rng() % (order.size() + 3);
    const uint32_t got = grid.kth(p, r, d, ok, all);
    ASSERT_EQ(got, r < order.size() ? order[r].second : kNoIndex)
        << "seed " << seed << " step " << step << " rank " << r;
    if (!order.empty()) {
      const size_t i = rng() % order.size();
      ASSERT_EQ(grid.rankOf(p, order[i].first, order[i].second, d, ok, all), i) << "seed " << seed << " step " << step;
    }
    // The nearest point within a radius: the smallest distance below r2, else r2 or more.
    const double r2 = 0.3 * std::abs(u(rng));
    double nearest = INFINITY;
    for (uint32_t s = 0; s < slots; ++s)
      if (m.live[s] && d(s) < nearest) nearest = d(s);
    const double within = grid.nearestWithin(p, r2, d, all);
    if (nearest < r2) {
      ASSERT_EQ(within, nearest) << "seed " << seed << " step " << step;
    } else {
      ASSERT_GE(within, r2) << "seed " << seed << " step " << step;
    }
  }
}

// kthBy / rankOfBy with a key that is not the distance to the rings' centre: the squared distance
// to another point q (then the distance to p, then the slot), final below (S - |q - c|)^2 once every
// point within S of the centre c has been seen. Same answers as sorting every point.
TEST(NearestGrid, KeyedRanksEqualAScanOfEveryPoint) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Model m;
  const uint32_t slots = 400;
  m.pos.resize(3 * slots);
  m.live.assign(slots, 1);
  for (uint32_t s = 0; s < slots; ++s)
    for (int i = 0; i < 3; ++i) m.pos[3 * s + i] = s % 7 == 0 ? 0.25 * std::round(u(rng) * 4) : u(rng);
  NearestGrid grid;
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  grid.build(lo, hi, slots);
  for (uint32_t s = 0; s < slots; ++s) grid.insert(s, m.P(s));
  for (int query = 0; query < 300; ++query) {
    double c[3], q[3], p[3];
    for (int i = 0; i < 3; ++i) {
      c[i] = u(rng);
      q[i] = c[i] + 0.3 * u(rng);
      p[i] = u(rng);
    }
    const double off =
        std::sqrt((q[0] - c[0]) * (q[0] - c[0]) + (q[1] - c[1]) * (q[1] - c[1]) + (q[2] - c[2]) * (q[2] - c[2]));
    auto key = [&](uint32_t s) { return NearestGrid::Key{dist(m, s, q), dist(m, s, p)}; };
    auto bound = [&](double safe2) {
      const double s = std::sqrt(safe2) * (1 - 1e-12) - off;
      return s > 0 ? s * s : -std::numeric_limits<double>::infinity();
    };
    auto ok = [&](uint32_t s) { return s % 5 != static_cast<uint32_t>(query % 5); };
    auto all = [&](auto fn) {
      for (uint32_t s = 0; s < slots; ++s) fn(s);
    };
    std::vector<std::pair<std::pair<double, double>, uint32_t>> order;
    for (uint32_t s = 0; s < slots; ++s)
      if (ok(s)) order.push_back({{key(s).k, key(s).d}, s});
    std::sort(order.begin(), order.end());
    const uint64_t r = query % 4 == 0 ? rng() % order.size() : rng() % 4;
    ASSERT_EQ(grid.kthBy(c, r, key, bound, ok, all), order[r].second) << "query " << query << " rank " << r;
    ASSERT_EQ(grid.kthBy(c, order.size(), key, bound, ok, all), kNoIndex);
    const size_t i = rng() % order.size();
    ASSERT_EQ(grid.rankOfBy(c, key(order[i].second), order[i].second, key, bound, ok, all), i) << "query " << query;
  }
}

TEST(NearestGrid, RanksEqualAScanOfEveryPoint) {
  for (uint32_t seed = 1; seed <= 4; ++seed) runScenario(seed, false);
}

TEST(NearestGrid, RanksEqualAScanWithManyTies) {
  // Coordinates on a coarse lattice: many equal distances, decided by the slot.
  for (uint32_t seed = 5; seed <= 8; ++seed) runScenario(seed, true);
}

TEST(NearestGrid, FlatAndSinglePointBoxes) {
  NearestGrid grid;
  const double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  grid.build(lo, hi, 10);
  std::vector<double> pos;
  for (uint32_t s = 0; s < 10; ++s) {
    pos.insert(pos.end(), {0.0, 0.0, static_cast<double>(s % 2)});
    grid.insert(s, &pos[3 * s]);
  }
  const double p[3] = {0, 0, 0.9};
  auto d = [&](uint32_t s) {
    const double dz = pos[3 * s + 2] - p[2];
    return dz * dz + p[0] * p[0] + p[1] * p[1];
  };
  auto ok = [](uint32_t) { return true; };
  auto all = [&](auto fn) {
    for (uint32_t s = 0; s < 10; ++s) fn(s);
  };
  EXPECT_EQ(grid.kth(p, 0, d, ok, all), 1u);  // odd slots at z = 1 are nearer, then by slot
  EXPECT_EQ(grid.kth(p, 4, d, ok, all), 9u);
  EXPECT_EQ(grid.kth(p, 5, d, ok, all), 0u);
  EXPECT_EQ(grid.rankOf(p, d(2), 2, d, ok, all), 6u);
}

TEST(NearestGrid, BoxTooSmallForItsCells) {
  // An extent of one denormal split into cells underflows to cells of size 0 (0 / 0 = NaN indices).
  NearestGrid grid;
  const double lo[3] = {0, 0, 0}, hi[3] = {std::numeric_limits<double>::denorm_min(), 0, 0};
  grid.build(lo, hi, 100);
  std::vector<double> pos;
  for (uint32_t s = 0; s < 6; ++s) {
    pos.insert(pos.end(), {s % 2 ? std::numeric_limits<double>::denorm_min() : 0.0, 0.0, 0.0});
    grid.insert(s, &pos[3 * s]);
  }
  const double p[3] = {0, 0, 1};
  auto d = [&](uint32_t s) { return pos[3 * s] * pos[3 * s] + 1.0; };
  auto ok = [](uint32_t) { return true; };
  auto all = [&](auto fn) {
    for (uint32_t s = 0; s < 6; ++s) fn(s);
  };
  for (uint32_t r = 0; r < 6; ++r) EXPECT_EQ(grid.kth(p, r, d, ok, all), r);  // equal distances: by slot
  EXPECT_EQ(grid.kth(p, 6, d, ok, all), kNoIndex);
}

TEST(NearestGrid, BoxNearTheDoubleRange) {
  // Cells of about 1e306: the distance to the first ring's faces squares to infinity. That must not
  // count as having seen the whole grid (the answers then came from the first rings only).
  NearestGrid grid;
  const double lo[3] = {0, 0, 0}, hi[3] = {1.7976931348623157e308, 10, 10};
  grid.build(lo, hi, 40);
  std::vector<double> pos;
  for (uint32_t s = 0; s < 40; ++s) {
    const double x = s % 4 == 0 ? 1e307 * (s / 4) : (s % 4 == 1 ? 1.7976931348623157e308 : 0.5 * s);
    pos.insert(pos.end(), {x, static_cast<double>(s % 10), static_cast<double>(s % 7)});
    grid.insert(s, &pos[3 * s]);
  }
  for (const double px : {1.0, 3e306, 9e307, 1.7e308}) {
    const double p[3] = {px, 4, 4};
    auto d = [&](uint32_t s) {
      const double dx = pos[3 * s] - p[0], dy = pos[3 * s + 1] - p[1], dz = pos[3 * s + 2] - p[2];
      const double e = dx * dx + dy * dy + dz * dz;
      return e <= kMaxKey ? e : kMaxKey;
    };
    auto ok = [](uint32_t s) { return s % 5 != 3; };
    auto all = [&](auto fn) {
      for (uint32_t s = 0; s < 40; ++s) fn(s);
    };
    std::vector<std::pair<double, uint32_t>> order;
    for (uint32_t s = 0; s < 40; ++s)
      if (ok(s)) order.push_back({d(s), s});
    std::sort(order.begin(), order.end());
    for (uint64_t r = 0; r < order.size(); ++r) {
      EXPECT_EQ(grid.kth(p, r, d, ok, all), order[r].second) << "query x " << px << " rank " << r;
      EXPECT_EQ(grid.rankOf(p, order[r].first, order[r].second, d, ok, all), r) << "query x " << px << " rank " << r;
    }
  }
}

}  // namespace
}  // namespace gtn
