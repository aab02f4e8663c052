// Walking one ray segment's cursors through tetrahedra, shared by the streaming and the generic
// renderer (internal to render/).
//
// A segment has a front cursor, composited front to back from the near end, and a back cursor,
// composited back to front from the far end. Each sits on a face crossing (t, s): the front has
// covered [t_near, tf), the back [tb, t_far). A cursor stops when it meets the other one (tf >= tb),
// when it must wait for a tetrahedron that has not arrived yet, when it reaches the boundary (a face
// with no neighbour: an unwelded seam, or the end of the volume), or when it is lost (numerically no
// exit face, or a neighbour already released); the other cursor then covers the rest.
#pragma once

#include <cstdint>

#include "render/ray_cast.h"

namespace gtn::render_internal {

// Where a segment's two cursors sit.
// Positions stay doubles (the crossings they are compared with are exact to the bit); the scalars
// there are only shaded, and float keeps them to far below a grey level (the streaming renderer
// holds a segment per pixel's ray part for the whole level: 8 bytes of 48).
struct SegmentCursors {
  double tf = 0, tb = 0;  // front and back cursor: position at its crossing
  float sf = 0, sb = 0;   // and the scalar there
  // The cursors met (advanceCursor then sets tf = tb), or the segment was empty from the start.
  bool done() const { return !(tf < tb); }
};

// A segment with what its cursors have composited (the streaming renderer keeps the back colour
// apart: see StreamSegment).
struct SegmentState : SegmentCursors {
  Rgba front, back;
};

enum class Link { kLinked, kOpen, kBoundary, kReleased };
enum class CursorEnd { kWait, kBoundary, kLost, kMet };

// Guard against cycling around an edge with zero-length steps.
constexpr int kMaxZeroSteps = 64;

// `Mesh` provides: `geom(uint32_t tet)` (a TetGeom or a TetCorners: what exitFace takes), `Link
// next(uint32_t tet, int face, uint32_t* next_tet, int* next_face)` and `void visited(uint32_t tet)`.
// The cursor enters `tet` through local face `face` and composites into `colour` (the segment's front or
// back colour). On kWait, *wait_tet/*wait_face say at which face of which tetrahedron it waits.
template <class Mesh>
CursorEnd advanceCursor(const RenderSetup& setup, const PreparedRay& ray, SegmentCursors& seg, bool front, Rgba& colour,
                        uint32_t tet, int face, Mesh& mesh, uint32_t* wait_tet, int* wait_face) {
  int zero_steps = 0;
  // Volume sampling: first(t) of the cursor's position (see firstSampleAtOrAfter), found once, when
  // the first interval to shade comes, and then stepped along with the cursor, not searched for at
  // both ends of every interval. The same samples as shadeInterval's.
  const bool volume = setup.sampling == Sampling::kVolume;
  bool have_k = false;
  int64_t k = 0;
  for (;;) {
    const auto& g = mesh.geom(tet);
    Crossing x;
    const int exit = exitFace(ray, g, face, front, &x);
    mesh.visited(tet);
    if (exit < 0) return CursorEnd::kLost;
    if (front) {
      const double t_out = x.t > seg.tf ? x.t : seg.tf;
      const double limit = seg.tb;
      const double hi = t_out < limit ? t_out : limit;
      if (!volume) {
        shadeInterval(setup, seg.tf, seg.sf, t_out, x.s, seg.tf, hi, true, &colour);
      } else if (hi > seg.tf) {
        if (!have_k) k = firstSampleAtOrAfter(seg.tf, setup.step), have_k = true;
        const int64_t k_hi = firstSampleFrom(k, hi, setup.step);
        // Most crossings hold no sample (blunt fin: 0.95 M of 1.7 M): no call for those.
        if (k_hi > k) shadeSamples(setup, seg.tf, seg.sf, t_out, x.s, k, k_hi, true, &colour);
        k = k_hi;
      }
      zero_steps = t_out == seg.tf ? zero_steps + 1 : 0;
      if (t_out >= limit) {
        seg.tf = limit;
        return CursorEnd::kMet;
      }
      seg.tf = t_out;
      seg.sf = static_cast<float>(x.s);
    } else {
      const double t_out = x.t < seg.tb ? x.t : seg.tb;
      const double limit = seg.tf;
      const double lo = t_out > limit ? t_out : limit;
      if (!volume) {
        shadeInterval(setup, t_out, x.s, seg.tb, seg.sb, lo, seg.tb, false, &colour);
      } else if (seg.tb > lo) {
        if (!have_k) k = firstSampleAtOrAfter(seg.tb, setup.step), have_k = true;
        const int64_t k_lo = firstSampleFrom(k, lo, setup.step);
        if (k > k_lo) shadeSamples(setup, t_out, x.s, seg.tb, seg.sb, k_lo, k, false, &colour);
        k = k_lo;
      }
      zero_steps = t_out == seg.tb ? zero_steps + 1 : 0;
      if (t_out <= limit) {
        seg.tb = limit;
        return CursorEnd::kMet;
      }
      seg.tb = t_out;
      seg.sb = static_cast<float>(x.s);
    }
    if (zero_steps > kMaxZeroSteps) return CursorEnd::kLost;
    uint32_t next_tet;
    int next_face;
    switch (mesh.next(tet, exit, &next_tet, &next_face)) {
      case Link::kLinked:
        tet = next_tet;
        face = next_face;
        break;
      case Link::kOpen:
        *wait_tet = tet;
        *wait_face = exit;
        return CursorEnd::kWait;
      case Link::kBoundary: return CursorEnd::kBoundary;
      case Link::kReleased: return CursorEnd::kLost;
    }
  }
}

}  // namespace gtn::render_internal
