// Lossless round trips of the level codec on synthetic meshes that exercise every structural case,
// and the decoder's behaviour on corrupt payloads.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <random>

#include "codec/level_codec.h"
#include "codec/value_coder.h"
#include "codec_test_util.h"
#include "mesh/mesh_stats.h"

namespace gtn {
namespace {

using test::gridMesh;
using test::roundTrip;

double bitsPerTet(const std::vector<uint8_t>& s, const TetMesh& m) { return 8.0 * s.size() / m.numTets(); }

TEST(LevelCodec, StructuredGridSixSplitWithFields) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  test::addFields(m);
  const EncodedLevel e = roundTrip(m);
  EXPECT_EQ(e.header.points, m.numPoints());
  EXPECT_EQ(e.header.tets, m.numTets());
  // Connectivity of a regular grid must be far below the 2.5 bits per tetrahedron target.
  EXPECT_LT(bitsPerTet(e.connectivity, m) + bitsPerTet(e.boundary, m), 2.5);
}

// A consumer that needs one field decodes that field's stream alone (the renderer reads one scalar):
// five point fields of five types and two cell fields, each decoded alone, the others left as zeros.
TEST(LevelCodec, EachFieldDecodesAlone) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  test::addFields(m);
  const EncodedLevel e = roundTrip(m);
  EXPECT_EQ(test::expectFieldsDecodeAlone(e, /*unselected_zero=*/true), 7);
}

TEST(LevelCodec, ComponentsRepeatedAsOtherFieldsCostAlmostNothing) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  test::addFields(m);
  // "velocity" (float64 x 3) stored again as its y component, and "pressure" once more: the copies
  // are declared as repeats of the earlier components and decode bit for bit.
  const Field& velocity = *m.findPointField("velocity");
  const Field& pressure = *m.findPointField("pressure");
  Field vy("vy", 1, ScalarType::kFloat64, m.numPoints()), p2("pressure_again", 1, ScalarType::kFloat32, m.numPoints());
  // Same as velocity.y except at one vertex: must not be treated as a repeat.
  Field almost("almost_vy", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) {
    vy.set<double>(v, 0, velocity.get(v, 1));
    p2.set<float>(v, 0, static_cast<float>(pressure.get(v, 0)));
    almost.set<double>(v, 0, v == 17 ? velocity.get(v, 1) + 1.0 : velocity.get(v, 1));
  }
  m.point_fields.push_back(vy);
  m.point_fields.push_back(p2);
  m.point_fields.push_back(almost);
  const EncodedLevel e = roundTrip(m);
  const size_t n = m.point_fields.size();
  ASSERT_EQ(e.point_fields.size(), n);
  EXPECT_LT(e.point_fields[n - 3].size(), 16u) << "vy repeats velocity's y component";
  EXPECT_LT(e.point_fields[n - 2].size(), 16u) << "pressure_again repeats pressure";
  EXPECT_GT(e.point_fields[n - 1].size(), e.point_fields[0].size()) << "almost_vy differs at one vertex";

  // Each field decodes alone; vy alone takes velocity along, whose y component it repeats, and
  // leaves pressure undecoded.
  EXPECT_EQ(test::expectFieldsDecodeAlone(e, /*unselected_zero=*/false), static_cast<int>(n + m.cell_fields.size()));
  DecodeFields only;
  only.point.assign(n, false);
  only.point[n - 3] = true;
  const TetMesh full = test::decodeToMesh(e), got = test::decodeToMesh(e, &only);
  EXPECT_TRUE(got.point_fields[1].bytes == full.point_fields[1].bytes) << "velocity decoded for vy";
  EXPECT_TRUE(std::all_of(got.point_fields[0].bytes.begin(), got.point_fields[0].bytes.end(), [](uint8_t b) {
    return b == 0;
  })) << "pressure left out";

  // Once the declarations are read, the decode says which streams it reads no further (velocity is
  // not among them: vy repeats it), and those may be freed: here their pages are made unreadable,
  // so that a read after the call would crash the test, and the decode goes on to the same mesh.
  const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  struct Mapped {
    void* base;
    size_t size;
  };
  std::vector<Mapped> maps;
  LevelPayload payload = payloadOf(e);
  for (size_t f = 0; f < n; ++f) {
    const std::vector<uint8_t>& src = e.point_fields[f];
    const size_t size = (src.size() + page - 1) / page * page;
    void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(base, MAP_FAILED);
    std::memcpy(base, src.data(), src.size());
    maps.push_back({base, size});
    payload.point_fields[f] = std::span<const uint8_t>(static_cast<const uint8_t*>(base), src.size());
  }
  int calls = 0;
  only.streams_done = [&](const std::vector<char>& point_out, const std::vector<char>& cell_out) {
    ++calls;
    EXPECT_EQ(point_out, (std::vector<char>{1, 0, 1, 1, 1, 0, 1, 1}));
    EXPECT_EQ(cell_out, (std::vector<char>{0, 0})) << "empty cell selection: every cell field";
    for (size_t f = 0; f < point_out.size(); ++f) {
      if (point_out[f]) {
        EXPECT_EQ(mprotect(maps[f].base, maps[f].size, PROT_NONE), 0);
      }
    }
  };
  test::CheckingSink sink;
  ASSERT_TRUE(decodeLevel(e.header, payload, sink, nullptr, "x", &only).isOk());
  EXPECT_EQ(calls, 1);
  const TetMesh& after = sink.builder.mesh();
  EXPECT_TRUE(after.point_fields[5].bytes == full.point_fields[5].bytes);
  EXPECT_TRUE(after.point_fields[1].bytes == full.point_fields[1].bytes);
  for (size_t f = 0; f < m.cell_fields.size(); ++f)
    EXPECT_TRUE(after.cell_fields[f].bytes == full.cell_fields[f].bytes);
  EXPECT_TRUE(after.tets == full.tets);
  for (const Mapped& map : maps) munmap(map.base, map.size);
}

