#include "convert/cell_split.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <string>

#include "convert/vtk_common.h"
#include "mesh/fresh_memory.h"
#include "mesh/hex_split.h"
#include "mesh/index.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {

// A face of a cell type in local vertex numbers, cyclic order; 3 to 6 vertices. Every face turns
// outward (right-hand rule) on a cell that VTK's vtkCellValidator accepts: the cone over the faces
// (Splitter::cone) then gives positively oriented tetrahedra, and only cells that really are
// inverted are reported as flipped. (A hexahedron's, pyramid's or prism's first face turns inward,
// towards the opposite face or the apex; a wedge's first face turns outward, as vtkWedge documents,
// although its parametric coordinates say otherwise.)
struct Face {
  int n;
  int v[6];
};

constexpr Face kHexFaces[] = {{4, {0, 3, 2, 1}}, {4, {4, 5, 6, 7}}, {4, {0, 1, 5, 4}},
                              {4, {1, 2, 6, 5}}, {4, {2, 3, 7, 6}}, {4, {3, 0, 4, 7}}};
constexpr Face kWedgeFaces[] = {
    {3, {0, 1, 2, 0}}, {3, {3, 5, 4, 0}}, {4, {0, 3, 4, 1}}, {4, {1, 4, 5, 2}}, {4, {2, 5, 3, 0}}};
constexpr Face kPyramidFaces[] = {
    {4, {0, 3, 2, 1}}, {3, {0, 1, 4, 0}}, {3, {1, 2, 4, 0}}, {3, {2, 3, 4, 0}}, {3, {3, 0, 4, 0}}};
// Prisms over a pentagon (points 0-4 the bottom, 5-9 the top, i + 5 above i) and over a hexagon
// (0-5, 6-11).
constexpr Face kPentagonalPrismFaces[] = {{5, {0, 4, 3, 2, 1}}, {5, {5, 6, 7, 8, 9}}, {4, {0, 1, 6, 5}},
                                          {4, {1, 2, 7, 6}},    {4, {2, 3, 8, 7}},    {4, {3, 4, 9, 8}},
                                          {4, {4, 0, 5, 9}}};
constexpr Face kHexagonalPrismFaces[] = {{6, {0, 5, 4, 3, 2, 1}}, {6, {6, 7, 8, 9, 10, 11}}, {4, {0, 1, 7, 6}},
                                         {4, {1, 2, 8, 7}},       {4, {2, 3, 9, 8}},         {4, {3, 4, 10, 9}},
                                         {4, {4, 5, 11, 10}},     {4, {5, 0, 6, 11}}};

int expectedPoints(int type) {
  switch (type) {
    case kVtkTetra: return 4;
    case kVtkVoxel: return 8;
    case kVtkHexahedron: return 8;
    case kVtkWedge: return 6;
    case kVtkPyramid: return 5;
    case kVtkPentagonalPrism: return 10;
    case kVtkHexagonalPrism: return 12;
    case kVtkQuadraticTetra: return 10;
    case kVtkQuadraticHexahedron: return 20;
    case kVtkQuadraticWedge: return 15;
    case kVtkQuadraticPyramid: return 13;
    case kVtkTriquadraticHexahedron: return 27;
    case 31: return 12;  // VTK_QUADRATIC_LINEAR_WEDGE
    case 32: return 18;  // VTK_BIQUADRATIC_QUADRATIC_WEDGE
    case 33: return 24;  // VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON
    case 37: return 19;  // VTK_TRIQUADRATIC_PYRAMID
    default: return -1;
  }
}

// Cells of dimension 0 to 2 (vertices, lines, faces, linear or not). Files of volume meshes often
// carry them beside the volume cells, as boundary faces and feature edges (Gmsh, MMG and meshio
// write them so); they bound no volume and are skipped.
bool isLowerDimensional(int type) {
  switch (type) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 4:
    case 5:
    case 6:
    case 7:
    case 8:
    case 9:  // linear
    case 21:
    case 22:
    case 23:
    case 28:
    case 30:
    case 34:
    case 35:
    case 36:  // quadratic, cubic
    case 51:  // parametric curve
    case 60:
    case 61:
    case 62:
    case 63:  // higher order
    case 68:
    case 69:
    case 70:
    case 75:
    case 76:
    case 77:  // Lagrange, Bezier
      return true;
    default: return false;
  }
}

// The corners of a quadratic, Lagrange or Bezier cell come first, in the order of its linear cell.
int linearType(int type) {
  switch (type) {
    case kVtkQuadraticTetra:
    case 64:
    case 71:
    case 78: return kVtkTetra;  // higher-order, Lagrange, Bezier tetrahedra
    case kVtkQuadraticHexahedron:
    case kVtkTriquadraticHexahedron:
    case 33:
    case 67:
    case 72:
    case 79: return kVtkHexahedron;
    case kVtkQuadraticWedge:
    case 31:
    case 32:
    case 65:
    case 73:
    case 80: return kVtkWedge;
    case kVtkQuadraticPyramid:
    case 37:
    case 74:
    case 81: return kVtkPyramid;
    default: return type;
  }
}

// Lagrange and Bezier volume cells (and VTK's "higher order" ones) have as many points as their
// order asks for, corners first: at least those of their linear cell. 0 for other types.
int arbitraryOrderCorners(int type) {
  switch (type) {
    case 64:
    case 71:
    case 78: return 4;
    case 67:
    case 72:
    case 79: return 8;
    case 65:
    case 73:
    case 80: return 6;
    case 74:
    case 81: return 5;
    default: return 0;
  }
}

std::string typeCounts(const std::map<int, size_t>& counts) {
  std::string list;
  for (const auto& [type, count] : counts) {
    if (!list.empty()) list += ", ";
    list += std::to_string(count) + " cell" + (count == 1 ? "" : "s") + " of type " + std::to_string(type) + " (" +
            vtkCellTypeName(type) + ")";
  }
  return list;
}

