// The cell values of spec section 10.7, run through a stand-in for the level coder: values round
// trip; a value equal to the previous tetrahedron's, to a recent one or to a neighbour's costs a
// symbol and no residual; the records that hold the values of tetrahedra with open faces are reused
// once released.
#include "codec/cell_values.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "codec/front.h"
#include "codec/packed_values.h"

namespace gtn::level {
namespace {

// What CellValues reads of the level coder: the header, the cell-field streams and their forms, the
// encoder's mesh and the front (whose faces hold the neighbours' records).
template <bool kE>
struct StandIn {
  static constexpr bool kEncode = kE;
  using Coder = EntropyCoder<kE>;
  LevelHeader header_;
  std::vector<char> cf_skip_, cf_packed_, cf_split_;
  std::vector<std::unique_ptr<PackedReader>> cf_readers_;
  std::vector<std::vector<uint8_t>>* cf_escaped_ = nullptr;
  std::vector<ValueCoder> cf_vc_;
  std::vector<std::unique_ptr<Coder>> cf_;
  struct Encoder {
    const TetMesh* mesh = nullptr;
  } encoder;
  Encoder* enc_ = &encoder;
  Front front_;
  explicit StandIn(const LevelHeader& h) : header_(h) {
    cf_skip_.assign(h.cell_fields.size(), 0);
    cf_packed_ = cf_split_ = cf_skip_;
    cf_readers_.resize(h.cell_fields.size());
    for (const FieldDesc& d : h.cell_fields) cf_vc_.emplace_back(d.type, d.components);
  }
  Status bad(const std::string& reason) const { return invalidData(reason); }
};

LevelHeader headerOf(const TetMesh& mesh) {
  LevelHeader h;
  h.tets = mesh.tets.size();
  for (const Field& f : mesh.cell_fields) h.cell_fields.push_back({f.name, f.components, f.type});
  return h;
}

// A mesh of n tetrahedra (their vertices do not matter here) with one int32 cell field.
TetMesh withValues(const std::vector<int32_t>& values) {
  TetMesh mesh;
  mesh.tets.resize(values.size(), Tet{0, 1, 2, 3});
  mesh.cell_fields.emplace_back("id", 1, ScalarType::kInt32, values.size());
  std::memcpy(mesh.cell_fields[0].bytes.data(), values.data(), 4 * values.size());
  return mesh;
}

// Encodes the values tetrahedron by tetrahedron (no neighbours) and decodes them back: returns the
// decoded values and the stream's size.
std::vector<int32_t> roundTrip(const TetMesh& mesh, size_t* bytes) {
  const LevelHeader h = headerOf(mesh);
  std::vector<uint8_t> stream;
  {
    StandIn<true> enc(h);
    enc.encoder.mesh = &mesh;
    enc.cf_.push_back(std::make_unique<EntropyCoder<true>>(&stream));
    CellValues<StandIn<true>> cells(enc, h);
    const long none[4] = {-1, -1, -1, -1};
    for (uint32_t t = 0; t < mesh.tets.size(); ++t) EXPECT_TRUE(cells.code(none, t, kNoIndex).isOk());
    enc.cf_[0]->finish();
  }
  *bytes = stream.size();
  StandIn<false> dec(h);
  dec.cf_.push_back(std::make_unique<EntropyCoder<false>>(stream));
  CellValues<StandIn<false>> cells(dec, h);
  std::vector<int32_t> out;
  const long none[4] = {-1, -1, -1, -1};
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    EXPECT_TRUE(cells.code(none, 0, kNoIndex).isOk());
    int32_t v;
    std::memcpy(&v, cells.values(), 4);
    out.push_back(v);
  }
  EXPECT_TRUE(dec.cf_[0]->finishedCleanly());
  return out;
}

TEST(CellValues, RoundTripAndRepeatsCostASymbol) {
  std::vector<int32_t> varied, repeating;
  for (int i = 0; i < 400; ++i) {
    varied.push_back(static_cast<int32_t>((static_cast<uint32_t>(i) * 2654435761u) >> 8));  // 24 bits, scattered
    repeating.push_back(i % 3 == 0 ? 123456 : (i % 3 == 1 ? -77 : 5000000));                // three recent values
  }
  size_t varied_bytes = 0, repeating_bytes = 0;
  EXPECT_EQ(roundTrip(withValues(varied), &varied_bytes), varied);
  EXPECT_EQ(roundTrip(withValues(repeating), &repeating_bytes), repeating);
  // Recent values cost a symbol (under a bit each once the model learns), new ones a residual.
  EXPECT_LT(repeating_bytes * 8, repeating.size());
  EXPECT_GT(varied_bytes * 8, 16 * varied.size());
}

// Three tetrahedra; the third closes a face of the first (whose record that face holds): returns
// the values each side's CellValues gives, and checks the records' reuse.
template <bool kE>
std::vector<int32_t> threeWithANeighbour(StandIn<kE>& side, const LevelHeader& h) {
  CellValues<StandIn<kE>> cells(side, h);
  SlotPool pool;
  for (int i = 0; i < 5; ++i) pool.alloc();
  std::vector<int32_t> out;
  auto value = [&] {
    int32_t v;
    std::memcpy(&v, cells.values(), 4);
    out.push_back(v);
  };
  const long none[4] = {-1, -1, -1, -1};
  EXPECT_TRUE(cells.code(none, 0, kNoIndex).isOk());
  value();
  const uint32_t rec = cells.record();  // held by the first tetrahedron's open face
  const uint32_t f[3] = {0, 1, 2};
  cells.hold(rec);
  const long face = side.front_.open(f, 3, rec, pool);
  cells.release(rec);
  EXPECT_TRUE(cells.code(none, 1, kNoIndex).isOk());
  value();
  const uint32_t second = cells.record();
  EXPECT_NE(second, rec);
  const long closes[4] = {face, -1, -1, -1};
  EXPECT_TRUE(cells.code(closes, 2, kNoIndex).isOk());
  value();
  cells.release(second);
  EXPECT_EQ(cells.record(), second);  // reused once released
  return out;
}

TEST(CellValues, ANeighboursValueRoundTrips) {
  // The third value is the first tetrahedron's, its neighbour's; the prediction (the previous
  // tetrahedron's) is another.
  const TetMesh mesh = withValues({42, 9, 42});
  const LevelHeader h = headerOf(mesh);
  std::vector<uint8_t> stream;
  StandIn<true> enc(h);
  enc.encoder.mesh = &mesh;
  enc.cf_.push_back(std::make_unique<EntropyCoder<true>>(&stream));
  EXPECT_EQ(threeWithANeighbour(enc, h), (std::vector<int32_t>{42, 9, 42}));
  enc.cf_[0]->finish();
  StandIn<false> dec(h);
  dec.cf_.push_back(std::make_unique<EntropyCoder<false>>(stream));
  EXPECT_EQ(threeWithANeighbour(dec, h), (std::vector<int32_t>{42, 9, 42}));
  EXPECT_TRUE(dec.cf_[0]->finishedCleanly());
}

TEST(CellValues, ACorruptNeighbourSymbolIsAnError) {
  // Symbol 9 ("the first other neighbour") where the tetrahedron has none.
  LevelHeader h;
  h.tets = 1;
  h.cell_fields.push_back({"id", 1, ScalarType::kInt32});
  std::vector<uint8_t> stream;
  {
    EntropyCoder<true> c(&stream);
    BitTree<4> tree;
    tree.code(c, kSymCellNeighbour);  // context 0: previous symbol 0, no neighbour
    c.finish();
  }
  StandIn<false> dec(h);
  dec.cf_.push_back(std::make_unique<EntropyCoder<false>>(stream));
  CellValues<StandIn<false>> cells(dec, h);
  const long none[4] = {-1, -1, -1, -1};
  const Status st = cells.code(none, 0, kNoIndex);
  EXPECT_FALSE(st.isOk());
  EXPECT_NE(st.message().find("neighbour that does not exist"), std::string::npos);
}

}  // namespace
}  // namespace gtn::level