// Grids often repeat their boundary values in the next layer (blunt fin's solver does on two planes).
// With random values elsewhere nothing else is predictable, so the repeats are what the field rules
// that copy a stencil vertex or an apex candidate save: a repeated value costs a few bits.
TEST(LevelCodec, ValuesRepeatedFromTheNextLayerAreCopied) {
  const int nx = 12, ny = 10, nz = 9;
  TetMesh m = gridMesh(nx, ny, nz, 6);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.5f, 2.0f);
  Field noise("noise", 1, ScalarType::kFloat32, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) noise.set<float>(v, 0, u(rng));
  m.point_fields = {noise};
  EncodeOptions predicted;  // the field rules alone: random values would be packed (spec 10.2.1)
  predicted.packed_streams = false;
  const EncodedLevel independent = roundTrip(m, nullptr, predicted);
  auto id = [&](int i, int j, int k) { return static_cast<size_t>(i + nx * (j + ny * k)); };
  size_t repeated = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (k == 0) noise.set<float>(id(i, j, 0), 0, static_cast<float>(noise.get(id(i, j, 1), 0)));
        else if (j == 0) noise.set<float>(id(i, 0, k), 0, static_cast<float>(noise.get(id(i, 1, k), 0)));
        else continue;
        ++repeated;
      }
  m.point_fields = {noise};
  const EncodedLevel copied = roundTrip(m, nullptr, predicted);
  const double per_value = 8.0 * independent.point_fields[0].size() / m.numPoints();
  const double saved = 8.0 * (double(independent.point_fields[0].size()) - double(copied.point_fields[0].size()));
  EXPECT_GT(per_value, 20.0);  // random float32 values: nothing to predict
  // The repeated values save most of their cost (74% measured; 8% before the copy rules existed).
  EXPECT_GT(saved, 0.6 * per_value * double(repeated)) << repeated << " repeated values";
}

