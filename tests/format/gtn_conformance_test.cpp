// The conformance files in samples/conformance/: valid files that must decode to known meshes and
// malformed files that must fail with a known reason. Beside each NAME.gtn, NAME.expected says what a
// reader must make of it (outcome, counts, fields and levels, or the status and message of the
// failure); this test reads those files and holds the reference reader to them. The .gtn files are
// committed; this test generates them procedurally and rewrites them only when GTN_UPDATE_GOLDEN=1 is
// set. Without it, it decodes the committed files (they are decode-compatibility vectors: a later
// codec must still read them) and compares them with the generated meshes too.
#include <gtest/gtest.h>

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>

#include "codec/codec_test_util.h"
#include "codec/packed_values.h"
#include "codec/pieces.h"
#include "codec/structured_piece.h"
#include "codec/value_coder.h"
#include "format/gtn_chunk.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "format/gtn_records.h"
#include "mesh/mesh_stats.h"
#include "simplify/apply.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "test_util.h"
#include "validate/write_gtn.h"

namespace gtn {
namespace {

const std::string kDir = std::string(GTN_SOURCE_DIR) + "/samples/conformance/";

// An n x n x n grid of cubes, each split into 6 tetrahedra around its main diagonal (conforming),
// offset by `origin` along x. Fields are filled with values derived from the position.
void addCubeGrid(TetMesh& m, int n, double origin, double scale) {
  const uint32_t base = static_cast<uint32_t>(m.numPoints());
  auto id = [&](int i, int j, int k) { return base + static_cast<uint32_t>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        // Slightly irregular positions so predictions have something to do; exact in float32.
        const double jitter = ((i * 7 + j * 3 + k * 5) % 4) * 0.0625;
        m.coords.push_back(origin + scale * (i + 0.25 * jitter));
        m.coords.push_back(scale * j);
        m.coords.push_back(scale * (k + 0.125 * jitter));
      }
  static const int kKuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        uint32_t c[8];
        for (int b = 0; b < 8; ++b) c[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        for (const auto& t : kKuhn) m.tets.push_back({c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
      }
}

template <class T>
void fillField(Field& f, size_t items, uint64_t seed) {
  f.bytes.assign(items * f.components * sizeof(T), 0);
  for (size_t i = 0; i < items; ++i)
    for (uint32_t c = 0; c < f.components; ++c) {
      const uint64_t x = (i * 2654435761u + c * 40503u + seed) % 1000;
      f.set<T>(i, c, static_cast<T>(x) / static_cast<T>(T(1) + (std::is_floating_point_v<T> ? 7 : 0)));
    }
}

TetMesh finish(TetMesh m) {
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  return m;
}

// An n x n x n grid of unit cubes, float32, with a float32 point field `density`.
TetMesh densityGrid(int n, uint64_t seed) {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  addCubeGrid(m, n, 0.0, 1.0);
  Field f("density", 1, ScalarType::kFloat32, 0);
  fillField<float>(f, m.numPoints(), seed);
  m.point_fields.push_back(f);
  return m;
}

TetMesh cubeF32() {
  TetMesh m = densityGrid(3, 1);
  m.setMetadata("source", "gtn conformance generator");
  return finish(m);
}

TetMesh cubeF64Fields() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  addCubeGrid(m, 3, 0.0, 0.1);
  const size_t np = m.numPoints(), nt = m.numTets();
  Field a("pressure", 1, ScalarType::kFloat64, 0), b("velocity", 3, ScalarType::kFloat32, 0),
      c("label", 1, ScalarType::kInt32, 0), d("flags", 2, ScalarType::kUInt8, 0);
  fillField<double>(a, np, 2);
  fillField<float>(b, np, 3);
  fillField<int32_t>(c, np, 4);
  fillField<uint8_t>(d, np, 5);
  m.point_fields = {a, b, c, d};
  Field r("region", 1, ScalarType::kInt32, 0), s("stress", 2, ScalarType::kFloat64, 0);
  fillField<int32_t>(r, nt, 6);
  fillField<double>(s, nt, 7);
  m.cell_fields = {r, s};
  return finish(m);
}

TetMesh unusedPoints() {
  TetMesh m = cubeF32();
  // Two points no tetrahedron uses (as in raptorTetra_19409.vtu), with field values of their own.
  for (double v : {9.0, 9.0, 9.0, -4.0, 0.5, 0.25}) m.coords.push_back(v);
  Field& f = m.point_fields[0];
  f.bytes.resize(f.bytes.size() + 8);
  f.set<float>(m.numPoints() - 2, 0, 42.0f);
  f.set<float>(m.numPoints() - 1, 0, -1.0f);
  return m;
}

TetMesh twoComponents() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  addCubeGrid(m, 2, 0.0, 1.0);
  addCubeGrid(m, 2, 10.0, 1.0);
  Field f("temperature", 1, ScalarType::kFloat32, 0);
  fillField<float>(f, m.numPoints(), 8);
  m.point_fields.push_back(f);
  return finish(m);
}

TetMesh repeatedComponents() {
  // A vector field stored once more as separate scalars (as fire_ug.vtu does): the copies are coded as
  // repeats of the vector's components (spec section 10.6).
  TetMesh m = cubeF64Fields();
  const Field& velocity = m.point_fields[1];
  Field vx("velocity_x", 1, ScalarType::kFloat32, m.numPoints()),
      vz("velocity_z", 1, ScalarType::kFloat32, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) {
    vx.set<float>(v, 0, static_cast<float>(velocity.get(v, 0)));
    vz.set<float>(v, 0, static_cast<float>(velocity.get(v, 2)));
  }
  m.point_fields.push_back(vx);
  m.point_fields.push_back(vz);
  return m;
}

// Values as text formats hold them (spec 10.2, decimal form): float64 coordinates and a float64 field
// printed with a few decimals, among them values that have no such form (full precision, -0.0), which
// the decoder reads through the per-value escape to the float form.
TetMesh decimals() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  addCubeGrid(m, 3, 0.0, 0.1);
  const size_t np = m.numPoints();
  for (size_t i = 0; i < m.coords.size(); ++i) m.coords[i] = std::nearbyint(m.coords[i] * 1e4 + 0.3 * (i % 7)) / 1e4;
  m.coords[3 * 5] += 1e-13;  // a generator's own point among the printed ones
  Field t("temperature", 1, ScalarType::kFloat64, np);
  for (size_t v = 0; v < np; ++v)
    t.set<double>(v, 0, std::nearbyint(300000.0 + 37.0 * static_cast<double>(v % 11)) / 1000.0);
  t.set<double>(7, 0, -0.0);
  t.set<double>(8, 0, 1.0 / 3.0);
  m.point_fields = {t};
  return finish(m);
}

// Float32 values printed with 15 digits and read back as doubles, as MMG's Medit files hold them
// (spec 10.2, printed-single form): coordinates and a float64 field, with a full double and a value
// beyond float32's range taking the per-value escape.
TetMesh printedSingles() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  addCubeGrid(m, 3, 0.0, 0.37);
  for (double& c : m.coords) c = printedSingle(static_cast<float>(c * 1.7 + 0.01), 15);
  m.coords[3 * 4 + 1] = 1.0 / 3.0;
  const size_t np = m.numPoints();
  Field t("temperature", 1, ScalarType::kFloat64, np);
  for (size_t v = 0; v < np; ++v)
    t.set<double>(v, 0, printedSingle(static_cast<float>(280.0 + 0.37 * static_cast<double>(v % 13)), 15));
  t.set<double>(9, 0, 1e300);
  m.point_fields = {t};
  return finish(m);
}

