#include "render/ray_cast.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "mesh/faces.h"

namespace gtn {

// ---------------------------------------------------------------------------------------------
// Field selection

StatusOr<FieldSelector> parseFieldSelector(const std::string& text) {
  FieldSelector sel;
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos) {
    sel.name = text;
    return sel;
  }
  sel.name = text.substr(0, colon);
  sel.whole = text;
  const std::string suffix = text.substr(colon + 1);
  if (sel.name.empty()) return usageError("field selection '" + text + "' has no field name");
  if (suffix == "mag") {
    sel.magnitude = true;
    return sel;
  }
  if (suffix.empty() || suffix.size() > 9 || suffix.find_first_not_of("0123456789") != std::string::npos) {
    sel.name = text;  // only a field of that very name can match
    sel.bad_suffix = true;
    return sel;
  }
  sel.component = static_cast<uint32_t>(std::stoul(suffix));
  return sel;
}

namespace {
double loadScalar(const uint8_t* p, ScalarType type) {
  auto load = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (type) {
    case ScalarType::kInt8: return load(int8_t{});
    case ScalarType::kUInt8: return load(uint8_t{});
    case ScalarType::kInt16: return load(int16_t{});
    case ScalarType::kUInt16: return load(uint16_t{});
    case ScalarType::kInt32: return load(int32_t{});
    case ScalarType::kUInt32: return load(uint32_t{});
    case ScalarType::kInt64: return load(int64_t{});
    case ScalarType::kUInt64: return load(uint64_t{});
    case ScalarType::kFloat32: return load(float{});
    case ScalarType::kFloat64: return load(double{});
  }
  return 0.0;
}
}  // namespace

StatusOr<ScalarReader> ScalarReader::create(const std::vector<FieldDesc>& fields, const FieldSelector& selector) {
  ScalarReader r;
  if (fields.empty()) {
    // A mesh without point fields renders its geometry: a constant scalar. A field asked for by
    // name is not there (it was ignored).
    if (!selector.name.empty())
      return usageError("no point field named '" + selector.name + "' (the mesh has no point fields)");
    r.components_ = 0;
    r.description_ = "(no point field: constant 0)";
    return r;
  }
  size_t offset = 0;
  const FieldDesc* found = nullptr;
  FieldSelector sel = selector;
  // A field named with the colon itself comes first ("a:b" is no component of "a").
  if (!sel.whole.empty()) {
    for (const FieldDesc& f : fields)
      if (f.name == sel.whole) {
        sel.name = sel.whole;
        sel.magnitude = sel.bad_suffix = false;
        sel.component = 0;
      }
  }
  if (sel.bad_suffix)
    return usageError("field selection '" + sel.whole +
                      "': expected NAME, NAME:COMPONENT or NAME:mag, or the name of a field");
  for (const FieldDesc& f : fields) {
    if (sel.name.empty() || f.name == sel.name) {
      found = &f;
      break;
    }
    offset += f.itemBytes();
  }
  if (!found) {
    std::string known;
    for (const FieldDesc& f : fields) known += (known.empty() ? "" : ", ") + f.name;
    return usageError("no point field named '" + sel.name + "' (fields: " + known + ")");
  }
  if (!sel.magnitude && sel.component >= found->components)
    return usageError("field '" + found->name + "' has " + std::to_string(found->components) +
                      " components; component " + std::to_string(sel.component) + " does not exist");
  r.offset_ = offset;
  r.field_ = static_cast<size_t>(found - fields.data());
  r.type_ = found->type;
  r.components_ = found->components;
  r.magnitude_ = sel.magnitude;
  r.component_ = sel.component;
  r.description_ = found->name;
  if (sel.magnitude) {
    r.description_ += ":mag";
  } else if (found->components > 1) {
    r.description_ += ':';
    r.description_ += std::to_string(sel.component);
  }
  return r;
}

DecodeFields ScalarReader::decodeFields(size_t point_fields, size_t cell_fields) const {
  DecodeFields d;
  d.point.assign(point_fields, false);
  d.cell.assign(cell_fields, false);
  if (field_ < point_fields) d.point[field_] = true;
  return d;
}