// Values whose stored patterns all end in zero bits (float32 data kept in a float64 array, small
// integers in floats and integers, negative values and signed zeros among them) are coded without
// those bits (spec 10.2, shifts): a float64 array of float32 values costs what the float32 array costs.
TEST(LevelCodec, TrailingZeroBitsOfEveryValueAreNotCoded) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  Field as32("as32", 1, ScalarType::kFloat32, m.numPoints()), as64("as64", 1, ScalarType::kFloat64, m.numPoints());
  Field wide("wide", 1, ScalarType::kFloat64, m.numPoints()), counts("counts", 2, ScalarType::kInt32, m.numPoints());
  Field small("small", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) {
    const float x = v % 97 == 0 ? -0.0f : u(rng);
    as32.set<float>(v, 0, x);
    as64.set<double>(v, 0, x);
    wide.set<double>(v, 0, static_cast<double>(x) + 1e-12 * static_cast<double>(v % 7));  // low bits in use
    counts.set<int32_t>(v, 0, -1024 * static_cast<int32_t>(v % 13));
    counts.set<int32_t>(v, 1, 4096 * static_cast<int32_t>(v % 5));
    small.set<double>(v, 0, static_cast<double>(static_cast<int>(v % 11) - 5));
  }
  m.point_fields = {as32, as64, wide, counts, small};
  EncodeOptions predicted;  // the shifts alone: random values would be packed (spec 10.2.1)
  predicted.packed_streams = false;
  const EncodedLevel e = roundTrip(m, nullptr, predicted);
  ASSERT_EQ(e.point_fields.size(), 5u);
  const double n = static_cast<double>(m.numPoints());
  const double b32 = 8.0 * e.point_fields[0].size() / n, b64 = 8.0 * e.point_fields[1].size() / n;
  const double bwide = 8.0 * e.point_fields[2].size() / n;
  // The float64 copy costs about what the float32 original does, far less than a float64 whose low
  // bits vary (29 mantissa bits more).
  EXPECT_LT(b64, b32 + 1.0) << "float32 values in a float64 array";
  EXPECT_GT(bwide, b64 + 20.0) << "a float64 array that uses its low bits";
  // Multiples of 1024 and 4096 and small integers in doubles: a few bits per value.
  EXPECT_LT(8.0 * e.point_fields[3].size() / n, 2 * 8.0);
  EXPECT_LT(8.0 * e.point_fields[4].size() / n, 8.0);
  // Float64 coordinates holding float32 values, likewise.
  TetMesh g = gridMesh(12, 10, 9, 6);
  for (double& x : g.coords) x = static_cast<float>(x * 1.37 + 0.001 * std::sin(x));
  const double f32_like = 8.0 * roundTrip(g).geometry.size() / n;
  for (double& x : g.coords) x += 1e-13 * std::cos(3 * x);
  const double f64_used = 8.0 * roundTrip(g).geometry.size() / n;
  EXPECT_GT(f64_used, f32_like + 30.0) << "coordinates of float32 precision in float64";
}

// Values that text formats printed with a few decimals (TetGen's 5.6770899999999997 is 5.67709) are
// coded as the integers they are in units of 10^-e (spec 10.2, decimal form); values without such a
// form among them (a mesh generator's own points, -0.0, NaN) are coded as floats and survive too.
TEST(LevelCodec, DecimalValuesAreCodedAsIntegers) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  const size_t n = m.numPoints();
  auto decimal = [](double x, int places) {
    return std::nearbyint(x * std::pow(10.0, places)) / std::pow(10.0, places);
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  Field printed("printed", 1, ScalarType::kFloat64, n), full("full", 1, ScalarType::kFloat64, n);
  Field mixed("mixed", 1, ScalarType::kFloat64, n), f32("f32", 1, ScalarType::kFloat32, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = m.point(v);
    const double smooth = 10.0 * std::sin(0.3 * p[0]) + p[1] * p[2] / 7.0;
    printed.set<double>(v, 0, decimal(smooth, 6));
    full.set<double>(v, 0, smooth);
    // One value in ten is not a short decimal; a -0.0 and a NaN among them.
    const double x = v % 10 == 3 ? smooth : decimal(smooth, 4);
    mixed.set<double>(v, 0, v == 17 ? -0.0 : v == 29 ? std::nan("") : x);
    f32.set<float>(v, 0, static_cast<float>(decimal(u(rng), 3)));
  }
  m.point_fields = {printed, full, mixed, f32};
  for (size_t i = 0; i < m.coords.size(); ++i) m.coords[i] = decimal(m.coords[i] * 3.1, 5);
  const EncodedLevel e = roundTrip(m);
  const double nv = static_cast<double>(n);
  const double b_printed = 8.0 * e.point_fields[0].size() / nv, b_full = 8.0 * e.point_fields[1].size() / nv;
  // Six decimals of a smooth field: far fewer bits than the double's 52-bit significand needs.
  EXPECT_LT(b_printed, b_full - 15.0);
  EXPECT_LT(8.0 * e.point_fields[2].size() / nv, b_full - 10.0) << "mostly four decimals";
  // Random values of 3 decimals in [-50, 50]: 17 bits of integer, not a float32's 24 bits of noise.
  EXPECT_LT(8.0 * e.point_fields[3].size() / nv, 20.0);
  EXPECT_LT(8.0 * e.geometry.size() / nv, 3 * 24.0) << "coordinates of 5 decimals";
}

