#include "render/generic_renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <unordered_map>

#include "mesh/faces.h"
#include "render/traversal.h"

namespace gtn {

using render_internal::advanceCursor;
using render_internal::CursorEnd;
using render_internal::Link;
using render_internal::SegmentState;

namespace {
uint64_t faceKey(uint32_t a, uint32_t b, uint32_t c) {
  // Sorted triple hashed into 64 bits for the boundary lookup; collisions are resolved by the caller
  // checking the vertices.
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) * 0x9E3779B97F4A7C15ull) ^ (static_cast<uint64_t>(b) << 21) ^
         (static_cast<uint64_t>(c) * 0xC2B2AE3D27D4EB4Full);
}

struct InMemoryMesh {
  const TetMesh& mesh;
  const std::vector<double>& scalars;
  const FaceAdjacency& adj;
  TetGeom scratch;

  const TetGeom& geom(uint32_t t) {
    for (int i = 0; i < 4; ++i) {
      const uint32_t v = mesh.tets[t][i];
      for (int c = 0; c < 3; ++c) scratch.p[i][c] = mesh.coords[3 * v + c];
      scratch.s[i] = scalars[v];
    }
    finishTetGeom(scratch);
    return scratch;
  }
  Link next(uint32_t t, int face, uint32_t* nt, int* nf) {
    const uint32_t n = adj.neighbor[4 * t + face];
    if (n == kNoNeighbor || n == kNonManifold) return Link::kBoundary;
    for (int j = 0; j < 4; ++j) {
      if (adj.neighbor[4 * n + j] == t) {
        *nt = n;
        *nf = j;
        return Link::kLinked;
      }
    }
    return Link::kBoundary;
  }
  void visited(uint32_t) {}
};

bool sameFace(const Tet& tet, int k, const std::array<uint32_t, 3>& tri) {
  int matched = 0;
  for (int i = 0; i < 3; ++i) {
    const uint32_t v = tet[kTetFace[k][i]];
    if (v == tri[0] || v == tri[1] || v == tri[2]) ++matched;
  }
  return matched == 3;
}
}  // namespace