// x rounded to float32, through a volatile: GCC 12.2 at -O3 vectorises the rounding of a point's
// first two coordinates into a plain copy that drops it (seen in Splitter::steinerCone; the float32
// Steiner point test fails without this).
double roundedToFloat32(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

class Splitter {
 public:
  // `coords`: the num_points points (3 per point), or nullptr to split by indices alone. `steiner`:
  // where to add a point inside a cell that no cone from a vertex splits without inversions, or
  // nullptr to add none; `float32`: whether its coordinates must be float32 values.
  Splitter(std::vector<Tet>* tets, std::vector<uint32_t>* tet_cell, const double* coords, size_t num_points,
           SteinerPoints* steiner, bool float32)
      : tets_(tets),
        tet_cell_(tet_cell),
        coords_(coords),
        num_points_(num_points),
        steiner_(steiner),
        float32_(float32) {}

  void emit(const Tet& t, uint32_t cell) {
    if (t[0] == t[1] || t[0] == t[2] || t[0] == t[3] || t[1] == t[2] || t[1] == t[3] || t[2] == t[3]) {
      ++collapsed_;
      return;
    }
    tets_->push_back(t);
    if (tet_cell_) tet_cell_->push_back(cell);
  }

  // The cone from the cell's smallest-index vertex over the faces that do not contain it. When the
  // cell is not convex (a twisted hexahedron, say) some of those tetrahedra can come out inverted
  // while the others are not, and flipping them would make them overlap their neighbours: then the
  // cone is taken from the next vertex (by global index) that the face rule allows as an apex (every
  // face through it cut through it) and whose cone has no such mix, if there is one.
  template <size_t N>
  void cone(const Face (&faces)[N], const uint32_t* g, int num_vertices, uint32_t cell) {
    int order[12];  // local vertices by ascending global index (insertion sort: at most 12)
    for (int k = 0; k < num_vertices; ++k) {
      int at = k;
      for (; at > 0 && g[order[at - 1]] > g[k]; --at) order[at] = order[at - 1];
      order[at] = k;
    }
    coneAvoidingMix(
        static_cast<size_t>(num_vertices), [&](size_t k) { return allowedApex(faces, g, order[k]); },
        [&](size_t k, std::vector<Tet>* out) { coneFrom(faces, g, order[k], g[order[k]], out); },
        [&](std::vector<uint32_t>* out) {
          for (int k = 0; k < num_vertices; ++k) out->push_back(g[order[k]]);
        },
        [&](uint32_t point, std::vector<Tet>* out) { coneFrom(faces, g, -1, point, out); }, cell);
  }

  // The face rule: the place in its cycle of the corner a face of n corners (global index idx(k),
  // cyclic order) is fanned from. Its smallest-index corner, unless that fan has a flat triangle
  // (three corners in a line: a straight angle, as a hanging node on an edge makes) and another
  // corner's does not: then the first such corner by global index. A quadrilateral is cut along the
  // diagonal through that corner. The choice depends on the face alone (its indices and points), so
  // the two cells that share a face cut it alike.
  template <class Index>
  int64_t fanCorner(int64_t n, Index idx) const {
    int64_t m = 0;
    for (int64_t k = 1; k < n; ++k)
      if (idx(k) < idx(m)) m = k;
    if (!coords_ || n <= 3 || !flatFan(n, idx, m)) return m;
    int64_t best = -1;
    for (int64_t k = 0; k < n; ++k)
      if (k != m && (best < 0 || idx(k) < idx(best)) && !flatFan(n, idx, k)) best = k;
    return best >= 0 ? best : m;
  }
  // Whether the fan of a face from its corner at place m has a triangle whose corners lie in a line
  // (exactly: its normal's three components, the projected orientations, are zero).
  template <class Index>
  bool flatFan(int64_t n, Index idx, int64_t m) const {
    const double* a = coords_ + 3 * size_t{idx(m)};
    for (int64_t k = 1; k + 1 < n; ++k) {
      const double* b = coords_ + 3 * size_t{idx((m + k) % n)};
      const double* c = coords_ + 3 * size_t{idx((m + k + 1) % n)};
      if (orient2dProjected(a, b, c, 0) == 0 && orient2dProjected(a, b, c, 1) == 0 &&
          orient2dProjected(a, b, c, 2) == 0)
        return true;
    }
    return false;
  }
  // Appends to *out the tetrahedra from `apex` to the fan of a face of n corners (global index
  // idx(k), cyclic order) from the corner the face rule chooses: a quadrilateral is cut along its
  // diagonal through that corner, a triangle stays whole.
  template <class Index>
  void fan(uint32_t apex, int64_t n, Index idx, std::vector<Tet>* out) const {
    const int64_t m = fanCorner(n, idx);
    for (int64_t k = 1; k + 1 < n; ++k) out->push_back({apex, idx(m), idx((m + k) % n), idx((m + k + 1) % n)});
  }
  // fanCorner of a cell's face (local vertices f.v, global g).
  int faceCorner(const Face& f, const uint32_t* g) const {
    return static_cast<int>(fanCorner(f.n, [&](int64_t k) { return g[f.v[k]]; }));
  }

  // A polyhedron from its face stream `f` (checked): the cone from its smallest vertex over the fans
  // of the faces without it; when that mixes orientations (a cell that is not convex), from the next
  // vertex the face rule allows whose cone does not, as cone() does (among the first kMaxApexTries).
  void polyhedron(const int64_t* stream, uint32_t cell) {
    const int64_t* f = windFacesAlike(stream);
    const int64_t num_faces = f[0];
    corners_.clear();
    for (int64_t k = 0, at = 1; k < num_faces; ++k, at += 1 + f[at])
      for (int64_t i = 0; i < f[at]; ++i) corners_.push_back(static_cast<uint32_t>(f[at + 1 + i]));
    std::sort(corners_.begin(), corners_.end());
    corners_.erase(std::unique(corners_.begin(), corners_.end()), corners_.end());
    constexpr size_t kMaxApexTries = 64;
    coneAvoidingMix(
        std::min(corners_.size(), kMaxApexTries), [&](size_t k) { return allowedPolyhedronApex(f, corners_[k]); },
        [&](size_t k, std::vector<Tet>* out) { polyhedronCone(f, corners_[k], out); },
        [&](std::vector<uint32_t>* out) { out->insert(out->end(), corners_.begin(), corners_.end()); },
        [&](uint32_t point, std::vector<Tet>* out) { polyhedronCone(f, point, out); }, cell);
  }

  // True when the hexahedron's six face diagonals (by the smallest-index rule) are the edges of one
  // inscribed tetrahedron; *odd says which ({1,3,4,6} rather than {0,2,5,7}).
  bool fiveSplittable(const uint32_t* g, bool* odd) const {
    int even_count = 0;
    for (const Face& f : kHexFaces) {
      const int corner = f.v[faceCorner(f, g)];
      if (corner == 0 || corner == 2 || corner == 5 || corner == 7) ++even_count;
    }
    *odd = even_count == 0;
    return even_count == 0 || even_count == 6;
  }

  void hex(const uint32_t* g, int split, uint32_t cell) {
    bool odd = false;
    if (split == 5 && fiveSplittable(g, &odd)) {
      five_scratch_.clear();
      splitHexFive(g, odd, five_scratch_);
      if (!coords_ || (!mixedOrientation(five_scratch_) && !flatBeside(five_scratch_))) {
        for (const Tet& t : five_scratch_) emit(t, cell);
        ++hex_five_;
        return;
      }
      ++five_inverted_;  // not convex enough for 5: the cone below may do
    }
    cone(kHexFaces, g, 8, cell);
  }

  // A structured grid's hexahedron h (VTK corner order) into 5 tetrahedra (odd: the cell's parity) or
  // 6, as splitHexFive and splitHexSix cut it; when those mix orientations (a warped cell), around a
  // Steiner point over its faces, each cut along the diagonal the 5 or 6 use, as its neighbours do.
  void gridHex(const uint32_t* h, int split, bool odd, uint32_t cell) {
    scratch_.clear();
    if (split == 5) splitHexFive(h, odd, scratch_);
    else splitHexSix(h, scratch_);
    if (coords_ && steiner_ && mixedOrientation(scratch_)) {
      pieces_ = scratch_;
      auto joined = [&](uint32_t x, uint32_t y) {
        for (const Tet& t : pieces_)
          if (std::find(t.begin(), t.end(), x) != t.end() && std::find(t.begin(), t.end(), y) != t.end()) return true;
        return false;
      };
      const bool fixed = steinerCone([&](std::vector<uint32_t>* out) { out->insert(out->end(), h, h + 8); },
                                     [&](uint32_t point, std::vector<Tet>* out) {
                                       out->clear();
                                       for (const Face& f : kHexFaces) {
                                         const uint32_t q[4] = {h[f.v[0]], h[f.v[1]], h[f.v[2]], h[f.v[3]]};
                                         const int m = joined(q[0], q[2]) ? 0 : 1;  // the diagonal's first end
                                         out->push_back({point, q[m], q[m + 1], q[m + 2]});
                                         out->push_back({point, q[m], q[m + 2], q[(m + 3) % 4]});
                                       }
                                     },
                                     [&](const std::vector<Tet>& t) { return !mixedOrientation(t); });
      ++(fixed ? steiner_cells_ : mixed_);
    }
    for (const Tet& t : scratch_) emit(t, cell);
  }

  // The warnings (and the Steiner point count) for the cells split around an added point, and for
  // those no split fixes.
  void reportAdded(ImportReport* report) const {
    if (steiner_cells_) {
      report->steiner_points += steiner_cells_;
      report->warnings.push_back(std::to_string(steiner_cells_) +
                                 " cells that are not convex split around a point added inside them (a Steiner point: "
                                 "the mean of their corners, or of their kernel's vertices; its point fields the mean "
                                 "of the corners'): split between their vertices alone, some of their tetrahedra "
                                 "come out inverted");
    }
    if (unflattened_ || steiner_flat_) {
      report->steiner_points += steiner_flat_;
      report->warnings.push_back(
          std::to_string(unflattened_ + steiner_flat_) +
          " cells with a straight angle in a face, or a vertex in the plane of a face, split so that none of their "
          "tetrahedra is flat: " +
          std::to_string(unflattened_) + " from another vertex than their smallest, " + std::to_string(steiner_flat_) +
          " around a point added inside them (a Steiner point, the mean of their corners or of their kernel's "
          "vertices; its point fields the mean of the corners')");
    }
    if (flat_kept_)
      report->warnings.push_back(std::to_string(flat_kept_) +
                                 " cells have flat tetrahedra however they are split (some of their corners coincide, "
                                 "or lie in a line or a plane); the flat tetrahedra are kept");
    if (mixed_)
      report->warnings.push_back(std::to_string(mixed_) +
                                 " cells that are not convex have inverted tetrahedra however they are split, even "
                                 "from a point added inside; once flipped these overlap their neighbours, which gtn "
                                 "validate sees only where the boundary folds");
  }

  size_t collapsed_ = 0;
  size_t resplit_ = 0;        // cells split from another vertex than their smallest (cone)
  size_t mixed_ = 0;          // cells whose every allowed cone mixes orientations, even from a Steiner point
  size_t steiner_cells_ = 0;  // cells split from an added point
  size_t unflattened_ = 0;    // cells split from another vertex than their smallest, so that none is flat
  size_t steiner_flat_ = 0;   // cells split from an added point, so that none is flat
  size_t flat_kept_ = 0;      // cells with flat tetrahedra however they are split
  size_t hex_five_ = 0;
  size_t five_inverted_ = 0;  // hexahedra whose diagonals allow 5 tetrahedra, of which some come out inverted
  size_t rewound_ = 0;        // polyhedra whose faces did not all wind the same way

 private:
  std::vector<Tet>* tets_;
  std::vector<uint32_t>* tet_cell_;
  // Emits the cone from apex 0 of n candidate apexes (ascending global index); when it mixes
  // orientations, the first cone from an allowed apex that does not (cone() says why), counted; when
  // every one does, the cone from a Steiner point inside the cell over all its faces (cut by the face
  // rule, so neighbours still agree; steinerCone), if that one does not.
  // allowed(k): whether the face rule allows apex k; coneOf(k, out): its cone into *out;
  // corners(out): the cell's distinct corners, appended; coneFromPoint(p, out): the cone from
  // point p (a vertex of no face) over every face, into *out.
  // A cone with a flat tetrahedron beside solid ones (and no mix) is treated alike: the first allowed
  // apex whose cone has neither, else a Steiner point whose cone has neither, else it is kept (counted
  // in flat_kept_). A mixed cone takes such a cone too when there is one, else as before the first
  // cone with no mix, flat pieces allowed.
  template <class Allowed, class ConeOf, class Corners, class ConeFromPoint>
  void coneAvoidingMix(size_t n, Allowed allowed, ConeOf coneOf, Corners corners, ConeFromPoint coneFromPoint,
                       uint32_t cell) {
    coneOf(0, &scratch_);
    const bool mixed = coords_ && mixedOrientation(scratch_);
    const bool flat = coords_ && !mixed && flatBeside(scratch_);
    if (mixed || flat) {
      auto clean = [&](const std::vector<Tet>& t) { return !mixedOrientation(t) && !flatBeside(t); };
      auto unmixed = [&](const std::vector<Tet>& t) { return !mixedOrientation(t); };
      bool fixed = false;
      for (int pass = 0; pass < (mixed ? 2 : 1) && !fixed; ++pass) {
        for (size_t k = 1; k < n && !fixed; ++k) {
          if (!allowed(k)) continue;
          coneOf(k, &other_);
          if (pass == 0 ? clean(other_) : unmixed(other_)) {
            scratch_.swap(other_);
            ++(flat ? unflattened_ : resplit_);
            fixed = true;
          }
        }
        if (!fixed && steiner_) {
          fixed = pass == 0 ? steinerCone(corners, coneFromPoint, clean) : steinerCone(corners, coneFromPoint, unmixed);
          if (fixed) ++(flat ? steiner_flat_ : steiner_cells_);
        }
      }
      if (!fixed) ++(mixed ? mixed_ : flat_kept_);
    }
    for (const Tet& t : scratch_) emit(t, cell);
  }
  // Adds a point inside the cell (rounded to float32 when the points are) and, when its cone over
  // the faces is one `accept` takes, takes that cone into scratch_ and keeps the point (the caller
  // counts it); otherwise adds nothing and returns false. The point tried first is the mean of
  // the corners; then, in a cell that it does not see whole, the mean of the vertices of the cell's
  // kernel (the points that see every face triangle from inside), when there is one.
  template <class Corners, class ConeFromPoint, class Accept>
  bool steinerCone(Corners corners, ConeFromPoint coneFromPoint, Accept accept) {
    const size_t first_corner = steiner_->corners.size();
    corners(&steiner_->corners);
    std::sort(steiner_->corners.begin() + first_corner, steiner_->corners.end());
    steiner_->corners.erase(std::unique(steiner_->corners.begin() + first_corner, steiner_->corners.end()),
                            steiner_->corners.end());
    const size_t count = steiner_->corners.size() - first_corner;
    const size_t point = num_points_ + steiner_->coords.size() / 3;
    if (point < UINT32_MAX) {
      double mean[3] = {0, 0, 0};
      for (size_t k = first_corner; k < steiner_->corners.size(); ++k)
        for (int d = 0; d < 3; ++d) mean[d] += coords_[3 * size_t{steiner_->corners[k]} + d];
      for (int d = 0; d < 3; ++d) mean[d] /= static_cast<double>(count);
      steiner_->coords.resize(steiner_->coords.size() + 3);
      double* at = &steiner_->coords[3 * (point - num_points_)];
      coneFromPoint(static_cast<uint32_t>(point), &other_);  // its tetrahedra: (point, face triangle)
      double kernel[3];
      for (const double* candidate : {static_cast<const double*>(mean), static_cast<const double*>(kernel)}) {
        if (candidate == kernel && !kernelMean(other_, mean, kernel)) break;
        for (int d = 0; d < 3; ++d) at[d] = float32_ ? roundedToFloat32(candidate[d]) : candidate[d];
        if (accept(other_)) {
          scratch_.swap(other_);
          steiner_->corner_offsets.push_back(steiner_->corners.size());
          return true;
        }
      }
      steiner_->coords.resize(steiner_->coords.size() - 3);
    }
    steiner_->corners.resize(first_corner);
    return false;
  }
  // The mean of the vertices of the kernel of the closed surface of the triangles (a, b, c) of
  // `cone`'s tetrahedra (p, a, b, c): the points from which every triangle turns the same way, all
  // one side or all the other. False when it is empty (or the surface has more than kMaxKernelPlanes
  // triangles). Each vertex is where three triangle planes meet (in coordinates relative to `origin`,
  // for precision); the mean of the vertices of a convex polytope lies inside it.
  bool kernelMean(const std::vector<Tet>& cone, const double origin[3], double out[3]) const {
    constexpr size_t kMaxKernelPlanes = 32;
    const size_t m = cone.size();
    if (m < 4 || m > kMaxKernelPlanes) return false;
    auto cross = [](const double* a, const double* b, double* c) {
      c[0] = a[1] * b[2] - a[2] * b[1];
      c[1] = a[2] * b[0] - a[0] * b[2];
      c[2] = a[0] * b[1] - a[1] * b[0];
    };
    double n[kMaxKernelPlanes][3], h[kMaxKernelPlanes], len[kMaxKernelPlanes];
    double extent = 0;
    for (size_t i = 0; i < m; ++i) {
      double q[3][3];
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) {
          q[k][d] = at(cone[i][k + 1])[d] - origin[d];
          extent = std::max(extent, std::fabs(q[k][d]));
        }
      const double u[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
      const double v[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
      cross(u, v, n[i]);
      h[i] = n[i][0] * q[0][0] + n[i][1] * q[0][1] + n[i][2] * q[0][2];
      len[i] = std::sqrt(n[i][0] * n[i][0] + n[i][1] * n[i][1] + n[i][2] * n[i][2]);
    }
    for (const double side : {1.0, -1.0}) {
      double sum[3] = {0, 0, 0};
      size_t vertices = 0;
      for (size_t i = 0; i < m; ++i)
        for (size_t j = i + 1; j < m; ++j)
          for (size_t k = j + 1; k < m; ++k) {
            double jk[3], ki[3], ij[3];
            cross(n[j], n[k], jk);
            cross(n[k], n[i], ki);
            cross(n[i], n[j], ij);
            const double det = n[i][0] * jk[0] + n[i][1] * jk[1] + n[i][2] * jk[2];
            if (!(std::fabs(det) > 1e-9 * len[i] * len[j] * len[k])) continue;  // planes nearly parallel
            double p[3];
            for (int d = 0; d < 3; ++d) p[d] = (h[i] * jk[d] + h[j] * ki[d] + h[k] * ij[d]) / det;
            bool inside = true;
            for (size_t l = 0; l < m && inside; ++l)
              inside = side * (h[l] - (n[l][0] * p[0] + n[l][1] * p[1] + n[l][2] * p[2])) >= -1e-12 * len[l] * extent;
            if (!inside) continue;
            for (int d = 0; d < 3; ++d) sum[d] += p[d];
            ++vertices;
          }
      if (vertices == 0) continue;
      for (int d = 0; d < 3; ++d) out[d] = origin[d] + sum[d] / static_cast<double>(vertices);
      return true;
    }
    return false;
  }
  // The cone from point `apex` over the faces without local vertex `skip` (the apex itself, or -1
  // for a point inside the cell), into *out.
  template <size_t N>
  void coneFrom(const Face (&faces)[N], const uint32_t* g, int skip, uint32_t apex, std::vector<Tet>* out) const {
    out->clear();
    for (const Face& f : faces) {
      if (std::find(f.v, f.v + f.n, skip) != f.v + f.n) continue;
      fan(
          apex, f.n, [&](int64_t k) { return g[f.v[k]]; }, out);
    }
  }
  // Whether the face rule (fan from the corner at place m, fanCorner) cuts a face of n corners
  // through its corner at place `at`: a triangle always, a quadrilateral when `at` ends the diagonal
  // from m, a larger face when `at` is m.
  static bool cutThrough(int64_t n, int64_t at, int64_t m) {
    return n == 3 || at == m || (n == 4 && at == (m + 2) % 4);
  }
  // True when every face through local vertex v is cut through v by the face rule: a triangle, a
  // quadrilateral whose diagonal ends at v, or a larger face fanned from v.
  template <size_t N>
  bool allowedApex(const Face (&faces)[N], const uint32_t* g, int v) const {
    for (const Face& f : faces) {
      const int at = static_cast<int>(std::find(f.v, f.v + f.n, v) - f.v);
      if (at != f.n && !cutThrough(f.n, at, faceCorner(f, g))) return false;
    }
    return true;
  }
  // The cone from vertex `apex` over the fans of the faces of face stream f without it, into *out.
  void polyhedronCone(const int64_t* f, uint32_t apex, std::vector<Tet>* out) const {
    out->clear();
    for (int64_t k = 0, at = 1; k < f[0]; ++k, at += 1 + f[at]) {
      const int64_t n = f[at];
      const int64_t* v = f + at + 1;
      if (std::find(v, v + n, int64_t{apex}) != v + n) continue;
      fan(
          apex, n, [&](int64_t i) { return static_cast<uint32_t>(v[i]); }, out);
    }
  }
  // A polyhedron's face stream whose faces all wind the same way, outward where they did not: f
  // itself where they already do (each edge of its faces is walked once each way), or where its faces
  // are not a closed surface that can be wound alike (an edge of one face, or of three); otherwise a
  // copy (wound_) with the faces that disagree reversed: the faces agreeing with the first are then
  // reversed or not as a whole, so that the cell's volume (their cones from a corner) is positive.
  // Reversing a face changes its fan's orientation, not its triangles (fanCorner reads no order), so
  // a face stays cut as its neighbour cuts it.
  const int64_t* windFacesAlike(const int64_t* f) {
    const int64_t num_faces = f[0];
    face_at_.clear();
    edges_.clear();
    for (int64_t k = 0, at = 1; k < num_faces; ++k, at += 1 + f[at]) {
      face_at_.push_back(at);
      const int64_t n = f[at];
      const int64_t* v = f + at + 1;
      for (int64_t i = 0; i < n; ++i) {
        const int64_t a = v[i], b = v[(i + 1) % n];
        edges_.push_back({std::min(a, b), std::max(a, b), static_cast<uint32_t>(k), a < b});
      }
    }
    std::sort(edges_.begin(), edges_.end(), [](const WoundEdge& x, const WoundEdge& y) {
      return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.face < y.face);
    });
    bool alike = true;
    for (size_t i = 0; i < edges_.size(); i += 2) {
      if (i + 1 >= edges_.size() || edges_[i + 1].lo != edges_[i].lo || edges_[i + 1].hi != edges_[i].hi ||
          (i + 2 < edges_.size() && edges_[i + 2].lo == edges_[i].lo && edges_[i + 2].hi == edges_[i].hi) ||
          edges_[i].face == edges_[i + 1].face)
        return f;  // not a closed surface of faces meeting in pairs along their edges
      alike = alike && edges_[i].up != edges_[i + 1].up;
    }
    if (alike) return f;
    // Each face's winding against the first's, spread across the shared edges.
    const size_t nf = static_cast<size_t>(num_faces);
    flip_.assign(nf, -1);
    flip_[0] = 0;
    for (bool changed = true; changed;) {
      changed = false;
      for (size_t i = 0; i < edges_.size(); i += 2) {
        const WoundEdge& x = edges_[i];
        const WoundEdge& y = edges_[i + 1];
        const int8_t differ = x.up == y.up ? 1 : 0;  // walked the same way: one of the two turns
        if (flip_[x.face] >= 0 && flip_[y.face] < 0) {
          flip_[y.face] = static_cast<int8_t>(flip_[x.face] ^ differ);
          changed = true;
        } else if (flip_[y.face] >= 0 && flip_[x.face] < 0) {
          flip_[x.face] = static_cast<int8_t>(flip_[y.face] ^ differ);
          changed = true;
        } else if (flip_[x.face] >= 0 && (flip_[x.face] ^ differ) != flip_[y.face]) {
          return f;  // a surface that cannot be wound alike
        }
      }
    }
    if (std::find(flip_.begin(), flip_.end(), int8_t{-1}) != flip_.end()) return f;  // in several parts
    if (!coords_) return f;  // which way is outward is not known
    // The volume the faces enclose, wound as the first: the cones from one corner over their fans.
    const double* o = at(static_cast<uint32_t>(f[2]));
    double volume = 0;
    for (size_t k = 0; k < nf; ++k) {
      const int64_t n = f[face_at_[k]];
      const int64_t* v = f + face_at_[k] + 1;
      for (int64_t i = 1; i + 1 < n; ++i) {
        const double cone = signedVolume(o, at(static_cast<uint32_t>(v[0])), at(static_cast<uint32_t>(v[i])),
                                         at(static_cast<uint32_t>(v[i + 1])));
        volume += flip_[k] ? -cone : cone;
      }
    }
    const int8_t all = volume < 0 ? 1 : 0;
    wound_.assign(f, f + (face_at_.back() + 1 + f[face_at_.back()]));
    for (size_t k = 0; k < nf; ++k)
      if (flip_[k] ^ all)
        std::reverse(wound_.begin() + face_at_[k] + 1, wound_.begin() + face_at_[k] + 1 + f[face_at_[k]]);
    ++rewound_;
    return wound_.data();
  }
  // allowedApex for a polyhedron: every face through `apex` is a triangle, a quadrilateral whose
  // diagonal ends at it, or a larger face the face rule fans from it.
  bool allowedPolyhedronApex(const int64_t* f, uint32_t apex) const {
    for (int64_t k = 0, at = 1; k < f[0]; ++k, at += 1 + f[at]) {
      const int64_t n = f[at];
      const int64_t* v = f + at + 1;
      const int64_t pos = std::find(v, v + n, int64_t{apex}) - v;
      if (pos != n && !cutThrough(n, pos, fanCorner(n, [&](int64_t i) { return static_cast<uint32_t>(v[i]); })))
        return false;
    }
    return true;
  }
  // Point i: an input point, or a Steiner point added so far.
  const double* at(uint32_t i) const {
    return i < num_points_ ? coords_ + 3 * size_t{i} : steiner_->coords.data() + 3 * (i - num_points_);
  }
  // A flat tetrahedron (four distinct points in a plane) beside one that is not: a split that a
  // straight angle in a face, or a vertex in the plane of a face it is coned to, made flat where
  // another split need not be. (One that repeats a point is dropped, not flat.)
  bool flatBeside(const std::vector<Tet>& tets) const {
    bool flat = false, solid = false;
    for (const Tet& t : tets) {
      if (t[0] == t[1] || t[0] == t[2] || t[0] == t[3] || t[1] == t[2] || t[1] == t[3] || t[2] == t[3]) continue;
      const bool zero = orient3d(at(t[0]), at(t[1]), at(t[2]), at(t[3])) == 0;
      flat |= zero;
      solid |= !zero;
    }
    return flat && solid;
  }
  // Some tetrahedra positively oriented and some negatively (flat ones count as neither).
  bool mixedOrientation(const std::vector<Tet>& tets) const {
    bool pos = false, neg = false;
    for (const Tet& t : tets) {
      const int o = orient3d(at(t[0]), at(t[1]), at(t[2]), at(t[3]));
      pos |= o > 0;
      neg |= o < 0;
    }
    return pos && neg;
  }

  const double* coords_;
  size_t num_points_;
  SteinerPoints* steiner_;
  bool float32_;
  std::vector<Tet> five_scratch_, scratch_, other_, pieces_;
  std::vector<uint32_t> corners_;  // a polyhedron's distinct vertices, ascending
  // windFacesAlike's scratch: each face's place in the stream, the faces' edges (ends ascending, the
  // face, whether the face walks it from lo to hi), each face's winding against the first face's
  // (-1: not reached yet), and the stream with its faces wound alike.
  struct WoundEdge {
    int64_t lo, hi;
    uint32_t face;
    bool up;
  };
  std::vector<int64_t> face_at_;
  std::vector<WoundEdge> edges_;
  std::vector<int8_t> flip_;
  std::vector<int64_t> wound_;
};

}  // namespace

