// Helpers for the codec tests: synthetic meshes, a sink that checks the mesh-stream rules, and a
// lossless comparison of a decoded level with its source.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <set>
#include <string>

#include "codec/level_check.h"
#include "codec/level_codec.h"
#include "mesh/faces.h"
#include "mesh/hex_split.h"
#include "mesh/mesh_stats.h"
#include "mesh/mesh_stream.h"

namespace gtn::test {

// An nx x ny x nz grid of points (i fastest) whose cells are split with `split` (5 or 6); `keep`
// selects cells (all when empty). Coordinates get a smooth deformation so that predictions are not
// trivially exact.
inline TetMesh gridMesh(int nx, int ny, int nz, int split, bool (*keep)(int, int, int) = nullptr, double ox = 0.0) {
  TetMesh m;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double x = ox + i + 0.1 * std::sin(0.7 * j + 0.3 * k), y = j + 0.05 * i * std::cos(0.2 * k),
                     z = k * 1.3 + 0.02 * i * j;
        m.coords.insert(m.coords.end(), {x, y, z});
      }
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>(i + nx * (j + ny * k)); };
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        if (keep && !keep(i, j, k)) continue;
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if (split == 6) splitHexSix(h, m.tets);
        else splitHexFive(h, (i + j + k) % 2 == 1, m.tets);
      }
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  return m;
}

// Adds point fields of several types (smooth functions of position) and two cell fields.
inline void addFields(TetMesh& m) {
  const size_t n = m.numPoints();
  Field f32("pressure", 1, ScalarType::kFloat32, n), f64("velocity", 3, ScalarType::kFloat64, n),
      i32("label", 1, ScalarType::kInt32, n), u8("flags", 2, ScalarType::kUInt8, n),
      i64("big", 1, ScalarType::kInt64, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = m.point(v);
    f32.set<float>(v, 0, static_cast<float>(std::sin(p[0] * 0.3) * std::exp(0.1 * p[1]) + p[2]));
    for (uint32_t c = 0; c < 3; ++c) f64.set<double>(v, c, std::cos(p[c] * 0.2 + c) * (1.0 + p[(c + 1) % 3]));
    i32.set<int32_t>(v, 0, static_cast<int32_t>(std::floor(p[0] * 10 - p[1] * 7)));
    u8.set<uint8_t>(v, 0, static_cast<uint8_t>(v % 7));
    u8.set<uint8_t>(v, 1, static_cast<uint8_t>(p[2] > 2 ? 255 : 0));
    i64.set<int64_t>(v, 0, static_cast<int64_t>(v) * -1000000007LL);
  }
  m.point_fields = {f32, f64, i32, u8, i64};
  Field region("region", 1, ScalarType::kInt32, m.numTets()), q("quality", 2, ScalarType::kFloat64, m.numTets());
  for (size_t t = 0; t < m.numTets(); ++t) {
    region.set<int32_t>(t, 0, m.point(m.tets[t][0])[0] < 3 ? 1 : 2);
    q.set<double>(t, 0, 1.0 / (1.0 + t));
    q.set<double>(t, 1, -static_cast<double>(t % 5));
  }
  m.cell_fields = {region, q};
}

// The distinct edges (a < b) of the mesh's tetrahedra, in increasing order.
inline std::set<std::pair<uint32_t, uint32_t>> tetEdges(const TetMesh& m) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (const Tet& t : m.tets)
    for (const auto& e : kTetEdge) edges.insert({std::min(t[e[0]], t[e[1]]), std::max(t[e[0]], t[e[1]])});
  return edges;
}

// A sink that enforces the mesh-stream rules and forwards to a TetMeshBuilder.
class CheckingSink : public MeshSink {
 public:
  Status beginLevel(const LevelHeader& h) override {
    header_ = h;
    return builder.beginLevel(h);
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    EXPECT_EQ(id, state.size());
    state.push_back(1);
    ++live;
    peak = std::max(peak, live);
    return builder.vertex(id, xyz, values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    EXPECT_FALSE(ended_boundary);
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(v[i] < state.size() && state[v[i]] == 1);
    return builder.boundaryTriangle(v);
  }
  Status endBoundary() override {
    ended_boundary = true;
    return Status::ok();
  }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    EXPECT_TRUE(ended_boundary);
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(v[i] < state.size() && state[v[i]] == 1) << "tet uses a retired vertex";
    return builder.tet(v, cell_values);
  }
  Status retireVertex(uint32_t id) override {
    EXPECT_TRUE(id < state.size() && state[id] == 1);
    if (id < state.size()) state[id] = 2;
    --live;
    return Status::ok();
  }
  Status endLevel() override {
    for (uint8_t s : state) EXPECT_EQ(s, 2) << "vertex never retired";
    ended = true;
    return Status::ok();
  }