// Float32 values that a program printed as doubles with 15 digits (MMG's Medit files: 0.2f as
// 0.200000002980232) are coded as the float32 values they are (spec 10.2, printed-single form): they
// cost what the float32 mesh costs, not a double's 52-bit significand; values of other forms among
// them (a full double, -0.0, a value beyond float32's range) take the escape and survive too.
TEST(LevelCodec, PrintedSingleValuesCostWhatTheirFloat32ValuesCost) {
  TetMesh singles = gridMesh(12, 10, 9, 6);
  singles.coord_type = ScalarType::kFloat32;
  for (double& c : singles.coords) c = static_cast<float>(c * 3.14159265358979);  // no decimal form
  const size_t n = singles.numPoints();
  Field f32("pressure", 1, ScalarType::kFloat32, n);
  for (size_t v = 0; v < n; ++v) f32.set<float>(v, 0, static_cast<float>(std::sin(0.3 * singles.point(v)[0]) * 1e3));
  singles.point_fields = {f32};

  TetMesh printed = singles;
  printed.coord_type = ScalarType::kFloat64;
  for (double& c : printed.coords) c = printedSingle(static_cast<float>(c), 15);
  Field f64("pressure", 1, ScalarType::kFloat64, n);
  for (size_t v = 0; v < n; ++v) f64.set<double>(v, 0, printedSingle(static_cast<float>(f32.get(v, 0)), 15));
  f64.set<double>(5, 0, 1.0 / 3.0);
  f64.set<double>(6, 0, -0.0);
  f64.set<double>(7, 0, 1e300);
  printed.point_fields = {f64};
  printed.coords[3 * 11] = 1.0 / 7.0;
  ASSERT_EQ(printed.coords[3], printedSingle(static_cast<float>(singles.coords[3]), 15));
  ASSERT_NE(printed.coords[3], singles.coords[3]) << "the printed value is not the float32 value";

  const EncodedLevel a = roundTrip(singles), b = roundTrip(printed);
  const double nv = static_cast<double>(n);
  EXPECT_LT(8.0 * b.geometry.size() / nv, 8.0 * a.geometry.size() / nv + 1.0);
  EXPECT_LT(8.0 * b.point_fields[0].size() / nv, 8.0 * a.point_fields[0].size() / nv + 1.0);
}

// Sums of float32 values kept in doubles (as an FEA code writes nodal averages) end in 24 or more zero
// bits, but a few values of the field are full doubles: the shift is declared with exceptions (spec
// 10.2), so the others still cost what they would without the full doubles, and each full double
// costs about a double.
TEST(LevelCodec, ShiftWithExceptionsSkipsTheZeroBitsOfMostValues) {
  TetMesh pure = gridMesh(12, 10, 9, 6);
  const size_t n = pure.numPoints();
  Field sums("stress", 1, ScalarType::kFloat64, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = pure.point(v);
    sums.set<double>(v, 0,
                     static_cast<double>(static_cast<float>(std::sin(0.3 * p[0]) * 1e3)) +
                         static_cast<double>(static_cast<float>(std::cos(0.2 * p[1] + p[2]) * 37.0)));
  }
  pure.point_fields = {sums};
  TetMesh mixed = pure;
  size_t exceptions = 0;
  for (size_t v = 0; v < n; v += 10, ++exceptions)
    mixed.point_fields[0].set<double>(v, 0, std::sqrt(2.0 + static_cast<double>(v)));
  for (size_t v = 5; v < n; v += 40) mixed.point_fields[0].set<double>(v, 0, 0.0);  // zeros have every low bit zero

  const EncodedLevel a = roundTrip(pure), b = roundTrip(mixed);
  const double nv = static_cast<double>(n), pure_bits = 8.0 * a.point_fields[0].size() / nv;
  // Without the exceptions every value would pay the 24 bits more that the full doubles force.
  EXPECT_LT(8.0 * b.point_fields[0].size() / nv, pure_bits + 66.0 * static_cast<double>(exceptions) / nv + 2.0);
  EXPECT_LT(pure_bits, 40.0);
}

// A curvilinear grid, as a PLOT3D grid split into tetrahedra: no rule predicts its vertices exactly,
// but what the best rule misses varies smoothly along the grid, so a vertex's error is close to a
// neighbour's. GEOM carries a stencil vertex's or an apex candidate's error over (spec 10.5).
TEST(LevelCodec, CarriedErrorsPredictCurvilinearGrids) {
  for (const int split : {5, 6}) {
    const int nx = 17, ny = 15, nz = 13;
    TetMesh m = gridMesh(nx, ny, nz, split);
    m.coord_type = ScalarType::kFloat32;
    const size_t n = m.numPoints();
    // A thick cylindrical shell, twisted along its axis: every grid line is curved. (Float
    // arithmetic for the stores: see FewDistinctValuesAreCodedAsPlacesInATable.)
    for (size_t v = 0; v < n; ++v) {
      const float i = static_cast<float>(v % nx), j = static_cast<float>(v / nx % ny),
                  k = static_cast<float>(v / (nx * ny));
      const float r = 2.0f + 0.15f * i + 0.01f * i * i, theta = 0.09f * j + 0.02f * k;
      m.coords[3 * v] = r * std::cos(theta);
      m.coords[3 * v + 1] = r * std::sin(theta);
      m.coords[3 * v + 2] = 0.2f * k + 0.004f * i * j;
    }
    const EncodedLevel e = roundTrip(m);
    // Without the carry: 50.6 bits per vertex (split 5) and 45.6 (split 6); with it 47.5 and 41.1.
    EXPECT_LT(8.0 * e.geometry.size() / static_cast<double>(n), split == 5 ? 49.0 : 43.4) << "split " << split;
  }
}

