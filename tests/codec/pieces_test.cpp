// A level as pieces (codec/pieces.h): lossless through pieces and seams, stitching, subsets, the
// mesh stream of a stitched level, determinism and corrupt input.
#include "codec/pieces.h"
#include "codec/grid_coder.h"
#include "codec/pieces_check.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "codec/codec_test_util.h"
#include "mesh/faces.h"
#include "mesh/index.h"

namespace gtn::test {
namespace {

// The orders of a pieced level, where expectSameMesh takes them.
EncodedLevel ordersOf(const PiecedLevel& level) {
  EncodedLevel e;
  e.vertex_order = level.vertex_order;
  e.tet_order = level.tet_order;
  return e;
}

TetMesh fieldGrid(int n) {
  TetMesh m = gridMesh(n, n, n, 5);
  addFields(m);
  return m;
}

TEST(Pieces, AGridCutIntoPiecesDecodesToItsSource) {
  const TetMesh m = fieldGrid(22);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
  ASSERT_TRUE(level.isOk()) << level.status().message();
  EXPECT_GE(level->pieces.size(), 8u);
  EXPECT_FALSE(level->classes.empty());
  uint64_t tets = 0, own = 0, seam = 0;
  for (const PieceInfo& p : level->pieces) {
    EXPECT_LE(p.tets, 4096u);
    EXPECT_GT(p.points, p.own_points);  // every piece of a cut grid has seam vertices
    tets += p.tets;
    own += p.own_points;
  }
  for (const SeamClass& c : level->classes) {
    EXPECT_GE(c.pieces.size(), 2u);
    EXPECT_TRUE(std::is_sorted(c.pieces.begin(), c.pieces.end()));
    seam += c.points;
  }
  EXPECT_EQ(tets, m.numTets());
  EXPECT_EQ(own + seam, m.numPoints());  // each vertex stored once
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "grid");
  ASSERT_TRUE(decoded.isOk()) << decoded.status().message();
  EXPECT_TRUE(decoded->global_vertex.empty());
  expectSameMesh(m, ordersOf(*level), decoded->mesh, decoded->boundary);
  EXPECT_EQ(decoded->boundary.size(), level->header.boundary_triangles);
}

TEST(Pieces, OnePieceIsTheLevelCodecsOwnCoding) {
  const TetMesh m = fieldGrid(8);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, kDefaultPieceTets);
  ASSERT_TRUE(level.isOk());
  ASSERT_EQ(level->pieces.size(), 1u);
  EXPECT_TRUE(level->classes.empty());
  StatusOr<EncodedLevel> direct = encodeLevel(m, {});
  ASSERT_TRUE(direct.isOk());
  EXPECT_EQ(level->encoded[0].connectivity, direct->connectivity);
  EXPECT_EQ(level->encoded[0].geometry, direct->geometry);
  EXPECT_EQ(level->vertex_order, direct->vertex_order);
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "one");
  ASSERT_TRUE(decoded.isOk());
  const TetMesh via_codec = decodeToMesh(*direct);
  EXPECT_EQ(decoded->mesh.coords, via_codec.coords);
  EXPECT_EQ(decoded->mesh.tets, via_codec.tets);
}

