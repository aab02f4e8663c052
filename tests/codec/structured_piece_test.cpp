// A level coded as one structured piece (codec/structured_piece.h): generated grids of each rule,
// with blanked and explicit cells, welded nodes and fields, decode bit for bit into TetMeshBuilder
// with the mesh stream's order (every vertex, the boundary the face adjacency finds, tetrahedra,
// retirement right after the last use); meshes that are not their block are refused; corrupt or
// truncated pieces fail cleanly; the real PLOT3D datasets come out of the importer with their block
// and decode losslessly; the importers offer a block for one structured block only.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "codec/codec_test_util.h"
#include "codec/grid_coder.h"
#include "codec/structured_piece.h"
#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/predicates.h"
#include "test_util.h"

namespace gtn {
namespace {

// A mesh that is `layout`: nodes on a smoothly warped grid (aliases take no point), a Steiner point
// at the mean of its cell's corners, the layout's tetrahedra; point fields of several types and,
// with `cell_fields`, a cell field constant per cell and one per tetrahedron.
TetMesh meshOf(const GridLayout& layout, ScalarType coord_type = ScalarType::kFloat32, bool cell_fields = false) {
  TetMesh m;
  m.coord_type = coord_type;
  const uint32_t ni = layout.dims[0], nj = layout.dims[1], nk = layout.dims[2];
  std::vector<bool> aliased(layout.nodes(), false);
  for (const auto& [a, t] : layout.aliases) aliased[a] = true;
  auto inType = [&](double v) {
    if (coord_type == ScalarType::kFloat64) return v;
    volatile float f = static_cast<float>(v);
    return static_cast<double>(f);
  };
  std::vector<std::array<double, 3>> node;
  for (uint32_t k = 0; k < nk; ++k)
    for (uint32_t j = 0; j < nj; ++j)
      for (uint32_t i = 0; i < ni; ++i) {
        const std::array<double, 3> p = {inType(i + 0.1 * std::sin(0.7 * j + 0.3 * k)),
                                         inType(j + 0.05 * i * std::cos(0.2 * k)), inType(1.3 * k + 0.02 * i * j)};
        node.push_back(p);
        if (!aliased[node.size() - 1]) m.coords.insert(m.coords.end(), p.begin(), p.end());
      }
  const uint32_t ci = ni - 1, cj = nj - 1;
  for (const GridException& x : layout.exceptions) {
    const uint32_t i = x.cell % ci, j = (x.cell / ci) % cj, k = x.cell / (ci * cj);
    for (int e = 0; e < x.extras; ++e) {
      double c[3] = {0, 0, 0};
      for (uint32_t q = 0; q < 8; ++q) {
        const auto& p = node[(i + (q == 1 || q == 2 || q == 5 || q == 6)) +
                             ni * ((j + (q == 2 || q == 3 || q == 6 || q == 7)) + nj * (k + (q >= 4)))];
        for (int a = 0; a < 3; ++a) c[a] += p[a] / 8;
      }
      for (int a = 0; a < 3; ++a) m.coords.push_back(inType(c[a]));
    }
  }
  m.tets = gridTets(layout);
  const size_t n = m.numPoints();
  Field pressure("pressure", 1, ScalarType::kFloat32, n), velocity("velocity", 3, ScalarType::kFloat64, n),
      label("label", 1, ScalarType::kInt32, n);
  for (size_t v = 0; v < n; ++v) {
    const double* p = m.point(v);
    pressure.set<float>(v, 0, static_cast<float>(std::sin(p[0] * 0.3) + p[2]));
    for (uint32_t c = 0; c < 3; ++c) velocity.set<double>(v, c, std::cos(p[c] * 0.2 + c) * (1.0 + p[(c + 1) % 3]));
    label.set<int32_t>(v, 0, static_cast<int32_t>(std::floor(p[0] * 10 - p[1] * 7)));
  }
  m.point_fields = {pressure, velocity, label};
  if (cell_fields) {
    Field region("region", 1, ScalarType::kInt32, m.numTets()),
        quality("quality", 1, ScalarType::kFloat64, m.numTets());
    for (size_t t = 0; t < m.numTets(); ++t) {
      region.set<int32_t>(t, 0, m.point(m.tets[t][0])[0] < 3 ? 1 : 2);
      quality.set<double>(t, 0, 1.0 / (1.0 + t));
    }
    m.cell_fields = {region, quality};
  }
  return m;
}

GridLayout grid(uint32_t ni, uint32_t nj, uint32_t nk, uint8_t split, uint8_t parity = 0, bool left = false) {
  GridLayout l;
  l.dims[0] = ni, l.dims[1] = nj, l.dims[2] = nk;
  l.split = split;
  l.parity = parity;
  l.left_handed = left;
  return l;
}

StructuredBlock blockOf(const GridLayout& l) {
  StructuredBlock b;
  for (int a = 0; a < 3; ++a) b.dims[a] = l.dims[a];
  b.aliases = l.aliases;
  return b;
}

// The mesh stream's rules (CheckingSink) and the structured piece's order on top: every vertex before
// the first boundary triangle, the header's count of boundary triangles, each vertex retired before
// the tetrahedron after its last one (a vertex no tetrahedron uses right after endBoundary).
class OrderSink : public test::CheckingSink {
 public:
  Status beginLevel(const LevelHeader& h) override {
    header = h;
    return CheckingSink::beginLevel(h);
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    EXPECT_EQ(triangles, 0u) << "a vertex after a boundary triangle";
    return CheckingSink::vertex(id, xyz, values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    EXPECT_EQ(state.size(), header.points) << "a boundary triangle before the last vertex";
    ++triangles;
    return CheckingSink::boundaryTriangle(v);
  }
  Status endBoundary() override {
    EXPECT_EQ(triangles, header.boundary_triangles);
    return CheckingSink::endBoundary();
  }
  Status tet(const uint32_t v[4], const uint8_t* values) override {
    // Every vertex the previous tetrahedra used for the last time is retired by now.
    for (uint32_t u : pending) EXPECT_EQ(state[u], 2) << "vertex " << u << " not retired after its last tetrahedron";
    pending.clear();
    for (int q = 0; q < 4; ++q)
      if (--uses[v[q]] == 0) pending.push_back(v[q]);
    ++tets;
    return CheckingSink::tet(v, values);
  }
  Status endLevel() override {
    for (uint32_t u : pending) EXPECT_EQ(state[u], 2) << "vertex " << u << " not retired after its last tetrahedron";
    return CheckingSink::endLevel();
  }
  LevelHeader header;
  std::vector<uint32_t> uses;  // per vertex: tetrahedra still to come that use it (set by the test)
  std::vector<uint32_t> pending;
  uint64_t triangles = 0, tets = 0;
};

// Encodes `m` as the structured piece of its block, decodes it into TetMeshBuilder through the
// order checks and compares with the source (values bit for bit, the boundary the face adjacency
// finds, each tetrahedron positively oriented as in the source). Returns the encoding.
EncodedLevel roundTrip(const TetMesh& m, const StructuredBlock& block) {
  auto enc = encodeStructuredPiece(m, block);
  EXPECT_TRUE(enc.isOk()) << enc.status().message();
  if (!enc.isOk()) return {};
  EXPECT_EQ(enc->header.points, m.numPoints());
  EXPECT_EQ(enc->header.tets, m.numTets());
  EXPECT_EQ(enc->header.boundary_triangles, computeFaceAdjacency(m).boundary_faces);
  EXPECT_TRUE(enc->boundary.empty() && enc->geometry.empty());
  EXPECT_EQ(enc->point_fields.size(), m.point_fields.size());
  EXPECT_EQ(enc->cell_fields.size(), m.cell_fields.size());
  OrderSink sink;
  sink.uses.assign(m.numPoints(), 0);
  for (const Tet& t : m.tets)
    for (uint32_t v : t) ++sink.uses[enc->vertex_order[v]];
  const Status st = decodeStructuredPiece(enc->header, enc->connectivity, sink, "test piece");
  EXPECT_TRUE(st.isOk()) << st.message();
  EXPECT_TRUE(sink.ended);
  test::expectSameMesh(m, *enc, sink.builder.mesh(), sink.builder.boundary());
  // The decoded tetrahedra are the source's, in order and vertex order (the order is the identity).
  EXPECT_TRUE(sink.builder.mesh().tets == m.tets);
  return std::move(enc).value();
}

TEST(StructuredPiece, SplitFiveBothParitiesAndSplitSix) {
  for (const GridLayout& l : {grid(9, 7, 6, 5, 0), grid(9, 7, 6, 5, 1), grid(8, 7, 5, 6), grid(2, 2, 2, 5),
                              grid(6, 5, 4, 5, 1, true), grid(5, 4, 4, 6, 0, true)}) {
    SCOPED_TRACE("split " + std::to_string(l.split) + " parity " + std::to_string(l.parity) +
                 (l.left_handed ? " left-handed" : ""));
    TetMesh m = meshOf(l);
    if (l.left_handed)  // a mirrored block: its rule tetrahedra are positive
      for (size_t v = 0; v < m.numPoints(); ++v) m.coords[3 * v] = -m.coords[3 * v];
    for (const Tet& t : m.tets) ASSERT_GT(orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])), 0);
    const EncodedLevel e = roundTrip(m, blockOf(l));
    // The outer box's quadrilaterals, two triangles each.
    const uint64_t ci = l.dims[0] - 1, cj = l.dims[1] - 1, ck = l.dims[2] - 1;
    EXPECT_EQ(e.header.boundary_triangles, 4 * (ci * cj + cj * ck + ci * ck));
  }
}

