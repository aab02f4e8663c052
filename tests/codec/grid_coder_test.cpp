// The structured-piece coder (spec/gtn-format-2.0-draft.md section 11): generated grids of every
// rule and exception decode bit for bit, the rule's tables are the importers', the real PLOT3D
// datasets decode to the importer's tetrahedra, and corrupt or truncated pieces fail cleanly.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "codec/codec_test_util.h"
#include "codec/grid_coder.h"
#include "codec/value_coder.h"
#include "convert/import.h"
#include "mesh/hex_split.h"
#include "mesh/predicates.h"
#include "test_util.h"

namespace gtn {
namespace {

// Node (i, j, k)'s position on a smoothly warped grid.
std::array<double, 3> warped(uint32_t i, uint32_t j, uint32_t k) {
  return {i + 0.1 * std::sin(0.7 * j + 0.3 * k), j + 0.05 * i * std::cos(0.2 * k), 1.3 * k + 0.02 * i * j};
}

// A mesh holding `layout`'s vertices and tetrahedra: nodes on the warped grid (a Steiner point at
// the mean of its cell's corners), coordinates in `coord_type`, point fields of several types (one
// constant) and, with `cell_fields`, two cell fields.
TetMesh meshOf(const GridLayout& layout, ScalarType coord_type, bool cell_fields = false) {
  TetMesh m;
  m.coord_type = coord_type;
  const uint32_t ni = layout.dims[0], nj = layout.dims[1], nk = layout.dims[2];
  std::vector<bool> aliased(layout.nodes(), false);
  for (const auto& [a, t] : layout.aliases) aliased[a] = true;
  const bool single = coord_type == ScalarType::kFloat32;
  auto inType = [single](double v) {
    if (!single) return v;
    volatile float f = static_cast<float>(v);  // volatile: GCC 12 at -O3 dropped the rounding here
    return static_cast<double>(f);
  };
  std::vector<std::array<double, 3>> node_pos;
  for (uint32_t k = 0; k < nk; ++k)
    for (uint32_t j = 0; j < nj; ++j)
      for (uint32_t i = 0; i < ni; ++i) {
        const std::array<double, 3> w = warped(i, j, k);
        const std::array<double, 3> p = {inType(w[0]), inType(w[1]), inType(w[2])};
        node_pos.push_back(p);
        if (!aliased[node_pos.size() - 1]) m.coords.insert(m.coords.end(), p.begin(), p.end());
      }
  const uint32_t ci = ni - 1, cj = nj - 1;
  for (const GridException& x : layout.exceptions) {
    const uint32_t i = x.cell % ci, j = (x.cell / ci) % cj, k = x.cell / (ci * cj);
    for (int e = 0; e < x.extras; ++e) {
      double c[3] = {0, 0, 0};
      for (uint32_t q = 0; q < 8; ++q) {
        const auto& p = node_pos[(i + (q == 1 || q == 2 || q == 5 || q == 6)) +
                                 ni * ((j + (q == 2 || q == 3 || q == 6 || q == 7)) + nj * (k + (q >= 4)))];
        for (int a = 0; a < 3; ++a) c[a] += p[a];
      }
      for (int a = 0; a < 3; ++a) m.coords.push_back(inType(c[a] / 8 + 0.01 * e));
    }
  }
  m.tets = gridTets(layout);
  const size_t n = m.numPoints();
  Field pressure("pressure", 1, ScalarType::kFloat32, n), velocity("velocity", 3, ScalarType::kFloat64, n),
      label("label", 1, ScalarType::kInt32, n), flags("flags", 2, ScalarType::kUInt8, n),
      zero("zero", 1, ScalarType::kFloat32, n), big("big", 1, ScalarType::kInt64, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = m.point(v);
    pressure.set<float>(v, 0, static_cast<float>(std::sin(p[0] * 0.3) * std::exp(0.1 * p[1]) + p[2]));
    for (uint32_t c = 0; c < 3; ++c) velocity.set<double>(v, c, std::cos(p[c] * 0.2 + c) * (1.0 + p[(c + 1) % 3]));
    label.set<int32_t>(v, 0, static_cast<int32_t>(std::floor(p[0] * 10 - p[1] * 7)));
    flags.set<uint8_t>(v, 0, static_cast<uint8_t>(v % 7));
    flags.set<uint8_t>(v, 1, static_cast<uint8_t>(p[2] > 2 ? 255 : 0));
    zero.set<float>(v, 0, 0.0f);
    big.set<int64_t>(v, 0, static_cast<int64_t>(v) * -1000000007LL);
  }
  m.point_fields = {pressure, velocity, label, flags, zero, big};
  if (cell_fields) {
    Field region("region", 1, ScalarType::kInt32, m.numTets()),
        quality("quality", 2, ScalarType::kFloat64, m.numTets());
    for (size_t t = 0; t < m.numTets(); ++t) {
      region.set<int32_t>(t, 0, m.point(m.tets[t][0])[0] < 3 ? 1 : 2);
      quality.set<double>(t, 0, 1.0 / (1.0 + t));
      quality.set<double>(t, 1, -static_cast<double>(t % 5));
    }
    m.cell_fields = {region, quality};
  }
  return m;
}

void expectSameLayout(const GridLayout& a, const GridLayout& b) {
  for (int d = 0; d < 3; ++d) EXPECT_EQ(a.dims[d], b.dims[d]);
  EXPECT_EQ(a.split, b.split);
  EXPECT_EQ(a.parity, b.parity);
  EXPECT_EQ(a.left_handed, b.left_handed);
  EXPECT_EQ(a.cell_values_per_cell, b.cell_values_per_cell);
  EXPECT_EQ(a.aliases, b.aliases);
  ASSERT_EQ(a.exceptions.size(), b.exceptions.size());
  for (size_t x = 0; x < a.exceptions.size(); ++x) {
    EXPECT_EQ(a.exceptions[x].cell, b.exceptions[x].cell);
    EXPECT_EQ(a.exceptions[x].kind, b.exceptions[x].kind);
    EXPECT_EQ(a.exceptions[x].extras, b.exceptions[x].extras);
    EXPECT_EQ(a.exceptions[x].tets, b.exceptions[x].tets);
  }
}

// Points, tetrahedra and every field equal bit for bit.
void expectSameMesh(const TetMesh& a, const TetMesh& b) {
  ASSERT_EQ(a.coords.size(), b.coords.size());
  for (size_t i = 0; i < a.coords.size(); ++i) {
    if (std::memcmp(&a.coords[i], &b.coords[i], sizeof(double)) != 0) {
      ADD_FAILURE() << "coordinate " << i << " differs: " << a.coords[i] << " against " << b.coords[i];
      break;
    }
  }
  EXPECT_TRUE(a.tets == b.tets) << "tetrahedra differ";
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (size_t f = 0; f < a.point_fields.size(); ++f) {
    EXPECT_EQ(a.point_fields[f].name, b.point_fields[f].name);
    EXPECT_TRUE(a.point_fields[f].bytes == b.point_fields[f].bytes) << "point field " << a.point_fields[f].name;
  }
  ASSERT_EQ(a.cell_fields.size(), b.cell_fields.size());
  for (size_t f = 0; f < a.cell_fields.size(); ++f)
    EXPECT_TRUE(a.cell_fields[f].bytes == b.cell_fields[f].bytes) << "cell field " << a.cell_fields[f].name;
}

// Encodes, decodes and compares; returns the piece's bytes.
std::vector<uint8_t> roundTripOnce(const GridLayout& layout, const TetMesh& mesh, GridEncodeReport* report,
                                   const GridEncodeOptions& options) {
  auto piece = encodeGridPiece(layout, mesh, options, report);
  EXPECT_TRUE(piece.isOk()) << piece.status().message();
  if (!piece.isOk()) return {};
  auto back = decodeGridPiece(*piece, gridSchemaOf(mesh), "test piece");
  EXPECT_TRUE(back.isOk()) << back.status().message();
  if (!back.isOk()) return *piece;
  expectSameLayout(back->layout, layout);
  expectSameMesh(back->mesh, mesh);
  return *piece;
}

// The same in the default value forms and with form 1 (static prefix codes) forced on every value
// stream that allows it; returns the default's bytes.
std::vector<uint8_t> roundTrip(const GridLayout& layout, const TetMesh& mesh, GridEncodeReport* report = nullptr,
                               const GridEncodeOptions& options = {}) {
  GridEncodeOptions fast = options;
  fast.value_form = 1;
  GridEncodeReport fast_report;
  roundTripOnce(layout, mesh, &fast_report, fast);
  EXPECT_TRUE(std::count(fast_report.stream_forms.begin(), fast_report.stream_forms.end(), 1) > 0)
      << "no stream took form 1";
  return roundTripOnce(layout, mesh, report, options);
}

GridLayout grid(uint32_t ni, uint32_t nj, uint32_t nk, uint8_t split, uint8_t parity = 0, bool left = false) {
  GridLayout l;
  l.dims[0] = ni, l.dims[1] = nj, l.dims[2] = nk;
  l.split = split;
  l.parity = parity;
  l.left_handed = left;
  return l;
}

TEST(GridCoder, RuleTablesAreTheImportersGridSplitter) {
  // gridTets of a whole block equals the tetrahedra of mesh/hex_split.h, cell by cell, parity by
  // parity, as the importers write them (codec_test_util's gridMesh splits with parity 0).
  for (int split : {5, 6}) {
    TetMesh m = test::gridMesh(5, 4, 3, split);
    EXPECT_TRUE(m.tets == gridTets(grid(5, 4, 3, static_cast<uint8_t>(split)))) << "split " << split;
  }
  // Parity 1 swaps the even and odd tables.
  std::vector<Tet> odd;
  const uint32_t h[8] = {0, 1, 4, 3, 12, 13, 16, 15};  // cell (0, 0, 0) of a 3 x 4 x k grid
  splitHexFive(h, true, odd);
  const std::vector<Tet> tets = gridTets(grid(3, 4, 2, 5, 1));
  ASSERT_GE(tets.size(), 5u);
  EXPECT_TRUE(std::equal(odd.begin(), odd.end(), tets.begin()));
}

TEST(GridCoder, RuleGridTetsAreGridTetsByIndex) {
  // Every split, parity and handedness, thin blocks (a dimension of 2: one cell across) included.
  for (const GridLayout& l : {grid(9, 7, 6, 5, 0), grid(9, 7, 6, 5, 1), grid(8, 7, 5, 6), grid(6, 5, 4, 5, 1, true),
                              grid(5, 4, 4, 6, 0, true), grid(2, 2, 2, 5, 0), grid(2, 3, 2, 6), grid(4, 2, 3, 5, 1),
                              grid(3, 5, 2, 5, 0, true), grid(301, 257, 3, 6)}) {
    SCOPED_TRACE("dims " + std::to_string(l.dims[0]) + " " + std::to_string(l.dims[1]) + " " +
                 std::to_string(l.dims[2]) + " split " + std::to_string(l.split) + " parity " +
                 std::to_string(l.parity) + (l.left_handed ? " left" : ""));
    const std::vector<Tet> tets = gridTets(l);
    const RuleGridTets rule(l);
    ASSERT_EQ(rule.size(), tets.size());
    EXPECT_EQ(rule.points(), l.nodes());
    for (size_t t = 0; t < tets.size(); ++t) ASSERT_EQ(rule[t], tets[t]) << "tetrahedron " << t;
    EXPECT_TRUE(rule.sameAs(tets));
    // One vertex changed, one tetrahedron missing: not the same.
    std::vector<Tet> changed = tets;
    changed[changed.size() / 2][1] ^= 1;
    EXPECT_FALSE(rule.sameAs(changed));
    changed = tets;
    changed.pop_back();
    EXPECT_FALSE(rule.sameAs(changed));
  }
}

TEST(GridCoder, SplitFiveBothParitiesAndSplitSix) {
  for (const GridLayout& l : {grid(9, 7, 6, 5, 0), grid(9, 7, 6, 5, 1), grid(8, 7, 5, 6)}) {
    SCOPED_TRACE("split " + std::to_string(l.split) + " parity " + std::to_string(l.parity));
    const TetMesh m = meshOf(l, ScalarType::kFloat32);
    EXPECT_EQ(m.numTets(), l.cells() * l.split);
    // Every rule tetrahedron of a right-handed grid is positively oriented.
    for (const Tet& t : m.tets) EXPECT_GT(orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])), 0);
    roundTrip(l, m);
  }
}