namespace {

// What the first pass of splitVtkCells finds: every cell checked and counted, so that an unsupported
// type is reported with the number of cells that have it, before any work.
struct CellCensus {
  std::map<int, size_t> rejected, skipped;  // per type: unsupported volume cells, lower-dimensional cells
  std::vector<const int64_t*> streams;      // each polyhedron's face stream, in faces or in connectivity
  size_t out_tets = 0;                      // tetrahedra the split will make (at most)
  size_t quadratic = 0, higher_order = 0, hexes = 0;
};

// The cell arrays agree with each other and fit 32-bit indices.
Status checkCellArrays(const std::string& path, const VtkCells& cells, size_t num_points) {
  const size_t num_cells = cells.types.size();
  if (cells.offsets.size() != num_cells + 1 || cells.offsets[0] != 0 ||
      cells.offsets.back() != static_cast<int64_t>(cells.connectivity.size()))
    return invalidData(path + ": cell offsets do not match the connectivity (" + std::to_string(cells.offsets.size()) +
                       " offsets for " + std::to_string(num_cells) + " cells and " +
                       std::to_string(cells.connectivity.size()) + " indices)");
  if (num_cells >= UINT32_MAX) return unsupported(path + ": more than 2^32-1 cells");
  if (num_points >= UINT32_MAX) return unsupported(path + ": more than 2^32-1 points");
  if (!cells.face_offsets.empty() && cells.face_offsets.size() != num_cells)
    return invalidData(path + ": " + std::to_string(cells.face_offsets.size()) + " face offsets for " +
                       std::to_string(num_cells) + " cells");
  return Status::ok();
}

// Polyhedron c's face stream: in faces from *face_pos to its face offset (moving *face_pos there),
// or its connectivity (the legacy layout). `at` names the cell in errors.
Status locateFaceStream(const std::string& at, const VtkCells& cells, size_t c, int64_t* face_pos, const int64_t** f,
                        int64_t* len) {
  if (cells.face_offsets.empty()) {
    *f = cells.connectivity.data() + cells.offsets[c];
    *len = cells.offsets[c + 1] - cells.offsets[c];
    return Status::ok();
  }
  const int64_t end = cells.face_offsets[c];
  if (end < *face_pos || end > static_cast<int64_t>(cells.faces.size()))
    return invalidData(at + ": its face offset " + std::to_string(end) + " is not between " +
                       std::to_string(*face_pos) + " and the " + std::to_string(cells.faces.size()) + " face entries");
  *f = cells.faces.data() + *face_pos;
  *len = end - *face_pos;
  *face_pos = end;
  return Status::ok();
}

// A face stream of `len` entries: the face count (at least 4), then each face's point count (at
// least 3) and points (each < num_points), and nothing after. Adds the tetrahedra its faces make to
// *out_tets.
Status checkFaceStream(const std::string& at, const int64_t* f, int64_t len, size_t num_points, size_t* out_tets) {
  if (len < 1 || f[0] < 4 || f[0] > len)
    return invalidData(at + ": a face stream must start with a face count of at least 4 (" +
                       std::to_string(len < 1 ? 0 : f[0]) + " in " + std::to_string(len) + " entries)");
  int64_t at_entry = 1;
  for (int64_t k = 0; k < f[0]; ++k) {
    if (at_entry >= len) return invalidData(at + ": the face stream ends at face " + std::to_string(k));
    const int64_t n = f[at_entry];
    if (n < 3 || n > len - at_entry - 1)
      return invalidData(at + ": face " + std::to_string(k) + " has " + std::to_string(n) +
                         " points (at least 3, within the stream)");
    for (int64_t i = 0; i < n; ++i) {
      const int64_t v = f[at_entry + 1 + i];
      if (v < 0 || static_cast<uint64_t>(v) >= num_points)
        return invalidData(at + " refers to point " + std::to_string(v) + " but there are " +
                           std::to_string(num_points) + " points");
    }
    *out_tets += static_cast<size_t>(n - 2);
    at_entry += 1 + n;
  }
  if (at_entry != len)
    return invalidData(at + ": " + std::to_string(len - at_entry) + " entries left after its " + std::to_string(f[0]) +
                       " faces");
  return Status::ok();
}

// Cell c of a supported fixed-size or arbitrary-order type: its number of points and its indices.
Status checkCellPoints(const std::string& path, const VtkCells& cells, size_t c, size_t num_points) {
  const int type = cells.types[c];
  const int want = expectedPoints(type);
  const int at_least = arbitraryOrderCorners(type);
  const int64_t begin = cells.offsets[c], end = cells.offsets[c + 1];
  if (end < begin || (want >= 0 && end - begin != want))
    return invalidData(path + ": cell " + std::to_string(c) + " (" + vtkCellTypeName(type) + ") has " +
                       std::to_string(end - begin) + " points, expected " + std::to_string(want));
  if (at_least > 0 && end - begin < at_least)
    return invalidData(path + ": cell " + std::to_string(c) + " (" + vtkCellTypeName(type) + ") has " +
                       std::to_string(end - begin) + " points, fewer than its " + std::to_string(at_least) +
                       " corners");
  for (int64_t k = begin; k < end; ++k) {
    const int64_t v = cells.connectivity[k];
    if (v < 0 || static_cast<uint64_t>(v) >= num_points)
      return invalidData(path + ": cell " + std::to_string(c) + " refers to point " + std::to_string(v) +
                         " but there are " + std::to_string(num_points) + " points");
  }
  return Status::ok();
}

// The tetrahedra a cell of linear type `linear` splits into (at most).
size_t tetsPerCell(int linear) {
  switch (linear) {
    case kVtkTetra: return 1;
    case kVtkVoxel:
    case kVtkHexahedron: return 6;
    case kVtkWedge: return 3;
    case kVtkPyramid: return 2;
    case kVtkPentagonalPrism: return 9;
    case kVtkHexagonalPrism: return 12;
  }
  return 0;
}

// The first pass: checks every cell and counts what the split will meet.
Status surveyCells(const std::string& path, const VtkCells& cells, size_t num_points, CellCensus* census) {
  const bool separate_faces = !cells.face_offsets.empty();
  int64_t face_pos = 0;  // where the next polyhedron's stream starts in faces
  for (size_t c = 0; c < cells.types.size(); ++c) {
    const int type = cells.types[c];
    if (isLowerDimensional(type)) {
      ++census->skipped[type];
      continue;
    }
    if (type == kVtkPolyhedron) {
      const std::string at = path + ": cell " + std::to_string(c) + " (VTK_POLYHEDRON)";
      const int64_t* f = nullptr;
      int64_t len = 0;
      GTN_RETURN_IF_ERROR(locateFaceStream(at, cells, c, &face_pos, &f, &len));
      GTN_RETURN_IF_ERROR(checkFaceStream(at, f, len, num_points, &census->out_tets));
      census->streams.push_back(f);
      continue;
    }
    // VTK writes -1 for the cells that are not polyhedra; an offset is an error only if it moves.
    if (separate_faces && cells.face_offsets[c] >= 0 && cells.face_offsets[c] != face_pos)
      return invalidData(path + ": cell " + std::to_string(c) + " (" + vtkCellTypeName(type) +
                         ") is not a polyhedron but has face offset " + std::to_string(cells.face_offsets[c]));
    if (expectedPoints(type) < 0 && arbitraryOrderCorners(type) == 0) {
      ++census->rejected[type];
      continue;
    }
    GTN_RETURN_IF_ERROR(checkCellPoints(path, cells, c, num_points));
    if (type == kVtkQuadraticTetra) ++census->quadratic;
    else if (linearType(type) != type) ++census->higher_order;
    const int linear = linearType(type);
    census->out_tets += tetsPerCell(linear);
    census->hexes += linear == kVtkVoxel || linear == kVtkHexahedron;
  }
  return Status::ok();
}

// Fails on unsupported volume cells, or when no cell is a volume cell; warns of the cells skipped.
Status checkCellTypes(const std::string& path, const CellCensus& census, size_t num_cells, ImportReport* report) {
  if (!census.rejected.empty()) {
    return unsupported(
        path + ": unsupported cell types: " + typeCounts(census.rejected) +
        "; only tetrahedra (10, 24, 64, 71, 78), hexahedra (11, 12, 25, 29, 33, 67, 72, 79), wedges "
        "(13, 26, 31, 32, 65, 73, 80), pyramids (14, 27, 37, 74, 81), pentagonal and hexagonal prisms (15, 16) "
        "and polyhedra (42) become tetrahedra");
  }
  if (!census.skipped.empty()) {
    size_t total = 0;
    for (const auto& entry : census.skipped) total += entry.second;
    if (total == num_cells)
      return unsupported(path + ": no volume cells, only " + typeCounts(census.skipped) +
                         ": a surface, line or point set is not a volume mesh");
    report->warnings.push_back("skipped " + std::to_string(total) + " cells of lower dimension (" +
                               typeCounts(census.skipped) + "): only volume cells become tetrahedra");
  }
  return Status::ok();
}

// The second pass for cell c (checked, not a polyhedron, not lower-dimensional): its tetrahedra.
void splitCell(const VtkCells& cells, size_t c, int split, Splitter& splitter, std::vector<Tet>* tets,
               std::vector<uint32_t>* tet_cell) {
  uint32_t g[27];
  const int64_t begin = cells.offsets[c];
  // Corners come first: an arbitrary-order cell's further points (beyond 27) are not needed.
  const int n = static_cast<int>(std::min<int64_t>(cells.offsets[c + 1] - begin, 27));
  for (int k = 0; k < n; ++k) g[k] = static_cast<uint32_t>(cells.connectivity[begin + k]);
  // VTK's Lagrange and Bezier wedges turn their first triangle towards the second one, its linear
  // and quadratic wedges away from it: their corners in the linear wedge's order, so that a cell VTK
  // stores positively is split into positive tetrahedra.
  if ((cells.types[c] == kVtkLagrangeWedge || cells.types[c] == kVtkBezierWedge) && n >= 6) {
    std::swap(g[1], g[2]);
    std::swap(g[4], g[5]);
  }
  const uint32_t cell = static_cast<uint32_t>(c);
  switch (linearType(cells.types[c])) {
    case kVtkTetra:
      // An input tetrahedron is kept as it is: finishImport reports a flat one and drops one that
      // repeats an index, as the split drops the pieces of other cells that a repeated index flattens.
      tets->push_back({g[0], g[1], g[2], g[3]});
      tet_cell->push_back(cell);
      break;
    case kVtkVoxel: {
      // A voxel numbers its corners x fastest, then y, then z; a hexahedron goes round each face.
      const uint32_t h[8] = {g[0], g[1], g[3], g[2], g[4], g[5], g[7], g[6]};
      splitter.hex(h, split, cell);
      break;
    }
    case kVtkHexahedron: splitter.hex(g, split, cell); break;
    case kVtkWedge: splitter.cone(kWedgeFaces, g, 6, cell); break;
    case kVtkPyramid: splitter.cone(kPyramidFaces, g, 5, cell); break;
    case kVtkPentagonalPrism: splitter.cone(kPentagonalPrismFaces, g, 10, cell); break;
    case kVtkHexagonalPrism: splitter.cone(kHexagonalPrismFaces, g, 12, cell); break;
  }
}

// The warnings of the split: cells reduced to their corners, hexahedra split into 6 rather than 5,
// cells coned from another vertex or around an added point, pieces dropped as flat.
void reportSplit(const CellCensus& census, const Splitter& splitter, int split, bool faces_shared,
                 ImportReport* report) {
  if (census.quadratic)
    report->warnings.push_back(std::to_string(census.quadratic) +
                               " quadratic tetrahedra (VTK_QUADRATIC_TETRA) reduced to their 4 corners; their "
                               "mid-edge points are kept as unreferenced points");
  if (census.higher_order)
    report->warnings.push_back(std::to_string(census.higher_order) +
                               " higher-order cells (quadratic hexahedra, wedges or pyramids; Lagrange or Bezier "
                               "cells) reduced to their corners and split as linear cells; their other points are "
                               "kept as unreferenced points");
  const size_t hexes = census.hexes;
  if (hexes && split == 5 && splitter.hex_five_ + splitter.five_inverted_ < hexes)
    report->warnings.push_back(std::to_string(hexes - splitter.hex_five_ - splitter.five_inverted_) + " of " +
                               std::to_string(hexes) +
                               " hexahedra split into 6 tetrahedra: their face diagonals do not allow 5");
  if (splitter.five_inverted_)
    report->warnings.push_back(std::to_string(splitter.five_inverted_) + " of " + std::to_string(hexes) +
                               " hexahedra split into 6 tetrahedra: not convex, 5 would invert some");
  if (splitter.rewound_ && !faces_shared)
    report->warnings.push_back(std::to_string(splitter.rewound_) +
                               " polyhedra (VTK_POLYHEDRON) whose faces do not all wind the same way split with "
                               "those faces turned to wind outward, as the others do");
  if (splitter.resplit_)
    report->warnings.push_back(std::to_string(splitter.resplit_) +
                               " cells that are not convex split from another vertex than their smallest, so that "
                               "none of their tetrahedra comes out inverted");
  splitter.reportAdded(report);
  if (splitter.collapsed_) {
    report->collapsed_tets += splitter.collapsed_;
    report->warnings.push_back(std::to_string(splitter.collapsed_) +
                               " tetrahedra of degenerate cells (repeated point indices) dropped");
  }
}

}  // namespace