TEST(StructuredPiece, BlankedCellsAndFields) {
  GridLayout l = grid(7, 6, 5, 5);
  // A corner cell, a run of three, an inner cell, the last cell: holes open onto the boundary.
  for (uint32_t c : {0u, 7u, 8u, 9u, 40u, static_cast<uint32_t>(l.cells() - 1)})
    l.exceptions.push_back({c, GridException::kBlanked, 0, {}});
  const TetMesh m = meshOf(l, ScalarType::kFloat64, true);
  ASSERT_EQ(m.numTets(), (l.cells() - 6) * 5);
  const EncodedLevel e = roundTrip(m, blockOf(l));
  EXPECT_GT(e.header.boundary_triangles, 4 * (6 * 5 + 5 * 4 + 6 * 4));  // the inner hole adds faces
}

TEST(StructuredPiece, UnusedNodesAreRetiredAfterTheBoundary) {
  // Blanking every cell around node (0, 0, 0) leaves it in no tetrahedron.
  GridLayout l = grid(4, 4, 4, 6);
  l.exceptions.push_back({0, GridException::kBlanked, 0, {}});
  TetMesh m = meshOf(l);
  roundTrip(m, blockOf(l));
}

// The 12 tetrahedra of a cell split around its Steiner point (corner 8) along the 6-split's diagonals.
std::vector<std::array<uint8_t, 4>> steinerCell() {
  return {{0, 1, 2, 8}, {0, 2, 3, 8}, {4, 6, 5, 8}, {4, 7, 6, 8}, {0, 5, 1, 8}, {0, 4, 5, 8},
          {3, 2, 6, 8}, {3, 6, 7, 8}, {0, 3, 7, 8}, {0, 7, 4, 8}, {1, 5, 6, 8}, {1, 6, 2, 8}};
}