StatusOr<Image> renderGeneric(const LevelHeader& header, const TetMesh& mesh,
                              const std::vector<std::array<uint32_t, 3>>& boundary, const RenderOptions& options,
                              GenericRenderStats* stats) {
  GTN_ASSIGN_OR_RETURN(ScalarReader reader, ScalarReader::create(header.point_fields, options.field));
  const size_t np = mesh.numPoints();
  for (const auto& tri : boundary)
    for (uint32_t v : tri)
      if (v >= np)
        return invalidData("generic renderer: boundary triangle refers to vertex " + std::to_string(v) + " of " +
                           std::to_string(np));
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t)
      if (v >= np) return invalidData("generic renderer: tetrahedron refers to vertex " + std::to_string(v));
  // Per-vertex scalars through the same reader as the stream (concatenated field items).
  std::vector<double> scalars(np);
  size_t record = 0;
  for (const Field& f : mesh.point_fields) record += f.components * f.valueSize();
  std::vector<uint8_t> values(record);
  for (size_t i = 0; i < np; ++i) {
    size_t off = 0;
    for (const Field& f : mesh.point_fields) {
      const size_t n = f.components * f.valueSize();
      std::memcpy(values.data() + off, f.bytes.data() + i * n, n);
      off += n;
    }
    scalars[i] = reader.read(values.data());
  }

  BoundarySurface surface;
  surface.points.resize(np);
  for (size_t i = 0; i < np; ++i)
    surface.points[i] = {mesh.coords[3 * i], mesh.coords[3 * i + 1], mesh.coords[3 * i + 2]};
  surface.scalars = scalars;
  surface.triangles = boundary;

  double bmin[3], bmax[3];
  sceneBox(options, header, surface, bmin, bmax);
  RenderSetup setup = resolveSetup(options, bmin, bmax);
  setup.field = reader.description();
  if (!setup.transfer.has_range) {
    const auto [lo, hi] = boundaryRange(surface);
    setup.transfer.lo = lo;
    setup.transfer.hi = hi;
  }
  buildSampleTable(setup);
  const RaySegments rays = castBoundary(setup.camera, surface);

  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  // Boundary face -> (tetrahedron, local face).
  std::unordered_multimap<uint64_t, uint64_t> boundary_faces;
  for (size_t t = 0; t < mesh.tets.size(); ++t)
    for (int k = 0; k < 4; ++k)
      if (adj.neighbor[4 * t + k] == kNoNeighbor) {
        const Tet& tet = mesh.tets[t];
        boundary_faces.emplace(faceKey(tet[kTetFace[k][0]], tet[kTetFace[k][1]], tet[kTetFace[k][2]]), 4 * t + k);
      }
  auto findFace = [&](uint32_t tri_index, uint32_t* tet, int* face) {
    const auto& tri = boundary[tri_index];
    auto range = boundary_faces.equal_range(faceKey(tri[0], tri[1], tri[2]));
    for (auto it = range.first; it != range.second; ++it) {
      const uint32_t t = static_cast<uint32_t>(it->second / 4);
      const int k = static_cast<int>(it->second % 4);
      if (sameFace(mesh.tets[t], k, tri)) {
        *tet = t;
        *face = k;
        return true;
      }
    }
    return false;
  };

  const int w = setup.camera.width(), h = setup.camera.height();
  std::vector<Rgba> pixels(static_cast<size_t>(w) * h);
  std::atomic<uint64_t> lost{0}, lost_rays{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    InMemoryMesh walker{mesh, scalars, adj, {}};
    for (size_t p = r.begin(); p < r.end(); ++p) {
      const uint32_t s0 = rays.pixel_start[p], s1 = rays.pixel_start[p + 1];
      if (s0 == s1) continue;
      const PreparedRay ray = prepareRay(setup.camera.ray(static_cast<int>(p % w), static_cast<int>(p / w)));
      Rgba acc;
      bool ray_lost = false;
      for (uint32_t si = s0; si < s1; ++si) {
        const RaySegment& rs = rays.segments[si];
        SegmentState seg;
        seg.tf = rs.t_near, seg.sf = static_cast<float>(rs.s_near), seg.tb = rs.t_far,
        seg.sb = static_cast<float>(rs.s_far);
        uint32_t tet, wait_tet;
        int face, wait_face;
        if (seg.tf >= seg.tb) continue;
        CursorEnd end = CursorEnd::kLost;
        if (findFace(rs.entry_tri, &tet, &face))
          end = advanceCursor(setup, ray, seg, true, seg.front, tet, face, walker, &wait_tet, &wait_face);
        if (end == CursorEnd::kLost) lost.fetch_add(1, std::memory_order_relaxed);
        // What the front could not reach, the back cursor covers from the far end. A segment without
        // an exit triangle ends where the front reaches the boundary.
        CursorEnd back_end = rs.exit_tri == kNoTriangle ? CursorEnd::kBoundary : CursorEnd::kLost;
        if (end != CursorEnd::kMet && rs.exit_tri != kNoTriangle && findFace(rs.exit_tri, &tet, &face)) {
          back_end = advanceCursor(setup, ray, seg, false, seg.back, tet, face, walker, &wait_tet, &wait_face);
          if (back_end == CursorEnd::kLost) lost.fetch_add(1, std::memory_order_relaxed);
        }
        if (!seg.done() && !(end == CursorEnd::kBoundary && back_end == CursorEnd::kBoundary)) ray_lost = true;
        acc = over(acc, over(seg.front, seg.back));
      }
      // (Pixels whose crossings did not pair are counted below, once.)
      if (ray_lost && !std::binary_search(rays.unpaired.begin(), rays.unpaired.end(), static_cast<uint32_t>(p)))
        lost_rays.fetch_add(1, std::memory_order_relaxed);
      pixels[p] = acc;
    }
  });
  if (stats) {
    stats->tets = mesh.tets.size();
    stats->segments = rays.segments.size();
    stats->lost_cursors = lost.load();
    stats->lost_rays = lost_rays.load() + rays.unpaired.size();
    stats->setup = setup;
  }
  return toImage(w, h, pixels);
}

}  // namespace gtn
