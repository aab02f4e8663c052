// The ray-casting core shared by the streaming (integrated) and the generic (in-memory) renderers, so
// that both compute bit-identical crossings and samples and differ only in the order of compositing.
//
// * Ray / face crossings use the watertight ray-triangle test of Woop, Benthin and Wald (JCGT 2013) in
//   double precision, with each triangle's vertices put in a canonical order (lexicographic by
//   position) first. The crossing of a face therefore has the same parameter t and the same
//   interpolated scalar whichever tetrahedron (or boundary triangle) it is computed from, so a ray
//   leaves one tetrahedron exactly where it enters the next, and a ray never slips between faces.
// * A ray is cut into segments where it lies inside the volume, from its crossings with the boundary
//   triangles (see castBoundary()).
// * Inside a tetrahedron the scalar is linear, so along the ray it is linear between the entry and exit
//   crossings. Volume sampling takes samples at t = k * step (a grid fixed per ray, independent of the
//   mesh), each belonging to the half-open interval [t_in, t_out) of exactly one tetrahedron; face
//   sampling integrates each tetrahedron's interval with the transfer function averaged over its two
//   face crossings (Bunyk et al.). Zero-volume tetrahedra have empty intervals and contribute nothing.
// * Compositing is front to back from a segment's near end and back to front from its far end; the two
//   partial results combine exactly (over operator), which is what lets the streaming renderer take a
//   tetrahedron's contribution as soon as it arrives.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "mesh/index.h"
#include "mesh/mesh_stream.h"
#include "render/camera.h"
#include "render/image.h"
#include "render/transfer_function.h"

namespace gtn {

enum class Sampling { kVolume, kFace };

// Which scalar to render: a component of a point field, or the magnitude of a vector field.
struct FieldSelector {
  std::string name;  // empty: the first point field
  bool magnitude = false;
  uint32_t component = 0;
  // The selection as given when it holds a colon: a field named so ("a:b", "v:2") is taken whole
  // first. `bad_suffix`: no NAME:COMPONENT or NAME:mag reading either (an error unless such a field
  // exists; `name` then holds the whole text).
  std::string whole;
  bool bad_suffix = false;
};
// "NAME", "NAME:2" (component), "NAME:mag" (magnitude); "" selects the first point field. A field
// whose name holds a colon is selected by that name (ScalarReader::create looks for it first).
StatusOr<FieldSelector> parseFieldSelector(const std::string& text);

// Reads the selected scalar from a vertex event's concatenated field values.
class ScalarReader {
 public:
  ScalarReader() = default;
  // Fails with kUsage naming the available fields when the selection does not exist.
  static StatusOr<ScalarReader> create(const std::vector<FieldDesc>& fields, const FieldSelector& selector);
  double read(const uint8_t* values) const;
  const std::string& description() const { return description_; }
  // The fields a decode must deliver for this reader: the selected point field alone (none for a mesh
  // without point fields), no cell field.
  DecodeFields decodeFields(size_t point_fields, size_t cell_fields) const;

 private:
  size_t field_ = SIZE_MAX;  // the selected field's index; SIZE_MAX without point fields
  size_t offset_ = 0;
  ScalarType type_ = ScalarType::kFloat32;
  uint32_t components_ = 1, component_ = 0;
  bool magnitude_ = false;
  std::string description_;
};

// Everything a renderer needs besides the mesh. Zero `step` / `opacity_unit_distance` mean automatic:
// the bounding box diagonal / 400 and / 40.
struct RenderOptions {
  CameraOptions camera;
  Sampling sampling = Sampling::kVolume;
  double step = 0;
  double opacity_unit_distance = 0;
  FieldSelector field;
  TransferFunction transfer;  // points required; its range used when has_range, else automatic
  // The box the camera frames, when set; else the level header's. RenderInput::fixView() sets level
  // 0's, so that every level and ratio of a file is seen from the same camera.
  bool has_scene_box = false;
  double scene_min[3] = {0, 0, 0}, scene_max[3] = {0, 0, 0};
  // Whether render_input.h and time_budget.h may read and write their cache (time_budget.h: budget
  // calibrations and level 0's colour range); false (--no-cache): neither read nor written.
  bool use_cache = true;
};

// The options resolved against a level: camera framed on the bounding box, range fixed.
struct RenderSetup {
  Camera camera;
  Sampling sampling = Sampling::kVolume;
  double step = 0;
  double inv_unit_distance = 1;
  TransferFunction transfer;
  std::string field;  // the rendered scalar, as ScalarReader::description() names it