TEST(GridCoder, LeftHandedBlock) {
  GridLayout l = grid(6, 5, 4, 5, 1, true);
  TetMesh m = meshOf(l, ScalarType::kFloat32);
  // The tetrahedra have their last two corners exchanged: as the rule's on a mirrored block.
  GridLayout right = l;
  right.left_handed = false;
  const std::vector<Tet> r = gridTets(right);
  ASSERT_EQ(r.size(), m.tets.size());
  for (size_t t = 0; t < r.size(); ++t) EXPECT_EQ(m.tets[t], (Tet{r[t][0], r[t][1], r[t][3], r[t][2]}));
  roundTrip(l, m);
  GridLayout six = grid(5, 4, 4, 6, 0, true);
  roundTrip(six, meshOf(six, ScalarType::kFloat64));
}

TEST(GridCoder, Float64CoordinatesAndConstantFields) {
  const GridLayout l = grid(10, 6, 5, 5);
  const TetMesh m = meshOf(l, ScalarType::kFloat64, true);
  GridEncodeReport report;
  roundTrip(l, m, &report);
  // The constant float field "zero" costs next to nothing: its stream is a few bytes.
  ASSERT_EQ(report.point_fields.size(), 6u);
  EXPECT_LT(report.point_fields[4], 40u);
  EXPECT_EQ(report.forms.size(), 3u + 1 + 3 + 1 + 2 + 1 + 1);
}