// A field of a few dozen distinct values (levels of a classification, a lattice's coordinates) is
// coded as places in a table of its values (spec 10.2): neighbours' places are close even where
// their values' bit patterns are not.
TEST(LevelCodec, FewDistinctValuesAreCodedAsPlacesInATable) {
  const int nx = 13, ny = 12, nz = 14;
  TetMesh m = gridMesh(nx, ny, nz, 6);
  m.coord_type = ScalarType::kFloat32;
  const size_t n = m.numPoints();
  // A lattice: 13, 12 and 14 values. (In float arithmetic: GCC 12.2 at -O3 drops the rounding of
  // static_cast<float>(double product) when it vectorises this loop's three stores.)
  for (size_t v = 0; v < n; ++v) {
    const size_t ijk[3] = {v % nx, v / nx % ny, v / (nx * ny)};
    for (int a = 0; a < 3; ++a) m.coords[3 * v + a] = static_cast<float>(ijk[a]) * 0.739085133f;
  }
  ASSERT_GE(n, 1024u);
  Field f("zone", 1, ScalarType::kFloat64, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = m.point(v);
    f.set<double>(v, 0, std::sqrt(2.0 + std::floor((p[0] + p[1] + p[2]) / 0.7390851332151607 / 2.0)));
  }
  m.point_fields = {f};
  const EncodedLevel e = roundTrip(m);
  const double nv = static_cast<double>(n);
  // Measured: 2.46 bits per value (coded as doubles: 11.27), coordinates 6.05 bits per vertex (6.56).
  EXPECT_LT(8.0 * e.point_fields[0].size() / nv, 4.0);
  EXPECT_LT(8.0 * e.geometry.size() / nv, 6.3);
}

TEST(LevelCodec, PrintedSingleKeysAreExact) {
  auto key = [](double v) {
    uint8_t raw[8];
    std::memcpy(raw, &v, 8);
    return keyFromRaw(ScalarType::kFloat64, raw);
  };
  uint64_t single = 0;
  ASSERT_TRUE(printedSingleKey(key(0.200000002980232), 15, &single));
  uint8_t raw[4];
  rawFromKey(ScalarType::kFloat32, single, raw);
  float f;
  std::memcpy(&f, raw, 4);
  EXPECT_EQ(f, 0.2f);
  EXPECT_FALSE(printedSingleKey(key(0.2), 15, &single)) << "0.2f prints as 0.200000002980232";
  EXPECT_FALSE(printedSingleKey(key(0.200000002980232), 16, &single));
  EXPECT_TRUE(printedSingleKey(key(0.2000000029802322), 16, &single));
  EXPECT_TRUE(printedSingleKey(key(-0.0), 15, &single));
  EXPECT_FALSE(printedSingleKey(key(std::nan("")), 15, &single));
  EXPECT_FALSE(printedSingleKey(key(1e39), 15, &single)) << "beyond float32's range";
  EXPECT_EQ(printedSingle(-1.472f, 15), -1.47200000286102);
  // The encoder tries only digit counts at least the shortest decimal's (the estimate's filter).
  EXPECT_EQ(shortestDigits(key(0.200000002980232)), 15);
  EXPECT_EQ(shortestDigits(key(0.1)), 1);
  EXPECT_EQ(shortestDigits(key(-0.0)), 1);
  EXPECT_EQ(shortestDigits(key(1.0 / 3.0)), 16);
  EXPECT_EQ(shortestDigits(key(std::nan(""))), 0);
}