TEST(Pieces, AStructuredBlockIsOneStructuredPieceWhenThatIsSmaller) {
  TetMesh m = fieldGrid(12);
  StructuredBlock block;
  block.first_point = 0;
  block.dims[0] = block.dims[1] = block.dims[2] = 12;
  m.blocks.push_back(block);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, kDefaultPieceTets);
  ASSERT_TRUE(level.isOk()) << level.status().message();
  ASSERT_EQ(level->pieces.size(), 1u);
  EXPECT_EQ(level->pieces[0].kind, 1);
  EXPECT_EQ(level->pieces[0].own_boundary_points, m.numPoints());
  EncodeOptions unstructured;
  unstructured.structured = false;
  StatusOr<PiecedLevel> plain = encodePieces(m, unstructured, kDefaultPieceTets);
  ASSERT_TRUE(plain.isOk());
  EXPECT_EQ(plain->pieces[0].kind, 0);
  auto bytes = [](const EncodedLevel& e) {
    size_t n = e.boundary.size() + e.connectivity.size() + e.geometry.size();
    for (const auto& f : e.point_fields) n += f.size();
    for (const auto& f : e.cell_fields) n += f.size();
    return n;
  };
  EXPECT_LT(bytes(level->encoded[0]), bytes(plain->encoded[0]));
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "block");
  ASSERT_TRUE(decoded.isOk()) << decoded.status().message();
  expectSameMesh(m, ordersOf(*level), decoded->mesh, decoded->boundary);
  TetMeshBuilder builder;
  ASSERT_TRUE(emitDecoded(level->header, *decoded, builder).isOk());
  expectSameMesh(m, ordersOf(*level), builder.mesh(), builder.boundary());
  // A mesh that is not the block it claims stays unstructured.
  TetMesh other = m;
  other.blocks[0].dims[2] = 11;
  StatusOr<PiecedLevel> fallback = encodePieces(other, {}, kDefaultPieceTets);
  ASSERT_TRUE(fallback.isOk());
  EXPECT_EQ(fallback->pieces[0].kind, 0);
}

// At the default bound, a grid of more tetrahedra than the bound is one structured piece (the level
// codec's pieces are not tried: they decode many times slower, and take more bytes, as here); at
// another bound, or unstructured, it is cut.
TEST(Pieces, AStructuredBlockLargerThanTheDefaultBoundStaysOnePiece) {
  const int n = 66;                  // 65^3 cells, 5 tetrahedra each: more than 2^20
  TetMesh m = gridMesh(n, n, n, 5);  // coordinates only: the level codec takes long on this many
  StructuredBlock block;
  block.first_point = 0;
  block.dims[0] = block.dims[1] = block.dims[2] = n;
  m.blocks.push_back(block);
  ASSERT_GT(m.numTets(), kDefaultPieceTets);
  const uint64_t piece_tets = kDefaultPieceTets;
  StatusOr<PiecedLevel> level = encodePieces(m, {}, piece_tets);
  ASSERT_TRUE(level.isOk()) << level.status().message();
  ASSERT_EQ(level->pieces.size(), 1u);
  EXPECT_EQ(level->pieces[0].kind, 1);
  EXPECT_TRUE(level->classes.empty());
  EXPECT_EQ(level->pieces[0].tets, m.numTets());
  EncodeOptions unstructured;
  unstructured.structured = false;
  StatusOr<PiecedLevel> cut = encodePieces(m, unstructured, piece_tets);
  ASSERT_TRUE(cut.isOk()) << cut.status().message();
  EXPECT_GE(cut->pieces.size(), 2u);
  auto bytes = [](const PiecedLevel& l) {
    size_t n = 0;
    for (const EncodedLevel& e : l.encoded) {
      n += e.boundary.size() + e.connectivity.size() + e.geometry.size();
      for (const auto& f : e.point_fields) n += f.size();
      for (const auto& f : e.cell_fields) n += f.size();
    }
    for (const auto& s : l.seam_streams) n += s.size();
    return n;
  };
  EXPECT_LT(bytes(*level), bytes(*cut));
  EXPECT_EQ(piecedLosslessMismatch(m, *level), "");
  // Its tetrahedra keep the source's order: no order of 8 bytes a tetrahedron is kept, and the check
  // still compares each tetrahedron with the one at its own place.
  EXPECT_TRUE(level->tet_order.empty());
  EXPECT_EQ(level->tetPosition(12345), 12345u);
  {
    // The check compares the decoder's events with the source as they come (nothing decoded is
    // held), and names the first difference: points come before tetrahedra.
    TetMesh turned = m;
    std::swap(turned.tets[777][0], turned.tets[777][1]);
    EXPECT_EQ(piecedLosslessMismatch(turned, *level), "source tetrahedron 777 (decoded 777) is reversed");
    turned.tets[778][2] = turned.tets[900][0];
    EXPECT_EQ(piecedLosslessMismatch(turned, *level), "source tetrahedron 777 (decoded 777) is reversed");
    TetMesh moved = turned;
    moved.coords[3 * 4321 + 1] += 0.5;
    moved.coords[3 * 5000] += 0.5;
    EXPECT_EQ(piecedLosslessMismatch(moved, *level), "source point 4321 (decoded 4321) moved");
    std::swap(turned.tets[777][0], turned.tets[777][1]);
    EXPECT_EQ(piecedLosslessMismatch(turned, *level), "source tetrahedron 778 (decoded 778) has other vertices");
    TetMesh fewer = m;
    fewer.tets.pop_back();
    EXPECT_EQ(piecedLosslessMismatch(fewer, *level), "more tetrahedra decoded than the source has");
    // The source's tetrahedra released (a large convert's), made from their indices: the same check.
    auto layout = matchGridLayout(m, block.dims);
    ASSERT_TRUE(layout.isOk()) << layout.status().message();
    const RuleGridTets rule(*layout);
    TetMesh bare = m;
    bare.tets.clear();
    EXPECT_EQ(piecedLosslessMismatch(bare, *level, &rule), "");
    moved.tets.clear();
    EXPECT_EQ(piecedLosslessMismatch(moved, *level, &rule), "source point 4321 (decoded 4321) moved");
    GridLayout other = *layout;
    other.parity ^= 1;  // another rule's tetrahedra
    const RuleGridTets wrong(other);
    EXPECT_EQ(piecedLosslessMismatch(bare, *level, &wrong), "source tetrahedron 0 (decoded 0) has other vertices");
    EXPECT_EQ(piecedLosslessMismatch(bare, *cut, &rule),
              "a grid's tetrahedra given for a level that is not one structured piece");
  }
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "block");
  ASSERT_TRUE(decoded.isOk()) << decoded.status().message();
  expectSameMesh(m, ordersOf(*level), decoded->mesh, decoded->boundary);
  // Another bound asks for pieces: a grid larger than it is cut as the level codec's.
  TetMesh small = fieldGrid(16);
  StructuredBlock small_block;
  small_block.first_point = 0;
  small_block.dims[0] = small_block.dims[1] = small_block.dims[2] = 16;
  small.blocks.push_back(small_block);
  StatusOr<PiecedLevel> asked = encodePieces(small, {}, 4096);
  ASSERT_TRUE(asked.isOk()) << asked.status().message();
  EXPECT_GE(asked->pieces.size(), 4u);
  for (const PieceInfo& p : asked->pieces) EXPECT_EQ(p.kind, 0);
  StatusOr<PiecedLevel> whole = encodePieces(small, {}, kDefaultPieceTets);
  ASSERT_TRUE(whole.isOk()) << whole.status().message();
  ASSERT_EQ(whole->pieces.size(), 1u);
  EXPECT_EQ(whole->pieces[0].kind, 1);
  // A grid's field values are compared too.
  ASSERT_FALSE(small.point_fields.empty());
  EXPECT_EQ(piecedLosslessMismatch(small, *whole), "");
  {
    Field& f = small.point_fields.back();
    f.bytes[7 * f.components * f.valueSize()] ^= 1;
  }
  EXPECT_EQ(piecedLosslessMismatch(small, *whole), "source point 7 (decoded 7) has other field values");
}