TEST(GridCoder, BlankedCells) {
  GridLayout l = grid(7, 6, 5, 5);
  for (uint32_t c : {0u, 7u, 8u, 9u, 40u, static_cast<uint32_t>(l.cells() - 1)})
    l.exceptions.push_back({c, GridException::kBlanked, 0, {}});
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  EXPECT_EQ(m.numTets(), (l.cells() - 6) * 5);
  GridEncodeReport report;
  roundTrip(l, m, &report);
  EXPECT_GT(report.excp, 0u);
}

// The 12 tetrahedra of a cell split around its Steiner point (corner 8): the cone over each face's
// two triangles, cut along the rule's diagonals (here the 6-split's, through corner 0 or 6).
std::vector<std::array<uint8_t, 4>> steinerCell() {
  return {{0, 1, 2, 8}, {0, 2, 3, 8}, {4, 6, 5, 8}, {4, 7, 6, 8}, {0, 5, 1, 8}, {0, 4, 5, 8},
          {3, 2, 6, 8}, {3, 6, 7, 8}, {0, 3, 7, 8}, {0, 7, 4, 8}, {1, 5, 6, 8}, {1, 6, 2, 8}};
}

TEST(GridCoder, ExplicitCellWithSteinerPointAndFlippedCell) {
  GridLayout l = grid(6, 5, 4, 6);
  l.exceptions.push_back({3, GridException::kExplicit, 1, steinerCell()});
  // A cell of two tetrahedra only, one listed in another vertex order (what an importer's flip gives).
  l.exceptions.push_back({10, GridException::kExplicit, 0, {{0, 1, 2, 6}, {0, 3, 6, 2}}});
  l.exceptions.push_back({25, GridException::kExplicit, 1, steinerCell()});
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  EXPECT_EQ(m.numPoints(), l.nodes() + 2);
  EXPECT_EQ(m.numTets(), (l.cells() - 3) * 6 + 12 + 2 + 12);
  roundTrip(l, m);
}

