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
  bool has_range = false;   // some component value is finite
  double min = 0, max = 0;  // over all finite component values (0 when none is)
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

// Orients every tetrahedron of zero volume (exact predicate) as its neighbours are oriented, so that
// each face it shares is listed in opposite orders by the two tetrahedra: its volume says nothing,
// and a file may list it either way. Reached from the tetrahedra of nonzero volume through shared
// faces (a flat one oriented counts as oriented for the next); one listed in the other order has its
// last two vertices swapped. Flat tetrahedra that no face chain links to a solid one are left as
// they are. Returns how many were swapped. Wrongly listed, a flat tetrahedron on the boundary turned
// its boundary triangles inward, and renderers saw rays leave the volume where they entered it.
size_t orientFlatTets(TetMesh& mesh);

}  // namespace gtn