TEST(Pieces, TheMeshStreamOfAStitchedLevelFollowsTheStreamOrder) {
  const TetMesh m = fieldGrid(18);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
  ASSERT_TRUE(level.isOk());
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "grid");
  ASSERT_TRUE(decoded.isOk());
  // A checking sink: ids in order, every reference to an emitted and live vertex, boundary first,
  // each vertex retired once after its last tetrahedron.
  struct Checker : TetMeshBuilder {
    std::vector<int> state;  // 0 not emitted, 1 live, 2 retired
    bool boundary_done = false, ok = true;
    Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
      ok = ok && id == state.size();
      state.push_back(1);
      return TetMeshBuilder::vertex(id, xyz, values);
    }
    Status boundaryTriangle(const uint32_t v[3]) override {
      for (int i = 0; i < 3; ++i) ok = ok && !boundary_done && v[i] < state.size() && state[v[i]] == 1;
      return TetMeshBuilder::boundaryTriangle(v);
    }
    Status endBoundary() override {
      boundary_done = true;
      return Status::ok();
    }
    Status tet(const uint32_t v[4], const uint8_t* c) override {
      for (int i = 0; i < 4; ++i) ok = ok && boundary_done && v[i] < state.size() && state[v[i]] == 1;
      return TetMeshBuilder::tet(v, c);
    }
    Status retireVertex(uint32_t id) override {
      ok = ok && id < state.size() && state[id] == 1;
      if (id < state.size()) state[id] = 2;
      return Status::ok();
    }
  } checker;
  ASSERT_TRUE(emitDecoded(level->header, *decoded, checker).isOk());
  EXPECT_TRUE(checker.ok);
  EXPECT_EQ(std::count(checker.state.begin(), checker.state.end(), 2), static_cast<long>(m.numPoints()));
  expectSameMesh(m, ordersOf(*level), checker.mesh(), checker.boundary());
}

