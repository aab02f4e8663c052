// Statistics of a tetrahedral mesh, as `gtn info` prints them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

struct FieldStats {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat32;
  bool per_cell = false;
  double min = 0, max = 0;  // over all finite component values
  uint64_t non_finite = 0;  // NaN or infinite values
};

struct MeshStats {
  uint64_t points = 0, tets = 0, faces = 0, boundary_faces = 0, non_manifold_faces = 0;
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  double min_volume = 0, max_volume = 0, total_volume = 0;
  uint64_t inverted = 0, zero_volume = 0;  // by exact predicates
  uint64_t unreferenced_points = 0;        // points no tetrahedron uses
  uint64_t coincident_points = 0;          // points at the same position as another (copies beyond the first)
  std::vector<FieldStats> fields;
};

MeshStats computeMeshStats(const TetMesh& mesh);

// The point field a command takes when none is named (the field `gtn render` shows, the density of
// the simplification): the first field whose first component varies; SIZE_MAX when every field is
// constant (or there is none). `varies[i]`: field i's first component takes at least two finite values.
size_t defaultPointField(const std::vector<bool>& varies);

// Whether the first component of a field takes at least two finite values.
bool firstComponentVaries(const Field& field);

// Reorients every tetrahedron with negative volume (exact predicate) by swapping its last two
// vertices; returns how many were flipped and counts zero-volume cells into *zero_volume.
size_t normalizeOrientation(TetMesh& mesh, size_t* zero_volume);

// Gives the zero-volume tetrahedra (exact predicate), whose orientation the geometry leaves open, the
// orientation of their neighbours: spreading from the tetrahedra of positive volume across shared
// faces, each flat tetrahedron reached is turned round (last two vertices swapped) when it lists the
// shared face in the same direction as the neighbour it is reached from. Call it after
// normalizeOrientation. Flat tetrahedra with no path to a tetrahedron of positive volume keep theirs,
// and so do those whose neighbours disagree (the first one reached decides). Returns how many were
// turned round.
size_t orientFlatTets(TetMesh& mesh);

}  // namespace gtn