double ScalarReader::read(const uint8_t* values) const {
  if (components_ == 0 || values == nullptr) return 0.0;
  const size_t size = scalarSize(type_);
  const uint8_t* p = values + offset_;
  if (!magnitude_) return loadScalar(p + component_ * size, type_);
  double sum = 0;
  for (uint32_t c = 0; c < components_; ++c) {
    const double v = loadScalar(p + c * size, type_);
    sum += v * v;
  }
  return std::sqrt(sum);
}

// ---------------------------------------------------------------------------------------------
// Setup

RenderSetup resolveSetup(const RenderOptions& options, const double bbox_min[3], const double bbox_max[3]) {
  RenderSetup s;
  s.camera = Camera(bbox_min, bbox_max, options.camera);
  const double diagonal = 2.0 * s.camera.radius();
  s.sampling = options.sampling;
  s.step = options.step > 0 ? options.step : diagonal / 400.0;
  const double unit = options.opacity_unit_distance > 0 ? options.opacity_unit_distance : diagonal / 40.0;
  s.inv_unit_distance = 1.0 / unit;
  s.transfer = options.transfer;
  return s;
}

void buildSampleTable(RenderSetup& s) {
  s.sample_table.clear();
  if (s.sampling != Sampling::kVolume) return;
  const int n = RenderSetup::kSampleTableSize;
  s.sample_table.resize(n);
  const double lo = s.transfer.lo, hi = s.transfer.hi;
  // hi - lo may exceed the largest double (sentinels of +-DBL_MAX): the table is then indexed by the
  // scalars' halves (table_pre), which is exact.
  const bool halves = !std::isfinite(hi - lo);
  for (int i = 0; i < n; ++i) {
    double scalar = lo;
    if (hi > lo) scalar = halves ? s.transfer.valueAt(static_cast<double>(i) / (n - 1)) : lo + (hi - lo) * i / (n - 1);
    double rgb[3], e;
    s.transfer.evaluate(scalar, rgb, &e);
    s.sample_table[i] = {rgb[0], rgb[1], rgb[2], -std::expm1(-e * s.inv_unit_distance * s.step)};
  }
  s.table_pre = halves ? 0.5 : 1.0;
  s.table_scale = hi > lo ? (n - 1) / (s.table_pre * hi - s.table_pre * lo) : 0.0;
}

// ---------------------------------------------------------------------------------------------
// Watertight crossings

PreparedRay prepareRay(const Ray& ray) {
  PreparedRay r;
  r.ray = ray;
  ShearFrame& f = r.frame;
  const double ad[3] = {std::fabs(ray.d[0]), std::fabs(ray.d[1]), std::fabs(ray.d[2])};
  f.kz = ad[0] > ad[1] ? (ad[0] > ad[2] ? 0 : 2) : (ad[1] > ad[2] ? 1 : 2);
  f.kx = (f.kz + 1) % 3;
  f.ky = (f.kx + 1) % 3;
  if (ray.d[f.kz] < 0) std::swap(f.kx, f.ky);
  f.sx = ray.d[f.kx] / ray.d[f.kz];
  f.sy = ray.d[f.ky] / ray.d[f.kz];
  f.sz = 1.0 / ray.d[f.kz];
  shearPoint(f, ray.o, r.origin);
  return r;
}

void shearPoint(const ShearFrame& f, const double p[3], double out[3]) {
  out[0] = p[f.kx] - f.sx * p[f.kz];
  out[1] = p[f.ky] - f.sy * p[f.kz];
  out[2] = f.sz * p[f.kz];
}

