// The generic (baseline) renderer of the paper's section 6.1: the whole level is first collected in
// memory (TetMeshBuilder), then every pixel's ray is cast through the tetrahedra by neighbour
// traversal, front to back. It shares the crossings and shading with the streaming renderer, so the
// two images agree to rounding. Parallel over pixels (TBB).
#pragma once

#include <array>
#include <vector>

#include "mesh/mesh_stream.h"
#include "render/ray_cast.h"

namespace gtn {

struct GenericRenderStats {
  uint64_t tets = 0;
  uint64_t segments = 0;
  uint64_t lost_cursors = 0;  // cursors that lost their way (numerical degeneracies)
  // Pixels whose ray has a part inside the volume that was not integrated: a segment whose cursors
  // neither met nor both stopped at the boundary. None in a valid mesh.
  uint64_t lost_rays = 0;
  RenderSetup setup;  // the resolved camera and transfer function (range fixed)
};

// Renders `mesh` (vertex ids as in the stream that built it), whose boundary surface is `boundary`
// (the stream's outward boundary triangles), described by `header`.
StatusOr<Image> renderGeneric(const LevelHeader& header, const TetMesh& mesh,
                              const std::vector<std::array<uint32_t, 3>>& boundary, const RenderOptions& options,
                              GenericRenderStats* stats = nullptr);

}  // namespace gtn