TEST(StructuredPiece, ExplicitCellsNeighbouringCellsAndTheBox) {
  GridLayout l = grid(6, 5, 4, 6);
  l.exceptions.push_back({0, GridException::kExplicit, 1, steinerCell()});  // on the box, beside a blanked cell
  l.exceptions.push_back({1, GridException::kBlanked, 0, {}});
  l.exceptions.push_back({2, GridException::kExplicit, 0, {{0, 1, 2, 6}, {0, 2, 3, 6}}});  // part of a cell
  l.exceptions.push_back({26, GridException::kExplicit, 1, steinerCell()});                // inside
  l.exceptions.push_back({27, GridException::kExplicit, 1, steinerCell()});                // beside it
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  for (const Tet& t : m.tets) ASSERT_GT(orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])), 0);
  roundTrip(m, blockOf(l));
}

TEST(StructuredPiece, WeldedNodes) {
  // The last i-plane welded onto the first (an O-grid, as after --weld): the faces there are inside.
  GridLayout l = grid(8, 5, 4, 6);
  for (uint32_t k = 0; k < 4; ++k)
    for (uint32_t j = 0; j < 5; ++j) l.aliases.emplace_back(7 + 8 * (j + 5 * k), 8 * (j + 5 * k));
  const TetMesh m = meshOf(l);
  const EncodedLevel e = roundTrip(m, blockOf(l));
  EXPECT_EQ(e.header.boundary_triangles, 4 * (4 * 3 + 7 * 3 + 7 * 4) - 4 * 4 * 3);
}