namespace {
bool lexLess(const double* a, const double* b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

// Position of a vertex relative to the ray, in the ray's sheared frame (ray along +z from the origin).
inline void shear(const PreparedRay& r, const double* p, double out[3]) {
  double q[3];
  shearPoint(r.frame, p, q);
  for (int i = 0; i < 3; ++i) out[i] = q[i] - r.origin[i];
}
}  // namespace

namespace {
// The three vertices of a triangle in canonical order: a fixed sorting network on the positions, so
// that the same face gives the same order (and so the same crossing) whoever computes it.
inline void canonicalOrder(const double* const p[3], int order[3]) {
  order[0] = 0, order[1] = 1, order[2] = 2;
  if (lexLess(p[order[1]], p[order[0]])) std::swap(order[0], order[1]);
  if (lexLess(p[order[2]], p[order[1]])) std::swap(order[1], order[2]);
  if (lexLess(p[order[1]], p[order[0]])) std::swap(order[0], order[1]);
}

// The crossing of the ray with the triangle of sheared vertices A, B, C (canonical order).
// The 2D cross product of the sheared points P and Q (their x and y).
inline double cross2(const double* P, const double* Q) { return P[0] * Q[1] - P[1] * Q[0]; }
inline Crossing crossSheared(const double* A, const double* B, const double* C, double sa, double sb, double sc) {
  const double u = cross2(C, B), v = cross2(A, C), w = cross2(B, A);
  Crossing x;
  if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return x;
  const double det = u + v + w;
  if (det == 0) return x;  // the ray lies in the triangle's plane
  x.hit = true;
  x.t = (u * A[2] + v * B[2] + w * C[2]) / det;
  x.s = (u * sa + v * sb + w * sc) / det;
  return x;
}
}  // namespace

Crossing crossTriangle(const PreparedRay& r, const double* a, const double* b, const double* c, double sa, double sb,
                       double sc) {
  const double* p[3] = {a, b, c};
  const double s[3] = {sa, sb, sc};
  int o[3];
  canonicalOrder(p, o);
  double S[3][3];
  for (int i = 0; i < 3; ++i) shear(r, p[o[i]], S[i]);
  return crossSheared(S[0], S[1], S[2], s[o[0]], s[o[1]], s[o[2]]);
}

void faceOrders(const double* const corner[4], uint8_t order[4][3]) {
  for (int k = 0; k < 4; ++k) {
    const int* f = kTetFace[k];
    const double* p[3] = {corner[f[0]], corner[f[1]], corner[f[2]]};
    int o[3];
    canonicalOrder(p, o);
    for (int i = 0; i < 3; ++i) order[k][i] = static_cast<uint8_t>(f[o[i]]);
  }
}

void finishTetGeom(TetGeom& g) {
  const double* corner[4] = {g.p[0], g.p[1], g.p[2], g.p[3]};
  faceOrders(corner, g.order);
  g.sheared = false;
}

void shearTetGeom(TetGeom& g, const ShearFrame& frame) {
  for (int i = 0; i < 4; ++i) {
    const double p[3] = {g.p[i][0], g.p[i][1], g.p[i][2]};
    shearPoint(frame, p, g.p[i]);
  }
  g.sheared = true;
}

namespace {
// The two ways of holding a tetrahedron, seen alike by the crossing functions below: corner i's
// position, as sheared by shearTetGeom (when g.sheared) or as given, and its scalar.
inline const double* shearedOf(const TetGeom& g, int i) { return g.p[i]; }
inline const double* positionOf(const TetGeom& g, int i) { return g.p[i]; }
inline double scalarOf(const TetGeom& g, int i) { return g.s[i]; }
inline const double* shearedOf(const TetCorners& g, int i) { return g.corner[i]->q; }
inline const double* positionOf(const TetCorners& g, int i) { return g.corner[i]->p; }
inline double scalarOf(const TetCorners& g, int i) { return g.corner[i]->s; }

// The corners of g relative to the ray, in its sheared frame.
template <class Tet>
inline void shearedCorners(const PreparedRay& r, const Tet& g, double S[4][3]) {
  if (g.sheared) {
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c) S[i][c] = shearedOf(g, i)[c] - r.origin[c];
  } else {
    for (int i = 0; i < 4; ++i) shear(r, positionOf(g, i), S[i]);
  }
}
}  // namespace

namespace {
template <class Tet>
void crossTetFacesOf(const PreparedRay& r, const Tet& g, int skip, Crossing out[4]) {
  double S[4][3];
  shearedCorners(r, g, S);
  for (int k = 0; k < 4; ++k) {
    if (k == skip) {
      out[k] = Crossing();
      continue;
    }
    const uint8_t* o = g.order[k];
    out[k] = crossSheared(S[o[0]], S[o[1]], S[o[2]], scalarOf(g, o[0]), scalarOf(g, o[1]), scalarOf(g, o[2]));
  }
}
}  // namespace

void crossTetFaces(const PreparedRay& r, const TetGeom& g, int skip, Crossing out[4]) {
  crossTetFacesOf(r, g, skip, out);
}
void crossTetFaces(const PreparedRay& r, const TetCorners& g, int skip, Crossing out[4]) {
  crossTetFacesOf(r, g, skip, out);
}

