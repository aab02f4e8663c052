#include "mesh/faces.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>

#include "mesh/fresh_memory.h"

namespace gtn {

const int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
const int kTetEdge[6][2] = {{0, 1}, {0, 2}, {1, 2}, {0, 3}, {1, 3}, {2, 3}};

bool facesOpposite(const Tet& a, int k, const Tet& b) {
  const uint32_t f0 = a[kTetFace[k][0]], f1 = a[kTetFace[k][1]], f2 = a[kTetFace[k][2]];
  int kb = 0;  // b's vertex off the face
  while (kb < 3 && (b[kb] == f0 || b[kb] == f1 || b[kb] == f2)) ++kb;
  const int* g = kTetFace[kb];
  // b's listing of the triangle, rotated to start at f0: opposite when f2 follows.
  for (int i = 0; i < 3; ++i)
    if (b[g[i]] == f0) return b[g[(i + 1) % 3]] == f2;
  return false;
}

namespace {
// Up to this many face slots (4 bytes each), the face adjacency groups them in one pass.
constexpr uint64_t kOnePassSlots = uint64_t{1} << 24;
// Groups (vertices) matched by one task.
constexpr size_t kGroupsPerTask = 4096;

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

// A distinct face of a group: its sorted vertices a < b < c (bc = b << 32 | c), the slots (4 * tet +
// local face) of its first two occurrences and how many there are.
struct GroupFace {
  uint32_t a;
  uint64_t bc;
  uint32_t first, second, count;
};
}  // namespace

// Faces are grouped by their smallest vertex (a counting sort of the face slots, 4 bytes each); equal
// faces share it, so they meet in one group, which is small and is matched on its own, in a hash
// table, while the tetrahedra it reads are still in cache. Sorting all the 16-byte face keys instead
// cost most of the encoder's set-up in cache misses, and sorting each group most of the rest.
// Vertices beyond `points` (a damaged mesh) share one last group rather than sizing the groups by
// them.
//
// Calls paired(slot, other_slot) for each slot of a face in exactly two tetrahedra (both ways),
// boundary(slot) for a face in one, in_three(slot) for each slot of a face in three or more, from
// the threads matching the groups (each slot once); returns the counts of FaceAdjacency.
namespace {
struct FaceCounts {
  uint64_t faces = 0, boundary_faces = 0, non_manifold_faces = 0;
};
template <class Paired, class Boundary, class InThree>
FaceCounts matchFaces(const TetMesh& mesh, uint64_t pass_slots, const Paired& paired, const Boundary& boundary,
                      const InThree& in_three) {
  const size_t nt = mesh.tets.size();
  const size_t groups = mesh.numPoints() + 1;
  auto groupOf = [&](uint32_t v) { return std::min<size_t>(v, groups - 1); };
  std::vector<uint32_t> start(groups + 1, 0);
  for (const Tet& t : mesh.tets) {
    uint32_t m[4];
    faceMinima(t, m);
    for (int k = 0; k < 4; ++k) ++start[groupOf(m[k]) + 1];
  }
  for (size_t g = 1; g <= groups; ++g) start[g] += start[g - 1];
  // A large mesh's slots in two passes, each over the groups that hold about half of them: the slots
  // were half of the peak of a check of a large mesh (16 of its 32 bytes per tetrahedron), and a
  // convert's peak was that check's. A pass costs a read of the tetrahedra.
  const uint64_t total = start[groups];
  if (pass_slots == 0) pass_slots = total <= kOnePassSlots ? total : (total + 1) / 2;
  // The passes: groups pass_begin[p] .. pass_begin[p + 1] - 1 (a group is never split).
  std::vector<size_t> pass_begin = {0};
  uint64_t most = 0;  // the slots of the largest pass
  while (pass_begin.back() < groups) {
    const size_t g0 = pass_begin.back();
    size_t g1 = g0 + 1;
    while (g1 < groups && start[g1 + 1] - start[g0] <= pass_slots) ++g1;
    most = std::max<uint64_t>(most, start[g1] - start[g0]);
    pass_begin.push_back(g1);
  }
  std::vector<uint32_t> slots;
  resizePopulated(slots, most);
  std::vector<uint32_t> next;
  std::atomic<uint64_t> all_faces{0}, boundary_faces{0}, non_manifold_faces{0};
  for (size_t p = 0; p + 1 < pass_begin.size(); ++p) {
    const size_t g0 = pass_begin[p], g1 = pass_begin[p + 1];
    // The slots of groups g0 .. g1 - 1, from start[g0] on.
    const uint32_t base = start[g0];
    next.assign(start.begin() + static_cast<std::ptrdiff_t>(g0), start.begin() + static_cast<std::ptrdiff_t>(g1));
    for (size_t t = 0; t < nt; ++t) {
      uint32_t m[4];
      faceMinima(mesh.tets[t], m);
      for (int k = 0; k < 4; ++k) {
        const size_t g = groupOf(m[k]);
        if (g >= g0 && g < g1) slots[next[g - g0]++ - base] = static_cast<uint32_t>(4 * t + k);
      }
    }
    // The groups are matched in parallel: each writes the neighbours of its own slots alone. Isolated:
    // the caller's thread, waiting for its share, takes no other task of its caller's (which could
    // run long).
    tbb::this_task_arena::isolate([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(g0, g1, kGroupsPerTask), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<GroupFace> faces;
        std::vector<uint32_t> table;    // open addressing, at most half full: index in faces, or kNoIndex
        std::vector<uint32_t> face_of;  // per slot of the group: its index in faces
        uint64_t count_faces = 0, count_boundary = 0, count_non_manifold = 0;
        for (size_t g = r.begin(); g < r.end(); ++g) {
          const uint32_t n = start[g + 1] - start[g];
          if (n == 0) continue;
          const int bits = std::max(4, static_cast<int>(std::bit_width(2 * n - 1)));
          table.assign(size_t{1} << bits, kNoIndex);
          faces.clear();
          face_of.resize(n);
          bool non_manifold = false;
          for (uint32_t i = 0; i < n; ++i) {
            const uint32_t slot = slots[start[g] - base + i];
            const Tet& t = mesh.tets[slot / 4];
            const int k = slot % 4;
            uint32_t a = t[kTetFace[k][0]], b = t[kTetFace[k][1]], c = t[kTetFace[k][2]];
            if (a > b) std::swap(a, b);
            if (b > c) std::swap(b, c);
            if (a > b) std::swap(a, b);
            const uint64_t bc = (uint64_t{b} << 32) | c;
            size_t h = ((bc ^ a) * 0x9E3779B97F4A7C15u) >> (64 - bits);
            while (table[h] != kNoIndex && !(faces[table[h]].bc == bc && faces[table[h]].a == a))
              h = (h + 1) & (table.size() - 1);
            if (table[h] == kNoIndex) {
              table[h] = static_cast<uint32_t>(faces.size());
              faces.push_back({a, bc, slot, 0, 1});
            } else {
              GroupFace& f = faces[table[h]];
              if (f.count == 1) f.second = slot;
              non_manifold |= ++f.count == 3;
            }
            face_of[i] = table[h];
          }
          count_faces += faces.size();
          for (const GroupFace& f : faces) {
            if (f.count == 1) {
              ++count_boundary;
              boundary(f.first);
            } else if (f.count == 2) {
              paired(f.first, f.second);
              paired(f.second, f.first);
            } else {
              ++count_non_manifold;
            }
          }
          if (non_manifold)
            for (uint32_t i = 0; i < n; ++i)
              if (faces[face_of[i]].count > 2) in_three(slots[start[g] - base + i]);
        }
        all_faces += count_faces;
        boundary_faces += count_boundary;
        non_manifold_faces += count_non_manifold;
      });
    });
  }
  return FaceCounts{all_faces, boundary_faces, non_manifold_faces};
}
}  // namespace