// Sums of float32 values kept in doubles (spec 10.2, shift with exceptions): float64 coordinates and a
// float64 field whose values mostly end in many zero bits, with full doubles among them that take the
// per-value escape, and a zero that does not need it.
TetMesh shiftExceptions() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  addCubeGrid(m, 3, 0.0, 0.37);
  for (double& c : m.coords)
    c = static_cast<double>(static_cast<float>(c * 1.7)) + static_cast<double>(static_cast<float>(c * 0.013));
  m.coords[3 * 4 + 1] = 1.0 / 3.0;
  const size_t np = m.numPoints();
  Field s("stress", 1, ScalarType::kFloat64, np);
  for (size_t v = 0; v < np; ++v)
    s.set<double>(v, 0,
                  static_cast<double>(static_cast<float>(4.1e6 + 977.3 * static_cast<double>(v % 13))) +
                      static_cast<double>(static_cast<float>(3100.7 * static_cast<double>(v % 7))));
  s.set<double>(9, 0, std::sqrt(2.0));
  s.set<double>(10, 0, 0.0);
  s.set<double>(20, 0, 1e300 / 3.0);
  m.point_fields = {s};
  return finish(m);
}

// A curvilinear grid (spec 10.5, error carries): 5 x 5 x 5 cubes bent into a twisted cylindrical
// shell, float32. No rule predicts a vertex exactly, but a neighbour's error nearly does, and GEOM
// carries it over.
TetMesh curvilinear() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  addCubeGrid(m, 5, 0.0, 1.0);
  for (size_t v = 0; v < m.numPoints(); ++v) {
    // Float arithmetic (GCC 12.2 at -O3 drops the rounding of a double product cast to float when it
    // vectorises three such stores).
    const float i = static_cast<float>(v % 6), j = static_cast<float>(v / 6 % 6), k = static_cast<float>(v / 36);
    const float r = 2.0f + 0.3f * i + 0.02f * i * i, theta = 0.15f * j + 0.03f * k;
    m.coords[3 * v] = r * std::cos(theta);
    m.coords[3 * v + 1] = r * std::sin(theta);
    m.coords[3 * v + 2] = 0.4f * k + 0.008f * i * j;
  }
  return finish(m);
}

// A field of a few distinct values (spec 10.2, table form): 6 x 6 x 6 cubes, float32, with a float64
// cell field `conductivity` that takes one of 9 irrational values per block of 2 x 2 x 2 cubes, and a
// float64 point field `level` of 5 values: the cell field is coded as places in its table.
TetMesh valueTable() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  addCubeGrid(m, 6, 0.0, 1.0);
  m = finish(m);
  Field c("conductivity", 1, ScalarType::kFloat64, m.numTets());
  for (size_t t = 0; t < m.numTets(); ++t) {
    const size_t cube = t / 6, i = cube % 6, j = cube / 6 % 6, k = cube / 36;
    c.set<double>(t, 0, std::sqrt(2.0 + static_cast<double>((i / 2 + 3 * (j / 2) + 2 * (k / 2)) % 9)));
  }
  Field l("level", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) l.set<double>(v, 0, std::log(3.0 + static_cast<double>(v % 5)));
  m.cell_fields = {c};
  m.point_fields = {l};
  return m;
}

// Values that no prediction helps (spec 10.2.1): the 8 x 8 x 8 cube grid (float32) with a float32
// point field `stress` whose values are 300 levels scattered over the points (a solver's table,
// std::mt19937_64 picks), a float64 point field `smooth` and a float32 cell field `damage` of 300
// other levels, one per cube (its 6 tetrahedra share it). Only `stress` is packed.
TetMesh packedValues() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat32;
  addCubeGrid(m, 8, 0.0, 1.0);
  m = finish(m);
  std::mt19937_64 rng(36);
  std::vector<float> levels(300), damage_levels(300);
  for (float& l : levels) l = static_cast<float>(rng() >> 40) * 1.1920929e-7f * 3.0e8f;
  for (float& l : damage_levels) l = static_cast<float>(rng() >> 40) * 5.9604645e-8f;
  Field stress("stress", 1, ScalarType::kFloat32, m.numPoints()),
      smooth("smooth", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) {
    stress.set<float>(v, 0, levels[rng() % levels.size()]);
    const double* p = m.point(v);
    smooth.set<double>(v, 0, std::sin(0.3 * p[0] + 0.2 * p[2]) * std::exp(0.1 * p[1]));
  }
  Field damage("damage", 1, ScalarType::kFloat32, m.numTets());
  float value = 0;
  for (size_t t = 0; t < m.numTets(); ++t) {
    if (t % 6 == 0) value = damage_levels[rng() % damage_levels.size()];
    damage.set<float>(t, 0, value);
  }
  m.point_fields = {stress, smooth};
  m.cell_fields = {damage};
  return m;
}

// A quadratic tetrahedral mesh as importers keep it (spec 10.5, edge points): the 2 x 2 x 2 cube grid,
// float64, with a node on every edge of every tetrahedron that no tetrahedron uses, most at the edge's
// midpoint, some off it (a curved cell's), and one point on no edge, coded after peeling.
TetMesh edgePoints() {
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  addCubeGrid(m, 2, 0.0, 0.5);
  m = finish(m);
  const std::set<std::pair<uint32_t, uint32_t>> edges = test::tetEdges(m);
  const size_t corners = m.numPoints();
  std::vector<double> pressure(corners);
  for (size_t v = 0; v < corners; ++v) pressure[v] = 100.0 + m.point(v)[0] * m.point(v)[1] + m.point(v)[2];
  size_t k = 0;
  for (const auto& [a, b] : edges) {
    const double bend = k++ % 5 == 0 ? 0.01 : 0.0;
    for (int i = 0; i < 3; ++i) m.coords.push_back((m.point(a)[i] + m.point(b)[i]) * 0.5 + (i == 2 ? bend : 0.0));
    pressure.push_back(0.5 * (pressure[a] + pressure[b]) + 0.001 * static_cast<double>(k % 3));
  }
  for (double v : {7.0, 7.0, 7.0}) m.coords.push_back(v);
  pressure.push_back(-1.0);
  Field f("pressure", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) f.set<double>(v, 0, pressure[v]);
  m.point_fields = {f};
  return m;
}