namespace {
template <class Tet>
int exitFaceOf(const PreparedRay& r, const Tet& g, int entry, bool forward, Crossing* out) {
  // crossTetFaces' crossings, inlined: the scalar is interpolated for the chosen face only.
  double S[4][3];
  shearedCorners(r, g, S);
  int best = -1;
  double best_t = 0, best_terms[3] = {0, 0, 0}, best_det = 1;
  for (int k = 0; k < 4; ++k) {
    if (k == entry) continue;
    const uint8_t* o = g.order[k];
    const double *A = S[o[0]], *B = S[o[1]], *C = S[o[2]];
    const double u = cross2(C, B), v = cross2(A, C), w = cross2(B, A);
    if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) continue;
    const double det = u + v + w;
    if (det == 0) continue;
    const double t = (u * A[2] + v * B[2] + w * C[2]) / det;
    // Where the ray passes through an edge or vertex of the entry face, faces sharing it are crossed
    // at the entry point too: the exit is the farthest crossing.
    if (best < 0 || (forward ? t > best_t : t < best_t)) {
      best = k;
      best_t = t;
      best_terms[0] = u, best_terms[1] = v, best_terms[2] = w;
      best_det = det;
    }
  }
  if (best >= 0) {
    const uint8_t* o = g.order[best];
    out->hit = true;
    out->t = best_t;
    out->s =
        (best_terms[0] * scalarOf(g, o[0]) + best_terms[1] * scalarOf(g, o[1]) + best_terms[2] * scalarOf(g, o[2])) /
        best_det;
  }
  return best;
}
}  // namespace

int exitFace(const PreparedRay& r, const TetGeom& g, int entry, bool forward, Crossing* out) {
  return exitFaceOf(r, g, entry, forward, out);
}
int exitFace(const PreparedRay& r, const TetCorners& g, int entry, bool forward, Crossing* out) {
  return exitFaceOf(r, g, entry, forward, out);
}

// ---------------------------------------------------------------------------------------------
// Shading

Rgba over(const Rgba& f, const Rgba& b) {
  const double k = 1.0 - f.a;
  return {f.r + k * b.r, f.g + k * b.g, f.b + k * b.b, f.a + k * b.a};
}

namespace {
inline void addSample(double alpha, const double rgb[3], bool front_to_back, Rgba* acc) {
  if (front_to_back) {
    const double k = (1.0 - acc->a) * alpha;
    acc->r += k * rgb[0];
    acc->g += k * rgb[1];
    acc->b += k * rgb[2];
    acc->a += k;
  } else {
    const double k = 1.0 - alpha;
    acc->r = alpha * rgb[0] + k * acc->r;
    acc->g = alpha * rgb[1] + k * acc->g;
    acc->b = alpha * rgb[2] + k * acc->b;
    acc->a = alpha + k * acc->a;
  }
}
}  // namespace

int64_t firstSampleAtOrAfter(double t, double step) {
  // An estimate, then the exact search.
  const double e = t / step;
  int64_t k = 0;
  if (std::fabs(e) < 4e18) {  // also false for NaN; truncation then one up is ceil without a libm call
    k = static_cast<int64_t>(e);
    if (static_cast<double>(k) < e) ++k;
  }
  return firstSampleFrom(k, t, step);
}

void shadeInterval(const RenderSetup& setup, double t_in, double s_in, double t_out, double s_out, double lo, double hi,
                   bool front_to_back, Rgba* acc) {
  if (!(hi > lo)) return;
  if (setup.sampling == Sampling::kFace) {
    double rgb_in[3], rgb_out[3], e_in, e_out;
    setup.transfer.evaluate(s_in, rgb_in, &e_in);
    setup.transfer.evaluate(s_out, rgb_out, &e_out);
    const double e = 0.5 * (e_in + e_out);
    double rgb[3];
    for (int c = 0; c < 3; ++c)
      rgb[c] =
          e_in + e_out > 0 ? (e_in * rgb_in[c] + e_out * rgb_out[c]) / (e_in + e_out) : 0.5 * (rgb_in[c] + rgb_out[c]);
    const double alpha = -std::expm1(-e * setup.inv_unit_distance * (hi - lo));
    addSample(alpha, rgb, front_to_back, acc);
    return;
  }
  shadeSamples(setup, t_in, s_in, t_out, s_out, firstSampleAtOrAfter(lo, setup.step),
               firstSampleAtOrAfter(hi, setup.step), front_to_back, acc);
}