TEST(GridCoder, WeldedNodes) {
  // An O-grid: the last i-plane is the first one again, as after --weld.
  GridLayout l = grid(8, 5, 4, 6);
  const uint32_t ni = 8, nj = 5, nk = 4;
  for (uint32_t k = 0; k < nk; ++k)
    for (uint32_t j = 0; j < nj; ++j) l.aliases.emplace_back(ni - 1 + ni * (j + nj * k), ni * (j + nj * k));
  const TetMesh m = meshOf(l, ScalarType::kFloat32);
  EXPECT_EQ(m.numPoints(), l.nodes() - nj * nk);
  // The last cells of each row use the first nodes of the row.
  EXPECT_EQ(m.tets[6 * (ni - 2)][1], 0u);  // corner 1 of cell (6, 0, 0) is node (7, 0, 0), which is node 0
  roundTrip(l, m);
}

TEST(GridCoder, CellFieldsPerCellAndPerTetrahedron) {
  GridLayout l = grid(7, 5, 4, 5, 1);
  l.exceptions.push_back({5, GridException::kBlanked, 0, {}});
  TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  roundTrip(l, m);  // per tetrahedron: values differ within cells
  // Values constant per cell (a cell label and a cell density, as VTK structured datasets carry).
  const std::vector<Tet> tets = gridTets(l);
  Field label("label", 1, ScalarType::kUInt16, tets.size()), density("density", 1, ScalarType::kFloat32, tets.size());
  size_t t = 0;
  for (uint32_t cell = 0; cell < l.cells(); ++cell) {
    if (cell == 5) continue;
    for (int q = 0; q < 5; ++q, ++t) {
      label.set<uint16_t>(t, 0, static_cast<uint16_t>(cell / 9));
      density.set<float>(t, 0, static_cast<float>(std::sin(0.1 * cell)));
    }
  }
  m.cell_fields = {label, density};
  l.cell_values_per_cell = true;
  GridEncodeReport per_cell, per_tet;
  roundTrip(l, m, &per_cell);
  GridLayout l2 = l;
  l2.cell_values_per_cell = false;
  roundTrip(l2, m, &per_tet);
  EXPECT_LT(per_cell.cell_fields[1], per_tet.cell_fields[1]);
  // The encoder refuses per-cell coding of values that differ within a cell.
  m.cell_fields[0].set<uint16_t>(1, 0, 999);
  EXPECT_FALSE(encodeGridPiece(l, m).isOk());
}