// The Delaunay tetrahedralization of `n` points drawn in the unit cube (std::mt19937_64, whose output
// the C++ standard fixes; coordinates multiples of 2^-20, in general position), made by CGAL. The
// tetrahedra are put in a canonical order (sorted corners, then sorted, then oriented), so the mesh is
// the same whatever order CGAL enumerates them in.
TetMesh delaunayPoints(size_t n) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_3<uint32_t, K>;
  using Tds = CGAL::Triangulation_data_structure_3<Vb, CGAL::Delaunay_triangulation_cell_base_3<K>>;
  using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  std::mt19937_64 rng(20261125);
  std::vector<std::pair<K::Point_3, uint32_t>> points;
  for (size_t i = 0; i < n; ++i) {
    double p[3];
    for (double& c : p) c = static_cast<double>(rng() >> 44) / 1048576.0;
    m.coords.insert(m.coords.end(), p, p + 3);
    points.emplace_back(K::Point_3(p[0], p[1], p[2]), static_cast<uint32_t>(i));
  }
  const Delaunay dt(points.begin(), points.end());
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    Tet t;
    for (int k = 0; k < 4; ++k) t[k] = c->vertex(k)->info();
    std::sort(t.begin(), t.end());
    m.tets.push_back(t);
  }
  std::sort(m.tets.begin(), m.tets.end());
  return finish(m);
}
// A Delaunay mesh (spec 10.4, "Delaunay first"): 400 random points, float64, with a float32 point field.
// The encoder sets the bit for it, and its candidates and escapes rank by the sweep key first.
TetMesh delaunayMesh() {
  TetMesh m = delaunayPoints(400);
  Field f("temperature", 1, ScalarType::kFloat32, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) {
    const double* p = m.point(v);
    f.set<float>(v, 0, static_cast<float>(300.0 + 20.0 * p[0] * p[1] - 7.0 * p[2]));
  }
  m.point_fields = {f};
  return m;
}
// A degenerate Delaunay sweep (spec 10.4.1, C-6 and C-8): delaunayPoints(400) plus 4 copies, far away,
// of a 3 x 3 x 3 point lattice (6 tetrahedra per cube) sheared in z and squashed by 2^-515 in y. Its
// gate faces are needles whose circumradius squared overflows: the sweep of such a face is degenerate,
// and an escape ranked there goes by distance, where ranking by the sweep key would name another vertex.
// The Delaunay part keeps the level's "Delaunay first" bit set.
TetMesh degenerateSweep() {
  TetMesh m = delaunayPoints(400);
  const double squash = std::ldexp(1.0, -515);
  for (int copy = 1; copy <= 4; ++copy) {
    const uint32_t base = static_cast<uint32_t>(m.numPoints());
    auto id = [&](int i, int j, int k) { return base + static_cast<uint32_t>((k * 3 + j) * 3 + i); };
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const double x = i * 0.37 + 0.013 * i * i, y = j * 1.1 + 0.2 * (j % 3),
                       z = k * 0.71 + 0.05 * (k % 2) + 0.3 * y;
          m.coords.insert(m.coords.end(), {x + 3000.0 * copy, y * squash, z - 2000.0});
        }
    static const int kKuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          uint32_t c[8];
          for (int b = 0; b < 8; ++b) c[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
          for (const auto& t : kKuhn) m.tets.push_back({c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
        }
  }
  return finish(m);
}
// A 5 x 5 x 5 grid of cubes with a density field: big enough for a merge tree and two mip levels.
TetMesh levelsMesh() { return finish(densityGrid(5, 9)); }

// levelsMesh() as the structured block it is (6 x 6 x 6 nodes in node order), as a PLOT3D importer
// would hand it over: level 0 is a structured piece, and its merge tree codes its parents as grid
// places (MTRE version 5, parent_form 4).
TetMesh gridTreeMesh() {
  TetMesh m = levelsMesh();
  StructuredBlock b;
  b.dims[0] = b.dims[1] = b.dims[2] = 6;
  m.blocks.push_back(b);
  return m;
}

// levelsMesh() plus 131000 points no tetrahedron uses, all at the origin with density 0: 131216 points,
// more than 2^17, so that the first records of its merge tree code their child in 17 + 1 direct bits
// (one call of 17 bits: spec sections 10.1 and 11).
constexpr size_t kWidePoints = 216 + 131000;
TetMesh wideMesh() {
  TetMesh m = levelsMesh();
  m.coords.resize(3 * kWidePoints, 0.0);
  Field& f = m.point_fields[0];
  f.bytes.resize(kWidePoints * f.components * f.valueSize(), 0);
  return m;
}

GtnWriteOptions options(bool directory = true) {
  GtnWriteOptions o;
  o.tool_version = "conformance";
  o.command_line = "GTN_UPDATE_GOLDEN=1 gtn_conformance_test";
  o.directory = directory;
  return o;
}

// `packed`: let the encoder keep packed and split streams (spec 10.2.1); the other samples pin the
// range-coded forms they are named after.
std::vector<uint8_t> encodeFile(const TetMesh& mesh, const GtnWriteOptions& o,
                                const std::function<void(GtnStreamWriter&)>& extra = nullptr, bool packed = false) {
  EncodeOptions eo;
  eo.packed_streams = packed;
  auto e = encodeLevel(mesh, eo);
  EXPECT_TRUE(e.isOk()) << e.status().message();
  std::vector<uint8_t> bytes;
  GtnStreamWriter w(
      [&](std::span<const uint8_t> b) {
        bytes.insert(bytes.end(), b.begin(), b.end());
        return Status::ok();
      },
      o);
  EXPECT_TRUE(w.begin(e->header, 1).isOk());
  if (extra) extra(w);
  EXPECT_TRUE(w.addLevel(e.value(), 0.0, std::nullopt).isOk());
  EXPECT_TRUE(w.finish().isOk());
  return bytes;
}

// `mesh` with its merge tree (MTRE, section 11) and `levels` mip levels, as `gtn convert --levels K`
// writes it: the ranked merges in batches (MTRE payload version 5). `level0`: level 0 as given (the
// writer encodes it otherwise). `mtre_version` 2, 3 or 4: the trees in that payload version instead,
// as the writer wrote them before (2 and 3: the ranking's own order, without batches); `greedy`: the
// ranking in the greedy order (RankingOptions::lazy off), as it was before the lazy one.
std::vector<uint8_t> encodeWithTree(const TetMesh& mesh, int levels, const GtnWriteOptions& o,
                                    std::shared_ptr<PiecedLevel> level0 = nullptr, int mtre_version = 5,
                                    bool greedy = false) {
  RankingOptions ranking;
  ranking.lazy = !greedy;
  auto tree = rankMerges(mesh, ranking, nullptr);
  EXPECT_TRUE(tree.isOk());
  const bool given = level0 != nullptr;
  if (!given) {
    auto encoded = encodePieces(mesh, EncodeOptions{}, o.piece_tets);
    EXPECT_TRUE(encoded.isOk());
    level0 = std::make_shared<PiecedLevel>(std::move(encoded).value());
  }
  auto stored = storedMergeTree(mesh, *tree, *level0);
  EXPECT_TRUE(stored.isOk());
  LevelOptions lo;
  lo.levels = levels;
  auto built = buildMipLevels(mesh, mtre_version >= 4 ? stored->tree : *tree, lo);
  EXPECT_TRUE(built.isOk());
  std::vector<GtnLevelInput> inputs = built->inputs(mesh, stored->level0_form);
  if (given) inputs[0].encoded = level0;
  if (mtre_version != 5) {
    const std::vector<const TetMesh*> meshes = built->levelMeshes(mesh);
    const MergeTreeForm form{static_cast<uint8_t>(mtre_version), mtre_version != 2};
    for (size_t i = 0; i < inputs.size(); ++i) {
      const std::shared_ptr<const MergeTree> t = built->trees[i];
      if (!t) continue;
      const TetMesh* m = meshes[i];
      inputs[i].merge_tree = [t, m, form](const std::vector<uint32_t>& order) {
        return encodeMergeTree(*t, order, m, form);
      };
      inputs[i].merge_tree_prefix = [t, m, form](const std::vector<uint32_t>& order, uint64_t n,
                                                 const std::vector<uint32_t>&) {
        return encodeMergeTree(n < t->merges ? prefixTree(*t, n) : *t, order, m, form);
      };
    }
  }
  const std::string path = test::tempDir("conformance-tree") + "/tree.gtn";
  const Status st = writeGtnFile(path, inputs, o);
  EXPECT_TRUE(st.isOk()) << st.message();
  const std::string bytes = test::readFile(path);
  return std::vector<uint8_t>(bytes.begin(), bytes.end());
}

// `mesh` (one structured block) with level 0 as a structured piece, whatever the level codec would
// take, its merge tree and `levels` mip levels, as `gtn convert` writes a grid.
std::vector<uint8_t> encodeGridWithTree(const TetMesh& mesh, int levels, const GtnWriteOptions& o) {
  auto piece = encodeStructuredPiece(mesh, mesh.blocks.at(0));
  EXPECT_TRUE(piece.isOk()) << piece.status().message();
  return encodeWithTree(mesh, levels, o,
                        std::make_shared<PiecedLevel>(onePieceLevel(std::move(piece).value(), kPieceStructured)));
}

// A 12 x 12 x 12 grid of cubes (10368 tetrahedra) with a density field: cut into pieces of at most
// 4096 tetrahedra (kMinPieceTets), it makes 4 pieces and their seams.
TetMesh piecesMesh() { return finish(densityGrid(12, 11)); }

// `mesh` coded as pieces of at most kMinPieceTets tetrahedra, as `gtn convert --piece-tets 4096
// --levels 0 --no-merge-tree` writes it.
std::vector<uint8_t> encodePiecesFile(const TetMesh& mesh, GtnWriteOptions o) {
  o.piece_tets = kMinPieceTets;
  GtnLevelInput level0;
  level0.mesh = &mesh;
  const std::string path = test::tempDir("conformance-pieces") + "/pieces.gtn";
  const Status st = writeGtnFile(path, {level0}, o);
  EXPECT_TRUE(st.isOk()) << st.message();
  const std::string bytes = test::readFile(path);
  return std::vector<uint8_t>(bytes.begin(), bytes.end());
}

// Offset of the first chunk with `tag` in a valid file.
uint64_t chunkOffset(const std::vector<uint8_t>& bytes, ChunkTag tag) {
  auto r = GtnReader::openMemory(std::string(bytes.begin(), bytes.end()), "gen");
  EXPECT_TRUE(r.isOk());
  for (const GtnChunkInfo& c : (*r)->level(0).chunks)
    if (c.tag == tag) return c.offset;
  return 0;
}

// The chunk of level 0 with `tag` in a valid file.
GtnChunkInfo levelChunk(const std::vector<uint8_t>& bytes, ChunkTag tag, size_t level = 0) {
  auto r = GtnReader::openMemory(std::string(bytes.begin(), bytes.end()), "gen");
  EXPECT_TRUE(r.isOk());
  for (const GtnChunkInfo& c : (*r)->level(level).chunks)
    if (c.tag == tag) return c;
  ADD_FAILURE() << "no chunk " << tag.str();
  return {};
}

// A level's header record as a valid file stores it, and what it is coded against (the levels'
// records are coded in turn, each against the one before).
std::pair<GtnLevelRecord, LevelRecordContext> levelRecord(const std::vector<uint8_t>& bytes, size_t level = 0) {
  auto reader = GtnReader::openMemory(std::string(bytes.begin(), bytes.end()), "gen");
  EXPECT_TRUE(reader.isOk());
  LevelRecordContext context = levelRecordContext((*reader)->file().header);
  GtnLevelRecord r;
  for (size_t i = 0; i <= level; ++i) {
    const GtnChunkInfo c = levelChunk(bytes, kTagLevelHeader, i);
    ChunkHeader h;
    size_t needed;
    EXPECT_TRUE(
        parseGtnChunkHeader(std::span(bytes).subspan(c.offset), c.offset, bytes.size() - c.offset, "gen", &h, &needed)
            .isOk());
    auto payload = openGtnChunk(h, std::span(bytes).subspan(c.offset, c.bytes), "gen");
    EXPECT_TRUE(payload.isOk());
    EXPECT_TRUE(decodeLevelRecord(*payload, 0, "gen", context, &r).isOk());
    if (i < level) context = nextLevelRecordContext(context, r);
  }
  return {r, context};
}

// The file header chunk of a valid file (offset and size), its record in `h`.
std::pair<uint64_t, uint64_t> fileChunk(const std::vector<uint8_t>& bytes, ChunkTag tag, GtnFileHeader* h) {
  auto r = GtnReader::openMemory(std::string(bytes.begin(), bytes.end()), "gen");
  EXPECT_TRUE(r.isOk());
  *h = (*r)->file().header;
  for (const GtnChunkInfo& c : (*r)->file().chunks)
    if (c.tag == tag) return {c.offset, c.bytes};
  ADD_FAILURE() << "no chunk " << tag.str();
  return {0, 0};
}

// `bytes` with the chunk at [offset, offset + size) replaced by a chunk of `tag` holding `payload`
// (zstd-compressed where that helps, as the writer does, unless `zstd` is false), its checksum right.
std::vector<uint8_t> replaceChunk(const std::vector<uint8_t>& bytes, uint64_t offset, uint64_t size, ChunkTag tag,
                                  const std::vector<uint8_t>& payload, bool zstd = true) {
  std::vector<uint8_t> chunk;
  appendGtnChunk(chunk, tag, payload, false, zstd, kGtnZstdLevel);
  std::vector<uint8_t> out(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(offset));
  out.insert(out.end(), chunk.begin(), chunk.end());
  out.insert(out.end(), bytes.begin() + static_cast<ptrdiff_t>(offset + size), bytes.end());
  return out;
}

struct Sample {
  std::string name;
  std::function<TetMesh()> mesh;  // valid samples: the mesh it holds; must-fail samples: none
  std::function<std::vector<uint8_t>()> make;
};

Sample valid(std::string name, std::function<TetMesh()> mesh, std::function<std::vector<uint8_t>()> make) {
  Sample s;
  s.name = std::move(name);
  s.mesh = std::move(mesh);
  s.make = std::move(make);
  return s;
}

std::vector<Sample> samples() {
  std::vector<Sample> s;
  s.push_back(valid("cube.f32.dir.v2.0-d6.gtn", cubeF32, [] { return encodeFile(cubeF32(), options()); }));
  s.push_back(
      valid("cube.f64.fields.dir.v2.0-d6.gtn", cubeF64Fields, [] { return encodeFile(cubeF64Fields(), options()); }));
  s.push_back(valid("cube.f64.fields.nodir.v2.0-d6.gtn", cubeF64Fields,
                    [] { return encodeFile(cubeF64Fields(), options(false)); }));
  s.push_back(
      valid("unused-points.f32.dir.v2.0-d6.gtn", unusedPoints, [] { return encodeFile(unusedPoints(), options()); }));
  s.push_back(valid("two-components.f32.dir.v2.0-d6.gtn", twoComponents,
                    [] { return encodeFile(twoComponents(), options()); }));
  s.push_back(valid("repeated-components.f64.dir.v2.0-d6.gtn", repeatedComponents,
                    [] { return encodeFile(repeatedComponents(), options()); }));
  s.push_back(valid("decimals.f64.dir.v2.0-d6.gtn", decimals, [] { return encodeFile(decimals(), options()); }));
  s.push_back(valid("printed-singles.f64.dir.v2.0-d6.gtn", printedSingles,
                    [] { return encodeFile(printedSingles(), options()); }));
  s.push_back(valid("shift-exceptions.f64.dir.v2.0-d6.gtn", shiftExceptions,
                    [] { return encodeFile(shiftExceptions(), options()); }));
  s.push_back(valid("value-table.f32.dir.v2.0-d6.gtn", valueTable, [] { return encodeFile(valueTable(), options()); }));
  s.push_back(valid("packed-values.f32.dir.v2.0-d6.gtn", packedValues,
                    [] { return encodeFile(packedValues(), options(), nullptr, true); }));
  s.push_back(
      valid("curvilinear.f32.dir.v2.0-d6.gtn", curvilinear, [] { return encodeFile(curvilinear(), options()); }));
  s.push_back(valid("edge-points.f64.dir.v2.0-d6.gtn", edgePoints, [] { return encodeFile(edgePoints(), options()); }));
  s.push_back(
      valid("delaunay.f64.dir.v2.0-d6.gtn", delaunayMesh, [] { return encodeFile(delaunayMesh(), options()); }));
  s.push_back(valid("degenerate-sweep.f64.dir.v2.0-d6.gtn", degenerateSweep,
                    [] { return encodeFile(degenerateSweep(), options()); }));
  s.push_back(
      valid("pieces.f32.dir.v2.0-d6.gtn", piecesMesh, [] { return encodePiecesFile(piecesMesh(), options()); }));
  s.push_back(valid("levels.f32.dir.v2.0-d6.gtn", levelsMesh,
                    [] { return encodeWithTree(levelsMesh(), 2, options(), nullptr, 2, true); }));
  s.push_back(valid("levels-mtre3.f32.dir.v2.0-d6.gtn", levelsMesh,
                    [] { return encodeWithTree(levelsMesh(), 2, options(), nullptr, 3); }));
  s.push_back(valid("levels-mtre4.f32.dir.v2.0-d6.gtn", levelsMesh,
                    [] { return encodeWithTree(levelsMesh(), 2, options(), nullptr, 4); }));
  s.push_back(
      valid("levels-mtre5.f32.dir.v2.0-d6.gtn", levelsMesh, [] { return encodeWithTree(levelsMesh(), 2, options()); }));
  s.push_back(valid("wide-merge-tree.f32.dir.v2.0-d6.gtn", wideMesh,
                    [] { return encodeWithTree(wideMesh(), 0, options(), nullptr, 3, true); }));
  s.push_back(valid("grid-tree.f32.dir.v2.0-d6.gtn", gridTreeMesh,
                    [] { return encodeGridWithTree(gridTreeMesh(), 1, options()); }));
  s.push_back(valid("ancillary-chunk.f32.nodir.v2.0-d6.gtn", cubeF32, [] {
    const std::vector<uint8_t> note = {'a', 'n', 'o', 't', 'e'};
    return encodeFile(cubeF32(), options(false),
                      [&](GtnStreamWriter& w) { EXPECT_TRUE(w.addChunk(ChunkTag("xNOT"), note, true).isOk()); });
  }));
  s.push_back(valid("newer-minor.f32.dir.v2.9-d6.gtn", cubeF32, [] {
    std::vector<uint8_t> b = encodeFile(cubeF32(), options());
    const auto p = encodeGtnPrefix(2, 9);
    std::copy(p.begin(), p.end(), b.begin());
    return b;
  }));
  // Must fail.
  s.push_back({"fail.bad-magic-text-mode.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 b.erase(b.begin() + 4);  // CR LF -> LF, as a text-mode transfer does
                 return b;
               }});
  s.push_back({"fail.bad-checksum.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 b[chunkOffset(b, kTagPiece) + 40] ^= 0x04;  // past the header, in the payload
                 return b;
               }});
  s.push_back({"fail.truncated.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 b.resize(chunkOffset(b, kTagPiece) + 20);
                 return b;
               }});
  s.push_back({"fail.unknown-critical-chunk.v2.0-d6.gtn", nullptr, [] {
                 const std::vector<uint8_t> payload = {1, 2, 3};
                 return encodeFile(cubeF32(), options(false), [&](GtnStreamWriter& w) {
                   EXPECT_TRUE(w.addChunk(ChunkTag("XTRA"), payload, false).isOk());
                 });
               }});
  s.push_back({"fail.newer-major.v3.0.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 const auto p = encodeGtnPrefix(3, 0);
                 std::copy(p.begin(), p.end(), b.begin());
                 return b;
               }});
  s.push_back({"fail.trailing-bytes.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 b.push_back('\n');
                 return b;
               }});
  s.push_back({"fail.older-major.v1.0.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options());
                 const auto p = encodeGtnPrefix(1, 0);
                 std::copy(p.begin(), p.end(), b.begin());
                 return b;
               }});
  s.push_back({"fail.draft-5.v2.0-d5.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeFile(cubeF32(), options(false));
                 GtnFileHeader h;
                 const auto [offset, size] = fileChunk(b, kTagFileHeader, &h);
                 h.draft = 5;
                 return replaceChunk(b, offset, size, kTagFileHeader, encodeFileHeader(h));
               }});
  // Must fail: pieces.
  s.push_back({"fail.seam-missing.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodePiecesFile(piecesMesh(), options(false));
                 const GtnChunkInfo seam = levelChunk(b, kTagSeam);
                 b.erase(b.begin() + static_cast<ptrdiff_t>(seam.offset),
                         b.begin() + static_cast<ptrdiff_t>(seam.offset + seam.bytes));
                 return b;
               }});
  s.push_back({"fail.piece-tets-sum.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodePiecesFile(piecesMesh(), options(false));
                 auto [r, context] = levelRecord(b);
                 r.pieces[1].tets -= 1;  // the pieces hold one tetrahedron fewer than the level
                 const GtnChunkInfo lhdr = levelChunk(b, kTagLevelHeader);
                 return replaceChunk(b, lhdr.offset, lhdr.bytes, kTagLevelHeader, encodeLevelRecord(r, context), false);
               }});
  s.push_back({"fail.seam-class-repeats-piece.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodePiecesFile(piecesMesh(), options(false));
                 auto r = GtnReader::openMemory(std::string(b.begin(), b.end()), "gen");
                 EXPECT_TRUE(r.isOk());
                 std::vector<uint8_t> payload;
                 auto table = (*r)->readSeamTable(0, &payload);
                 EXPECT_TRUE(table.isOk());
                 std::vector<SeamClass> classes = table->classes;
                 std::vector<std::vector<uint8_t>> streams;
                 for (const auto& [at, n] : table->streams)
                   streams.emplace_back(payload.begin() + static_cast<ptrdiff_t>(at),
                                        payload.begin() + static_cast<ptrdiff_t>(at + n));
                 classes[0].pieces[1] = classes[0].pieces[0];  // the first class names its first piece twice
                 const GtnChunkInfo seam = levelChunk(b, kTagSeam);
                 return replaceChunk(b, seam.offset, seam.bytes, kTagSeam, encodeSeamTable(classes, streams));
               }});
  // Must fail: levels that name the next level's vertices.
  s.push_back({"fail.last-level-names-next.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodeWithTree(levelsMesh(), 2, options(false));
                 auto [r, context] = levelRecord(b, 2);
                 r.base = 1;  // the last level claims to name the vertices of a level the file lacks
                 const GtnChunkInfo lhdr = levelChunk(b, kTagLevelHeader, 2);
                 return replaceChunk(b, lhdr.offset, lhdr.bytes, kTagLevelHeader, encodeLevelRecord(r, context), false);
               }});
  s.push_back({"fail.base-of-several-pieces.v2.0-d6.gtn", nullptr, [] {
                 std::vector<uint8_t> b = encodePiecesFile(piecesMesh(), options(false));
                 auto [r, context] = levelRecord(b);
                 r.base = 1;  // a level of 4 pieces claims to name the next level's vertices
                 const GtnChunkInfo lhdr = levelChunk(b, kTagLevelHeader);
                 return replaceChunk(b, lhdr.offset, lhdr.bytes, kTagLevelHeader, encodeLevelRecord(r, context), false);
               }});
  return s;
}