void shadeSamples(const RenderSetup& setup, double t_in, double s_in, double t_out, double s_out, int64_t k0,
                  int64_t k1, bool front_to_back, Rgba* acc) {
  if (k1 <= k0) return;
  const double step = setup.step;
  const double span = t_out - t_in;
  const double slope = span > 0 ? (s_out - s_in) / span : 0.0;
  const bool table = !setup.sample_table.empty();
  // pre is 1 but for ranges wider than the largest double (then 0.5, exact): s * 1.0 is s.
  const double pre = setup.table_pre, lo_s = pre * setup.transfer.lo, scale = setup.table_scale;
  constexpr double kLast = RenderSetup::kSampleTableSize - 1;
  for (int64_t i = 0; i < k1 - k0; ++i) {
    const int64_t k = front_to_back ? k0 + i : k1 - 1 - i;
    const double t = static_cast<double>(k) * step;
    const double s = s_in + slope * (t - t_in);
    double rgb[3], alpha;
    if (table) {
      double x = (pre * s - lo_s) * scale;
      if (!(x >= 0)) x = 0;  // also catches NaN
      if (x > kLast) x = kLast;
      const int j = std::min(static_cast<int>(x), RenderSetup::kSampleTableSize - 2);
      const double f = x - j;
      const auto& a = setup.sample_table[j];
      const auto& b = setup.sample_table[j + 1];
      for (int c = 0; c < 3; ++c) rgb[c] = a[c] + f * (b[c] - a[c]);
      alpha = a[3] + f * (b[3] - a[3]);
    } else {
      double e;
      setup.transfer.evaluate(s, rgb, &e);
      alpha = -std::expm1(-e * setup.inv_unit_distance * step);
    }
    addSample(alpha, rgb, front_to_back, acc);
  }
}

// ---------------------------------------------------------------------------------------------
// Boundary crossings and segments

bool pixelFootprint(const Camera& camera, const double* const* points, int n, int box[4], double* xs, double* ys) {
  const int w = camera.width(), h = camera.height();
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  bool ok = true;
  for (int k = 0; k < n; ++k) {
    double x = 0, y = 0;
    if (camera.project(points[k], &x, &y)) {
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    } else {
      ok = false;
    }
    if (xs) xs[k] = x, ys[k] = y;
  }
  if (!ok) {
    box[0] = 0, box[1] = 0, box[2] = w - 1, box[3] = h - 1;
    return true;
  }
  // Pixels whose centre (px + 0.5) lies in the projected box, with a margin for rounding (the
  // projection and the crossing test are computed differently).
  constexpr double kMargin = 1e-3;
  x0 = std::clamp(x0, -2.0, w + 2.0), x1 = std::clamp(x1, -2.0, w + 2.0);
  y0 = std::clamp(y0, -2.0, h + 2.0), y1 = std::clamp(y1, -2.0, h + 2.0);
  box[0] = std::max(0, ceilToInt(x0 - 0.5 - kMargin));
  box[1] = std::max(0, ceilToInt(y0 - 0.5 - kMargin));
  box[2] = std::min(w - 1, floorToInt(x1 - 0.5 + kMargin));
  box[3] = std::min(h - 1, floorToInt(y1 - 0.5 + kMargin));
  return box[0] <= box[2] && box[1] <= box[3];
}