TEST(StructuredPiece, CellValuesPerCellCostLess) {
  GridLayout l = grid(8, 7, 6, 5);
  TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  m.cell_fields.pop_back();
  for (size_t t = 0; t < m.numTets(); ++t) m.cell_fields[0].set<int32_t>(t, 0, static_cast<int32_t>(t / 5 % 4));
  GridEncodeReport per_cell;
  ASSERT_TRUE(encodeStructuredPiece(m, blockOf(l), {}, &per_cell).isOk());
  roundTrip(m, blockOf(l));
  // One tetrahedron of each cell differs: values per tetrahedron.
  for (size_t t = 0; t < m.numTets(); t += 5) m.cell_fields[0].set<int32_t>(t, 0, static_cast<int32_t>(t % 3));
  GridEncodeReport per_tet;
  ASSERT_TRUE(encodeStructuredPiece(m, blockOf(l), {}, &per_tet).isOk());
  roundTrip(m, blockOf(l));
  ASSERT_EQ(per_cell.cell_fields.size(), 1u);
  ASSERT_EQ(per_tet.cell_fields.size(), 1u);
  EXPECT_LT(per_cell.cell_fields[0], per_tet.cell_fields[0]);
}

TEST(StructuredPiece, FieldsLeftOutAreNotDecoded) {
  GridLayout l = grid(7, 6, 5, 5);
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  auto enc = encodeStructuredPiece(m, blockOf(l));
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  DecodeFields only;
  only.point = {false, true, false};
  only.cell = {true, false};
  std::vector<char> point_out, cell_out;
  only.streams_done = [&](const std::vector<char>& p, const std::vector<char>& c) { point_out = p, cell_out = c; };
  TetMeshBuilder b;
  ASSERT_TRUE(decodeStructuredPiece(enc->header, enc->connectivity, b, "test piece", &only).isOk());
  EXPECT_EQ(point_out, (std::vector<char>{1, 0, 1}));
  EXPECT_EQ(cell_out, (std::vector<char>{0, 1}));
  const TetMesh& got = b.mesh();
  EXPECT_TRUE(got.coords == m.coords);
  EXPECT_TRUE(got.tets == m.tets);
  EXPECT_TRUE(got.point_fields[1].bytes == m.point_fields[1].bytes);
  EXPECT_TRUE(got.cell_fields[0].bytes == m.cell_fields[0].bytes);
  for (const Field* f : {&got.point_fields[0], &got.point_fields[2], &got.cell_fields[1]})
    EXPECT_TRUE(std::all_of(f->bytes.begin(), f->bytes.end(), [](uint8_t x) { return x == 0; })) << f->name;
}

TEST(StructuredPiece, RefusesAMeshThatIsNotItsBlock) {
  const GridLayout l = grid(6, 5, 4, 5);
  const TetMesh m = meshOf(l);
  // Other dimensions.
  StructuredBlock other = blockOf(l);
  other.dims[0] = 5;
  auto r = encodeStructuredPiece(m, other);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  // Tetrahedra not cell by cell.
  TetMesh shuffled = m;
  std::swap(shuffled.tets[0], shuffled.tets[shuffled.tets.size() - 1]);
  r = encodeStructuredPiece(shuffled, blockOf(l));
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  // Points in another order.
  TetMesh moved = m;
  for (int a = 0; a < 3; ++a) std::swap(moved.coords[a], moved.coords[3 + a]);
  for (Tet& t : moved.tets)
    for (uint32_t& v : t) v = v == 0 ? 1 : v == 1 ? 0 : v;
  r = encodeStructuredPiece(moved, blockOf(l));
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  // A block that does not start at the first point.
  StructuredBlock later = blockOf(l);
  later.first_point = 1;
  r = encodeStructuredPiece(m, later);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  // A face in three tetrahedra: an explicit cell that repeats one of the rule's tetrahedra twice.
  GridLayout twice = grid(4, 4, 4, 6);
  twice.exceptions.push_back({5, GridException::kExplicit, 0, {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 1, 2, 6}}});
  r = encodeStructuredPiece(meshOf(twice), blockOf(twice));
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
}

