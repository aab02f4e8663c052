// Exact geometric predicates (CGAL's filtered Epick kernel): signs are decided exactly, never with an
// epsilon. Coordinates are doubles; float32 sources convert to double exactly.
#pragma once

#include <cmath>

namespace gtn {

// Sign of det[b - a, c - a, d - a]: +1 positive volume, 0 flat, -1 inverted.
int orient3d(const double* a, const double* b, const double* c, const double* d);

// The same sign when a floating-point evaluation proves it (Shewchuk's stage A error bound), else 0
// (flat or too close to flat to tell without exact arithmetic). Pure IEEE double operations in a
// fixed order: the codec's candidate filter (spec section 10.4) relies on every platform agreeing.
int orient3dCertain(const double* a, const double* b, const double* c, const double* d);

// orient3dCertain(a, b, c, d) for one triangle (a, b, c) and many points d: the terms that depend
// only on the triangle are computed once. Every operation, and its order, is orient3dCertain's, so
// the signs are the same bit for bit.
class Orient3dFilter {
 public:
  Orient3dFilter(const double* a, const double* b, const double* c)
      : ax_(a[0]),
        ay_(a[1]),
        az_(a[2]),
        ux_(b[0] - a[0]),
        uy_(b[1] - a[1]),
        uz_(b[2] - a[2]),
        vx_(c[0] - a[0]),
        vy_(c[1] - a[1]),
        vz_(c[2] - a[2]),
        uxvy_(ux_ * vy_),
        uyvx_(uy_ * vx_),
        fuz_(std::fabs(uz_)),
        fvz_(std::fabs(vz_)),
        fuv_(std::fabs(uxvy_) + std::fabs(uyvx_)),
        cross_(uxvy_ - uyvx_) {}

  int sign(const double* d) const {
    const double wx = d[0] - ax_, wy = d[1] - ay_, wz = d[2] - az_;
    const double vxwy = vx_ * wy, vywx = vy_ * wx, wxuy = wx * uy_, wyux = wy * ux_;
    const double det = uz_ * (vxwy - vywx) + vz_ * (wxuy - wyux) + wz * cross_;
    const double permanent =
        (std::fabs(vxwy) + std::fabs(vywx)) * fuz_ + (std::fabs(wxuy) + std::fabs(wyux)) * fvz_ + fuv_ * std::fabs(wz);
    constexpr double kEps = 0x1p-53;
    constexpr double kBound = (7.0 + 56.0 * kEps) * kEps;
    const double err = kBound * permanent;
    return (det > err) - (-det > err);
  }

 private:
  double ax_, ay_, az_, ux_, uy_, uz_, vx_, vy_, vz_, uxvy_, uyvx_, fuz_, fvz_, fuv_, cross_;
};

// Sign of the orientation of triangle (a, b, c) projected on the plane orthogonal to axis `drop`
// (0, 1, 2), i.e. the 2D orientation of the other two coordinates in cyclic order.
int orient2dProjected(const double* a, const double* b, const double* c, int drop);

// Signed volume det[b - a, c - a, d - a] / 6 in floating point (for statistics, not for decisions).
double signedVolume(const double* a, const double* b, const double* c, const double* d);

}  // namespace gtn