namespace {
// A crossing of a pixel's ray with a boundary triangle; the pixel is where it lies in the array.
struct Hit {
  double t, s;
  uint32_t tri;
  bool leaving;
};

// One boundary triangle ready to be crossed by pixels' rays. Orthographic rays share one direction,
// hence one shear frame: the triangle's canonical order and sheared corners are then computed once,
// and each pixel only shears its ray's origin. The arithmetic is crossTriangle's, step for step, so
// the crossings are the same bits.
class BoundaryTriangle {
 public:
  BoundaryTriangle(const Camera& camera, const ShearFrame& frame, const BoundarySurface& surface, uint32_t tri)
      : camera_(camera), frame_(frame), ortho_(camera.options().projection == Projection::kOrthographic) {
    const auto& t = surface.triangles[tri];
    for (int k = 0; k < 3; ++k) corner_[k] = surface.points[t[k]].data(), sc_[k] = surface.scalars[t[k]];
    const double *a = corner_[0], *b = corner_[1], *c = corner_[2];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n_[0] = e1[1] * e2[2] - e1[2] * e2[1], n_[1] = e1[2] * e2[0] - e1[0] * e2[2], n_[2] = e1[0] * e2[1] - e1[1] * e2[0];
    canonicalOrder(corner_, o_);
    if (ortho_)
      for (int k = 0; k < 3; ++k) shearPoint(frame, corner_[o_[k]], q_[k]);
  }
  const double* const* corners() const { return corner_; }
  bool ortho() const { return ortho_; }
  // Whether the ray of pixel (px, py) crosses the triangle, facing it one way or the other (from the
  // outward normal of the triangle as given): *x the crossing, *leaving the facing.
  bool cross(int px, int py, Crossing* x, bool* leaving) const {
    PreparedRay ray;
    if (ortho_) {
      ray.ray = camera_.ray(px, py);
      ray.frame = frame_;
      shearPoint(frame_, ray.ray.o, ray.origin);
      double S[3][3];
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) S[k][j] = q_[k][j] - ray.origin[j];
      *x = crossSheared(S[0], S[1], S[2], sc_[o_[0]], sc_[o_[1]], sc_[o_[2]]);
    } else {
      ray = prepareRay(camera_.ray(px, py));
      *x = crossTriangle(ray, corner_[0], corner_[1], corner_[2], sc_[0], sc_[1], sc_[2]);
    }
    if (!x->hit) return false;
    const double dn = n_[0] * ray.ray.d[0] + n_[1] * ray.ray.d[1] + n_[2] * ray.ray.d[2];
    *leaving = dn > 0;
    return dn != 0;
  }

 private:
  const Camera& camera_;
  const ShearFrame& frame_;
  bool ortho_;
  const double* corner_[3];
  double sc_[3], n_[3];
  int o_[3];
  double q_[3][3];  // orthographic: the sheared corners in canonical order
};

// The boundary's crossings with every pixel's ray, grouped by pixel (hits[start[p], start[p + 1]))
// and sorted by depth within a pixel. Each triangle is first tested against the pixels of its screen
// footprint (parallel over triangles: far fewer pairs than pixels against bins), keeping only which
// pairs cross (8 bytes each); the crossings of those pairs are then computed again straight into
// place, so that they are never held twice over.
struct PixelHits {
  std::vector<Hit> hits;
  std::vector<uint32_t> start;
};
PixelHits crossBoundary(const Camera& camera, const BoundarySurface& surface) {
  const int w = camera.width();
  const size_t num_pixels = static_cast<size_t>(w) * camera.height();
  const ShearFrame frame = prepareRay(camera.ray(0, 0)).frame;
  struct Pair {
    uint32_t tri, pixel;
  };
  tbb::enumerable_thread_specific<std::vector<Pair>> pairs;
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, surface.triangles.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<Pair>& mine = pairs.local();
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const BoundaryTriangle tri(camera, frame, surface, static_cast<uint32_t>(i));
          int box[4];
          double sx[3], sy[3];
          if (!pixelFootprint(camera, tri.corners(), 3, box, sx, sy)) continue;
          const ScreenHull hull(sx, sy, 3);
          for (int py = box[1]; py <= box[3]; ++py) {
            // Orthographic: the pixels clearly outside the projected triangle are not tested (the
            // crossing test agrees with the projection to about 1e-10 pixels).
            constexpr double kSure = ScreenHull::kSure;
            int px0 = box[0], px1 = box[2];
            double xl, xr;
            if (tri.ortho() && hull.span(py + 0.5, kSure, &xl, &xr))
              ScreenHull::columns(xl, xr, kSure, box, &px0, &px1);
            for (int px = px0; px <= px1; ++px) {
              Crossing x;
              bool leaving;
              if (tri.cross(px, py, &x, &leaving))
                mine.push_back({static_cast<uint32_t>(i),
                                static_cast<uint32_t>(py) * static_cast<uint32_t>(w) + static_cast<uint32_t>(px)});
            }
          }
        }
      });
  PixelHits out;
  out.start.assign(num_pixels + 1, 0);
  for (const std::vector<Pair>& list : pairs)
    for (const Pair& pr : list) ++out.start[pr.pixel + 1];
  for (size_t p = 0; p < num_pixels; ++p) out.start[p + 1] += out.start[p];
  out.hits.resize(out.start.back());
  {
    std::vector<std::atomic<uint32_t>> fill(num_pixels);
    for (size_t p = 0; p < num_pixels; ++p) fill[p].store(out.start[p], std::memory_order_relaxed);
    for (const std::vector<Pair>& list : pairs) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t j = r.begin(); j < r.end();) {
          // A triangle's pairs are consecutive: it is set up once for them.
          const uint32_t t = list[j].tri;
          const BoundaryTriangle tri(camera, frame, surface, t);
          for (; j < r.end() && list[j].tri == t; ++j) {
            const uint32_t pixel = list[j].pixel;
            Crossing x;
            bool leaving = false;
            tri.cross(static_cast<int>(pixel % static_cast<uint32_t>(w)),
                      static_cast<int>(pixel / static_cast<uint32_t>(w)), &x, &leaving);
            out.hits[fill[pixel].fetch_add(1, std::memory_order_relaxed)] = {x.t, x.s, t, leaving};
          }
        }
      });
    }
  }
  // Within a pixel the order is total (a triangle crosses a ray once), so the sort fixes it.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_pixels, 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p < r.end(); ++p) {
      std::sort(out.hits.data() + out.start[p], out.hits.data() + out.start[p + 1], [](const Hit& x, const Hit& y) {
        if (x.t != y.t) return x.t < y.t;
        if (x.leaving != y.leaving) return x.leaving;
        return x.tri < y.tri;
      });
    }
  });
  return out;
}