// Importers split a hexahedron into 5 or 6 tetrahedra and give each its cell's values. The siblings
// are seldom behind the gate face but often across the other faces a tetrahedron closes, and a
// symbol names those (spec section 10.7): a value new to the field is escaped about once per
// hexahedron, not once per tetrahedron.
TEST(LevelCodec, SplitHexahedraTakeTheirCellValuesFromTheirSiblings) {
  const int nx = 13, ny = 12, nz = 11;
  // Bits per tetrahedron at most. Measured: six-split 8.88 and 0.258 (32.78 and 0.625 when only
  // the gate face's neighbour was named); five-split 16.39 and 0.362 (16.86 and 0.393): its four
  // corner tetrahedra touch the central one only, so corners peeled before it do not see each other.
  struct Case {
    int split;
    double strain, material;
  };
  for (const Case c : {Case{6, 10.0, 0.3}, Case{5, 17.5, 0.4}}) {
    SCOPED_TRACE(c.split);
    TetMesh m = gridMesh(nx, ny, nz, c.split);  // each hexahedron's tetrahedra one after another
    Field strain("strain", 1, ScalarType::kFloat64, m.numTets()),
        material("material", 1, ScalarType::kInt32, m.numTets());
    for (size_t t = 0; t < m.numTets(); ++t) {
      const int h = static_cast<int>(t) / c.split, i = h % (nx - 1), j = h / (nx - 1) % (ny - 1),
                k = h / ((nx - 1) * (ny - 1));
      // Smooth, and distinct in every hexahedron; a label constant over blocks of 4 x 4 x 4.
      strain.set<double>(t, 0, std::sin(0.3 * i) * std::cos(0.2 * j) + 0.05 * k + 1e-3 * std::sin(i * j + k));
      material.set<int32_t>(t, 0, 1 + (i / 4 + 3 * (j / 4) + 7 * (k / 4)) % 5);
    }
    m.cell_fields = {strain, material};
    const EncodedLevel e = roundTrip(m);
    ASSERT_EQ(e.cell_fields.size(), 2u);
    EXPECT_EQ(encodeLevel(m, EncodeOptions{})->cell_fields, e.cell_fields) << "encoder is not deterministic";
    EXPECT_LT(bitsPerTet(e.cell_fields[0], m), c.strain);
    EXPECT_LT(bitsPerTet(e.cell_fields[1], m), c.material);
  }
}

TEST(LevelCodec, StructuredGridFiveSplitFloat32) {
  TetMesh m = gridMesh(11, 9, 8, 5);
  m.coord_type = ScalarType::kFloat32;
  for (double& c : m.coords) c = static_cast<float>(c);
  test::addFields(m);
  const EncodedLevel e = roundTrip(m);
  EXPECT_LT(bitsPerTet(e.connectivity, m) + bitsPerTet(e.boundary, m), 2.5);
}

TEST(LevelCodec, CoincidentPointsAndZeroVolumeTets) {
  // A grid whose j = 0 row collapses onto one line: unwelded coincident points, flat tetrahedra.
  TetMesh m = gridMesh(6, 5, 5, 5);
  for (size_t v = 0; v < m.numPoints(); ++v) {
    const size_t j = (v / 6) % 5;
    if (j == 0) m.coords[3 * v] = m.coords[3 * v + 1] = 0.0;
  }
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  EXPECT_GT(zero, 0u);
  test::addFields(m);
  roundTrip(m);
}

TEST(LevelCodec, InternalCavity) {
  TetMesh m = gridMesh(8, 8, 8, 6,
                       [](int i, int j, int k) { return !(i >= 3 && i <= 4 && j >= 3 && j <= 4 && k >= 3 && k <= 4); });
  roundTrip(m);
}

TEST(LevelCodec, DisconnectedPiecesAndUnusedPoints) {
  TetMesh a = gridMesh(5, 4, 4, 6);
  TetMesh b = gridMesh(4, 5, 3, 5, nullptr, 20.0);
  const uint32_t off = static_cast<uint32_t>(a.numPoints());
  a.coords.insert(a.coords.end(), b.coords.begin(), b.coords.end());
  for (Tet t : b.tets) {
    for (uint32_t& v : t) v += off;
    a.tets.push_back(t);
  }
  // Points that no tetrahedron uses, one of them coincident with a used point.
  a.coords.insert(a.coords.end(), {100.0, 1.0, 2.0, 0.0, 0.0, 0.0, -5.5, 3.25, 1e-300});
  test::addFields(a);
  roundTrip(a);
}

TEST(LevelCodec, NonManifoldBoundaryVerticesAndEdges) {
  // Cells in a checkerboard touch each other only along edges and at vertices.
  TetMesh m = gridMesh(5, 5, 5, 6, [](int i, int j, int k) { return (i + j + k) % 2 == 0; });
  test::addFields(m);
  roundTrip(m);
}

TEST(LevelCodec, ClosedPairWithoutBoundaryNeedsASeed) {
  // Two copies of one tetrahedron glued along all four faces: no boundary at all.
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 3}};
  const EncodedLevel e = roundTrip(m);
  EXPECT_EQ(e.header.boundary_triangles, 0u);
}

TEST(LevelCodec, SingleTetAndPointsOnly) {
  TetMesh one;
  one.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  one.tets = {{0, 1, 2, 3}};
  roundTrip(one);
  TetMesh pts;
  pts.coords = {1, 2, 3, -4, 5, 6.5};
  roundTrip(pts);
  TetMesh empty;
  roundTrip(empty);
}

