// Exact geometric predicates (CGAL's filtered Epick kernel): signs are decided exactly, never with an
// epsilon. Coordinates are doubles; float32 sources convert to double exactly.
#pragma once

namespace gtn {

// Sign of det[b - a, c - a, d - a]: +1 positive volume, 0 flat, -1 inverted.
int orient3d(const double* a, const double* b, const double* c, const double* d);

// The same sign when a floating-point evaluation proves it (Shewchuk's stage A error bound), else 0
// (flat or too close to flat to tell without exact arithmetic). Pure IEEE double operations in a
// fixed order: the codec's candidate filter (spec section 10.4) relies on every platform agreeing.
int orient3dCertain(const double* a, const double* b, const double* c, const double* d);

// Sign of the orientation of triangle (a, b, c) projected on the plane orthogonal to axis `drop`
// (0, 1, 2), i.e. the 2D orientation of the other two coordinates in cyclic order.
int orient2dProjected(const double* a, const double* b, const double* c, int drop);

// Signed volume det[b - a, c - a, d - a] / 6 in floating point (for statistics, not for decisions).
double signedVolume(const double* a, const double* b, const double* c, const double* d);

}  // namespace gtn