// Pairs one pixel's sorted crossings into segments, calling emit(segment) for each in order; returns
// how many. A group of crossings at the same depth (within eps) counts at most one step in and one
// step out. *unpaired is set when a group steps out where the ray is outside (a boundary triangle
// facing inward: that part of the ray is lost).
template <class Emit>
uint32_t pairCrossings(const Hit* first, const Hit* last, uint32_t pixel, double eps, Emit&& emit,
                       bool* unpaired = nullptr) {
  RaySegment seg;  // the last segment begun: its far end may still come
  uint32_t made = 0;
  int depth = 0;
  for (const Hit* i = first; i < last;) {
    const Hit* j = i;
    const Hit* enter = nullptr;
    const Hit* leave = nullptr;
    // The crossings within eps of i's, i itself always (a NaN depth, from a degenerate camera, is
    // within nothing: testing it against itself never moved on).
    do {
      if (j->leaving) {
        if (!leave) leave = j;
      } else if (!enter) {
        enter = j;
      }
      ++j;
    } while (j < last && j->t - i->t <= eps);
    const int delta = (enter ? 1 : 0) - (leave ? 1 : 0);
    if (delta > 0) {
      if (depth == 0) {
        if (made++) emit(seg);
        seg = RaySegment();
        seg.pixel = pixel;
        seg.entry_tri = enter->tri;
        seg.t_near = enter->t;
        seg.s_near = enter->s;
      }
      ++depth;
    } else if (delta < 0 && depth > 0) {
      if (--depth == 0) {
        seg.exit_tri = leave->tri;
        seg.t_far = leave->t;
        seg.s_far = leave->s;
      }
    } else if (delta < 0 && unpaired) {
      *unpaired = true;
    }
    i = j;
  }
  if (made) emit(seg);
  return made;
}

// pixel_start from the crossings: the segments of each pixel counted (parallel), then summed; the
// pixels whose crossings do not pair (pairCrossings) into *unpaired, in order.
std::vector<uint32_t> segmentStarts(const PixelHits& ph, double eps, std::vector<uint32_t>* unpaired) {
  const size_t num_pixels = ph.start.size() - 1;
  std::vector<uint32_t> start(num_pixels + 1, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_pixels, 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p < r.end(); ++p) {
      const Hit* hits = ph.hits.data();
      bool bad = false;
      start[p + 1] = pairCrossings(
          hits + ph.start[p], hits + ph.start[p + 1], static_cast<uint32_t>(p), eps, [](const RaySegment&) {}, &bad);
      // The top bit marks the pixel (counts stay far below it: a pixel has at most its crossings).
      if (bad) start[p + 1] |= 0x80000000u;
    }
  });
  unpaired->clear();
  for (size_t p = 0; p < num_pixels; ++p) {
    if (start[p + 1] & 0x80000000u) {
      start[p + 1] &= 0x7FFFFFFFu;
      unpaired->push_back(static_cast<uint32_t>(p));
    }
    start[p + 1] += start[p];
  }
  return start;
}
}  // namespace

