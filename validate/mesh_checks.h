// The mesh layer of the validator: checks on one decoded level held as a TetMesh, and the comparison
// of two meshes up to a renumbering of vertices and tetrahedra.
#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "mesh/faces.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"
#include "validate/report.h"

namespace gtn {

struct MeshCheckStats {
  uint64_t points = 0, tets = 0, faces = 0, boundary_faces = 0;
  uint64_t inverted = 0, zero_volume = 0, unreferenced_points = 0;
};

// Checks one level: indices in range and distinct, field sizes, finite coordinates (error) and values
// (warning), unreferenced points (info), every face in at most two tetrahedra, no duplicate
// tetrahedra, the boundary surface closed and consistently oriented, no boundary triangles covering
// a quadrilateral that others cover facing the other way along its other diagonal (a non-conforming
// interface: warning), and each tetrahedron's orientation by exact predicates (inverted: error; zero
// volume: warning). `scope` is the level's logical path ("/levels/2"); messages locate items below
// it ("/levels/2/tets/1234"). Returns false when the indices are too broken for any later check that
// walks the mesh (an index out of range or a repeated vertex stops the checks there). Boundary edges
// and interfaces are checked only when every face is manifold, the edges' orientation only when no
// tetrahedron is inverted (one code per defect).
bool checkMesh(const TetMesh& mesh, const std::string& scope, ValidationReport& report,
               MeshCheckStats* stats = nullptr);

// The structural check `gtn convert` runs on the mip levels it made before their file is written:
// every level (levels[0] is level 0, the source) passes checkMesh with no error that level 0 does not
// have too (those are the source's own, not the simplifier's). A failure is kInvalidData naming
// `what`, the level and its errors, and saying that it is a bug to report.
Status checkLevelStructure(const std::vector<const TetMesh*>& levels, const std::string& what);

// checkLevelStructure one level at a time, as the levels are made: level 0 is checked once, when the
// first mip level is. check() may be called from several threads at once.
class LevelStructureCheck {
 public:
  LevelStructureCheck(const TetMesh& level0, std::string what) : level0_(&level0), what_(std::move(what)) {}
  // Mip level `index` (>= 1).
  Status check(const TetMesh& level, size_t index);
  // Checks level 0 now rather than in the first check() (on another thread while the merges are
  // ranked, say); thread-safe, and level 0 is still checked once.
  void checkLevel0();
  // The errors level 0 has of its own, "CODE: message; ..." ("" when none), checking it first if needed.
  std::string level0Errors();

 private:
  const TetMesh* level0_;
  std::string what_;
  std::once_flag level0_once_;
  std::optional<ValidationReport> level0_report_;
};

// Checks that a boundary surface stored in the file (outward triangles) is closed (BOUNDARY_NOT_CLOSED)
// and then that it equals the boundary faces of the level's tetrahedra, orientation included
// (BOUNDARY_MISMATCH). The boundary of tetrahedra whose faces are manifold is always closed; an
// edge in four or more boundary triangles (two parts touching along it) is allowed.
void checkStoredBoundary(const TetMesh& mesh, const std::vector<Triangle>& stored, const std::string& scope,
                         ValidationReport& report);

// A 64-bit key of each point: its coordinate bits and its point-field bytes. Two points have the same
// key exactly when (up to hash collisions) they are bit-identical in position and values.
std::vector<uint64_t> pointKeys(const TetMesh& mesh);

// A 128-bit key of one tetrahedron from its vertices' keys and its cell-field bytes, invariant under
// the even permutations of its vertices (orientation-preserving renumbering); for a flat tetrahedron
// (zero volume, whose orientation is not defined) invariant under all permutations.
std::array<uint64_t, 2> tetKey(const uint64_t vertex_keys[4], bool flat, const uint8_t* cell_bytes, size_t cell_size);

// Sorted keys of every tetrahedron of `mesh` given its point keys (tetrahedra with an index out of
// range are skipped).
std::vector<std::array<uint64_t, 2>> sortedTetKeys(const TetMesh& mesh, const std::vector<uint64_t>& point_keys);

// The number of items of `a` not matched in `b` and of `b` not in `a` (sorted multisets).
template <class T>
std::pair<uint64_t, uint64_t> multisetDifference(const std::vector<T>& a, const std::vector<T>& b) {
  uint64_t only_a = 0, only_b = 0;
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] < b[j]) {
      ++only_a;
      ++i;
    } else if (b[j] < a[i]) {
      ++only_b;
      ++j;
    } else {
      ++i;
      ++j;
    }
  }
  return {only_a + (a.size() - i), only_b + (b.size() - j)};
}

// Cell-field bytes of tetrahedron t concatenated (as a level stores them) into `out`, for tetKey.
void cellBytes(const TetMesh& mesh, size_t t, std::vector<uint8_t>& out);

}  // namespace gtn