FaceAdjacency computeFaceAdjacency(const TetMesh& mesh, uint64_t pass_slots) {
  FaceAdjacency adj;
  assignPopulated(adj.neighbor, 4 * mesh.tets.size(), kNoNeighbor);
  uint32_t* neighbor = adj.neighbor.data();
  const FaceCounts c = matchFaces(
      mesh, pass_slots, [&](uint32_t slot, uint32_t other) { neighbor[slot] = other / 4; }, [](uint32_t) {},
      [&](uint32_t slot) { neighbor[slot] = kNonManifold; });
  adj.faces = c.faces;
  adj.boundary_faces = c.boundary_faces;
  adj.non_manifold_faces = c.non_manifold_faces;
  return adj;
}

FaceClasses classifyFaces(const TetMesh& mesh, const std::vector<uint8_t>* flat, uint64_t pass_slots, bool alike) {
  FaceClasses out;
  assignPopulated(out.mask, mesh.tets.size(), uint16_t{0});
  // A tetrahedron's faces are in groups that other threads may match at the same time.
  auto set = [&](uint32_t t, uint16_t bits) {
    std::atomic_ref<uint16_t>(out.mask[t]).fetch_or(bits, std::memory_order_relaxed);
  };
  const FaceCounts c = matchFaces(
      mesh, pass_slots,
      [&](uint32_t slot, uint32_t other) {
        if (flat && (*flat)[other / 4]) set(slot / 4, FaceClasses::kNextToFlat);
        if (alike && !facesOpposite(mesh.tets[slot / 4], static_cast<int>(slot % 4), mesh.tets[other / 4]))
          set(slot / 4, FaceClasses::kAlike);
      },
      [&](uint32_t slot) { set(slot / 4, static_cast<uint16_t>(FaceClasses::kBoundary << (slot % 4))); },
      [&](uint32_t slot) { set(slot / 4, static_cast<uint16_t>(FaceClasses::kNonManifold << (slot % 4))); });
  out.faces = c.faces;
  out.boundary_faces = c.boundary_faces;
  out.non_manifold_faces = c.non_manifold_faces;
  return out;
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

std::vector<Triangle> boundaryTriangles(const TetMesh& mesh, const FaceClasses& classes) {
  std::vector<Triangle> out;
  out.reserve(classes.boundary_faces);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      if (!(classes.mask[t] & (FaceClasses::kBoundary << k))) continue;
      out.push_back({mesh.tets[t][kTetFace[k][0]], mesh.tets[t][kTetFace[k][1]], mesh.tets[t][kTetFace[k][2]]});
    }
  }
  return out;
}

}  // namespace gtn