Status splitVtkCells(const std::string& path, const VtkCells& cells, size_t num_points, const double* coords, int split,
                     std::vector<Tet>* tets, std::vector<uint32_t>* tet_cell, ImportReport* report,
                     SteinerPoints* steiner, bool float32) {
  GTN_RETURN_IF_ERROR(checkCellArrays(path, cells, num_points));
  CellCensus census;
  GTN_RETURN_IF_ERROR(surveyCells(path, cells, num_points, &census));
  GTN_RETURN_IF_ERROR(checkCellTypes(path, census, cells.types.size(), report));
  // Room for every tetrahedron, its pages mapped in one call.
  reservePopulated(*tets, tets->size() + census.out_tets);
  reservePopulated(*tet_cell, tet_cell->size() + census.out_tets);
  Splitter splitter(tets, tet_cell, coords, num_points, coords ? steiner : nullptr, float32);
  size_t next_stream = 0;
  for (size_t c = 0; c < cells.types.size(); ++c) {
    const int type = cells.types[c];
    if (isLowerDimensional(type)) continue;
    if (type == kVtkPolyhedron) splitter.polyhedron(census.streams[next_stream++], static_cast<uint32_t>(c));
    else splitCell(cells, c, split, splitter, tets, tet_cell);
  }
  reportSplit(census, splitter, split, cells.faces_shared, report);
  return Status::ok();
}