TEST(StructuredPiece, CorruptAndTruncatedPiecesFailCleanly) {
  GridLayout l = grid(7, 6, 5, 5);
  l.exceptions.push_back({11, GridException::kBlanked, 0, {}});
  const TetMesh m = meshOf(l, ScalarType::kFloat32, true);
  auto enc = encodeStructuredPiece(m, blockOf(l));
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  const std::vector<uint8_t>& piece = enc->connectivity;
  auto decode = [&](std::span<const uint8_t> bytes, const LevelHeader& h) {
    CountingSink sink;
    return decodeStructuredPiece(h, bytes, sink, "file.gtn level 0");
  };
  for (size_t n = 0; n < piece.size(); n += 1 + n / 16) {
    const Status st = decode(std::span<const uint8_t>(piece.data(), n), enc->header);
    ASSERT_FALSE(st.isOk()) << "truncated to " << n << " bytes";
    EXPECT_EQ(st.code(), StatusCode::kInvalidData);
    EXPECT_EQ(st.message().rfind("file.gtn level 0", 0), 0u) << st.message();
  }
  std::vector<uint8_t> longer = piece;
  longer.push_back(0);
  EXPECT_FALSE(decode(longer, enc->header).isOk());
  // Flipped bits anywhere: an error or a mesh, never a crash.
  for (size_t at = 0; at < piece.size(); at += 1 + at / 8) {
    std::vector<uint8_t> bad = piece;
    bad[at] ^= static_cast<uint8_t>(1u << (at % 8));
    (void)decode(bad, enc->header);
  }
  // Counts that disagree with the header.
  for (int which = 0; which < 3; ++which) {
    LevelHeader h = enc->header;
    (which == 0 ? h.points : which == 1 ? h.tets : h.boundary_triangles) += 1;
    const Status st = decode(piece, h);
    ASSERT_FALSE(st.isOk());
    EXPECT_EQ(st.code(), StatusCode::kInvalidData);
    EXPECT_NE(st.message().find("the header says"), std::string::npos) << st.message();
  }
}

// A sink that assembles the whole mesh (TetMeshBuilder) takes the level in one call: the mesh and
// boundary it gets are those its events build (a subclass of it, which may watch them, gets the
// events), for every kind of layout; a corrupt piece fails or decodes alike either way.
TEST(StructuredPiece, WholeLevelIsTheMeshTheEventsBuild) {
  class Watching : public TetMeshBuilder {};
  GridLayout welded = grid(8, 5, 4, 6);
  for (uint32_t k = 0; k < 4; ++k)
    for (uint32_t j = 0; j < 5; ++j) welded.aliases.emplace_back(7 + 8 * (j + 5 * k), 8 * (j + 5 * k));
  GridLayout holes = grid(6, 5, 4, 6);
  holes.exceptions.push_back({0, GridException::kExplicit, 1, steinerCell()});
  holes.exceptions.push_back({1, GridException::kBlanked, 0, {}});
  holes.exceptions.push_back({26, GridException::kExplicit, 1, steinerCell()});
  const std::vector<std::pair<GridLayout, ScalarType>> cases = {{grid(9, 7, 6, 5, 1), ScalarType::kFloat32},
                                                                {grid(7, 6, 5, 6), ScalarType::kFloat64},
                                                                {welded, ScalarType::kFloat32},
                                                                {holes, ScalarType::kFloat64}};
  for (const auto& [l, type] : cases) {
    SCOPED_TRACE("split " + std::to_string(l.split) + ", " + std::to_string(l.aliases.size()) + " aliases, " +
                 std::to_string(l.exceptions.size()) + " exceptions");
    const TetMesh m = meshOf(l, type, true);
    auto enc = encodeStructuredPiece(m, blockOf(l));
    ASSERT_TRUE(enc.isOk()) << enc.status().message();
    auto same = [&](const std::vector<uint8_t>& piece, bool must_decode) {
      TetMeshBuilder whole;
      Watching events;
      ASSERT_TRUE(whole.takesWholeLevel());
      ASSERT_FALSE(events.takesWholeLevel());
      const Status a = decodeStructuredPiece(enc->header, piece, whole, "test piece");
      const Status b = decodeStructuredPiece(enc->header, piece, events, "test piece");
      ASSERT_EQ(a.isOk(), b.isOk()) << a.message() << " / " << b.message();
      if (must_decode) {
        ASSERT_TRUE(a.isOk()) << a.message();
      }
      if (!a.isOk()) return;
      const TetMesh &x = whole.mesh(), &y = events.mesh();
      EXPECT_EQ(x.coord_type, y.coord_type);
      EXPECT_TRUE(x.coords == y.coords);
      EXPECT_TRUE(x.tets == y.tets);
      ASSERT_EQ(x.point_fields.size(), y.point_fields.size());
      for (size_t f = 0; f < x.point_fields.size(); ++f) {
        EXPECT_EQ(x.point_fields[f].name, y.point_fields[f].name);
        EXPECT_TRUE(x.point_fields[f].bytes == y.point_fields[f].bytes) << x.point_fields[f].name;
      }
      ASSERT_EQ(x.cell_fields.size(), y.cell_fields.size());
      for (size_t f = 0; f < x.cell_fields.size(); ++f)
        EXPECT_TRUE(x.cell_fields[f].bytes == y.cell_fields[f].bytes) << x.cell_fields[f].name;
      EXPECT_TRUE(whole.boundary() == events.boundary());
      EXPECT_EQ(whole.header().points, events.header().points);
    };
    same(enc->connectivity, true);
    if (l.aliases.empty()) continue;
    for (size_t at = 0; at < enc->connectivity.size(); at += 1 + at / 8) {
      std::vector<uint8_t> bad = enc->connectivity;
      bad[at] ^= static_cast<uint8_t>(1u << (at % 8));
      same(bad, false);
    }
  }
}