RaySegments castBoundary(const Camera& camera, const BoundarySurface& surface) {
  const double eps = 1e-9 * camera.radius();
  const PixelHits ph = crossBoundary(camera, surface);
  RaySegments result;
  result.pixel_start = segmentStarts(ph, eps, &result.unpaired);
  result.segments.resize(result.pixel_start.back());
  const size_t num_pixels = ph.start.size() - 1;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_pixels, 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p < r.end(); ++p) {
      RaySegment* out = result.segments.data() + result.pixel_start[p];
      pairCrossings(ph.hits.data() + ph.start[p], ph.hits.data() + ph.start[p + 1], static_cast<uint32_t>(p), eps,
                    [&](const RaySegment& seg) { *out++ = seg; });
    }
  });
  return result;
}

void castBoundary(const Camera& camera, const BoundarySurface& surface, std::vector<uint32_t>* pixel_start,
                  SegmentSink& sink, std::vector<uint32_t>* unpaired) {
  const double eps = 1e-9 * camera.radius();
  const PixelHits ph = crossBoundary(camera, surface);
  std::vector<uint32_t> none;
  *pixel_start = segmentStarts(ph, eps, unpaired ? unpaired : &none);
  sink.begin(pixel_start->back());
  const size_t num_pixels = ph.start.size() - 1;
  for (size_t p = 0; p < num_pixels; ++p)
    pairCrossings(ph.hits.data() + ph.start[p], ph.hits.data() + ph.start[p + 1], static_cast<uint32_t>(p), eps,
                  [&](const RaySegment& seg) { sink.segment(seg); });
}

std::pair<double, double> boundaryRange(const BoundarySurface& surface) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& tri : surface.triangles) {
    for (uint32_t v : tri) {
      const double s = surface.scalars[v];
      if (!std::isfinite(s)) continue;
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
  }
  if (!(lo <= hi)) return {0.0, 1.0};
  if (lo == hi) return {lo - 0.5, hi + 0.5};
  return {lo, hi};
}

void sceneBox(const RenderOptions& options, const LevelHeader& header, const BoundarySurface& surface,
              double bbox_min[3], double bbox_max[3]) {
  if (options.has_scene_box) {
    for (int i = 0; i < 3; ++i) bbox_min[i] = options.scene_min[i], bbox_max[i] = options.scene_max[i];
    return;
  }
  bool usable = true;
  for (int i = 0; i < 3; ++i) {
    bbox_min[i] = header.bbox_min[i];
    bbox_max[i] = header.bbox_max[i];
    if (!std::isfinite(bbox_min[i]) || !std::isfinite(bbox_max[i]) || bbox_min[i] > bbox_max[i]) usable = false;
  }
  if (usable && (bbox_min[0] < bbox_max[0] || bbox_min[1] < bbox_max[1] || bbox_min[2] < bbox_max[2])) return;
  for (int i = 0; i < 3; ++i) {
    bbox_min[i] = std::numeric_limits<double>::infinity();
    bbox_max[i] = -bbox_min[i];
  }
  for (const auto& tri : surface.triangles) {
    for (uint32_t v : tri) {
      for (int i = 0; i < 3; ++i) {
        bbox_min[i] = std::min(bbox_min[i], surface.points[v][i]);
        bbox_max[i] = std::max(bbox_max[i], surface.points[v][i]);
      }
    }
  }
  if (surface.triangles.empty()) {
    for (int i = 0; i < 3; ++i) bbox_min[i] = 0, bbox_max[i] = 1;
  }
}

void toRgb8(const Rgba& c, uint8_t out[3]) {
  auto to8 = [](double v) {
    // std::lround without the library call: x - trunc(x) is exact on [0, 255], and halves round up
    // as lround rounds them (away from zero). NaN gives 0, as lround's cast did.
    const double x = v > 0 ? std::min(v, 1.0) * 255.0 : 0.0;
    const int r = static_cast<int>(x);
    return static_cast<uint8_t>(x - r >= 0.5 ? r + 1 : r);
  };
  out[0] = to8(c.r);
  out[1] = to8(c.g);
  out[2] = to8(c.b);
}

Image toImage(int width, int height, const std::vector<Rgba>& pixels) {
  Image image(width, height);
  for (size_t i = 0; i < pixels.size() && i < static_cast<size_t>(width) * height; ++i)
    toRgb8(pixels[i], &image.rgb[3 * i]);
  return image;
}

}  // namespace gtn