namespace {

// Appends the Steiner points to `mesh`, each point field's value the mean of its corners' (in double,
// rounded to the field's type) for floating-point fields, and its smallest corner's for integer
// fields (labels and ids, which a mean would not keep).
void appendSteinerPoints(const SteinerPoints& steiner, TetMesh* mesh) {
  const size_t first = mesh->numPoints(), count = steiner.coords.size() / 3;
  if (count == 0) return;
  mesh->coords.insert(mesh->coords.end(), steiner.coords.begin(), steiner.coords.end());
  for (Field& f : mesh->point_fields) {
    f.bytes.resize((first + count) * f.components * f.valueSize());
    for (size_t k = 0; k < count; ++k) {
      const uint32_t* corner = steiner.corners.data() + steiner.corner_offsets[k];
      const size_t n = steiner.corner_offsets[k + 1] - steiner.corner_offsets[k];
      if (!isFloatType(f.type)) {
        f.copyItem(f, corner[0], first + k);
        continue;
      }
      for (uint32_t c = 0; c < f.components; ++c) {
        double sum = 0;
        for (size_t i = 0; i < n; ++i) sum += f.get(corner[i], c);
        const double mean = sum / static_cast<double>(n);
        if (f.type == ScalarType::kFloat32) f.set(first + k, c, static_cast<float>(mean));
        else f.set(first + k, c, mean);
      }
    }
  }
}

}  // namespace