// ---- The importers' block ------------------------------------------------------------------------

// A PLOT3D grid file (big-endian, 4-byte record markers, float32; a grid count first for several
// grids) of warped blocks of the given node counts, side by side.
std::string plot3dGrid(const std::vector<std::array<int, 3>>& blocks) {
  std::string out, record;
  auto put32 = [&](uint32_t v) {
    for (int b = 3; b >= 0; --b) record.push_back(static_cast<char>((v >> (8 * b)) & 0xFF));
  };
  auto flush = [&] {
    const std::string body = record;
    record.clear();
    put32(static_cast<uint32_t>(body.size()));
    const std::string marker = record;
    out += marker + body + marker;
    record.clear();
  };
  if (blocks.size() > 1) {
    put32(static_cast<uint32_t>(blocks.size()));
    flush();
  }
  for (const auto& d : blocks)
    for (int a = 0; a < 3; ++a) put32(static_cast<uint32_t>(d[a]));
  flush();
  float offset = 0;
  for (const auto& d : blocks) {
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < d[2]; ++k)
        for (int j = 0; j < d[1]; ++j)
          for (int i = 0; i < d[0]; ++i) {
            const float v = a == 0 ? offset + i + 0.1f * std::sin(0.7f * j) : a == 1 ? j + 0.05f * i : 1.3f * k;
            uint32_t bits;
            std::memcpy(&bits, &v, 4);
            put32(bits);
          }
    flush();
    offset += 100;
  }
  return out;
}

TEST(StructuredPieceImport, Plot3dSingleBlockOffersItsBlock) {
  const std::string dir = test::tempDir("structured_piece_plot3d");
  const std::string one = dir + "/one.xyz", two = dir + "/two.xyz";
  test::writeFile(one, plot3dGrid({{5, 4, 3}}));
  test::writeFile(two, plot3dGrid({{5, 4, 3}, {3, 3, 3}}));
  for (int split : {5, 6}) {
    ImportOptions options;
    options.split = split;
    auto r = importMesh({one}, options);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    ASSERT_EQ(r->mesh.blocks.size(), 1u);
    const StructuredBlock& b = r->mesh.blocks[0];
    EXPECT_EQ(b.first_point, 0u);
    EXPECT_EQ(b.dims[0], 5u);
    EXPECT_EQ(b.dims[1], 4u);
    EXPECT_EQ(b.dims[2], 3u);
    roundTrip(r->mesh, b);
    // Several blocks: none offered (a level of several blocks is not one structured piece).
    auto multi = importMesh({two}, options);
    ASSERT_TRUE(multi.isOk()) << multi.status().message();
    EXPECT_TRUE(multi->mesh.blocks.empty());
  }
}