TEST(Pieces, ASubsetOfPiecesDecodesAsThoseTetrahedraOfTheWholeLevel) {
  const TetMesh m = fieldGrid(20);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
  ASSERT_TRUE(level.isOk());
  ASSERT_GE(level->pieces.size(), 4u);
  const PiecedLevelView view = piecedViewOf(*level);
  StatusOr<DecodedPieces> whole = decodePieces(view, {}, "grid");
  ASSERT_TRUE(whole.isOk());
  const std::vector<uint32_t> chosen = {1, 3};
  StatusOr<DecodedPieces> part = decodePieces(view, chosen, "grid");
  ASSERT_TRUE(part.isOk()) << part.status().message();
  const uint64_t want_tets = level->pieces[1].tets + level->pieces[3].tets;
  ASSERT_EQ(part->mesh.numTets(), want_tets);
  ASSERT_EQ(part->global_tet.size(), want_tets);
  ASSERT_EQ(part->global_vertex.size(), part->mesh.numPoints());
  for (size_t t = 0; t < part->mesh.numTets(); ++t) {
    const Tet& a = part->mesh.tets[t];
    const Tet& b = whole->mesh.tets[part->global_tet[t]];
    for (int j = 0; j < 4; ++j) ASSERT_EQ(part->global_vertex[a[j]], b[j]);
    for (size_t f = 0; f < m.cell_fields.size(); ++f) {
      const size_t ib = m.cell_fields[f].components * m.cell_fields[f].valueSize();
      ASSERT_EQ(std::memcmp(&part->mesh.cell_fields[f].bytes[t * ib],
                            &whole->mesh.cell_fields[f].bytes[part->global_tet[t] * ib], ib),
                0);
    }
  }
  for (size_t v = 0; v < part->mesh.numPoints(); ++v) {
    const uint32_t g = part->global_vertex[v];
    for (int i = 0; i < 3; ++i) ASSERT_EQ(part->mesh.coords[3 * v + i], whole->mesh.coords[3 * size_t{g} + i]);
  }
  // The subset's boundary is the boundary of its tetrahedra (cut faces to pieces left out included).
  const FaceAdjacency adj = computeFaceAdjacency(part->mesh);
  EXPECT_EQ(part->boundary.size(), adj.boundary_faces);
  // Pieces in a box: a box around piece 0's bounding box holds piece 0.
  const std::vector<uint32_t> in_box = piecesInBox(level->pieces, level->pieces[0].bbox_min, level->pieces[0].bbox_max);
  EXPECT_NE(std::find(in_box.begin(), in_box.end(), 0u), in_box.end());
  EXPECT_LT(in_box.size(), level->pieces.size());
  const double far_lo[3] = {1e9, 1e9, 1e9}, far_hi[3] = {2e9, 2e9, 2e9};
  EXPECT_TRUE(piecesInBox(level->pieces, far_lo, far_hi).empty());
}

TEST(Pieces, TheSameBytesForAnyThreadCount) {
  const TetMesh m = fieldGrid(20);
  auto encodeWith = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
    EXPECT_TRUE(level.isOk());
    return std::move(*level);
  };
  const PiecedLevel one = encodeWith(1), two = encodeWith(2);
  ASSERT_EQ(one.encoded.size(), two.encoded.size());
  for (size_t p = 0; p < one.encoded.size(); ++p) {
    EXPECT_EQ(one.encoded[p].connectivity, two.encoded[p].connectivity);
    EXPECT_EQ(one.encoded[p].geometry, two.encoded[p].geometry);
    EXPECT_EQ(one.encoded[p].point_fields, two.encoded[p].point_fields);
  }
  EXPECT_EQ(one.seam_streams, two.seam_streams);
  EXPECT_EQ(one.vertex_order, two.vertex_order);
}

