// The packed form of a value stream (spec section 10.2.1): an FEA-like hexahedral mesh whose fields the
// predictions do not help codes no value stream larger than xz -9 of its raw array; the packed form
// keeps every bit pattern; it is taken only where it is smaller; a damaged packed stream is an error.
#include <gtest/gtest.h>
#include <lzma.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "codec/packed_values.h"
#include "codec_test_util.h"

namespace gtn {
namespace {

// What `xz -9` makes of `data` (liblzma, preset 9, the xz container with its CRC64, as the program).
size_t xz9(const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out(lzma_stream_buffer_bound(data.size()));
  size_t pos = 0;
  EXPECT_EQ(
      lzma_easy_buffer_encode(9, LZMA_CHECK_CRC64, nullptr, data.data(), data.size(), out.data(), &pos, out.size()),
      LZMA_OK);
  return pos;
}

// A small deterministic generator (xorshift64*).
struct Random {
  uint64_t s = 0x9E3779B97F4A7C15u;
  uint64_t next() {
    s ^= s >> 12, s ^= s << 25, s ^= s >> 27;
    return s * 2685821657736338717u;
  }
  double unit() { return static_cast<double>(next() >> 11) / 9007199254740992.0; }
};

// An FEA model of hexahedra split into 6 tetrahedra (22 x 22 x 12 cells, 34848 tetrahedra) with float32
// results: a smooth temperature with noise, a displacement vector, a nodal stress that takes one of
// 2000 levels (a solver's table values, scattered over the model) and a per-cell stress of the same
// kind, which every tetrahedron of a hexahedron shares.
TetMesh feaMesh() {
  TetMesh m = test::gridMesh(23, 23, 13, 6);
  const size_t np = m.numPoints(), nt = m.numTets();
  Random rng;
  std::vector<float> levels(2000);
  for (float& l : levels) l = static_cast<float>(2.0e8 * (rng.unit() - 0.3));
  Field temperature("temperature", 1, ScalarType::kFloat32, np),
      displacement("displacement", 3, ScalarType::kFloat32, np), stress("stress", 1, ScalarType::kFloat32, np);
  for (size_t v = 0; v < np; ++v) {
    const double* p = m.point(v);
    temperature.set<float>(
        v, 0, static_cast<float>(300 + 40 * std::sin(0.2 * p[0]) * std::cos(0.3 * p[1]) + 0.01 * rng.unit()));
    for (uint32_t c = 0; c < 3; ++c)
      displacement.set<float>(v, c, static_cast<float>(1e-3 * p[c] * p[(c + 1) % 3] + 1e-7 * rng.unit()));
    stress.set<float>(v, 0, levels[rng.next() % levels.size()]);
  }
  m.point_fields = {temperature, displacement, stress};
  Field cell_stress("cell_stress", 1, ScalarType::kFloat32, nt);
  float value = 0;
  for (size_t t = 0; t < nt; ++t) {
    if (t % 6 == 0) value = levels[rng.next() % levels.size()];
    cell_stress.set<float>(t, 0, value);
  }
  m.cell_fields = {cell_stress};
  return m;
}

// The raw arrays that xz is given: the coordinates axis after axis in their type, each field as stored.
std::vector<uint8_t> rawCoordinates(const TetMesh& m) {
  std::vector<uint8_t> raw;
  for (int c = 0; c < 3; ++c)
    for (size_t v = 0; v < m.numPoints(); ++v) {
      const float x = static_cast<float>(m.coords[3 * v + c]);
      raw.insert(raw.end(), reinterpret_cast<const uint8_t*>(&x), reinterpret_cast<const uint8_t*>(&x) + 4);
    }
  return raw;
}

void expectLossless(const TetMesh& m, const EncodedLevel& enc) {
  EXPECT_EQ(losslessMismatch(m, enc), "");
  test::CheckingSink sink;
  ASSERT_TRUE(decodeLevel(enc.header, payloadOf(enc), sink, nullptr, "test").isOk());
  test::expectSameMesh(m, enc, sink.builder.mesh(), sink.builder.boundary());
}

TEST(PackedValues, FeaHexMeshCodesNoValueStreamLargerThanXz) {
  TetMesh m = feaMesh();
  m.coord_type = ScalarType::kFloat32;
  for (double& x : m.coords) x = static_cast<float>(x);
  ASSERT_GT(m.numTets(), 30000u);
  auto enc = encodeLevel(m, EncodeOptions{});
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  EXPECT_LE(enc->geometry.size(), xz9(rawCoordinates(m)));
  for (size_t f = 0; f < m.point_fields.size(); ++f)
    EXPECT_LE(enc->point_fields[f].size(), xz9(m.point_fields[f].bytes)) << m.point_fields[f].name;
  for (size_t f = 0; f < m.cell_fields.size(); ++f)
    EXPECT_LE(enc->cell_fields[f].size(), xz9(m.cell_fields[f].bytes)) << m.cell_fields[f].name;
  // The scattered levels are packed; the smooth fields stay predicted.
  EXPECT_TRUE(isPackedStream(enc->point_fields[2]));
  // The per-cell levels: symbols say which tetrahedra share a hexahedron's value, the new values
  // are packed.
  EXPECT_TRUE(isSplitStream(enc->cell_fields[0]));
  EXPECT_FALSE(isPackedStream(enc->point_fields[0]));
  EXPECT_FALSE(isPackedStream(enc->geometry));
  expectLossless(m, *enc);
}

// Values drawn from a set of 1500 bit patterns (too many for a table, scattered: no prediction
// helps) with NaN payloads, signed zeros, infinities and subnormals among them.
TEST(PackedValues, PackedFormKeepsEveryBitPattern) {
  TetMesh m = test::gridMesh(20, 20, 10, 6);
  const size_t np = m.numPoints(), nt = m.numTets();
  Random rng;
  std::vector<uint64_t> set64(1500);
  for (uint64_t& b : set64) b = rng.next();
  const uint64_t specials[] = {0x7FF8000000000123u,
                               0xFFF0000000000001u,
                               0x8000000000000000u,
                               0x7FF0000000000000u,
                               0xFFF0000000000000u,
                               0x0000000000000001u,
                               0};
  for (size_t i = 0; i < std::size(specials); ++i) set64[i] = specials[i];
  std::vector<uint32_t> set32(1500);
  for (uint32_t& b : set32) b = static_cast<uint32_t>(rng.next());
  const uint32_t specials32[] = {0x7FC00123u, 0xFF800001u, 0x80000000u, 0x7F800000u, 0x00000001u};
  for (size_t i = 0; i < std::size(specials32); ++i) set32[i] = specials32[i];
  Field f64("f64", 2, ScalarType::kFloat64, np), f32("f32", 1, ScalarType::kFloat32, np);
  for (size_t v = 0; v < np; ++v) {
    for (uint32_t c = 0; c < 2; ++c) std::memcpy(&f64.bytes[(2 * v + c) * 8], &set64[rng.next() % set64.size()], 8);
    std::memcpy(&f32.bytes[v * 4], &set32[rng.next() % set32.size()], 4);
  }
  for (size_t i = 0; i < std::size(specials); ++i)
    std::memcpy(&f64.bytes[i * 16], &specials[i], 8);  // each one present
  Field c64("c64", 1, ScalarType::kFloat64, nt);
  for (size_t t = 0; t < nt; ++t) std::memcpy(&c64.bytes[t * 8], &set64[rng.next() % 40], 8);
  m.point_fields = {f64, f32};
  m.cell_fields = {c64};
  auto enc = encodeLevel(m, EncodeOptions{});
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  EXPECT_TRUE(isPackedStream(enc->point_fields[0]));
  EXPECT_TRUE(isPackedStream(enc->point_fields[1]));
  expectLossless(m, *enc);
}

// The packed form is taken only where it is smaller: against the predictions alone no stream grows
// (those left predicted may differ by a byte or two: they share a few models with the packed ones),
// and the smooth float64 field stays predicted.
TEST(PackedValues, PackedOnlyWhereSmaller) {
  TetMesh m = test::gridMesh(12, 10, 8, 5);
  test::addFields(m);
  EncodeOptions predicted;
  predicted.packed_streams = false;
  auto with = encodeLevel(m, EncodeOptions{}), without = encodeLevel(m, predicted);
  ASSERT_TRUE(with.isOk()) << with.status().message();
  ASSERT_TRUE(without.isOk()) << without.status().message();
  auto check = [](const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, const std::string& name) {
    if (isPackedStream(a) || isSplitStream(a)) {
      EXPECT_LT(a.size(), b.size()) << name;
    } else {
      EXPECT_LE(a.size(), b.size() + 2) << name;
    }
  };
  size_t total_with = with->geometry.size(), total_without = without->geometry.size();
  check(with->geometry, without->geometry, "coordinates");
  for (size_t f = 0; f < m.point_fields.size(); ++f) {
    check(with->point_fields[f], without->point_fields[f], m.point_fields[f].name);
    total_with += with->point_fields[f].size(), total_without += without->point_fields[f].size();
  }
  for (size_t f = 0; f < m.cell_fields.size(); ++f) {
    check(with->cell_fields[f], without->cell_fields[f], m.cell_fields[f].name);
    total_with += with->cell_fields[f].size(), total_without += without->cell_fields[f].size();
  }
  EXPECT_LE(total_with, total_without);
  EXPECT_FALSE(isPackedStream(with->point_fields[1]));  // velocity, smooth float64
  expectLossless(m, *with);
}

// A packed stream that is truncated, has bytes after its values, or declares an unknown layout or a
// dictionary larger than its values need, is an error naming the stream; so is a packed stream's
// item count that differs (a field declared with more components than it holds).
TEST(PackedValues, DamagedPackedStreamsAreRejected) {
  TetMesh m = feaMesh();
  auto enc = encodeLevel(m, EncodeOptions{});
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  ASSERT_TRUE(isPackedStream(enc->point_fields[2]));
  auto decodeWith = [&](const std::vector<uint8_t>& stream, const LevelHeader& header) {
    EncodedLevel copy = *enc;
    copy.header = header;
    copy.point_fields[2] = stream;
    CountingSink sink;
    return decodeLevel(copy.header, payloadOf(copy), sink, nullptr, "damaged.gtn level 0");
  };
  const std::vector<uint8_t> good = enc->point_fields[2];
  ASSERT_TRUE(decodeWith(good, enc->header).isOk());
  std::vector<std::vector<uint8_t>> bad;
  bad.emplace_back(good.begin(), good.end() - 1);  // truncated
  bad.emplace_back(good.begin(), good.begin() + good.size() / 2);
  bad.push_back(good), bad.back().push_back(0);                 // a byte after the end marker
  bad.push_back(good), bad.back()[1] = 7;                       // unknown layout
  bad.push_back(good), bad.back()[2] = 40;                      // 4 GiB dictionary
  bad.push_back(good), bad.back()[2] = kMaxPackedDictProperty;  // 64 MiB for 27 KiB of values
  bad.push_back({kPackedFormByte, 0});                          // no header
  for (const auto& stream : bad) {
    const Status st = decodeWith(stream, enc->header);
    ASSERT_FALSE(st.isOk());
    EXPECT_EQ(st.code(), StatusCode::kInvalidData);
    EXPECT_NE(st.message().find("damaged.gtn level 0: point field 'stress'"), std::string::npos) << st.message();
  }
  // The cell field in split form: a range-coded part cut off, its length beyond the stream, the
  // packed part truncated or followed by a byte.
  ASSERT_TRUE(isSplitStream(enc->cell_fields[0]));
  const std::vector<uint8_t> cells = enc->cell_fields[0];
  std::vector<std::vector<uint8_t>> bad_cells;
  bad_cells.emplace_back(cells.begin(), cells.begin() + 5);
  bad_cells.push_back({kSplitFormByte, 0, 0, 0xFF, 0xFF, 0xFF, 0x7F, 0});
  bad_cells.emplace_back(cells.begin(), cells.end() - 1);
  bad_cells.push_back(cells), bad_cells.back().push_back(0);
  for (const auto& stream : bad_cells) {
    EncodedLevel copy = *enc;
    copy.cell_fields[0] = stream;
    CountingSink sink;
    const Status st = decodeLevel(copy.header, payloadOf(copy), sink, nullptr, "damaged.gtn level 0");
    ASSERT_FALSE(st.isOk());
    EXPECT_NE(st.message().find("damaged.gtn level 0: "), std::string::npos) << st.message();
    EXPECT_NE(st.message().find("cell field"), std::string::npos) << st.message();
  }
  LevelHeader wider = enc->header;
  wider.point_fields[2].components = 2;
  const Status st = decodeWith(good, wider);
  ASSERT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("point field 'stress'"), std::string::npos) << st.message();
}

// The reader alone: items come back in both layouts, across several blocks, and reading past the end
// is an error, not a crash.
TEST(PackedValues, ReaderReturnsItemsAcrossBlocks) {
  const size_t count = 3 * packedBlockItems(12) + 5, item = 12;
  std::vector<uint8_t> items(count * item);
  Random rng;
  for (size_t i = 0; i < items.size(); ++i) items[i] = static_cast<uint8_t>(i % 12 < 6 ? rng.next() % 4 : i / 12);
  const std::vector<uint8_t> packed = packValues(items.data(), count, item, 4);
  ASSERT_TRUE(isPackedStream(packed));
  PackedReader r;
  ASSERT_TRUE(r.open(packed, count, item, 4, "s").isOk());
  for (size_t i = 0; i < count; ++i) {
    const uint8_t* p = r.next();
    ASSERT_NE(p, nullptr) << r.error();
    ASSERT_EQ(std::memcmp(p, &items[i * item], item), 0) << i;
  }
  EXPECT_TRUE(r.finish().isOk());
  EXPECT_EQ(r.next(), nullptr);
  EXPECT_NE(r.error().find("more values"), std::string::npos);
  PackedReader fewer;
  ASSERT_TRUE(fewer.open(packed, count - 1, item, 4, "s").isOk());
  for (size_t i = 0; i + 1 < count; ++i) ASSERT_NE(fewer.next(), nullptr);
  EXPECT_FALSE(fewer.finish().isOk());
}

}  // namespace
}  // namespace gtn