struct GridHexSplitter::Impl {
  Impl(TetMesh* m, std::vector<uint32_t>* tet_cell)
      : mesh(m),
        splitter(&m->tets, tet_cell, m->coords.data(), m->numPoints(), &steiner,
                 m->coord_type == ScalarType::kFloat32) {}
  TetMesh* mesh;
  SteinerPoints steiner;
  Splitter splitter;
};

GridHexSplitter::GridHexSplitter(TetMesh* mesh, std::vector<uint32_t>* tet_cell)
    : impl_(std::make_unique<Impl>(mesh, tet_cell)) {}
GridHexSplitter::~GridHexSplitter() = default;

void GridHexSplitter::split(const uint32_t h[8], int split, bool odd, uint32_t cell) {
  impl_->splitter.gridHex(h, split, odd, cell);
}

void GridHexSplitter::finish(ImportReport* report) {
  appendSteinerPoints(impl_->steiner, impl_->mesh);
  impl_->splitter.reportAdded(report);
}

void rectilinearPoints(const std::vector<double> axes[3], std::vector<double>* coords) {
  coords->resize(3 * axes[0].size() * axes[1].size() * axes[2].size());
  size_t v = 0;
  for (double z : axes[2])
    for (double y : axes[1])
      for (double x : axes[0]) {
        (*coords)[v++] = x;
        (*coords)[v++] = y;
        (*coords)[v++] = z;
      }
}

