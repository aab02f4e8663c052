#include "codec/level_check.h"

#include <cstring>
#include <limits>
#include <vector>

#include "codec/structured_piece.h"
#include "mesh/mesh_stream.h"

namespace gtn {

namespace {

// Compares the decoder's events with the source as they come; stops at the first difference (the
// decoder then stops too: the sink's error ends the decode).
class LosslessCheckSink : public MeshSink {
 public:
  // `tet_order` null: the tetrahedra come in the source's order (a structured piece's).
  // `grid`, where given: the source's tetrahedra, made from their indices (the mesh's released).
  LosslessCheckSink(const TetMesh& source, const std::vector<uint32_t>& vertex_order,
                    const std::vector<uint64_t>* tet_order, const RuleGridTets* grid = nullptr)
      : src_(source),
        vertex_order_(vertex_order),
        tet_order_(tet_order),
        grid_(grid),
        nt_(grid ? grid->size() : source.numTets()) {}

  // "" after a decode that gave the source back.
  Status prepare() {
    const size_t np = src_.numPoints(), nt = nt_;
    if (grid_ && grid_->points() != np) return mismatch("the grid's tetrahedra name other points than the source's");
    if (vertex_order_.size() != np || (tet_order_ && tet_order_->size() != nt))
      return mismatch("the encoder's renumbering does not cover the source");
    if (np >= kNone || nt >= kNone) return mismatch("more points or tetrahedra than the check can number");
    vertex_src_.assign(np, kNone);
    for (size_t v = 0; v < np; ++v) {
      const uint32_t d = vertex_order_[v];
      if (d >= np || vertex_src_[d] != kNone) return mismatch("the encoder's vertex order is not a permutation");
      vertex_src_[d] = static_cast<uint32_t>(v);
    }
    if (!tet_order_) return Status::ok();
    tet_src_.assign(nt, kNone);
    for (size_t t = 0; t < nt; ++t) {
      const uint64_t d = (*tet_order_)[t];
      if (d >= nt || tet_src_[d] != kNone) return mismatch("the encoder's tetrahedron order is not a permutation");
      tet_src_[d] = static_cast<uint32_t>(t);
    }
    return Status::ok();
  }
  Status finish() const {
    if (vertices_ != src_.numPoints() || tets_ != nt_)
      return mismatch(std::to_string(vertices_) + " points and " + std::to_string(tets_) +
                      " tetrahedra decoded, the source has " + std::to_string(src_.numPoints()) + " and " +
                      std::to_string(nt_));
    return Status::ok();
  }

  Status beginLevel(const LevelHeader& h) override {
    if (h.coord_type != src_.coord_type) return mismatch("the coordinate type changed");
    if (!sameLayout(h.point_fields, src_.point_fields) || !sameLayout(h.cell_fields, src_.cell_fields))
      return mismatch("field names, types or components changed");
    return Status::ok();
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    if (id != vertices_ || id >= vertex_src_.size())
      return mismatch("vertex " + std::to_string(id) + " is not expected");
    ++vertices_;
    const uint32_t v = vertex_src_[id];
    auto which = [&] {
      return "source point " + std::to_string(v) + " (decoded " + std::to_string(id) + ")";
    };  // made only for a difference
    if (std::memcmp(xyz, src_.point(v), 3 * sizeof(double)) != 0) return mismatch(which() + " moved");
    if (!sameItem(src_.point_fields, v, values)) return mismatch(which() + " has other field values");
    return Status::ok();
  }
  Status boundaryTriangle(const uint32_t*) override { return Status::ok(); }
  Status endBoundary() override { return Status::ok(); }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    if (tets_ >= nt_) return mismatch("more tetrahedra decoded than the source has");
    const uint64_t t = tet_order_ ? tet_src_[tets_] : tets_;
    const uint64_t decoded = tets_++;
    auto which = [&] {
      return "source tetrahedron " + std::to_string(t) + " (decoded " + std::to_string(decoded) + ")";
    };
    int perm[4], inversions = 0;
    const Tet source_tet = grid_ ? (*grid_)[t] : src_.tets[t];
    for (int i = 0; i < 4; ++i) {
      perm[i] = -1;
      const uint32_t want = vertex_order_[source_tet[i]];
      for (int j = 0; j < 4; ++j)
        if (v[j] == want) perm[i] = j;
      if (perm[i] < 0) return mismatch(which() + " has other vertices");
      for (int j = 0; j < i; ++j) inversions += perm[j] > perm[i];
    }
    if (inversions % 2) return mismatch(which() + " is reversed");
    if (!sameItem(src_.cell_fields, t, cell_values)) return mismatch(which() + " has other field values");
    return Status::ok();
  }
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }

  // The first difference, kept apart from the decoder's own errors.
  const std::string& difference() const { return difference_; }

 private:
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

  Status mismatch(std::string why) const {
    difference_ = why;
    return invalidData(std::move(why));
  }
  static bool sameLayout(const std::vector<FieldDesc>& decoded, const std::vector<Field>& source) {
    if (decoded.size() != source.size()) return false;
    for (size_t f = 0; f < source.size(); ++f)
      if (decoded[f].name != source[f].name || decoded[f].type != source[f].type ||
          decoded[f].components != source[f].components)
        return false;
    return true;
  }
  // Whether the concatenated items at `values` equal item i of `fields`, byte for byte.
  static bool sameItem(const std::vector<Field>& fields, size_t i, const uint8_t* values) {
    for (const Field& f : fields) {
      const size_t n = f.components * f.valueSize();
      if (std::memcmp(values, &f.bytes[i * n], n) != 0) return false;
      values += n;
    }
    return true;
  }

  const TetMesh& src_;
  const std::vector<uint32_t>& vertex_order_;
  const std::vector<uint64_t>* tet_order_;
  const RuleGridTets* grid_;
  size_t nt_;
  std::vector<uint32_t> vertex_src_;  // decoded vertex id -> source point
  std::vector<uint32_t> tet_src_;     // decoded position -> source tetrahedron
  uint64_t vertices_ = 0, tets_ = 0;
  mutable std::string difference_;
};

}  // namespace

namespace {
// Runs `decode` into a LosslessCheckSink and says what differs ("" when nothing does).
template <class Decode>
std::string checkDecode(LosslessCheckSink& sink, const Decode& decode) {
  if (Status st = sink.prepare(); !st.isOk()) return st.message();
  const Status st = decode(sink);
  if (!sink.difference().empty()) return sink.difference();
  if (!st.isOk()) return "it does not decode: " + st.message();
  if (Status end = sink.finish(); !end.isOk()) return end.message();
  return "";
}
}  // namespace

std::string losslessMismatch(const TetMesh& source, const EncodedLevel& encoded, const SeamValues* seams) {
  LosslessCheckSink sink(source, encoded.vertex_order, &encoded.tet_order);
  return checkDecode(sink, [&](MeshSink& s) {
    return decodeLevel(encoded.header, payloadOf(encoded), s, nullptr, "the encoded level", nullptr, seams);
  });
}

std::string structuredLosslessMismatch(const TetMesh& source, const LevelHeader& header, std::span<const uint8_t> piece,
                                       const std::vector<uint32_t>& vertex_order, const RuleGridTets* tets) {
  LosslessCheckSink sink(source, vertex_order, nullptr, tets);
  return checkDecode(sink, [&](MeshSink& s) { return decodeStructuredPiece(header, piece, s, "the encoded level"); });
}

}  // namespace gtn