// NAME.expected beside NAME.gtn: "key: value" lines (a key may repeat, as "point field" does),
// blank lines and "#" comments.
using Expected = std::multimap<std::string, std::string>;
Expected readExpected(const std::string& path) {
  Expected out;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path << ": missing";
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    const size_t colon = line.find(": ");
    EXPECT_NE(colon, std::string::npos) << path << " line " << n << ": not \"key: value\"";
    if (colon != std::string::npos) out.emplace(line.substr(0, colon), line.substr(colon + 2));
  }
  return out;
}
// The value of `key`, which must appear once.
std::string one(const Expected& e, const std::string& key) {
  EXPECT_EQ(e.count(key), 1u) << "key \"" << key << "\"";
  const auto it = e.find(key);
  return it == e.end() ? std::string() : it->second;
}
std::vector<std::string> all(const Expected& e, const std::string& key) {
  std::vector<std::string> out;
  for (auto [it, end] = e.equal_range(key); it != end; ++it) out.push_back(it->second);
  return out;
}
std::string expectedPath(const std::string& gtn_name) {
  return kDir + gtn_name.substr(0, gtn_name.size() - 4) + ".expected";
}

// A status as the .expected files name it.
std::string statusName(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidData: return "invalid data";
    case StatusCode::kUnsupported: return "unsupported";
    case StatusCode::kNotOurFile: return "not our file";
    case StatusCode::kVersionTooNew: return "version too new";
    case StatusCode::kUsage: return "usage";
    case StatusCode::kIo: return "io";
  }
  return "?";
}