  // Volume sampling's per-sample colour and opacity tabulated over the range (buildSampleTable(),
  // once the range is final): the transfer function and exp() cost far more than a table lookup,
  // and the step is fixed. Linear interpolation between kSampleTableSize entries differs from the
  // exact evaluation by far less than one grey level.
  static constexpr int kSampleTableSize = 4096;
  std::vector<std::array<double, 4>> sample_table;  // rgb, alpha per step
  double table_scale = 0;                           // (kSampleTableSize - 1) / (pre hi - pre lo), pre = table_pre
  double table_pre = 1;  // 1, or 0.5 when hi - lo overflows: entry (pre s - pre lo) * table_scale
};
RenderSetup resolveSetup(const RenderOptions& options, const double bbox_min[3], const double bbox_max[3]);
// Fills setup.sample_table for the transfer function's final range (volume sampling only).
void buildSampleTable(RenderSetup& setup);

// The direction-dependent part of the watertight test's shear: the axis permutation and shear
// factors. Orthographic rays all share one, so a vertex's sheared position (shearPoint) can be
// computed once and reused for every ray.
struct ShearFrame {
  int kx = 0, ky = 1, kz = 2;
  double sx = 0, sy = 0, sz = 1;
  bool operator==(const ShearFrame& o) const {
    return kx == o.kx && ky == o.ky && kz == o.kz && sx == o.sx && sy == o.sy && sz == o.sz;
  }
};
// (p[kx] - sx p[kz], p[ky] - sy p[kz], sz p[kz]): a point in the sheared frame, before the ray's
// origin is subtracted. A point's position relative to a ray is shearPoint(p) - ray.origin, the same
// computation whoever asks, which is what keeps crossings consistent between tetrahedra.
void shearPoint(const ShearFrame& f, const double p[3], double out[3]);

// A ray prepared for the watertight test: its frame and its origin, sheared.
struct PreparedRay {
  Ray ray;
  ShearFrame frame;
  double origin[3] = {0, 0, 0};
};
PreparedRay prepareRay(const Ray& ray);

struct Crossing {
  bool hit = false;
  double t = 0;  // ray parameter (distance) of the crossing with the face's plane
  double s = 0;  // scalar interpolated at the crossing
};
// The crossing of the ray with triangle (a, b, c) carrying scalars (sa, sb, sc); `hit` includes the
// triangle's edges and vertices. The result does not depend on the order of the three vertices.
Crossing crossTriangle(const PreparedRay& r, const double* a, const double* b, const double* c, double sa, double sb,
                       double sc);

// One tetrahedron's geometry and scalars, copied out of whatever holds the mesh. finishTetGeom()
// must be called once the corners are set (it fixes each face's canonical vertex order, so that it
// is not recomputed per ray); shearTetGeom() then optionally replaces the corners by their sheared
// positions in the one frame all rays share (orthographic cameras), and then `frame` must be the
// rays' frame.
struct TetGeom {
  double p[4][3];  // corners; after shearTetGeom, their shearPoint positions
  double s[4];
  uint8_t order[4][3];  // face k: local corners of kTetFace[k] in canonical (lexicographic) order
  bool sheared = false;
};
void finishTetGeom(TetGeom& g);
void shearTetGeom(TetGeom& g, const ShearFrame& frame);
// TetGeom::order for corners at these positions (what finishTetGeom computes).
void faceOrders(const double* const corner[4], uint8_t order[4][3]);

// A tetrahedron whose corners are records shared with its neighbours (the streaming renderer's
// vertices: held tetrahedra need no copies of their corners). `order` as TetGeom's; when `sheared`,
// the corners' q (shearPoint positions, as shearTetGeom computes them) are used, else their p.
// Every function below that takes a TetGeom or a TetCorners computes the same bits for either.
struct CornerRecord {
  double p[3];
  double q[3];
  double s;
};
struct TetCorners {
  const CornerRecord* const* corner;  // four
  const uint8_t (*order)[3];
  bool sheared;
};

// The crossings of the ray with the four faces of `g` (face `skip` left out: not hit), each exactly as
// crossTriangle computes it, sharing the vertices' transformation. When `g.sheared`, the ray's frame
// must be the one shearTetGeom used.
void crossTetFaces(const PreparedRay& r, const TetGeom& g, int skip, Crossing out[4]);
void crossTetFaces(const PreparedRay& r, const TetCorners& g, int skip, Crossing out[4]);

// Where a ray inside tetrahedron `g`, having come in through local face `entry` (kTetFace numbering),
// leaves it: forward (increasing t) or backward. Returns the local face, or -1 when no other face is
// crossed (the ray only grazed the tetrahedron, numerically). `out->t` is not clamped.
int exitFace(const PreparedRay& r, const TetGeom& g, int entry, bool forward, Crossing* out);
int exitFace(const PreparedRay& r, const TetCorners& g, int entry, bool forward, Crossing* out);

// Premultiplied colour and opacity of a part of a ray.
struct Rgba {
  double r = 0, g = 0, b = 0, a = 0;
};
// `front` composited over `back`.
Rgba over(const Rgba& front, const Rgba& back);

// Adds the part [lo, hi) of a tetrahedron's interval [t_in, t_out] (scalars s_in, s_out at its ends)
// to `acc`: behind what `acc` holds when `front_to_back`, in front of it otherwise.
void shadeInterval(const RenderSetup& setup, double t_in, double s_in, double t_out, double s_out, double lo, double hi,
                   bool front_to_back, Rgba* acc);

// Volume sampling's samples are t = k * step; [lo, hi) holds samples [first(lo), first(hi)), where
// first(t) is the least k with k * step >= t, exactly (k * step is monotonic in k).
int64_t firstSampleAtOrAfter(double t, double step);
// first(t) found by stepping from any k: cheap from first(t') for a nearby t' (where a cursor was).
inline int64_t firstSampleFrom(int64_t k, double t, double step) {
  while (static_cast<double>(k) * step < t) ++k;
  while (static_cast<double>(k - 1) * step >= t) --k;
  return k;
}
// Volume sampling's shadeInterval with the samples [k0, k1) of [lo, hi) already found.
void shadeSamples(const RenderSetup& setup, double t_in, double s_in, double t_out, double s_out, int64_t k0,
                  int64_t k1, bool front_to_back, Rgba* acc);

// The boundary surface as the renderers see it: positions and scalars of its vertices and the
// outward-oriented triangles over them.
struct BoundarySurface {
  std::vector<std::array<double, 3>> points;
  std::vector<double> scalars;
  std::vector<std::array<uint32_t, 3>> triangles;  // indices into points
};

inline constexpr uint32_t kNoTriangle = kNoIndex;

// A part of a pixel's ray inside the volume: from the near crossing (entering through triangle
// `entry_tri`) to the far crossing (leaving through `exit_tri`, kNoTriangle when the ray's crossings
// do not pair up: then the segment runs until the traversal reaches the boundary).
struct RaySegment {
  uint32_t pixel = 0;
  uint32_t entry_tri = kNoTriangle, exit_tri = kNoTriangle;
  double t_near = 0, s_near = 0;
  double t_far = std::numeric_limits<double>::infinity(), s_far = 0;
};

// Segments of every pixel's ray, grouped by pixel in image order and sorted by depth within a pixel;
// `pixel_start` has width*height+1 offsets into `segments`. Crossings are paired by inside/outside
// depth counting over groups of crossings at equal depth (within a tolerance relative to the scene's
// size), so that duplicated crossings on shared edges, silhouette grazes and coincident boundary
// sheets of unwelded seams neither split nor drop parts of the volume. Parallel (TBB) over triangles,
// then over pixels. `unpaired`: the pixels, in order, where a group of crossings leaves the volume
// while the ray is outside it (a boundary triangle facing inward): that crossing is ignored, and
// the part of the ray it bounds is lost. None for a consistently oriented boundary.
struct RaySegments {
  std::vector<RaySegment> segments;
  std::vector<uint32_t> pixel_start;
  std::vector<uint32_t> unpaired;
};
RaySegments castBoundary(const Camera& camera, const BoundarySurface& surface);

// Receives castBoundary's segments one at a time, in order, so that they need not be stored together.
class SegmentSink {
 public:
  virtual ~SegmentSink() = default;
  // Called once, before the segments: how many there will be.
  virtual void begin(size_t segments) = 0;
  virtual void segment(const RaySegment& segment) = 0;
};
// The same segments as above, handed to `sink` (the i-th call is segment i) after *pixel_start (and
// *unpaired, when given) is filled.
void castBoundary(const Camera& camera, const BoundarySurface& surface, std::vector<uint32_t>* pixel_start,
                  SegmentSink& sink, std::vector<uint32_t>* unpaired = nullptr);

// floor and ceil of v as an int, for |v| < 2^31 (callers clamp first): truncation then one step,
// which costs a few instructions where std::floor and std::ceil are library calls on baseline x86-64.
inline int floorToInt(double v) {
  const int t = static_cast<int>(v);
  return t > v ? t - 1 : t;
}
inline int ceilToInt(double v) {
  const int t = static_cast<int>(v);
  return t < v ? t + 1 : t;
}

// The projection of a convex polygon or polyhedron (a triangle, a tetrahedron) row by row, from its
// n <= 4 corners' screen positions: the segments between every pair of corners, slopes taken once.
// `span` gives a row's extent [xl, xr] at height yc, and says whether yc lies inside the projection's
// height by more than `margin` (else the row is better left whole). Rounding differences between
// this and the crossing test are about 1e-10 pixels: callers skip pixels clearly outside by a margin.
class ScreenHull {
 public:
  // The margin, in pixels, by which a pixel centre counts as clearly inside or outside.
  static constexpr double kSure = 1e-3;