TEST(Pieces, UnusedPointsAndFieldSubsetsSurviveThePieces) {
  TetMesh m = fieldGrid(20);
  // Unused points: mid-edge points of a few edges and a stray point.
  const size_t n = m.numPoints();
  std::vector<std::array<uint32_t, 2>> edges = {{m.tets[0][0], m.tets[0][1]}, {m.tets[9000][2], m.tets[9000][3]}};
  for (const auto& e : edges)
    for (int i = 0; i < 3; ++i)
      m.coords.push_back(0.5 * (m.coords[3 * size_t{e[0]} + i] + m.coords[3 * size_t{e[1]} + i]));
  m.coords.insert(m.coords.end(), {100.0, 100.0, 100.0});
  for (Field& f : m.point_fields) f.bytes.resize((n + 3) * f.components * f.valueSize(), 7);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
  ASSERT_TRUE(level.isOk()) << level.status().message();
  StatusOr<DecodedPieces> decoded = decodePieces(piecedViewOf(*level), {}, "grid");
  ASSERT_TRUE(decoded.isOk()) << decoded.status().message();
  expectSameMesh(m, ordersOf(*level), decoded->mesh, decoded->boundary);
  // One point field: the others are left out (zero), the chosen one exact.
  DecodeFields fields;
  fields.point = {true, false, false, false, false};
  fields.cell = {false, true};
  StatusOr<DecodedPieces> some = decodePieces(piecedViewOf(*level), {}, "grid", &fields);
  ASSERT_TRUE(some.isOk()) << some.status().message();
  EXPECT_EQ(some->mesh.point_fields[0].bytes, decoded->mesh.point_fields[0].bytes);
  EXPECT_EQ(some->mesh.cell_fields[1].bytes, decoded->mesh.cell_fields[1].bytes);
  EXPECT_EQ(some->mesh.coords, decoded->mesh.coords);
}

TEST(Pieces, CorruptSeamsAndPieceTablesAreRefused) {
  const TetMesh m = fieldGrid(18);
  StatusOr<PiecedLevel> level = encodePieces(m, {}, 4096);
  ASSERT_TRUE(level.isOk());
  {
    PiecedLevel bad = *level;
    for (size_t i = 3; i < bad.seam_streams[0].size(); i += 7) bad.seam_streams[0][i] ^= 0x5A;
    StatusOr<DecodedPieces> d = decodePieces(piecedViewOf(bad), {}, "grid.gtn");
    ASSERT_FALSE(d.isOk());
    EXPECT_NE(d.status().message().find("grid.gtn"), std::string::npos) << d.status().message();
  }
  {
    PiecedLevel bad = *level;
    bad.pieces[1].own_boundary_points += 1;
    bad.pieces[2].own_boundary_points -= 1;
    EXPECT_FALSE(decodePieces(piecedViewOf(bad), {}, "grid").isOk());
  }
  {
    PiecedLevel bad = *level;
    bad.classes[0].points += 1;
    EXPECT_FALSE(decodePieces(piecedViewOf(bad), {}, "grid").isOk());
  }
  {
    PiecedLevel bad = *level;
    bad.encoded[2].connectivity.resize(bad.encoded[2].connectivity.size() / 2);
    StatusOr<DecodedPieces> d = decodePieces(piecedViewOf(bad), {}, "grid");
    ASSERT_FALSE(d.isOk());
    EXPECT_NE(d.status().message().find("piece 2"), std::string::npos) << d.status().message();
  }
  EXPECT_FALSE(decodePieces(piecedViewOf(*level), {3, 1}, "grid").isOk());
  EXPECT_FALSE(decodePieces(piecedViewOf(*level), {9999}, "grid").isOk());
  EXPECT_FALSE(encodePieces(m, {}, 100).isOk());
}

}  // namespace
}  // namespace gtn::test