void imagePoints(const uint64_t dims[3], const int64_t first[3], const double origin[3], const double spacing[3],
                 const double* direction, std::vector<double>* coords) {
  coords->resize(3 * dims[0] * dims[1] * dims[2]);
  size_t v = 0;
  for (uint64_t k = 0; k < dims[2]; ++k)
    for (uint64_t j = 0; j < dims[1]; ++j)
      for (uint64_t i = 0; i < dims[0]; ++i) {
        const double d[3] = {static_cast<double>(first[0] + static_cast<int64_t>(i)) * spacing[0],
                             static_cast<double>(first[1] + static_cast<int64_t>(j)) * spacing[1],
                             static_cast<double>(first[2] + static_cast<int64_t>(k)) * spacing[2]};
        for (int c = 0; c < 3; ++c) {
          double p = d[c];
          if (direction) p = direction[3 * c] * d[0] + direction[3 * c + 1] * d[1] + direction[3 * c + 2] * d[2];
          (*coords)[v++] = origin[c] + p;
        }
      }
}

Status finishStructuredImport(const std::string& path, const uint64_t dims[3], const std::vector<Field>& cell_fields,
                              const ImportOptions& options, ImportResult* result) {
  const uint64_t nx = dims[0], ny = dims[1], nz = dims[2];
  TetMesh& mesh = result->mesh;
  if (mesh.numPoints() != nx * ny * nz)
    return invalidData(path + ": " + std::to_string(mesh.numPoints()) + " points for a grid of " + std::to_string(nx) +
                       " x " + std::to_string(ny) + " x " + std::to_string(nz));
  const uint64_t num_cells = (nx - 1) * (ny - 1) * (nz - 1);
  for (const Field& f : cell_fields)
    if (f.itemCount() != num_cells)
      return invalidData(path + ": cell field '" + f.name + "' has " + std::to_string(f.itemCount()) + " values for " +
                         std::to_string(num_cells) + " cells");
  // VTK's blanking (vtkStructuredGrid::BlankCell, BlankPoint): a cell marked HIDDENCELL in the cell
  // ghost array, or with a corner marked HIDDENPOINT in the point one, is not part of the grid (an
  // overset hole, like a PLOT3D IBLANK of 0). Such cells are dropped, as IBLANK holes are.
  // The block, for the structured encoder (importMesh keeps it when the mesh is it).
  if (nx >= 2 && ny >= 2 && nz >= 2 && nx * ny * nz < kNoIndex) {
    StructuredBlock block;
    for (int a = 0; a < 3; ++a) block.dims[a] = static_cast<uint32_t>(dims[a]);
    mesh.blocks = {block};
  }
  const uint8_t* cell_ghost = vtkGhostMarks(cell_fields, num_cells);
  const uint8_t* point_ghost = vtkGhostMarks(mesh.point_fields, mesh.numPoints());
  std::vector<uint32_t> tet_cell;
  reservePopulated(mesh.tets, num_cells * static_cast<uint64_t>(options.split == 5 ? 5 : 6));
  reservePopulated(tet_cell, mesh.tets.capacity());
  auto id = [&](uint64_t i, uint64_t j, uint64_t k) { return static_cast<uint32_t>(i + nx * (j + ny * k)); };
  uint32_t cell = 0;
  size_t hidden = 0;
  GridHexSplitter grid(&mesh, &tet_cell);
  for (uint64_t k = 0; k + 1 < nz; ++k)
    for (uint64_t j = 0; j + 1 < ny; ++j)
      for (uint64_t i = 0; i + 1 < nx; ++i, ++cell) {
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if ((cell_ghost && (cell_ghost[cell] & kVtkHiddenCell)) ||
            (point_ghost &&
             std::any_of(h, h + 8, [&](uint32_t v) { return (point_ghost[v] & kVtkHiddenPoint) != 0; }))) {
          ++hidden;
          continue;
        }
        grid.split(h, options.split, (i + j + k) % 2 == 1, cell);
      }
  grid.finish(&result->report);
  for (const Field& f : cell_fields) mesh.cell_fields.push_back(expandCellField(f, tet_cell));
  if (hidden > 0) {
    result->report.dropped_cells += hidden;
    result->report.warnings.push_back(std::to_string(hidden) +
                                      " cells blanked by VTK (vtkGhostType HIDDENCELL, or a "
                                      "HIDDENPOINT corner) dropped");
  }
  finishImport(*result);
  return mesh.checkConsistency(path);
}