TEST(GridCoder, PredictorChosenByMeasurement) {
  // f = i * g(j, k) with g noisy: exact along i for the linear predictor, not for Lorenzo.
  const GridLayout l = grid(12, 9, 7, 5);
  TetMesh m = meshOf(l, ScalarType::kFloat32);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.5f, 2.0f);
  std::vector<float> g(9 * 7);
  for (float& x : g) x = u(rng);
  Field f("ramp", 1, ScalarType::kFloat32, m.numPoints());
  for (uint32_t n = 0; n < l.nodes(); ++n) f.set<float>(n, 0, static_cast<float>(n % 12) * g[n / 12]);
  m.point_fields = {f};
  GridEncodeReport chosen, lorenzo;
  roundTrip(l, m, &chosen);
  GridEncodeOptions force;
  force.predictor = 0;
  roundTrip(l, m, &lorenzo, force);
  ASSERT_EQ(chosen.predictors.size(), 4u);
  EXPECT_NE(chosen.predictors[3], 0) << "the ramp along i should not take Lorenzo";
  EXPECT_LT(chosen.point_fields[0] * 2, lorenzo.point_fields[0]);
}

TEST(GridCoder, DecimalAndTableForms) {
  const GridLayout l = grid(20, 12, 10, 6);
  TetMesh m = meshOf(l, ScalarType::kFloat64);
  Field dec("printed", 1, ScalarType::kFloat64, m.numPoints()),
      levels("levels", 1, ScalarType::kFloat64, m.numPoints());
  std::mt19937 rng(3);
  for (size_t v = 0; v < m.numPoints(); ++v) {
    dec.set<double>(v, 0, std::round(std::sin(0.05 * v) * 1e4 + rng() % 7) / 1e4);  // 4 decimal places
    levels.set<double>(v, 0, std::exp(static_cast<double>(rng() % 5)));             // 5 distinct values, no pattern
  }
  m.point_fields = {dec, levels};
  GridEncodeReport report;
  roundTrip(l, m, &report);
  ASSERT_EQ(report.forms.size(), 5u);
  EXPECT_EQ(report.forms[3], "decimal 4");
  EXPECT_EQ(report.forms[4], "table 5");
}

TEST(GridCoder, MatchFindsRuleAndExceptions) {
  GridLayout l = grid(7, 6, 5, 5, 1, true);
  l.exceptions.push_back({4, GridException::kBlanked, 0, {}});
  l.exceptions.push_back({11, GridException::kExplicit, 1, steinerCell()});
  l.exceptions.push_back({12, GridException::kExplicit, 0, {{0, 1, 3, 4}}});
  const TetMesh m = meshOf(l, ScalarType::kFloat32);
  auto found = matchGridLayout(m, l.dims);
  ASSERT_TRUE(found.isOk()) << found.status().message();
  expectSameLayout(*found, l);
  // Tetrahedra out of cell order are no grid.
  TetMesh shuffled = m;
  std::swap(shuffled.tets[0], shuffled.tets[40]);
  EXPECT_FALSE(matchGridLayout(shuffled, l.dims).isOk());
}

TEST(GridCoder, EncoderRejectsAMeshThatIsNotTheLayout) {
  const GridLayout l = grid(5, 4, 3, 5);
  TetMesh m = meshOf(l, ScalarType::kFloat32);
  std::swap(m.tets[3][2], m.tets[3][3]);
  auto piece = encodeGridPiece(l, m);
  ASSERT_FALSE(piece.isOk());
  EXPECT_NE(piece.status().message().find("tetrahedra are not the layout's"), std::string::npos);
  GridLayout bad = l;
  bad.exceptions.push_back({3, GridException::kExplicit, 0, {{0, 0, 1, 2}}});
  EXPECT_FALSE(encodeGridPiece(bad, meshOf(l, ScalarType::kFloat32)).isOk());
}

class GridCoderCorrupt : public ::testing::TestWithParam<int> {};

