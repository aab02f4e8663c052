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

// Groups equal faces together (the order within a group, and of the groups, does not matter to the
// callers). An in-place bucket sort on the smallest vertex (American flag sort: no second copy of
// the keys, which would double the largest allocation of the generic pipeline), then a sort of each
// small bucket: several times faster than sorting all the keys, which dominated the encoder's
// set-up. Keys with a vertex beyond `points` (a damaged mesh) fall back to a plain sort rather than
// sizing buckets by them.
void sortFaceKeys(std::vector<FaceKey>& keys, size_t points) {
  uint32_t max_v = 0;
  for (const FaceKey& k : keys) max_v = std::max(max_v, k.a);
  if (keys.empty() || max_v >= points) {
    std::sort(keys.begin(), keys.end());
    return;
  }
  const size_t buckets = size_t{max_v} + 1;
  std::vector<uint32_t> start(buckets + 1, 0);
  for (const FaceKey& k : keys) ++start[k.a + 1];
  for (size_t v = 1; v <= buckets; ++v) start[v] += start[v - 1];
  std::vector<uint32_t> next(start.begin(), start.end() - 1);
  for (size_t b = 0; b < buckets; ++b) {
    while (next[b] < start[b + 1]) {
      const uint32_t target = keys[next[b]].a;
      if (target == b) {
        ++next[b];
      } else {
        std::swap(keys[next[b]], keys[next[target]++]);
      }
    }
  }
  for (size_t b = 0; b < buckets; ++b) {
    if (start[b + 1] - start[b] > 1)
      std::sort(keys.begin() + start[b], keys.begin() + start[b + 1],
                [](const FaceKey& x, const FaceKey& y) { return x.bc < y.bc; });
  }
}
}  // namespace

FaceAdjacency computeFaceAdjacency(const TetMesh& mesh) {
  FaceAdjacency adj;
  const size_t nt = mesh.tets.size();
  adj.neighbor.assign(4 * nt, kNoNeighbor);
  std::vector<FaceKey> keys(4 * nt);
  for (size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      FaceKey& key = keys[4 * t + k];
      uint32_t a = mesh.tets[t][kTetFace[k][0]], b = mesh.tets[t][kTetFace[k][1]], c = mesh.tets[t][kTetFace[k][2]];
      if (a > b) std::swap(a, b);
      if (b > c) std::swap(b, c);
      if (a > b) std::swap(a, b);
      key.a = a;
      key.bc = (uint64_t{b} << 32) | c;
      key.slot = static_cast<uint32_t>(4 * t + k);
    }
  }
  sortFaceKeys(keys, mesh.numPoints());
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