  ScreenHull(const double* xs, const double* ys, int n) {
    ymin_ = 1e300, ymax_ = -1e300;
    for (int i = 0; i < n; ++i) {
      ymin_ = std::min(ymin_, ys[i]), ymax_ = std::max(ymax_, ys[i]);
      for (int j = i + 1; j < n; ++j) {
        const double lo = std::min(ys[i], ys[j]), hi = std::max(ys[i], ys[j]);
        edges_[n_++] = {xs[i], ys[i], xs[j], lo, hi, hi > lo ? (xs[j] - xs[i]) / (ys[j] - ys[i]) : 0.0};
      }
    }
  }
  bool span(double yc, double margin, double* xl, double* xr) const {
    *xl = 1e300, *xr = -1e300;
    for (int k = 0; k < n_; ++k) {
      const Edge& e = edges_[k];
      if (yc < e.lo || yc > e.hi) continue;
      const double x = e.hi > e.lo ? e.x0 + (yc - e.y0) * e.slope : e.x0;
      *xl = std::min({*xl, x, e.hi > e.lo ? x : e.x1});
      *xr = std::max({*xr, x, e.hi > e.lo ? x : e.x1});
    }
    return yc > ymin_ + margin && yc < ymax_ - margin && *xr >= *xl;
  }
  // The pixels [*px0, *px1] of box's columns whose centres may lie within `margin` of [xl, xr].
  static void columns(double xl, double xr, double margin, const int box[4], int* px0, int* px1) {
    const double lo = box[0] - 1, hi = box[2] + 1;  // clamped first: the ends may lie far off
    *px0 = std::max(box[0], floorToInt(std::clamp(xl - margin - 0.5, lo, hi)));
    *px1 = std::min(box[2], ceilToInt(std::clamp(xr + margin - 0.5, lo, hi)));
  }