  TetMeshBuilder builder;
  std::vector<uint8_t> state;
  uint64_t live = 0, peak = 0;
  bool ended_boundary = false, ended = false;

 private:
  LevelHeader header_;
};

inline std::array<uint32_t, 3> canonicalTriangle(std::array<uint32_t, 3> t) {
  while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  return t;
}

// Checks that `decoded` equals `src` up to the renumbering the encoder reported.
inline void expectSameMesh(const TetMesh& src, const EncodedLevel& enc, const TetMesh& decoded,
                           const std::vector<std::array<uint32_t, 3>>& boundary) {
  ASSERT_EQ(decoded.numPoints(), src.numPoints());
  ASSERT_EQ(decoded.numTets(), src.numTets());
  ASSERT_EQ(enc.vertex_order.size(), src.numPoints());
  if (!enc.tet_order.empty()) {  // empty: the identity
    ASSERT_EQ(enc.tet_order.size(), src.numTets());
  }
  EXPECT_EQ(decoded.coord_type, src.coord_type);
  std::vector<uint8_t> seen(src.numPoints(), 0);
  for (size_t v = 0; v < src.numPoints(); ++v) {
    const uint32_t d = enc.vertex_order[v];
    ASSERT_LT(d, decoded.numPoints());
    ASSERT_FALSE(seen[d]);
    seen[d] = 1;
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(std::memcmp(&src.coords[3 * v + i], &decoded.coords[3 * d + i], 8), 0) << "coordinate of vertex " << v;
    }
  }
  ASSERT_EQ(decoded.point_fields.size(), src.point_fields.size());
  for (size_t f = 0; f < src.point_fields.size(); ++f) {
    const Field &a = src.point_fields[f], &b = decoded.point_fields[f];
    ASSERT_EQ(a.name, b.name);
    ASSERT_EQ(a.type, b.type);
    ASSERT_EQ(a.components, b.components);
    ASSERT_EQ(a.bytes.size(), b.bytes.size());
    const size_t ib = a.components * a.valueSize();
    for (size_t v = 0; v < src.numPoints(); ++v)
      ASSERT_EQ(std::memcmp(&a.bytes[v * ib], &b.bytes[enc.vertex_order[v] * ib], ib), 0)
          << "field " << a.name << " vertex " << v;
  }
  ASSERT_EQ(decoded.cell_fields.size(), src.cell_fields.size());
  std::vector<uint8_t> tseen(src.numTets(), 0);
  for (size_t t = 0; t < src.numTets(); ++t) {
    const uint64_t d = enc.tetPosition(t);
    ASSERT_LT(d, decoded.numTets());
    ASSERT_FALSE(tseen[d]);
    tseen[d] = 1;
    const Tet& s = src.tets[t];
    const Tet& o = decoded.tets[d];
    // Same vertices, and the decoded order is an even permutation of the mapped source order.
    int perm[4];
    for (int i = 0; i < 4; ++i) {
      perm[i] = -1;
      for (int j = 0; j < 4; ++j)
        if (o[j] == enc.vertex_order[s[i]]) perm[i] = j;
      ASSERT_GE(perm[i], 0) << "tetrahedron " << t << " lost a vertex";
    }
    int inv = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) inv += perm[i] > perm[j];
    ASSERT_EQ(inv % 2, 0) << "tetrahedron " << t << " changed orientation";
    for (size_t f = 0; f < src.cell_fields.size(); ++f) {
      const Field &a = src.cell_fields[f], &b = decoded.cell_fields[f];
      const size_t ib = a.components * a.valueSize();
      ASSERT_EQ(std::memcmp(&a.bytes[t * ib], &b.bytes[d * ib], ib), 0) << "cell field " << a.name << " tet " << t;
    }
  }
  const FaceAdjacency adj = computeFaceAdjacency(src);
  std::multiset<std::array<uint32_t, 3>> want, got;
  for (const Triangle& t : boundaryTriangles(src, adj))
    want.insert(canonicalTriangle({enc.vertex_order[t[0]], enc.vertex_order[t[1]], enc.vertex_order[t[2]]}));
  for (const auto& t : boundary) got.insert(canonicalTriangle(t));
  EXPECT_TRUE(want == got) << "boundary triangles differ";
}

inline size_t payloadBytes(const EncodedLevel& e) {
  size_t n = e.boundary.size() + e.connectivity.size() + e.geometry.size();
  for (const auto& s : e.point_fields) n += s.size();
  for (const auto& s : e.cell_fields) n += s.size();
  return n;
}