TEST(LevelCodec, SpecialFloatValuesSurvive) {
  TetMesh m = gridMesh(4, 4, 4, 6);
  Field f("weird", 1, ScalarType::kFloat32, m.numPoints());
  const uint32_t patterns[] = {0x7FC00001u, 0xFF800000u, 0x7F800000u, 0x80000000u, 0x00000001u, 0xFFFFFFFFu};
  for (size_t v = 0; v < m.numPoints(); ++v) {
    uint32_t bits = patterns[v % 6];
    std::memcpy(f.bytes.data() + 4 * v, &bits, 4);
  }
  m.point_fields.push_back(f);
  roundTrip(m);
}

TEST(LevelCodec, CoordinatesNearTheDoubleRangeStillRoundTrip) {
  // Predictions, distances and Delaunay keys overflow to infinity or NaN here; the candidate order must
  // stay well defined (sorting NaN keys is undefined behaviour) and the mesh must come back exactly.
  TetMesh m = gridMesh(4, 3, 3, 6);
  m.coord_type = ScalarType::kFloat64;
  for (double& c : m.coords) c = c * 4e307 - 8e307;
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  const EncodedLevel e = roundTrip(m);
  EXPECT_EQ(e.header.tets, m.numTets());
}

TEST(LevelCodec, EscapesRankedOverABoxNearTheDoubleRange) {
  // Two points far out (2^53 + 1 and the largest double) make the escape grid's cells so large that
  // squared distances to them overflow: the encoder once ranked an escape among the grid's first
  // rings only and wrote a file the decoder refused ("escape rank beyond the live vertices").
  TetMesh m;
  m.coord_type = ScalarType::kFloat64;
  m.coords = {10, 0, 0, 10, 10, 0, 9007199254740993.0,     0, 10, 10, 0, 10, 4, 4, 4, 6, 4, 4, 6, 6, 4, 4, 6, 4,
              4,  4, 6, 6,  4,  6, 1.7976931348623157e308, 6, 6,  4,  6, 6,  2, 2, 1, 1, 1, 2, 2, 1, 2, 1, 2, 2};
  const uint32_t tets[14][4] = {{14, 15, 9, 3}, {10, 5, 11, 6}, {15, 9, 3, 10}, {12, 16, 9, 3}, {10, 3, 4, 11},
                                {9, 3, 10, 11}, {9, 12, 3, 11}, {5, 13, 7, 6},  {5, 12, 9, 11}, {5, 9, 10, 11},
                                {5, 8, 12, 7},  {4, 10, 11, 1}, {11, 10, 6, 1}, {11, 7, 2, 1}};
  for (const auto& t : tets) m.tets.push_back({t[0] - 1, t[1] - 1, t[2] - 1, t[3] - 1});
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  const EncodedLevel e = roundTrip(m);
  EXPECT_EQ(e.header.tets, 14u);
}

TEST(LevelCodec, RejectsNonManifoldFaces) {
  TetMesh m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 1, 1, 1};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
  EXPECT_FALSE(encodeLevel(m, EncodeOptions{}).isOk());
}

TEST(LevelCodec, ValueKeysRoundTripEveryType) {
  for (int t = 0; t < kNumScalarTypes; ++t) {
    const ScalarType type = static_cast<ScalarType>(t);
    uint8_t raw[8] = {0x12, 0x9A, 0xFF, 0x01, 0x80, 0x7F, 0x00, 0xC3}, back[8] = {};
    rawFromKey(type, keyFromRaw(type, raw), back);
    EXPECT_EQ(std::memcmp(raw, back, scalarSize(type)), 0) << scalarTypeName(type);
  }
  // Key order is numeric order for floats.
  const float a = -2.0f, b = -1.0f, c = 0.5f;
  uint8_t ra[4], rb[4], rc[4];
  std::memcpy(ra, &a, 4);
  std::memcpy(rb, &b, 4);
  std::memcpy(rc, &c, 4);
  EXPECT_LT(keyFromRaw(ScalarType::kFloat32, ra), keyFromRaw(ScalarType::kFloat32, rb));
  EXPECT_LT(keyFromRaw(ScalarType::kFloat32, rb), keyFromRaw(ScalarType::kFloat32, rc));
}

// ---- corrupt payloads -----------------------------------------------------------------------------

EncodedLevel smallEncoded() {
  TetMesh m = gridMesh(4, 4, 3, 5);
  test::addFields(m);
  auto e = encodeLevel(m, EncodeOptions{});
  EXPECT_TRUE(e.isOk());
  return std::move(e).value();
}

