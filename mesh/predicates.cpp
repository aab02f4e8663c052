#include "mesh/predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>

namespace gtn {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Point2 = Kernel::Point_2;

int toInt(CGAL::Orientation o) { return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0); }
}  // namespace

int orient3dCertain(const double* a, const double* b, const double* c, const double* d) {
  // Shewchuk's orient3d stage A bound, for the determinant of the three difference vectors: when
  // |det| exceeds it, its sign is the exact one. The expansion is Orient3dFilter's.
  return Orient3dFilter(a, b, c).sign(d);
}

int orient3d(const double* a, const double* b, const double* c, const double* d) {
  // The filter decides the common case without leaving the function.
  if (const int sign = orient3dCertain(a, b, c, d)) return sign;
  // CGAL::orientation(p, q, r, s) is POSITIVE when s lies on the positive side of (p, q, r), that is
  // when det[q - p, r - p, s - p] > 0, the convention of docs/design.md.
  return toInt(CGAL::orientation(Point3(a[0], a[1], a[2]), Point3(b[0], b[1], b[2]), Point3(c[0], c[1], c[2]),
                                 Point3(d[0], d[1], d[2])));
}

int orient2dProjected(const double* a, const double* b, const double* c, int drop) {
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  return toInt(CGAL::orientation(Point2(a[u], a[v]), Point2(b[u], b[v]), Point2(c[u], c[v])));
}

double signedVolume(const double* a, const double* b, const double* c, const double* d) {
  const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  return (bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx)) / 6.0;
}

}  // namespace gtn