// Encodes, decodes through a CheckingSink, compares; returns the encoded level.
inline EncodedLevel roundTrip(const TetMesh& m, uint64_t* peak_live = nullptr, const EncodeOptions& options = {}) {
  auto enc = encodeLevel(m, options);
  EXPECT_TRUE(enc.isOk()) << enc.status().message();
  if (!enc.isOk()) return {};
  auto again = encodeLevel(m, options);
  EXPECT_TRUE(again.isOk());
  if (again.isOk()) {
    EXPECT_EQ(again->connectivity, enc->connectivity) << "encoder is not deterministic";
    EXPECT_EQ(again->geometry, enc->geometry) << "encoder is not deterministic";
    EXPECT_EQ(again->boundary, enc->boundary) << "encoder is not deterministic";
  }
  CheckingSink sink;
  DecodeStats stats;
  const Status st = decodeLevel(enc->header, payloadOf(*enc), sink, &stats, "test level");
  EXPECT_TRUE(st.isOk()) << st.message();
  EXPECT_TRUE(sink.ended);
  EXPECT_EQ(stats.peak_live_vertices, sink.peak);
  if (peak_live) *peak_live = stats.peak_live_vertices;
  expectSameMesh(m, *enc, sink.builder.mesh(), sink.builder.boundary());
  EXPECT_EQ(losslessMismatch(m, *enc), "");  // the writer's check agrees
  return std::move(enc).value();
}

// Decodes `e`, with the fields `fields` selects (null: all), into a mesh; fails the test on an error.
inline TetMesh decodeToMesh(const EncodedLevel& e, const DecodeFields* fields = nullptr) {
  CheckingSink sink;
  const Status st = decodeLevel(e.header, payloadOf(e), sink, nullptr, "test level", fields);
  EXPECT_TRUE(st.isOk()) << st.message();
  EXPECT_TRUE(sink.ended);
  return std::move(sink.builder.mesh());
}

// Decodes `e` once per field with that field alone selected and compares with the full decode: the same
// points and tetrahedra in the same order, and the selected field's values bit for bit. `unselected_zero`:
// no field of the level repeats a component of another, so every field left out must arrive as zero bytes
// (its values were not decoded). Returns the number of decodes that matched.
inline int expectFieldsDecodeAlone(const EncodedLevel& e, bool unselected_zero) {
  const TetMesh full = decodeToMesh(e);
  const size_t np = e.header.point_fields.size(), nc = e.header.cell_fields.size();
  int matched = 0;
  for (size_t i = 0; i < np + nc; ++i) {
    DecodeFields only;
    only.point.assign(np, false);
    only.cell.assign(nc, false);
    (i < np ? only.point[i] : only.cell[i - np]) = true;
    const TetMesh got = decodeToMesh(e, &only);
    const std::string name = i < np ? e.header.point_fields[i].name : e.header.cell_fields[i - np].name;
    EXPECT_TRUE(got.coords == full.coords) << name;
    EXPECT_TRUE(got.tets == full.tets) << name;
    bool same = got.coords == full.coords && got.tets == full.tets;
    for (size_t f = 0; f < np + nc; ++f) {
      const Field& a = f < np ? full.point_fields[f] : full.cell_fields[f - np];
      const Field& b = f < np ? got.point_fields[f] : got.cell_fields[f - np];
      if (f == i) {
        EXPECT_TRUE(a.bytes == b.bytes) << "field " << name << " decoded alone differs";
        same = same && a.bytes == b.bytes;
      } else if (unselected_zero) {
        const bool zero = std::all_of(b.bytes.begin(), b.bytes.end(), [](uint8_t x) { return x == 0; });
        EXPECT_TRUE(zero) << "field " << b.name << " was decoded with " << name << " alone";
        same = same && zero;
      }
    }
    matched += same;
  }
  return matched;
}

// The mesh as a renumbering-independent multiset: points as (coordinates, field bytes), tetrahedra as
// the sorted keys of their corners with their cell values.
inline std::multiset<std::string> canonicalMesh(const TetMesh& m) {
  std::vector<std::string> key(m.numPoints());
  for (size_t i = 0; i < m.numPoints(); ++i) {
    key[i].assign(reinterpret_cast<const char*>(m.point(i)), 24);
    for (const Field& f : m.point_fields) {
      const size_t n = f.components * f.valueSize();
      key[i].append(reinterpret_cast<const char*>(f.bytes.data() + i * n), n);
    }
  }
  std::multiset<std::string> out;
  for (const std::string& k : key) out.insert("p" + k);
  for (size_t t = 0; t < m.numTets(); ++t) {
    std::vector<std::string> c;
    for (uint32_t v : m.tets[t]) c.push_back(key[v]);
    std::sort(c.begin(), c.end());
    std::string k = "t";
    for (const std::string& s : c) k += s;
    for (const Field& f : m.cell_fields) {
      const size_t n = f.components * f.valueSize();
      k.append(reinterpret_cast<const char*>(f.bytes.data() + t * n), n);
    }
    out.insert(k);
  }
  return out;
}

}  // namespace gtn::test