 private:
  struct Edge {
    double x0, y0, x1, lo, hi, slope;
  };
  Edge edges_[6];
  int n_ = 0;
  double ymin_, ymax_;
};

// The pixels whose centres may lie in the projection of the n points: box = {x0, y0, x1, y1}
// (inclusive), from their screen bounding box with a small margin for rounding; the whole image when
// a point is behind a perspective eye. False when no pixel qualifies. When `xs` and `ys` are given,
// they receive the points' screen positions (Camera::project's; meaningless for a point behind the eye).
bool pixelFootprint(const Camera& camera, const double* const* points, int n, int box[4], double* xs = nullptr,
                    double* ys = nullptr);

// The scalar range over the boundary vertices (what the automatic transfer-function range uses when
// the stream carries no field ranges: the boundary arrives first). A unit range centred on the value
// when constant, {0, 1} when empty.
std::pair<double, double> boundaryRange(const BoundarySurface& surface);

// The box the camera frames: the options' scene box when set, else the level header's bounding box,
// or the boundary vertices' box when the header's is empty or not finite.
void sceneBox(const RenderOptions& options, const LevelHeader& header, const BoundarySurface& surface,
              double bbox_min[3], double bbox_max[3]);

// Converts per-pixel colours (premultiplied, over black) to 8-bit RGB.
void toRgb8(const Rgba& c, uint8_t out[3]);
Image toImage(int width, int height, const std::vector<Rgba>& pixels);

}  // namespace gtn