TEST_P(GridCoderCorrupt, CorruptAndTruncatedPiecesFailCleanly) {
  GridLayout l = grid(6, 5, 4, 5);
  l.exceptions.push_back({2, GridException::kBlanked, 0, {}});
  l.exceptions.push_back({9, GridException::kExplicit, 1, steinerCell()});
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  GridEncodeOptions options;
  options.value_form = GetParam();
  GridEncodeReport report;
  const std::vector<uint8_t> piece = roundTripOnce(l, m, &report, options);
  EXPECT_EQ(report.stream_forms[0], GetParam());
  ASSERT_FALSE(piece.empty());
  const GridSchema schema = gridSchemaOf(m);
  // Every truncation fails, naming the piece.
  for (size_t n = 0; n < piece.size(); ++n) {
    auto r = decodeGridPiece(std::span<const uint8_t>(piece.data(), n), schema, "cut piece");
    ASSERT_FALSE(r.isOk()) << "truncated to " << n << " bytes";
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
    EXPECT_NE(r.status().message().find("cut piece"), std::string::npos) << r.status().message();
  }
  // Flipped bytes fail or decode to something else, never crash; in the header they fail.
  std::mt19937 rng(11);
  size_t failed = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<uint8_t> bad = piece;
    bad[rng() % bad.size()] ^= static_cast<uint8_t>(1 + rng() % 255);
    auto r = decodeGridPiece(bad, schema, "bad piece");
    if (!r.isOk()) {
      ++failed;
      EXPECT_EQ(r.status().code(), StatusCode::kInvalidData) << r.status().message();
    }
  }
  // Form 0's range-coded streams end cleanly only when intact; a flipped raw bit of a form-1 stream
  // decodes to another value (the container's chunk checksum catches those).
  EXPECT_GT(failed, GetParam() == 0 ? 300u : 200u);
  // The streams decode in parallel: a piece damaged in several places fails with the first damaged
  // stream's message, or decodes to the same mesh, whatever the number of threads.
  tbb::task_arena one(1);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<uint8_t> bad = piece;
    for (int k = 0; k < 3; ++k)
      bad[piece.size() / 2 + rng() % (piece.size() / 2)] ^= static_cast<uint8_t>(1 + rng() % 255);
    auto many = decodeGridPiece(bad, schema, "bad piece");
    StatusOr<DecodedGridPiece> alone = invalidData("not run");
    one.execute([&] { alone = decodeGridPiece(bad, schema, "bad piece"); });
    ASSERT_EQ(many.isOk(), alone.isOk()) << trial;
    if (!many.isOk()) {
      EXPECT_EQ(many.status().message(), alone.status().message());
    } else {
      EXPECT_EQ(many->mesh.coords, alone->mesh.coords);
      EXPECT_EQ(many->mesh.tets, alone->mesh.tets);
      ASSERT_EQ(many->mesh.point_fields.size(), alone->mesh.point_fields.size());
      for (size_t f = 0; f < many->mesh.point_fields.size(); ++f)
        EXPECT_EQ(many->mesh.point_fields[f].bytes, alone->mesh.point_fields[f].bytes);
    }
  }
  // A header claiming a huge block in a few bytes is rejected before allocating.
  std::vector<uint8_t> huge = {0, 0, 0, 0, 0xFF, 0xFF, 0x03, 0xFF, 0xFF, 0x03, 0xFF, 0x03, 5, 0, 0, 0, 0};
  auto r = decodeGridPiece(huge, schema, "huge piece");
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find("dims"), std::string::npos) << r.status().message();
  // The schema must match the stream table.
  GridSchema fewer = schema;
  fewer.point_fields.pop_back();
  EXPECT_FALSE(decodeGridPiece(piece, fewer, "piece").isOk());
}

INSTANTIATE_TEST_SUITE_P(ValueForms, GridCoderCorrupt, ::testing::Values(0, 1));

TEST(GridCoder, FormOneDeclinesFormsItCannotCode) {
  // Printed-single float64 values (float32 values printed with 9 digits) have no form-1 coding: the
  // stream stays in form 0 even when form 1 is asked for.
  const GridLayout l = grid(14, 10, 9, 6);
  TetMesh m = meshOf(l, ScalarType::kFloat32);
  Field printed("printed", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v)
    printed.set<double>(v, 0, printedSingle(static_cast<float>(std::sin(0.01 * v)), 9));
  m.point_fields = {printed};
  GridEncodeOptions fast;
  fast.value_form = 1;
  GridEncodeReport report;
  roundTripOnce(l, m, &report, fast);
  ASSERT_EQ(report.stream_forms.size(), 2u);
  EXPECT_EQ(report.forms[3], "printed 9");
  EXPECT_EQ(report.stream_forms[1], 0);
}

// Point fields with long runs of exactly predicted values: `linear` is linear along i, predicted
// exactly but on the first row (one run from there to the stream's end), `bumps` is linear in i, j
// and k but for isolated bumps, the last one at node `last_bump` (runs between them, and a run to
// the stream's end when it is not the last node), `decimal` is n / 1000 but for a few values that
// are not (form 1's escapes).
TetMesh runsMesh(const GridLayout& l, uint64_t last_bump) {
  TetMesh m = meshOf(l, ScalarType::kFloat32);
  const uint64_t n = m.numPoints();
  Field linear("linear", 1, ScalarType::kInt32, n), bumps("bumps", 2, ScalarType::kInt32, n),
      decimal("decimal", 1, ScalarType::kFloat64, n);
  for (uint64_t v = 0; v < n; ++v) {
    const uint64_t i = v % l.dims[0], j = (v / l.dims[0]) % l.dims[1], k = v / (uint64_t{l.dims[0]} * l.dims[1]);
    linear.set<int32_t>(v, 0, static_cast<int32_t>(3 * i) - 7);
    const bool bump = v == last_bump || (v < last_bump && v % 397 == 5);
    bumps.set<int32_t>(v, 0, static_cast<int32_t>(2 * (i + 2 * j - 3 * k) + (bump ? 6 : 0)));
    bumps.set<int32_t>(v, 1, bump ? 3 : 1);
    decimal.set<double>(v, 0, v % 211 == 7 ? 1.0 / 3.0 + v : std::round(1000.0 * std::sin(0.01 * v)) / 1000.0);
  }
  m.point_fields = {linear, bumps, decimal};
  return m;
}