TEST(StructuredPieceImport, VtkStructuredOffersItsBlockUnstructuredNone) {
  const std::string dir = test::tempDir("structured_piece_vtk");
  const std::string points = dir + "/points.vtk", rect = dir + "/rect.vtk", sgrid = dir + "/sgrid.vtk",
                    unstructured = dir + "/hex.vtk";
  test::writeFile(
      points,
      "# vtk DataFile Version 3.0\nimage\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 4 3 3\n"
      "ORIGIN 0 0 0\nSPACING 1 0.5 2\nPOINT_DATA 36\nSCALARS s float 1\nLOOKUP_TABLE default\n" +
          [] {
            std::string s;
            for (int i = 0; i < 36; ++i) s += std::to_string(i * 0.25) + "\n";
            return s;
          }());
  test::writeFile(rect,
                  "# vtk DataFile Version 3.0\nrect\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 3 3 2\n"
                  "X_COORDINATES 3 float\n0 1 3\nY_COORDINATES 3 float\n0 2 2.5\nZ_COORDINATES 2 float\n0 1\n");
  {
    std::string s =
        "# vtk DataFile Version 3.0\nsgrid\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 3 2 2\nPOINTS 12 float\n";
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 3; ++i)
          s += std::to_string(i + 0.1 * j) + " " + std::to_string(j) + " " + std::to_string(k) + "\n";
    test::writeFile(sgrid, s);
  }
  test::writeFile(unstructured, test::shearedHexGridVtk(3));
  // An XML StructuredGrid with a cell field (one value per cell: coded once per cell).
  const std::string vts = dir + "/g.vts";
  test::writeFile(vts, R"(<?xml version="1.0"?>
<VTKFile type="StructuredGrid" version="0.1" byte_order="LittleEndian">
<StructuredGrid WholeExtent="0 2 0 1 0 1"><Piece Extent="0 2 0 1 0 1">
<PointData><DataArray type="Float32" Name="t" format="ascii">0 1 2 3 4 5 6 7 8 9 10 11.5</DataArray></PointData>
<CellData><DataArray type="Int32" Name="zone" format="ascii">5 6</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">
0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0  0.5 0 1  1.5 0 1  2.5 0 1  0.5 1 1  1.5 1 1  2.5 1 1</DataArray></Points>
</Piece></StructuredGrid></VTKFile>
)");
  for (const std::string& path : {points, rect, sgrid, vts}) {
    SCOPED_TRACE(path);
    auto r = importMesh({path}, ImportOptions{});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    ASSERT_EQ(r->mesh.blocks.size(), 1u);
    EXPECT_EQ(r->mesh.blocks[0].dims[0] * r->mesh.blocks[0].dims[1] * r->mesh.blocks[0].dims[2], r->mesh.numPoints());
    roundTrip(r->mesh, r->mesh.blocks[0]);
  }
  auto u = importMesh({unstructured}, ImportOptions{});
  ASSERT_TRUE(u.isOk()) << u.status().message();
  EXPECT_TRUE(u->mesh.blocks.empty());
}

// ---- The real PLOT3D datasets --------------------------------------------------------------------

void realDataset(const std::string& xyz, const std::string& q, bool weld, const uint32_t dims[3]) {
  ImportOptions options;
  options.split = 5;
  options.weld = weld;
  auto imported = importMesh({test::dataPath(xyz), test::dataPath(q)}, options);
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  const TetMesh& mesh = imported->mesh;
  ASSERT_EQ(mesh.blocks.size(), 1u);
  const StructuredBlock& b = mesh.blocks[0];
  for (int a = 0; a < 3; ++a) EXPECT_EQ(b.dims[a], dims[a]);
  EXPECT_EQ(b.aliases.size(), imported->report.welded_points);
  const EncodedLevel e = roundTrip(mesh, b);
  const double bits = 8.0 * static_cast<double>(e.connectivity.size()) / static_cast<double>(mesh.numTets());
  // Format 1.0's level 0 of the 5-split grids takes 18.3 and 28.7 bits per tetrahedron.
  EXPECT_LT(bits, xyz.find("bluntfin") != std::string::npos ? 18.3 : 28.7);
}

TEST(StructuredPieceReal, BluntFinSplitFive) {
  const uint32_t dims[3] = {40, 32, 32};
  realDataset("plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin", false, dims);
}
TEST(StructuredPieceReal, CombustionSplitFive) {
  const uint32_t dims[3] = {57, 33, 25};
  realDataset("plot3d/combxyz.bin", "plot3d/combq.bin", false, dims);
}
TEST(StructuredPieceReal, BluntFinWeldedHasAliases) {
  // --weld merges 39 points of blunt fin's block into others: they become the layout's aliases.
  const uint32_t dims[3] = {40, 32, 32};
  realDataset("plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin", true, dims);
}

}  // namespace
}  // namespace gtn
