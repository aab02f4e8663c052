// The integrated, decompression-driven renderer (paper section 3.2): a MeshSink that ray-casts the
// level while it streams in, in one pass, keeping only what the rays still need.
//
// Design (see render/README.md for the whole picture):
// * The boundary surface arrives first. At endBoundary every pixel's ray is cut into segments where it
//   lies inside the volume (castBoundary), and each segment gets a front cursor waiting at its entry
//   triangle and a back cursor waiting at its exit triangle. Boundary vertices and triangles are then
//   dropped.
// * Cursors wait at faces: a hash map from a face (its sorted vertex ids) to the one arrived
//   tetrahedron that has it (if still held) and the cursors waiting for the tetrahedron on its other
//   side. When a tetrahedron arrives it is linked to the held neighbours that share its faces, the
//   cursors waiting at its faces enter it and advance through it and through any held neighbours,
//   front to back or back to front, until they must wait again, meet, or reach the boundary.
// * Each arriving tetrahedron counts the rays whose uncovered part it overlaps; cursors passing
//   through it count down, and at zero it is released. A tetrahedron that no ray needs is never held.
//   Vertices are shared records that arrived and held tetrahedra point to; a record is freed once
//   the stream has retired its vertex and no held tetrahedron has it.
//   Memory is therefore the peeling front plus the tetrahedra waiting for rays, plus the image.
// * Tetrahedra are processed in batches so that the work on a batch runs in parallel (TBB): counting
//   over the batch's tetrahedra, advancing over the triggered segments. A full batch is rendered on
//   another thread while the decoder fills the next one. The decode stays one pass.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "mesh/mesh_stream.h"
#include "render/ray_cast.h"

namespace gtn {

struct StreamRenderStats {
  uint64_t tets = 0;               // tetrahedra received
  uint64_t tets_held = 0;          // tetrahedra that were held at all (some ray needed them)
  uint64_t peak_tets_held = 0;     // largest number held at once
  uint64_t peak_vertices = 0;      // largest number of live (emitted, not retired) vertices
  uint64_t peak_face_entries = 0;  // largest size of the face map
  uint64_t segments = 0;           // ray segments
  uint64_t lost_cursors = 0;       // cursors that lost their way (numerical degeneracies)
  // Pixels whose ray has a part inside the volume that was not integrated: a segment whose cursors
  // neither met nor both stopped at the boundary (a cursor lost, or waiting for a tetrahedron that
  // never came). None in a valid mesh.
  uint64_t lost_rays = 0;
  // Tetrahedra still held when the level ended: more rays were counted for them than passed. None
  // in a valid mesh (a ray is counted for every tetrahedron it will cross); the image is right either
  // way, but these were held longer than needed.
  uint64_t tets_left_held = 0;
};

class StreamRenderer : public MeshSink {
 public:
  explicit StreamRenderer(const RenderOptions& options);
  ~StreamRenderer() override;

  Status beginLevel(const LevelHeader& header) override;
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override;
  Status boundaryTriangle(const uint32_t v[3]) override;
  Status endBoundary() override;
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override;
  Status retireVertex(uint32_t id) override;
  Status endLevel() override;

  // Valid after endLevel.
  const Image& image() const { return image_; }
  const StreamRenderStats& stats() const { return stats_; }
  // The resolved setup (camera, range), valid after endBoundary.
  const RenderSetup& setup() const { return setup_; }

  struct State;  // internal

 private:
  Status flushBatch();

  RenderOptions options_;
  RenderSetup setup_;
  Image image_;
  StreamRenderStats stats_;
  std::unique_ptr<State> state_;
};

}  // namespace gtn