TEST(GridCoder, FormOneCodesRunsOfZeroResidualsAsOneSymbol) {
  const GridLayout l = grid(24, 19, 13, 5);
  const uint64_t n = l.nodes();
  for (uint64_t last_bump : {n - 1, n - 2, n - 300, uint64_t{0}}) {
    SCOPED_TRACE("last bump at node " + std::to_string(last_bump));
    const TetMesh m = runsMesh(l, last_bump);
    GridEncodeOptions fast;
    fast.value_form = 1;
    GridEncodeReport report;
    roundTripOnce(l, m, &report, fast);
    ASSERT_EQ(report.stream_forms.size(), 4u);
    EXPECT_EQ(report.stream_forms, (std::vector<uint8_t>{1, 1, 1, 1}));
    EXPECT_EQ(report.forms.back(), "decimal 3");
    // Runs code `linear` and `bumps` in well under one bit per value (a prefix code alone takes at
    // least one), and `linear` within a few words of form 0.
    GridEncodeOptions adaptive;
    adaptive.value_form = 0;
    GridEncodeReport slow;
    roundTripOnce(l, m, &slow, adaptive);
    EXPECT_LT(report.point_fields[0] * 8, n / 4);
    EXPECT_LT(report.point_fields[1] * 8, 2 * n / 4);
    EXPECT_LT(report.point_fields[0], slow.point_fields[0] + 64);
  }
}

// The piece's streams: the byte offset and size of each (the header of section 11.1 parsed).
struct PieceStreams {
  size_t table = 0;  // where the stream count starts
  std::vector<uint8_t> forms;
  std::vector<size_t> offsets, sizes;
};

uint64_t readVarint(const std::vector<uint8_t>& b, size_t* at) {
  uint64_t v = 0;
  for (int shift = 0;; shift += 7) {
    const uint8_t x = b.at((*at)++);
    v |= uint64_t{x & 0x7Fu} << shift;
    if (!(x & 0x80)) return v;
  }
}

PieceStreams pieceStreams(const std::vector<uint8_t>& piece) {
  PieceStreams s;
  size_t at = 0;
  for (int x = 0; x < 7; ++x) readVarint(piece, &at);  // block, origin, dims
  at += 2;                                             // split, flags
  for (int x = 0; x < 3; ++x) readVarint(piece, &at);  // exceptions, extra points, aliases
  s.table = at;
  const uint64_t n = readVarint(piece, &at);
  for (uint64_t x = 0; x < n; ++x) {
    s.forms.push_back(piece.at(at++));
    s.sizes.push_back(readVarint(piece, &at));
  }
  for (size_t size : s.sizes) {
    s.offsets.push_back(at);
    at += size;
  }
  return s;
}

void putTestVarint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) out.push_back(static_cast<uint8_t>(v | 0x80)), v >>= 7;
  out.push_back(static_cast<uint8_t>(v));
}

// `piece` with stream `index` replaced by `stream` (the stream table rewritten).
std::vector<uint8_t> withStream(const std::vector<uint8_t>& piece, size_t index, const std::vector<uint8_t>& stream) {
  const PieceStreams s = pieceStreams(piece);
  std::vector<uint8_t> out(piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(s.table));
  putTestVarint(out, s.sizes.size());
  for (size_t x = 0; x < s.sizes.size(); ++x) {
    out.push_back(s.forms[x]);
    putTestVarint(out, x == index ? stream.size() : s.sizes[x]);
  }
  for (size_t x = 0; x < s.sizes.size(); ++x) {
    if (x == index) {
      out.insert(out.end(), stream.begin(), stream.end());
    } else {
      const auto begin = piece.begin() + static_cast<std::ptrdiff_t>(s.offsets[x]);
      out.insert(out.end(), begin, begin + static_cast<std::ptrdiff_t>(s.sizes[x]));
    }
  }
  return out;
}