std::vector<std::vector<uint8_t>*> streamsOf(EncodedLevel& e) {
  std::vector<std::vector<uint8_t>*> s = {&e.boundary, &e.connectivity, &e.geometry};
  for (auto& f : e.point_fields) s.push_back(&f);
  for (auto& f : e.cell_fields) s.push_back(&f);
  return s;
}

TEST(LevelCodecCorrupt, EveryTruncatedStreamFailsCleanly) {
  EncodedLevel e = smallEncoded();
  const size_t n_streams = streamsOf(e).size();
  for (size_t k = 0; k < n_streams; ++k) {
    const std::vector<uint8_t> full = *streamsOf(e)[k];
    for (size_t len = 0; len < full.size(); ++len) {
      EncodedLevel c = e;
      streamsOf(c)[k]->resize(len);
      CountingSink sink;
      const Status st = decodeLevel(c.header, payloadOf(c), sink, nullptr, "level 0 of t.gtn");
      ASSERT_FALSE(st.isOk()) << "stream " << k << " cut to " << len << " bytes decoded";
      EXPECT_EQ(st.code(), StatusCode::kInvalidData);
      EXPECT_NE(st.message().find("level 0 of t.gtn"), std::string::npos) << st.message();
    }
    // Trailing bytes are rejected too.
    EncodedLevel c = e;
    streamsOf(c)[k]->push_back(0);
    CountingSink sink;
    EXPECT_FALSE(decodeLevel(c.header, payloadOf(c), sink, nullptr, "x").isOk());
  }
}

// A field left out is not decoded: the damage in its values goes unnoticed by a decode of another
// field (its chunk checksum is what guards it in a file), and the other field comes out whole.
TEST(LevelCodecCorrupt, AFieldLeftOutIsNotDecoded) {
  TetMesh m = gridMesh(12, 10, 9, 6);
  test::addFields(m);
  const EncodedLevel e = roundTrip(m);
  const TetMesh full = test::decodeToMesh(e);
  EncodedLevel c = e;
  c.point_fields[1].resize(c.point_fields[1].size() / 2);  // velocity, cut after its declarations
  CountingSink counting;
  EXPECT_FALSE(decodeLevel(c.header, payloadOf(c), counting, nullptr, "x").isOk());
  DecodeFields only;
  only.point = {true, false, false, false, false};
  const TetMesh got = test::decodeToMesh(c, &only);
  EXPECT_TRUE(got.point_fields[0].bytes == full.point_fields[0].bytes);
  EXPECT_TRUE(got.tets == full.tets);
  only.point = {false, true, false, false, false};
  test::CheckingSink sink;
  const Status st = decodeLevel(c.header, payloadOf(c), sink, nullptr, "x", &only);
  EXPECT_EQ(st.code(), StatusCode::kInvalidData) << "velocity itself is decoded, and found cut";
}

TEST(LevelCodecCorrupt, RandomByteFlipsNeverCrash) {
  const EncodedLevel e = smallEncoded();
  std::mt19937 rng(12345);
  int failures = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    EncodedLevel c = e;
    auto streams = streamsOf(c);
    const int flips = 1 + static_cast<int>(rng() % 3);
    for (int f = 0; f < flips; ++f) {
      auto* s = streams[rng() % streams.size()];
      if (s->empty()) continue;
      (*s)[rng() % s->size()] ^= static_cast<uint8_t>(1 + rng() % 255);
    }
    CountingSink sink;
    const Status st = decodeLevel(c.header, payloadOf(c), sink, nullptr, "flip");
    if (!st.isOk()) {
      ++failures;
      EXPECT_EQ(st.code(), StatusCode::kInvalidData);
    }
  }
  EXPECT_GT(failures, 2000);
}

TEST(LevelCodecCorrupt, HeaderCountsMustMatch) {
  EncodedLevel e = smallEncoded();
  for (int which = 0; which < 4; ++which) {
    LevelHeader h = e.header;
    if (which == 0) h.tets += 1;
    if (which == 1) h.points = h.points * 1000000;
    if (which == 2) h.boundary_triangles -= 1;
    if (which == 3) h.tets = uint64_t{1} << 40;
    CountingSink sink;
    EXPECT_FALSE(decodeLevel(h, payloadOf(e), sink, nullptr, "x").isOk()) << which;
  }
  LevelHeader h = e.header;
  h.point_fields.pop_back();
  CountingSink sink;
  EXPECT_FALSE(decodeLevel(h, payloadOf(e), sink, nullptr, "x").isOk());
}

}  // namespace
}  // namespace gtn