namespace {

// --weld: `cells` with each point as its welded identity (rep), so that the face rule, which orders a
// face's points by index, cuts a face that two pieces share alike on both sides (each piece numbers
// its copies of the shared points in its own order). A cell that welding would make degenerate keeps
// its own points (weldPoints drops what collapses, as for any input), as does an entry the split
// will reject (an index out of range, a malformed face stream).
VtkCells weldedCells(const VtkCells& cells, const std::vector<uint32_t>& rep) {
  VtkCells out = cells;
  const size_t num_cells = cells.types.size();
  if (cells.offsets.size() != num_cells + 1) return out;
  const bool separate_faces = cells.face_offsets.size() == num_cells;
  auto valid = [&](int64_t v) { return v >= 0 && static_cast<uint64_t>(v) < rep.size(); };
  std::vector<int64_t*> entries;  // the point entries of one cell
  std::vector<int64_t> own, welded;
  int64_t face_pos = 0;
  for (size_t c = 0; c < num_cells; ++c) {
    entries.clear();
    const int64_t begin = cells.offsets[c], end = cells.offsets[c + 1];
    if (begin < 0 || end < begin || end > static_cast<int64_t>(cells.connectivity.size())) return out;
    if (cells.types[c] == kVtkPolyhedron) {
      // Its face stream (the face count, then each face's point count and points): in faces (XML,
      // with the cell's points in connectivity too) or in connectivity (legacy).
      int64_t* f = out.connectivity.data() + begin;
      int64_t len = end - begin;
      if (separate_faces) {
        const int64_t stop = cells.face_offsets[c];
        if (stop < face_pos || stop > static_cast<int64_t>(cells.faces.size())) return out;
        for (int64_t k = begin; k < end; ++k) entries.push_back(&out.connectivity[k]);
        f = out.faces.data() + face_pos;
        len = stop - face_pos;
        face_pos = stop;
      }
      bool ok = len >= 1;
      int64_t at = 1;
      for (int64_t k = 0; ok && k < f[0]; ++k) {
        ok = at < len && f[at] >= 0 && f[at] <= len - at - 1;
        if (!ok) break;
        for (int64_t i = 0; i < f[at]; ++i) entries.push_back(f + at + 1 + i);
        at += 1 + f[at];
      }
      if (!ok) continue;
    } else {
      for (int64_t k = begin; k < end; ++k) entries.push_back(&out.connectivity[k]);
    }
    if (!std::all_of(entries.begin(), entries.end(), [&](const int64_t* e) { return valid(*e); })) continue;
    own.clear();
    welded.clear();
    for (const int64_t* e : entries) {
      own.push_back(*e);
      welded.push_back(rep[*e]);
    }
    for (std::vector<int64_t>* v : {&own, &welded}) {
      std::sort(v->begin(), v->end());
      v->erase(std::unique(v->begin(), v->end()), v->end());
    }
    if (own.size() != welded.size()) continue;
    for (int64_t* e : entries) *e = rep[*e];
  }
  return out;
}

}  // namespace

Status finishVtkImport(const std::string& path, const VtkCells& cells, const std::vector<Field>& cell_fields,
                       const ImportOptions& options, ImportResult* result, size_t* duplicate_tets) {
  std::vector<uint32_t> tet_cell;
  SteinerPoints steiner;
  VtkCells welded;
  if (options.weld) {
    const std::vector<uint32_t> rep = weldIdentities(result->mesh);
    for (size_t p = 0; p < rep.size(); ++p) {
      if (rep[p] == p) continue;
      welded = weldedCells(cells, rep);
      break;
    }
  }
  const VtkCells& split_cells = welded.types.empty() ? cells : welded;
  GTN_RETURN_IF_ERROR(splitVtkCells(path, split_cells, result->mesh.numPoints(), result->mesh.coords.data(),
                                    options.split, &result->mesh.tets, &tet_cell, &result->report, &steiner,
                                    result->mesh.coord_type == ScalarType::kFloat32));
  appendSteinerPoints(steiner, &result->mesh);
  // Cells blanked by VTK (HIDDENCELL) are not part of the mesh, as in structured grids; in a piece of
  // a parallel file, neither are the copies of other pieces' cells (DUPLICATECELL).
  if (const uint8_t* marks = vtkGhostMarks(cell_fields, cells.types.size())) {
    std::vector<Tet>& tets = result->mesh.tets;
    size_t kept = 0, duplicates = 0;
    for (size_t t = 0; t < tets.size(); ++t) {
      const uint8_t m = marks[tet_cell[t]];
      if (m & kVtkHiddenCell) continue;
      if (duplicate_tets && (m & kVtkDuplicateCell)) {
        ++duplicates;
        continue;
      }
      tets[kept] = tets[t];
      tet_cell[kept++] = tet_cell[t];
    }
    tets.resize(kept);
    tet_cell.resize(kept);
    if (duplicate_tets) *duplicate_tets += duplicates;
    size_t hidden = 0;
    for (size_t c = 0; c < cells.types.size(); ++c) hidden += (marks[c] & kVtkHiddenCell) != 0;
    if (hidden > 0) {
      result->report.dropped_cells += hidden;
      result->report.warnings.push_back(std::to_string(hidden) +
                                        " cells blanked by VTK (vtkGhostType HIDDENCELL) dropped");
    }
  }
  for (const Field& f : cell_fields) {
    if (f.itemCount() != cells.types.size())
      return invalidData(path + ": cell field '" + f.name + "' has " + std::to_string(f.itemCount()) + " values for " +
                         std::to_string(cells.types.size()) + " cells");
    result->mesh.cell_fields.push_back(expandCellField(f, tet_cell));
  }
  finishImport(*result);
  return result->mesh.checkConsistency(path);
}

}  // namespace gtn
