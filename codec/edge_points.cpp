#include "codec/edge_points.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "mesh/faces.h"

namespace gtn {

namespace {

constexpr double kMaxOffset = 0.25;  // of the edge's length, from its midpoint
constexpr int64_t kMaxCells = 512;   // cells one edge's search may visit
// Points a cell may hold and still be searched: more are coincident points (placeholders at the
// origin, say), and searching them from every edge nearby would take time quadratic in their number.
constexpr uint32_t kMaxCellPoints = 256;
constexpr int64_t kCellRange = int64_t{1} << 20;  // cell coordinates, clamped to [-range, range)

}  // namespace

std::vector<EdgePoint> findEdgePoints(const TetMesh& mesh) {
  const size_t np = mesh.numPoints();
  std::vector<uint8_t> used(np, 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t)
      if (v < np) used[v] = 1;
  std::vector<uint32_t> unused;
  for (size_t v = 0; v < np; ++v) {
    const double* p = mesh.point(v);
    if (!used[v] && std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
      unused.push_back(static_cast<uint32_t>(v));
  }
  if (unused.empty()) return {};

  // Only edges whose search reaches the box of the unused points: a mesh with a few stray points
  // (raptorTetra has 2) does not sort all its edges to find theirs.
  double box_lo[3], box_hi[3];
  for (int i = 0; i < 3; ++i) {
    box_lo[i] = std::numeric_limits<double>::infinity();
    box_hi[i] = -std::numeric_limits<double>::infinity();
    for (uint32_t v : unused)
      box_lo[i] = std::min(box_lo[i], mesh.point(v)[i]), box_hi[i] = std::max(box_hi[i], mesh.point(v)[i]);
  }
  auto reachesBox = [&](uint32_t a, uint32_t b) {
    const double *p = mesh.point(a), *q = mesh.point(b);
    double len2 = 0;
    for (int i = 0; i < 3; ++i) len2 += (q[i] - p[i]) * (q[i] - p[i]);
    const double r = kMaxOffset * std::sqrt(len2);
    for (int i = 0; i < 3; ++i) {
      const double m = (p[i] + q[i]) * 0.5;
      if (m + r < box_lo[i] || m - r > box_hi[i]) return false;  // NaN reaches: the search skips it
    }
    return true;
  };
  std::vector<uint64_t> edges;
  for (const Tet& t : mesh.tets)
    for (const auto& e : kTetEdge) {
      const uint32_t a = std::min(t[e[0]], t[e[1]]), b = std::max(t[e[0]], t[e[1]]);
      if (a != b && b < np && reachesBox(a, b)) edges.push_back(uint64_t{a} << 32 | b);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  auto lengthSquared = [&](uint64_t e) {
    const double *p = mesh.point(e >> 32), *q = mesh.point(static_cast<uint32_t>(e));
    double s = 0;
    for (int i = 0; i < 3; ++i) s += (q[i] - p[i]) * (q[i] - p[i]);
    return s;
  };
  double total = 0;
  size_t counted = 0;
  for (uint64_t e : edges) {
    const double l = std::sqrt(lengthSquared(e));
    if (l > 0 && std::isfinite(l)) total += l, ++counted;
  }
  if (counted == 0) return {};
  // Cells of half the mean edge length: a typical edge's search visits 8 of them.
  const double cell = 0.5 * total / static_cast<double>(counted);
  auto cellOf = [&](double x, int i) {
    const double c = std::floor((x - box_lo[i]) / cell);
    return static_cast<int64_t>(std::clamp(c, -static_cast<double>(kCellRange), static_cast<double>(kCellRange - 1)));
  };
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return static_cast<uint64_t>(x + kCellRange) << 42 | static_cast<uint64_t>(y + kCellRange) << 21 |
           static_cast<uint64_t>(z + kCellRange);
  };
  std::vector<std::pair<uint64_t, uint32_t>> grid;  // (cell key, index into unused)
  grid.reserve(unused.size());
  for (uint32_t i = 0; i < unused.size(); ++i) {
    const double* p = mesh.point(unused[i]);
    grid.push_back({key(cellOf(p[0], 0), cellOf(p[1], 1), cellOf(p[2], 2)), i});
  }
  std::sort(grid.begin(), grid.end());
  // Each occupied cell's range of `grid`, in an open-addressing table of twice as many entries or more
  // (a cell is then one probe or two, where a binary search of `grid` would miss the cache every step).
  struct Cell {
    uint64_t key = ~uint64_t{0};  // ~0: empty (keys use 63 bits)
    uint32_t begin = 0, end = 0;
  };
  int bits = 1;
  while ((size_t{1} << bits) < 2 * grid.size()) ++bits;
  std::vector<Cell> table(size_t{1} << bits);
  auto home = [&](uint64_t k) { return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> (64 - bits)); };
  const size_t mask = table.size() - 1;
  for (uint32_t i = 0; i < grid.size();) {
    uint32_t j = i;
    while (j < grid.size() && grid[j].first == grid[i].first) ++j;
    size_t h = home(grid[i].first);
    while (table[h].key != ~uint64_t{0}) h = (h + 1) & mask;
    table[h] = {grid[i].first, i, j};
    i = j;
  }
  auto cellRange = [&](uint64_t k) -> const Cell* {
    for (size_t h = home(k);; h = (h + 1) & mask) {
      if (table[h].key == k) return &table[h];
      if (table[h].key == ~uint64_t{0}) return nullptr;
    }
  };

  std::vector<double> best(unused.size(), std::numeric_limits<double>::infinity());
  std::vector<uint64_t> best_edge(unused.size(), 0);
  for (uint64_t e : edges) {
    const double len2 = lengthSquared(e);
    if (!(len2 > 0) || !std::isfinite(len2)) continue;
    const double *p = mesh.point(e >> 32), *q = mesh.point(static_cast<uint32_t>(e));
    const double m[3] = {(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5, (p[2] + q[2]) * 0.5};
    const double r = kMaxOffset * std::sqrt(len2);
    int64_t c0[3], c1[3], cells = 1;
    for (int i = 0; i < 3; ++i) {
      c0[i] = cellOf(m[i] - r, i);
      c1[i] = cellOf(m[i] + r, i);
      cells *= c1[i] - c0[i] + 1;
    }
    if (cells > kMaxCells) continue;
    for (int64_t x = c0[0]; x <= c1[0]; ++x)
      for (int64_t y = c0[1]; y <= c1[1]; ++y)
        for (int64_t z = c0[2]; z <= c1[2]; ++z) {
          const Cell* c = cellRange(key(x, y, z));
          if (!c || c->end - c->begin > kMaxCellPoints) continue;
          for (uint32_t g = c->begin; g < c->end; ++g) {
            const uint32_t i = grid[g].second;
            const double* w = mesh.point(unused[i]);
            double d2 = 0;
            for (int k = 0; k < 3; ++k) d2 += (w[k] - m[k]) * (w[k] - m[k]);
            const double score = d2 / len2;  // edges come in increasing (a, b): the first of equals stays
            if (score <= kMaxOffset * kMaxOffset && score < best[i]) {
              best[i] = score;
              best_edge[i] = e;
            }
          }
        }
  }
  std::vector<EdgePoint> out;
  for (size_t i = 0; i < unused.size(); ++i)
    if (best[i] <= kMaxOffset * kMaxOffset)
      out.push_back({unused[i], static_cast<uint32_t>(best_edge[i] >> 32), static_cast<uint32_t>(best_edge[i])});
  return out;
}

}  // namespace gtn