// The fields as the .expected files list them: "NAME TYPE COMPONENTS".
std::vector<std::string> fieldLines(const std::vector<Field>& fields) {
  std::vector<std::string> out;
  for (const Field& f : fields)
    out.push_back(f.name + " " + scalarTypeName(f.type) + " " + std::to_string(f.components));
  return out;
}

// A must-fail file: the reader rejects it with the status and message its .expected file gives,
// naming the file.
void checkRejected(const std::string& path, const Expected& expected) {
  auto r = GtnReader::open(path);
  ASSERT_FALSE(r.isOk()) << "opened, but must fail with: " << one(expected, "message");
  EXPECT_EQ(statusName(r.status().code()), one(expected, "status")) << r.status().message();
  EXPECT_NE(r.status().message().find(one(expected, "message")), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
}

// A valid file: what the reader says of it and of its level 0 (`got`, decoded) is what its .expected
// file gives (whether it is opened by its directory is checked where it is opened without verifying).
void checkAsExpected(const GtnReader& reader, const TetMesh& got, const Expected& expected) {
  EXPECT_EQ(std::to_string(reader.file().major) + "." + std::to_string(reader.file().minor),
            one(expected, "format version"));
  EXPECT_EQ(std::to_string(reader.file().header.draft), one(expected, "draft revision"));
  EXPECT_EQ(reader.file().has_directory, one(expected, "directory") == "yes");
  EXPECT_EQ(scalarTypeName(got.coord_type), one(expected, "coordinates"));
  EXPECT_EQ(std::to_string(got.numPoints()), one(expected, "points"));
  EXPECT_EQ(std::to_string(got.numTets()), one(expected, "tetrahedra"));
  EXPECT_EQ(fieldLines(got.point_fields), all(expected, "point field"));
  EXPECT_EQ(fieldLines(got.cell_fields), all(expected, "cell field"));
  EXPECT_EQ(std::to_string(reader.levels()), one(expected, "levels"));
  for (size_t i = 0; i < reader.levels(); ++i) {
    const LevelHeader& h = reader.level(i).header;
    EXPECT_EQ(std::to_string(h.points) + " points, " + std::to_string(h.tets) + " tetrahedra, " +
                  std::to_string(h.merges) + " merges",
              one(expected, "level " + std::to_string(i)));
    EXPECT_EQ(std::to_string(reader.level(i).pieces.size()), one(expected, "level " + std::to_string(i) + " pieces"));
  }
}

// Every .gtn file has its .expected file and every .expected file its .gtn file.
TEST(GtnConformance, EveryFileHasItsExpectedOutcome) {
  std::set<std::string> gtn, expected;
  for (const auto& entry : std::filesystem::directory_iterator(kDir)) {
    const std::string name = entry.path().filename().string();
    const std::string ext = entry.path().extension().string();
    if (ext == ".gtn") gtn.insert(name.substr(0, name.size() - 4));
    if (ext == ".expected") expected.insert(name.substr(0, name.size() - 9));
  }
  EXPECT_FALSE(gtn.empty());
  EXPECT_EQ(gtn, expected);
  std::set<std::string> generated;
  for (const Sample& s : samples()) generated.insert(s.name.substr(0, s.name.size() - 4));
  EXPECT_EQ(gtn, generated);
}

TEST(GtnConformance, CommittedFilesDecodeOrFailAsExpected) {
  const char* update = std::getenv("GTN_UPDATE_GOLDEN");
  const bool regenerate = update && std::string(update) == "1";
  for (const Sample& s : samples()) {
    SCOPED_TRACE(s.name);
    const std::string path = kDir + s.name;
    if (regenerate) {
      const std::vector<uint8_t> b = s.make();
      test::writeFile(path, std::string(b.begin(), b.end()));
    }
    ASSERT_TRUE(test::fileExists(path)) << "missing; regenerate with GTN_UPDATE_GOLDEN=1";
    const Expected expected = readExpected(expectedPath(s.name));
    ASSERT_EQ(one(expected, "outcome"), s.mesh ? "valid" : "invalid") << expectedPath(s.name);
    if (!s.mesh) {
      checkRejected(path, expected);
      continue;
    }
    auto r = GtnReader::open(path);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const TetMesh want = s.mesh();
    TetMeshBuilder b;
    DecodeStats stats;
    const Status st = (*r)->decodeLevel(0, b, &stats);
    ASSERT_TRUE(st.isOk()) << st.message();
    const TetMesh& got = b.mesh();
    EXPECT_EQ(got.numPoints(), want.numPoints());
    EXPECT_EQ(got.numTets(), want.numTets());
    EXPECT_EQ(got.coord_type, want.coord_type);
    ASSERT_EQ(got.point_fields.size(), want.point_fields.size());
    ASSERT_EQ(got.cell_fields.size(), want.cell_fields.size());
    for (size_t i = 0; i < want.point_fields.size(); ++i) {
      EXPECT_EQ(got.point_fields[i].name, want.point_fields[i].name);
      EXPECT_EQ(got.point_fields[i].type, want.point_fields[i].type);
      EXPECT_EQ(got.point_fields[i].components, want.point_fields[i].components);
    }
    EXPECT_TRUE(test::canonicalMesh(got) == test::canonicalMesh(want)) << "decoded mesh differs from the generated one";
    if ((*r)->level(0).pieces.at(0).kind != kPieceStructured) {
      EXPECT_GT(stats.peak_live_vertices, 0u);  // a structured piece keeps no front
    }
    checkAsExpected(**r, got, expected);
    // Opened through the directory (when there is one), the same level decodes the same.
    GtnOpenOptions fast;
    fast.verify = false;
    auto lazy = GtnReader::open(path, fast);
    ASSERT_TRUE(lazy.isOk());
    EXPECT_EQ((*lazy)->openedByDirectory(), one(expected, "directory") == "yes");
    TetMeshBuilder b2;
    ASSERT_TRUE((*lazy)->decodeLevel(0, b2).isOk());
    EXPECT_EQ(b2.mesh().tets, got.tets);
    // Each field decoded alone (as a renderer decodes the one it shows) comes out as in the full
    // decode: the repeats and value forms of every stream are read, the values of the others skipped.
    const size_t np = got.point_fields.size(), nc = got.cell_fields.size();
    for (size_t i = 0; i < np + nc; ++i) {
      DecodeFields only;
      only.point.assign(np, false);
      only.cell.assign(nc, false);
      (i < np ? only.point[i] : only.cell[i - np]) = true;
      TetMeshBuilder alone;
      const Status sa = (*lazy)->decodeLevel(0, alone, nullptr, &only);
      ASSERT_TRUE(sa.isOk()) << sa.message();
      const Field& full_field = i < np ? got.point_fields[i] : got.cell_fields[i - np];
      const Field& alone_field = i < np ? alone.mesh().point_fields[i] : alone.mesh().cell_fields[i - np];
      EXPECT_TRUE(full_field.bytes == alone_field.bytes) << full_field.name << " decoded alone differs";
      EXPECT_EQ(alone.mesh().tets, got.tets);
    }
  }
}

// The merge tree of more than 2^17 points decodes to the ranking's tree: the same merges as the
// levels file's grid (the unused points are never merged), in the wide file's vertex numbering. The
// file's tree was ranked in the greedy order (RankingOptions::lazy off).
TEST(GtnConformance, WideMergeTreeDecodes) {
  auto r = GtnReader::open(kDir + "wide-merge-tree.f32.dir.v2.0-d6.gtn");
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ((*r)->levels(), 1u);
  TetMeshBuilder b0;
  ASSERT_TRUE((*r)->decodeLevel(0, b0).isOk());
  const TetMesh& level0 = b0.mesh();
  ASSERT_EQ(level0.numPoints(), kWidePoints);
  auto payload = (*r)->mergeTreePayload(0);
  ASSERT_TRUE(payload.isOk());
  ASSERT_TRUE(payload->has_value());
  auto tree = decodeMergeTree(**payload, level0.numPoints(), "wide level 0", &level0);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  RankingOptions greedy;
  greedy.lazy = false;
  auto ranked = rankMerges(wideMesh(), greedy, nullptr);
  ASSERT_TRUE(ranked.isOk());
  EXPECT_EQ(tree->merges, ranked->merges);
  EXPECT_GT(tree->merges, 150u);
  EXPECT_EQ(tree->boundaryMergesUpTo(tree->merges), ranked->boundaryMergesUpTo(ranked->merges));
  EXPECT_EQ(tree->tetsRemovedUpTo(tree->merges), ranked->tetsRemovedUpTo(ranked->merges));
  for (uint64_t n : {uint64_t{1}, uint64_t{50}, tree->merges}) {
    auto got = applyMerges(level0, *tree, n);
    auto want = applyMerges(wideMesh(), *ranked, n);
    ASSERT_TRUE(got.isOk() && want.isOk());
    EXPECT_TRUE(test::canonicalMesh(*got) == test::canonicalMesh(*want)) << n << " merges";
  }
}

// The files with levels: every stored level is what its merges make of level 0, with level 0's merge
// tree as the file stores it, and on-the-fly simplification from the finest stored level gives the
// same mesh as applying the merges to level 0, at every merge count. levels.f32 stores MTRE payload
// version 2, levels-mtre3.f32 version 3 (parents among the neighbours in the level's mesh),
// levels-mtre4.f32 version 4 (batches), levels-mtre5.f32 version 5 (removed counts and boundary bits
// inferred, each band's children among its level's own vertices).
void expectLevelsAndTreesAgree(const std::string& path, int version);

TEST(GtnConformance, LevelsAndMergeTreesAgree) {
  for (const auto& [name, version] : {std::pair<std::string, int>{"levels.f32.dir.v2.0-d6.gtn", 2},
                                      std::pair<std::string, int>{"levels-mtre3.f32.dir.v2.0-d6.gtn", 3},
                                      std::pair<std::string, int>{"levels-mtre4.f32.dir.v2.0-d6.gtn", 4},
                                      std::pair<std::string, int>{"levels-mtre5.f32.dir.v2.0-d6.gtn", 5}}) {
    SCOPED_TRACE(name);
    expectLevelsAndTreesAgree(kDir + name, version);
  }
}

// grid-tree.f32: level 0 is a structured piece whose merge tree codes its parents as grid places
// (MTRE version 5, parent_form 4, the block's dims in the header): it decodes without the level, its
// batches are ordered by id, level 1 is what its merges make of level 0, and every merge count on the
// fly is level 0 after that many merges.
TEST(GtnConformance, GridTreeDecodesWithoutTheLevel) {
  auto r = GtnReader::open(kDir + "grid-tree.f32.dir.v2.0-d6.gtn");
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ((*r)->levels(), 2u);
  ASSERT_EQ((*r)->level(0).pieces.size(), 1u);
  EXPECT_EQ((*r)->level(0).pieces[0].kind, kPieceStructured);
  EXPECT_EQ((*r)->level(0).base, 0);
  auto payload = (*r)->mergeTreePayload(0);
  ASSERT_TRUE(payload.isOk() && payload->has_value());
  auto h = readMergeTreeHeader(**payload, 216, "level 0");
  ASSERT_TRUE(h.isOk()) << h.status().message();
  EXPECT_EQ(h->version, 5);
  EXPECT_EQ(h->inferred, 0);
  EXPECT_FALSE(h->needs_mesh);
  EXPECT_EQ(h->grid, (std::array<uint32_t, 3>{6, 6, 6}));
  auto tree = decodeMergeTree(**payload, 216, "level 0", nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  EXPECT_EQ(tree->field, "density");
  EXPECT_GT(tree->batches.size(), 4u);
  TetMeshBuilder b0, b1;
  ASSERT_TRUE((*r)->decodeLevel(0, b0).isOk());
  ASSERT_TRUE((*r)->decodeLevel(1, b1).isOk());
  const uint64_t n1 = (*r)->level(1).header.merges;
  EXPECT_EQ(n1, 108u);
  auto want = applyMerges(b0.mesh(), *tree, n1);
  ASSERT_TRUE(want.isOk());
  EXPECT_TRUE(test::canonicalMesh(b1.mesh()) == test::canonicalMesh(*want));
  for (uint64_t n = 0; n <= tree->merges; n += 9) {
    TetMeshBuilder bn;
    SimplifyPlan plan;
    ASSERT_TRUE(streamSimplified(**r, n, bn, &plan).isOk()) << n;
    auto expect = applyMerges(b0.mesh(), *tree, n);
    ASSERT_TRUE(expect.isOk());
    EXPECT_TRUE(test::canonicalMesh(bn.mesh()) == test::canonicalMesh(*expect))
        << n << " merges, from level " << plan.level;
  }
}

void expectLevelsAndTreesAgree(const std::string& path, int version) {
  auto r = GtnReader::open(path);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ((*r)->levels(), 3u);
  TetMeshBuilder b0;
  std::vector<uint32_t> ids;  // level 0's vertices' ids in level 1
  ASSERT_TRUE((*r)->decodeLevel(0, b0, nullptr, nullptr, &ids).isOk());
  const TetMesh level0 = b0.mesh();
  // Levels 0 and 1 name the next level's vertices (spec 7.7) and store only their merges down to it;
  // level 2 stores all its vertices and the rest of the tree.
  EXPECT_EQ((*r)->level(0).base, 1);
  EXPECT_EQ((*r)->level(1).base, 1);
  EXPECT_EQ((*r)->level(2).base, 0);
  auto payload = (*r)->mergeTreePayload(0);
  ASSERT_TRUE(payload.isOk());
  ASSERT_TRUE(payload->has_value());
  EXPECT_EQ((**payload)[0], version);
  auto header = readMergeTreeHeader(**payload, level0.numPoints(), "level 0");
  ASSERT_TRUE(header.isOk()) << header.status().message();
  // Version 5 codes level 0's children among the vertices level 1 lacks, which the level names.
  EXPECT_EQ(header->needs_next_ids, version >= 5);
  EXPECT_EQ(header->inferred, version >= 5 ? 7 : 0);
  auto own = decodeMergeTree(**payload, level0.numPoints(), "level 0", &level0, UINT64_MAX, &ids);
  ASSERT_TRUE(own.isOk()) << own.status().message();
  EXPECT_EQ(own->merges, (*r)->level(1).header.merges);
  auto whole = wholeMergeTree(**r, 0);
  ASSERT_TRUE(whole.isOk()) << whole.status().message();
  ASSERT_TRUE(whole->has_value());
  const MergeTree* tree = &**whole;
  EXPECT_GT(tree->merges, 162u) << "enough merges for both levels";
  EXPECT_EQ(tree->field, "density");
  for (size_t i = 0; i < 3; ++i) {
    const uint64_t n = (*r)->level(i).header.merges;
    EXPECT_EQ(n, levelMerges(static_cast<int>(i), level0.numPoints(), tree->merges));
    TetMeshBuilder bi;
    ASSERT_TRUE((*r)->decodeLevel(i, bi).isOk());
    auto want = applyMerges(level0, *tree, n);
    ASSERT_TRUE(want.isOk());
    EXPECT_TRUE(test::canonicalMesh(bi.mesh()) == test::canonicalMesh(*want)) << "level " << i;
  }
  for (uint64_t n = 0; n <= tree->merges; n += 7) {
    TetMeshBuilder bn;
    SimplifyPlan plan;
    ASSERT_TRUE(streamSimplified(**r, n, bn, &plan).isOk()) << n;
    auto want = applyMerges(level0, *tree, n);
    ASSERT_TRUE(want.isOk());
    EXPECT_TRUE(test::canonicalMesh(bn.mesh()) == test::canonicalMesh(*want))
        << n << " merges, from level " << plan.level;
  }
}

// The packed-values file holds its `stress` stream in packed form (spec 10.2.1), the other streams
// range coded (the split form of cell fields is exercised by tests/codec/packed_values_test.cpp).
TEST(GtnConformance, PackedValuesFileHasAPackedStream) {
  auto enc = encodeLevel(packedValues(), EncodeOptions{});
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  EXPECT_TRUE(isPackedStream(enc->point_fields[0]));
  EXPECT_FALSE(isPackedStream(enc->point_fields[1]));
  EXPECT_EQ(enc->cell_fields[0][0], 0);
  EXPECT_EQ(enc->geometry[0], 0);
}

TEST(GtnConformance, GeneratorIsDeterministic) {
  for (const Sample& s : samples()) EXPECT_EQ(s.make(), s.make()) << s.name;
}

}  // namespace
}  // namespace gtn