TEST(GridCoder, FormOneRejectsRunsBeyondTheLastValue) {
  // `linear` ends in one run over all values after the first row: its stream from a larger grid declares a run longer than
  // the smaller grid's values, and one from a smaller grid a run that ends before them (the value
  // after it has no code in the class that follows a run).
  const GridLayout small = grid(9, 7, 5, 5), large = grid(9, 7, 6, 5), smaller = grid(9, 7, 4, 5);
  GridEncodeOptions fast;
  fast.value_form = 1;
  auto encode = [&](const GridLayout& l) {
    auto piece = encodeGridPiece(l, runsMesh(l, 0), fast);
    EXPECT_TRUE(piece.isOk()) << piece.status().message();
    return piece.isOk() ? *piece : std::vector<uint8_t>{};
  };
  const std::vector<uint8_t> piece = encode(small), longer = encode(large), shorter = encode(smaller);
  ASSERT_FALSE(piece.empty() || longer.empty() || shorter.empty());
  const GridSchema schema = gridSchemaOf(runsMesh(small, 0));
  ASSERT_TRUE(decodeGridPiece(piece, schema, "piece").isOk());
  auto streamOf = [](const std::vector<uint8_t>& p, size_t index) {
    const PieceStreams s = pieceStreams(p);
    EXPECT_EQ(s.forms.at(index), 1);
    return std::vector<uint8_t>(p.begin() + static_cast<std::ptrdiff_t>(s.offsets[index]),
                                p.begin() + static_cast<std::ptrdiff_t>(s.offsets[index] + s.sizes[index]));
  };
  const size_t linear = 3;  // EXCP, GRID, GEOM, then the point fields
  auto r = decodeGridPiece(withStream(piece, linear, streamOf(longer, linear)), schema, "long run");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(r.status().message().find("long run"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("run of zero residuals"), std::string::npos) << r.status().message();
  r = decodeGridPiece(withStream(piece, linear, streamOf(shorter, linear)), schema, "short run");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(r.status().message().find("short run"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("PFLD stream 'linear' (form 1)"), std::string::npos) << r.status().message();
}

// ---- The real PLOT3D datasets ----------------------------------------------------------------------

// The node counts of a single-grid big-endian PLOT3D file without record markers (the datasets').
void plot3dDims(const std::string& path, uint32_t dims[3]) {
  const std::string bytes = test::readFile(path);
  ASSERT_GE(bytes.size(), 12u);
  for (int a = 0; a < 3; ++a) {
    uint32_t v = 0;
    for (int b = 0; b < 4; ++b) v = (v << 8) | static_cast<uint8_t>(bytes[4 * a + b]);
    dims[a] = v;
  }
}

void realDataset(const std::string& xyz, const std::string& q, int split, size_t want_explicit) {
  ImportOptions options;
  options.split = split;
  auto imported = importPlot3d({test::dataPath(xyz), test::dataPath(q)}, options);
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  const TetMesh& mesh = imported->mesh;
  uint32_t dims[3];
  plot3dDims(test::dataPath(xyz), dims);
  auto layout = matchGridLayout(mesh, dims);
  ASSERT_TRUE(layout.isOk()) << layout.status().message();
  EXPECT_EQ(layout->split, split);
  EXPECT_EQ(layout->parity, 0);  // the importer's parity for a single block without --weld
  EXPECT_FALSE(layout->left_handed);
  size_t n_explicit = 0;
  for (const GridException& x : layout->exceptions) n_explicit += x.kind == GridException::kExplicit;
  EXPECT_EQ(n_explicit, want_explicit);
  EXPECT_EQ(layout->extras(), imported->report.steiner_points);
  for (int form : {-1, 1}) {
    GridEncodeReport report;
    GridEncodeOptions options;
    options.value_form = form;
    auto piece = encodeGridPiece(*layout, mesh, options, &report);
    ASSERT_TRUE(piece.isOk()) << piece.status().message();
    auto back = decodeGridPiece(*piece, gridSchemaOf(mesh), xyz);
    ASSERT_TRUE(back.isOk()) << back.status().message();
    // The decoder's tetrahedra are the importer's, in its order; values bit for bit.
    expectSameMesh(back->mesh, mesh);
    EXPECT_EQ(back->mesh.coord_type, mesh.coord_type);
    // Smaller than format 1.0's level 0 of the same mesh (gtn info: 18.30 and 28.75 bits per
    // tetrahedron for the 5-split blunt fin and combustion chamber), in either form.
    const double bits = 8.0 * piece->size() / mesh.numTets();
    if (split == 5) {
      EXPECT_LT(bits, xyz.find("bluntfin") != std::string::npos ? 18.3 : 28.7) << "form " << form;
    }
  }
}

TEST(GridCoderReal, BluntFinSplitFive) { realDataset("plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin", 5, 0); }
TEST(GridCoderReal, CombustionSplitFive) { realDataset("plot3d/combxyz.bin", "plot3d/combq.bin", 5, 2); }
TEST(GridCoderReal, BluntFinSplitSix) { realDataset("plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin", 6, 0); }

}  // namespace
}  // namespace gtn
