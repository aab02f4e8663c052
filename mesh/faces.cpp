#include "mesh/faces.h"

#include <algorithm>

namespace gtn {

const int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

namespace {
struct FaceKey {
  uint32_t a;     // the smallest vertex
  uint32_t slot;  // 4 * tet + local face
  uint64_t bc;    // the other two, b << 32 | c with b < c: one comparison orders and matches them
  bool operator<(const FaceKey& o) const { return a != o.a ? a < o.a : bc < o.bc; }
  bool sameFace(const FaceKey& o) const { return a == o.a && bc == o.bc; }
};

// The smallest vertex of each local face of t: t's smallest vertex, but for the face opposite it,
// which has the second smallest.
void faceMinima(const Tet& t, uint32_t out[4]) {
  int lo = 0;
  for (int i = 1; i < 4; ++i)
    if (t[i] < t[lo]) lo = i;
  uint32_t second = 0xFFFFFFFFu;
  for (int i = 0; i < 4; ++i)
    if (i != lo) second = std::min(second, t[i]);
  for (int k = 0; k < 4; ++k) out[k] = k == lo ? second : t[lo];
}
}  // namespace

// Faces are grouped by their smallest vertex (a counting sort of the face slots, 4 bytes each), then
// each small group is keyed and sorted on its own, while the tetrahedra it reads are still in cache:
// sorting all the 16-byte keys at once, or bucketing them in place, cost most of the encoder's
// set-up in cache misses. Equal faces share their smallest vertex, so they meet in one group.
// Vertices beyond `points` (a damaged mesh) share one last group rather than sizing the groups by
// them.
FaceAdjacency computeFaceAdjacency(const TetMesh& mesh) {
  FaceAdjacency adj;
  const size_t nt = mesh.tets.size();
  adj.neighbor.assign(4 * nt, kNoNeighbor);
  const size_t groups = mesh.numPoints() + 1;
  auto groupOf = [&](uint32_t v) { return std::min<size_t>(v, groups - 1); };
  std::vector<uint32_t> start(groups + 1, 0);
  for (const Tet& t : mesh.tets) {
    uint32_t m[4];
    faceMinima(t, m);
    for (int k = 0; k < 4; ++k) ++start[groupOf(m[k]) + 1];
  }
  for (size_t g = 1; g <= groups; ++g) start[g] += start[g - 1];
  std::vector<uint32_t> slots(4 * nt);
  {
    std::vector<uint32_t> next(start.begin(), start.end() - 1);
    for (size_t t = 0; t < nt; ++t) {
      uint32_t m[4];
      faceMinima(mesh.tets[t], m);
      for (int k = 0; k < 4; ++k) slots[next[groupOf(m[k])]++] = static_cast<uint32_t>(4 * t + k);
    }
  }
  std::vector<FaceKey> keys;
  for (size_t g = 0; g < groups; ++g) {
    keys.clear();
    for (uint32_t i = start[g]; i < start[g + 1]; ++i) {
      const uint32_t slot = slots[i];
      const Tet& t = mesh.tets[slot / 4];
      const int k = slot % 4;
      uint32_t a = t[kTetFace[k][0]], b = t[kTetFace[k][1]], c = t[kTetFace[k][2]];
      if (a > b) std::swap(a, b);
      if (b > c) std::swap(b, c);
      if (a > b) std::swap(a, b);
      keys.push_back({a, slot, (uint64_t{b} << 32) | c});
    }
    std::sort(keys.begin(), keys.end());
    size_t i = 0;
    while (i < keys.size()) {
      size_t j = i + 1;
      while (j < keys.size() && keys[j].sameFace(keys[i])) ++j;
      const size_t count = j - i;
      ++adj.faces;
      if (count == 1) {
        ++adj.boundary_faces;
      } else if (count == 2) {
        adj.neighbor[keys[i].slot] = keys[i + 1].slot / 4;
        adj.neighbor[keys[i + 1].slot] = keys[i].slot / 4;
      } else {
        ++adj.non_manifold_faces;
        for (size_t m = i; m < j; ++m) adj.neighbor[keys[m].slot] = kNonManifold;
      }
      i = j;
    }
  }
  return adj;
}

std::vector<Triangle> boundaryTriangles(const TetMesh& mesh, const FaceAdjacency& adjacency) {
  std::vector<Triangle> out;
  out.reserve(adjacency.boundary_faces);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      if (adjacency.neighbor[4 * t + k] != kNoNeighbor) continue;
      out.push_back({mesh.tets[t][kTetFace[k][0]], mesh.tets[t][kTetFace[k][1]], mesh.tets[t][kTetFace[k][2]]});
    }
  }
  return out;
}

}  // namespace gtn
