// The level codec: boundary surface first, then surface peeling (codec/level_codec.h).
//
// One template, LevelCoder<kEncode>, runs the whole algorithm for both directions: the encoder knows
// the source mesh and passes the true symbol to each coding call, the decoder reads it back. Both
// therefore keep exactly the same front state, candidate lists and predictions.
//
// Stream overview (all binary adaptive range coding, codec/range_coder.h):
//  boundary:     for each popped open half-edge (p, q): bit "a triangle (q, p, x) follows", then x as
//                new vertex / rank among the loop neighbours next(q), prev(p), ... / escape + slot,
//                in contexts of the angles around the ear vertex (the one the first candidate would
//                close a fan at: the angle it would open, and how much its triangles leave open);
//                when the half-edge queue empties: bit "another component", then a seed triangle
//                (per vertex: bit existing, then a slot index, else a new vertex).
//  connectivity: for each popped open face (a, b, c): x as new / rank among the front vertices that
//                share front edges with a, b or c (ordered by how many of them, then by distance to
//                the predicted position; the context counts the front faces the first candidate
//                would close) / escape + either the rank by distance to the predicted
//                position among the live vertices (codec/nearest_grid.h finds it) or the slot; a bit
//                for reversed orientation; after the
//                tetrahedron, for each of its vertices left on no open face, a bit "retired". When the
//                face queue empties: bit "seed tetrahedron follows", then the seed's four vertices.
//  geometry:     coordinates of each vertex when it is introduced, predicted from decoded neighbours;
//                unused points that lie on an edge (mid-edge nodes) right after the first tetrahedron
//                with that edge, predicted at its midpoint; the other unused points after peeling.
//  fields:       one stream per field, values predicted in the same order.
// Vertices are identified while live by a "slot" in a pool that only holds the front, so the
// decoder's memory follows the front and not the mesh.
#include "codec/level_codec.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "codec/boundary_phase.h"
#include "codec/candidates.h"
#include "codec/cell_values.h"
#include "codec/edge_points.h"
#include "codec/flat_maps.h"
#include "codec/front.h"
#include "codec/nearest_grid.h"
#include "codec/packed_values.h"
#include "codec/peeling.h"
#include "codec/prediction.h"
#include "codec/range_coder.h"
#include "codec/slot_pool.h"
#include "codec/symbols.h"
#include "codec/value_coder.h"
#include "codec/value_forms.h"
#include "mesh/faces.h"
#include "mesh/index.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {

using namespace level;

// What the encoder knows and the decoder does not.
struct EncoderSide {
  const TetMesh* mesh = nullptr;
  bool delaunay_first = false;  // the level's "Delaunay first" bit (looksDelaunay)
  const std::vector<uint32_t>* neighbor = nullptr;
  std::vector<uint32_t> src_slot;   // source vertex -> live slot
  std::vector<uint32_t> slot_src;   // slot -> source vertex
  std::vector<uint32_t> remaining;  // tetrahedra of each source vertex not yet coded
  std::vector<uint8_t> tet_done;
  struct BoundaryTri {
    uint32_t v[3];
    uint32_t tet;
  };
  std::vector<BoundaryTri> btris;
  std::vector<uint8_t> btri_done;
  // Every directed edge (a, b) of every boundary triangle, grouped by a (bedges[edge_start[a]] up to
  // bedges[edge_start[a + 1]]) and in triangle order within a group: a counting sort, not a sort.
  struct DirectedEdge {
    uint32_t b, tri;
  };
  std::vector<size_t> edge_start;
  std::vector<DirectedEdge> bedges;
  size_t next_seed_tet = 0, next_seed_tri = 0;
  std::vector<uint32_t> vertex_order;
  std::vector<uint64_t> tet_order;
  std::vector<uint32_t> alias;  // per point-field component (flattened): earlier identical component, or ~0
  // Unused points on an edge (findEdgePoints) in (a, b, point) order, those of the edges whose lower
  // source vertex is a from edge_point_start[a] on; a coded point's entry becomes kNoIndex.
  std::vector<EdgePoint> edge_points;
  std::vector<uint32_t> edge_point_start;
  std::vector<uint32_t> face_tet;               // FaceMap index of an open face -> the undecoded tetrahedron behind it
  const std::vector<uint32_t>* seam = nullptr;  // EncodeOptions::seam (null: no seam vertex)

  // The boundary triangle not coded yet on the open half-edge (p, q) (slots), if any: its index and
  // its third vertex.
  bool partnerTriangle(uint32_t p, uint32_t q, uint32_t* tri, uint32_t* x_src) const {
    const uint32_t sp = slot_src[p], sq = slot_src[q];
    for (size_t i = edge_start[sq]; i < edge_start[sq + 1]; ++i) {
      const DirectedEdge& e = bedges[i];
      if (e.b == sp && !btri_done[e.tri]) {
        *tri = e.tri;
        const BoundaryTri& bt = btris[e.tri];
        for (int j = 0; j < 3; ++j)
          if (bt.v[j] != sp && bt.v[j] != sq) *x_src = bt.v[j];
        return true;
      }
    }
    return false;
  }
  // The first boundary triangle not coded yet, as the seed of another component, if any.
  bool nextSeedTriangle(uint32_t* tri) {
    while (next_seed_tri < btris.size() && btri_done[next_seed_tri]) ++next_seed_tri;
    *tri = static_cast<uint32_t>(next_seed_tri);
    return next_seed_tri < btris.size();
  }

  // The source is read in the front's order, which jumps about the arrays: these start loading what
  // the coder will need a little later, as its own front data is (prefetchGate).
  // Tetrahedron t's vertices and neighbours, read when t's gate face is coded.
  void prefetchTet(uint32_t t) const {
    __builtin_prefetch(&mesh->tets[t]);
    __builtin_prefetch(&(*neighbor)[4 * size_t{t}]);
  }
  // What coding tetrahedron t (vertices v) with apex x reads after its candidates: the apex's
  // coordinates and values when it is new, then (emitTet) the vertices' remaining counts and
  // whether the neighbours are done.
  void prefetchCoding(uint32_t t, const Tet& v, uint32_t x) const {
    if (src_slot[x] == kNoIndex) {
      __builtin_prefetch(&mesh->coords[3 * size_t{x}]);
      for (const Field& f : mesh->point_fields) __builtin_prefetch(&f.bytes[size_t{x} * f.components * f.valueSize()]);
    }
    for (uint32_t u : v) __builtin_prefetch(&remaining[u]);
    for (int j = 0; j < 4; ++j) {
      const uint32_t nb = (*neighbor)[4 * size_t{t} + j];
      if (nb < tet_done.size()) __builtin_prefetch(&tet_done[nb]);
    }
  }
};

template <bool kEncodeDirection>
class LevelCoder {
 public:
  static constexpr bool kEncode = kEncodeDirection;
  using Coder = EntropyCoder<kEncode>;

  LevelCoder(const LevelHeader& header, std::unique_ptr<Coder> boundary, std::unique_ptr<Coder> connectivity,
             std::unique_ptr<Coder> geometry, std::vector<std::unique_ptr<Coder>> point_fields,
             std::vector<std::unique_ptr<Coder>> cell_fields)
      : header_(header),
        bnd_(std::move(boundary)),
        con_(std::move(connectivity)),
        geo_(std::move(geometry)),
        pf_(std::move(point_fields)),
        cf_(std::move(cell_fields)),
        coord_vc_(header.coord_type, 3) {
    for (const FieldDesc& d : header.point_fields) {
      pf_vc_.emplace_back(d.type, d.components);
      pf_offset_.push_back(item_bytes_);
      item_bytes_ += d.itemBytes();
    }
    for (const FieldDesc& d : header.cell_fields) cf_vc_.emplace_back(d.type, d.components);
    pred_vals_.resize(std::max<size_t>(1, item_bytes_));
    for (size_t f = 0; f < header.point_fields.size(); ++f)
      for (uint32_t c = 0; c < header.point_fields[f].components; ++c)
        comp_type_.push_back(header.point_fields[f].type);
    alias_.assign(comp_type_.size(), kNoIndex);
    field_coded_comps_.resize(header.point_fields.size());
    for (size_t f = 0; f < header.point_fields.size(); ++f) field_coded_comps_[f] = header.point_fields[f].components;
    pf_rule_.resize(header.point_fields.size());
    pf_last_rule_.assign(header.point_fields.size(), 0);
    pf_packed_.assign(header.point_fields.size(), 0);
    cf_packed_.assign(header.cell_fields.size(), 0);
    cf_split_.assign(header.cell_fields.size(), 0);
  }

  // The streams in packed form (spec section 10.2.1): the encoder's choice, which codes nothing in
  // them (the caller stores the packed values), and the decoder's readers (null: not packed).
  // `cf_split`: cell-field streams in split form, whose escaped values the encoder collects in
  // `escaped` (per field, the items in order).
  void setPacked(bool geo, std::vector<char> pf, std::vector<char> cf, std::vector<char> cf_split,
                 std::vector<std::vector<uint8_t>>* escaped) {
    geo_packed_ = geo;
    pf_packed_ = std::move(pf);
    cf_packed_ = std::move(cf);
    cf_split_ = std::move(cf_split);
    cf_escaped_ = escaped;
  }
  void setPackedReaders(std::unique_ptr<PackedReader> geo, std::vector<std::unique_ptr<PackedReader>> pf,
                        std::vector<std::unique_ptr<PackedReader>> cf, std::vector<char> cf_split) {
    geo_packed_ = geo != nullptr;
    for (size_t f = 0; f < pf.size(); ++f) pf_packed_[f] = pf[f] != nullptr;
    for (size_t f = 0; f < cf.size(); ++f) cf_packed_[f] = cf[f] != nullptr && !cf_split[f];
    cf_split_ = std::move(cf_split);
    geo_reader_ = std::move(geo);
    pf_readers_ = std::move(pf);
    cf_readers_ = std::move(cf);
  }

  void setEncoder(EncoderSide* enc) { enc_ = enc; }
  // The piece's seam vertices (EncodeOptions::seam_count; the decoder's SeamValues).
  void setSeamCount(uint32_t count) {
    seam_count_ = count;
    seam_bits_ = bitLength(count > 0 ? count - 1 : 0);
    seam_seen_.assign(count, 0);
  }
  void setSeams(const SeamValues* seams) {
    seams_ = seams;
    setSeamCount(seams ? seams->count : 0);
  }
  void setDecoder(MeshSink* sink, const std::string* what) {
    sink_ = sink;
    what_ = what;
  }
  // The fields to decode (decoder only; null or empty vectors: all). Takes effect in run(), once the
  // repeat declarations say which other fields the kept ones need.
  void setFields(const DecodeFields* fields) {
    fields_ = fields;
    pf_skip_.assign(header_.point_fields.size(), 0);
    cf_skip_.assign(header_.cell_fields.size(), 0);
    if (!fields) return;
    if (!fields->point.empty())
      for (size_t f = 0; f < pf_skip_.size(); ++f) pf_skip_[f] = f >= fields->point.size() || !fields->point[f];
    if (!fields->cell.empty())
      for (size_t f = 0; f < cf_skip_.size(); ++f) cf_skip_[f] = f >= fields->cell.size() || !fields->cell[f];
  }

  Status run() {
    pf_skip_.resize(header_.point_fields.size(), 0);
    cf_skip_.resize(header_.cell_fields.size(), 0);
    GTN_RETURN_IF_ERROR(codeAliases());
    keepRepeatedFields();
    layOutSlotValues();
    GTN_RETURN_IF_ERROR(codeValueForms());
    // The streams left out are read no further.
    if (fields_ && fields_->streams_done) fields_->streams_done(pf_skip_, cf_skip_);
    uint32_t edge_points = 0;
    if constexpr (kEncode) edge_points = !enc_->edge_points.empty();
    // A packed GEOM codes no symbol: its level has no edge points (the encoder packs only such).
    peeling_.setEdgePoints(geo_packed_ ? 0 : geo_->bit(edge_points_flag_, edge_points));
    uint32_t delaunay_first = 0;
    if constexpr (kEncode) delaunay_first = enc_->delaunay_first;
    peeling_.candidates().setDelaunayFirst(con_->bit(delaunay_first_flag_, delaunay_first));
    GTN_RETURN_IF_ERROR(boundary_.run());
    boundary_points_ = next_id_;
    boundary_done_ = true;
    if constexpr (!kEncode) GTN_RETURN_IF_ERROR(sink_->endBoundary());
    GTN_RETURN_IF_ERROR(peeling_.run());
    GTN_RETURN_IF_ERROR(unusedPoints());
    if constexpr (kEncode) {
      bnd_->finish();
      con_->finish();
      geo_->finish();
      for (auto& c : pf_) c->finish();
      for (auto& c : cf_) c->finish();
    } else {
      if (tets_done_ != header_.tets) return bad("fewer tetrahedra than the header announces");
      if (btris_done_ != header_.boundary_triangles) return bad("boundary triangle count differs from the header");
      if (next_id_ != header_.points) return bad("point count differs from the header");
      if (seams_introduced_ != seam_count_) return bad("the streams do not name every seam vertex of the piece");
      if (live_ != 0) return bad("vertices left unretired at the end of the level");
      if (!bnd_->finishedCleanly()) return bad("boundary stream is corrupt, truncated or has trailing bytes");
      if (!con_->finishedCleanly()) return bad("connectivity stream is corrupt, truncated or has trailing bytes");
      if (geo_packed_) {
        GTN_RETURN_IF_ERROR(packedEnd(*geo_reader_));
      } else if (!geo_->finishedCleanly()) {
        return bad("geometry stream is corrupt, truncated or has trailing bytes");
      }
      for (size_t f = 0; f < pf_.size(); ++f) {
        if (pf_skip_[f]) continue;
        if (pf_packed_[f]) {
          GTN_RETURN_IF_ERROR(packedEnd(*pf_readers_[f]));
        } else if (!pf_[f]->finishedCleanly()) {
          return bad("point field stream '" + header_.point_fields[f].name +
                     "' is corrupt, truncated or has trailing bytes");
        }
      }
      for (size_t f = 0; f < cf_.size(); ++f) {
        if (cf_skip_[f]) continue;
        if (!cf_packed_[f] && !cf_[f]->finishedCleanly())
          return bad("cell field stream '" + header_.cell_fields[f].name +
                     "' is corrupt, truncated or has trailing bytes");
        if (cf_packed_[f] || cf_split_[f]) GTN_RETURN_IF_ERROR(packedEnd(*cf_readers_[f]));
      }
      GTN_RETURN_IF_ERROR(sink_->endLevel());
    }
    return Status::ok();
  }

  uint64_t peakLive() const { return peak_live_; }
  uint64_t boundaryPoints() const { return boundary_points_; }

  // Slot s's values as the sink takes them: every field at its offset, those left out zero.
  const uint8_t* sinkValues(uint32_t s) {
    if (item_bytes_ == 0) return nullptr;
    if (pool_.slot_bytes == item_bytes_) return &pool_.vals[s * pool_.slot_bytes];
    for (size_t f = 0; f < header_.point_fields.size(); ++f)
      if (!pf_skip_[f])
        std::memcpy(&sink_vals_[pf_offset_[f]], &pool_.vals[s * pool_.slot_bytes + slot_off_[f]],
                    header_.point_fields[f].itemBytes());
    return sink_vals_.data();
  }

 private:
  // Point-field components that repeat an earlier component bit for bit at every vertex (a vector
  // field stored again as scalars, say) are declared at the start of their field's stream and cost
  // nothing more.
  Status codeAliases() {
    size_t k = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      if (pf_packed_[f]) {  // a packed stream declares nothing
        k += header_.point_fields[f].components;
        continue;
      }
      for (uint32_t c = 0; c < header_.point_fields[f].components; ++c, ++k) {
        uint32_t is_alias = 0, source = 0;
        if constexpr (kEncode) {
          is_alias = enc_->alias[k] != kNoIndex;
          source = is_alias ? enc_->alias[k] : 0;
        }
        is_alias = pf_[f]->bit(alias_flag_, is_alias);
        if (!is_alias) continue;
        source = pf_[f]->direct(source, bitLength(k > 0 ? k - 1 : 0));
        if constexpr (!kEncode) {
          if (source >= k || comp_type_[source] != comp_type_[k])
            return bad("point field '" + header_.point_fields[f].name + "' repeats an invalid component");
        }
        alias_[k] = source;
        --field_coded_comps_[f];
      }
    }
    return Status::ok();
  }

  // The slots keep the values of the decoded fields alone, packed (the sink is handed them at the
  // offsets of every field, pf_offset_, the others zero): a render that shows one of blunt fin's 5
  // components keeps 4 bytes a slot, not 20.
  void layOutSlotValues() {
    slot_off_.assign(header_.point_fields.size(), 0);
    pool_.slot_bytes = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      if (pf_skip_[f]) continue;
      slot_off_[f] = pool_.slot_bytes;
      pool_.slot_bytes += header_.point_fields[f].itemBytes();
    }
    comp_slot_off_.clear();
    for (size_t f = 0; f < header_.point_fields.size(); ++f)
      for (uint32_t c = 0; c < header_.point_fields[f].components; ++c)
        comp_slot_off_.push_back(slot_off_[f] + c * scalarSize(header_.point_fields[f].type));
    last_vals_.assign(pool_.slot_bytes, 0);
    if (pool_.slot_bytes != item_bytes_) sink_vals_.assign(item_bytes_, 0);
  }

  // A field left out of the decode is decoded after all when a kept field repeats one of its
  // components. A component repeats an earlier one, so one pass from the last field back takes
  // repeats of repeats along.
  void keepRepeatedFields() {
    std::vector<size_t> field_of;
    for (size_t f = 0; f < header_.point_fields.size(); ++f)
      field_of.insert(field_of.end(), header_.point_fields[f].components, f);
    for (size_t k = field_of.size(); k-- > 0;)
      if (!pf_skip_[field_of[k]] && alias_[k] != kNoIndex) pf_skip_[field_of[alias_[k]]] = 0;
  }

  // Each value-coded component's form (section 10.2), at the start of its stream. For a float type a
  // bit (one model for the level) says whether it is coded in decimal form, then its decimal places
  // in 5 direct bits; otherwise, for float64, a bit (another model) whether it is in printed-single
  // form, then its digits in 5 direct bits; otherwise a bit (a third model) says whether it has a
  // shift, then the shift in 6 direct bits.
  Status codeValueForms() {
    const ScalarType ct = header_.coord_type;
    for (uint32_t i = 0; i < 3 && !geo_packed_; ++i) {
      ValueForm form;
      if constexpr (kEncode) {
        const std::vector<double>& xyz = enc_->mesh->coords;
        const size_t n = xyz.size() / 3;
        std::vector<uint8_t> raw(n * scalarSize(ct));
        for (size_t v = 0; v < n; ++v) storeCoordinate(ct, xyz[3 * v + i], &raw[v * scalarSize(ct)]);
        form = chooseValueForm(ct, raw.data(), n, scalarSize(ct));
      }
      const std::string error = codeValueForm(*geo_, form_models_, coord_vc_, ct, i, std::move(form), header_.points);
      if (!error.empty()) return bad("the geometry stream" + error);
    }
    size_t k = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      const FieldDesc& d = header_.point_fields[f];
      for (uint32_t c = 0; c < d.components; ++c, ++k) {
        if (alias_[k] != kNoIndex || pf_packed_[f]) continue;
        ValueForm form;
        if constexpr (kEncode) {
          const Field& src = enc_->mesh->point_fields[f];
          form = chooseValueForm(d.type, src.bytes.data() + c * scalarSize(d.type), src.itemCount(), d.itemBytes());
        }
        const std::string error =
            codeValueForm(*pf_[f], form_models_, pf_vc_[f], d.type, c, std::move(form), header_.points);
        if (!error.empty()) return bad("point field '" + d.name + "'" + error);
      }
    }
    for (size_t f = 0; f < header_.cell_fields.size(); ++f) {
      const FieldDesc& d = header_.cell_fields[f];
      for (uint32_t c = 0; c < d.components && !cf_packed_[f] && !cf_split_[f]; ++c) {
        ValueForm form;
        if constexpr (kEncode) {
          const Field& src = enc_->mesh->cell_fields[f];
          form = chooseValueForm(d.type, src.bytes.data() + c * scalarSize(d.type), src.itemCount(), d.itemBytes());
        }
        const std::string error =
            codeValueForm(*cf_[f], form_models_, cf_vc_[f], d.type, c, std::move(form), header_.tets);
        if (!error.empty()) return bad("cell field '" + d.name + "'" + error);
      }
    }
    return Status::ok();
  }

 public:
  // ---- what the phases (boundary_phase.h, peeling.h) use -----------------------------------------
  Coder& bnd() { return *bnd_; }
  Coder& con() { return *con_; }
  Coder& geo() { return *geo_; }
  EncoderSide* enc() { return enc_; }
  Front& front() { return front_; }
  const SlotPool& pool() const { return pool_; }

  Status bad(const std::string& reason) const {
    std::string where = " (after " + std::to_string(tets_done_) + " tetrahedra, " + std::to_string(next_id_) +
                        " vertices, " + std::to_string(btris_done_) + " boundary triangles)";
    return invalidData((what_ ? *what_ : std::string("level")) + ": " + reason + where);
  }
  // The end of a packed stream (its reader names the stream).
  Status packedEnd(PackedReader& r) const {
    const Status st = r.finish();
    return st.isOk() ? st : bad(st.message());
  }
  Status internal(const std::string& reason) const { return invalidData("encodeLevel: inconsistent mesh: " + reason); }

  // ---- slot pool -------------------------------------------------------------------------------
  // A slot for a new vertex; the per-slot arrays of the other parts grow with the pool's.
  uint32_t allocSlot() {
    if (pool_.full()) reserveSlots(pool_.grownSize());
    const uint32_t s = pool_.alloc();
    if (!boundary_.loop().done()) boundary_.loop().addSlot(s);
    if constexpr (kEncode)
      if (s >= enc_->slot_src.size()) enc_->slot_src.push_back(kNoIndex);
    return s;
  }
  // Room for n slots in every per-slot array.
  void reserveSlots(size_t n) {
    pool_.reserve(n);
    if (!boundary_.loop().done()) boundary_.loop().reserve(n);
    front_.faces.reserveSlots(n);
    if (peeling_.grid().built()) peeling_.grid().reserveSlots(n);
  }
  bool isLive(uint32_t s) const { return pool_.isLive(s); }
  const double* P(uint32_t s) const { return pool_.position(s); }

  Status retire(uint32_t s) {
    --live_;
    if (peeling_.grid().built()) peeling_.grid().erase(s);
    if constexpr (kEncode) {
      enc_->src_slot[enc_->slot_src[s]] = kNoIndex;
    } else {
      GTN_RETURN_IF_ERROR(sink_->retireVertex(pool_.ids[s]));
    }
    pool_.retire(s);
    return Status::ok();
  }

  // Slot index coded uniformly over the pool size.
  uint32_t codeSlot(Coder& c, uint32_t s) { return c.direct(kEncode ? s : 0, pool_.slotBits()); }

  // ---- values ----------------------------------------------------------------------------------
  // Coordinate i of the stencil vertices (0 where there is none): the values rules weigh.
  void coordStencil(const FieldPrediction& fp, int i, double x[4]) const {
    for (int j = 0; j < 4; ++j) x[j] = fp.s[j] != kNoIndex ? P(fp.s[j])[i] : 0.0;
  }
  double fieldRule(uint32_t r, const FieldPrediction& fp, ScalarType type, size_t off) const {
    if (r >= kRules) return doubleFromRaw(type, &pool_.vals[near_[r - kRules] * pool_.slot_bytes + off]);
    double x[4];
    for (int j = 0; j < 4; ++j)
      x[j] = fp.s[j] != kNoIndex ? doubleFromRaw(type, &pool_.vals[fp.s[j] * pool_.slot_bytes + off]) : 0.0;
    return kWeightedRule[r](x);
  }

  void computeFieldPrediction(const FieldPrediction& fp, const double* x) {
    size_t k = 0;
    const double* s[4] = {};
    for (int j = 0; j < 4; ++j)
      if (fp.s[j] != kNoIndex) s[j] = P(fp.s[j]);
    double lambda[4];
    const int n = stencilWeights(fp.kind, s, x, lambda);
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      const FieldDesc& d = header_.point_fields[f];
      const size_t vs = scalarSize(d.type);
      if (pf_skip_[f]) {
        k += d.components;
        continue;
      }
      for (uint32_t c = 0; c < d.components; ++c, ++k) {
        const size_t off = slot_off_[f] + c * vs;
        if (n == 0) {
          pred_vals_[k] = doubleFromRaw(d.type, &last_vals_[off]);
          continue;
        }
        double v = 0;
        for (int i = 0; i < n; ++i)
          v += lambda[i] * doubleFromRaw(d.type, &pool_.vals[fp.s[i] * pool_.slot_bytes + off]);
        pred_vals_[k] = v;
      }
    }
  }

  // The encoder's choice of field rule for field f (its first component flattened at k): the
  // cheapest by signalling plus residual magnitudes, the lowest rule among equals. Every rule is
  // priced on every component, a component at a time: that straight-line loop costs less than
  // trying the rules one by one and stopping each once it cannot win.
  uint32_t chooseFieldRule(size_t f, size_t k, const FieldPrediction& fp, bool has_d, const uint8_t* src_item) {
    const FieldDesc& d = header_.point_fields[f];
    const size_t vs = scalarSize(d.type);
    const uint32_t n_cand = std::min<uint32_t>(n_near_, kCandidateRules);
    const SymbolCosts<4> signal = symbolCosts(pf_rule_[f][pf_last_rule_[f]]);
    int cost[kFieldRules];
    for (uint32_t r = 0; r < kFieldRules; ++r) cost[r] = signal[r];
    // `type` is d.type, as a compile-time constant for the usual float types (the key conversion in
    // the innermost loop then has no switch).
    auto price = [&](auto type) {
      for (uint32_t c = 0; c < d.components; ++c) {
        if (alias_[k + c] != kNoIndex) continue;
        const size_t off = slot_off_[f] + c * vs;
        const uint64_t actual = keyFromRaw(type, src_item + c * vs);
        double x[4], v[kFieldRules] = {};
        for (int j = 0; j < 4; ++j)
          x[j] = fp.s[j] != kNoIndex ? doubleFromRaw(type, &pool_.vals[fp.s[j] * pool_.slot_bytes + off]) : 0.0;
        weightedRules(x, v, std::make_integer_sequence<uint32_t, kRules>());
        v[0] = pred_vals_[k + c];
        for (uint32_t j = 0; j < n_cand; ++j)
          v[kRules + j] = doubleFromRaw(type, &pool_.vals[near_[j] * pool_.slot_bytes + off]);
        addRuleCosts<kFieldRules>(type, actual, v, cost);
      }
    };
    if (d.type == ScalarType::kFloat32) {
      price(std::integral_constant<ScalarType, ScalarType::kFloat32>());
    } else if (d.type == ScalarType::kFloat64) {
      price(std::integral_constant<ScalarType, ScalarType::kFloat64>());
    } else {
      price(d.type);
    }
    uint32_t rule = 0;
    int best = std::numeric_limits<int>::max();
    for (uint32_t r = 0; r < kFieldRules; ++r)
      if (fieldRuleAllowed(r, has_d) && cost[r] < best) {
        best = cost[r];
        rule = r;
      }
    return rule;
  }

  // The vertex whose error carry m (1 to kCarries - 1) names, or kNoIndex if there is none: the
  // stencil's a, b, c, d (d only with has_d), then the first three apex candidates.
  uint32_t carrySource(uint32_t m, const FieldPrediction& fp, bool has_d) const {
    if (m >= 1 && m <= 3) return fp.s[m - 1];
    if (m == 4) return has_d ? fp.s[3] : kNoIndex;
    if (m >= 5 && m < kCarries && static_cast<int>(m - 5) < n_near_) return near_[m - 5];
    return kNoIndex;
  }
  bool fieldRuleAllowed(uint32_t rule, bool has_d) const {
    if (rule >= kRules) return rule < kRules + std::min<uint32_t>(kCandidateRules, n_near_);
    return ruleAllowed(rule, has_d, kRules);
  }

  // Introduces a vertex: codes its coordinates and field values and emits it. For a vertex behind a
  // front face the encoder picks, separately for the coordinates and for each field, the rule that
  // predicts best among rule 0 (`pred` for coordinates, the interpolant for fields) and the
  // parallelogram-like rules of kRuleWeights, and codes its index.
  Status introduceVertex(uint32_t src, const double pred[3], const FieldPrediction& fp, uint32_t* slot_out) {
    if constexpr (!kEncode) {
      if (next_id_ >= header_.points) return bad("more vertices than the header announces");
    }
    const uint32_t s = allocSlot();
    if (seam_count_ > 0) {
      bool is_seam = false;
      GTN_RETURN_IF_ERROR(codeSeamVertex(src, pred, fp, s, &is_seam));
      if (is_seam) {
        *slot_out = s;
        return Status::ok();
      }
    }
    if (seams_ && seams_->seam_of_id) seams_->seam_of_id->push_back(kNoIndex);
    if (geo_packed_) {
      GTN_RETURN_IF_ERROR(codePackedCoordinates(src, s));
    } else {
      GTN_RETURN_IF_ERROR(codeCoordinates(src, pred, fp, s));
    }
    if (pool_.slot_bytes > 0) GTN_RETURN_IF_ERROR(codeFieldValues(src, fp, s));
    GTN_RETURN_IF_ERROR(emitVertex(src, s));
    *slot_out = s;
    return Status::ok();
  }

  // An unsigned number as its bit length in an adaptive tree, then the bits below the leading one.
  uint64_t codeLength(BitTree<6>& tree, uint64_t z) {
    const uint32_t length = tree.code(*con_, static_cast<uint32_t>(bitLength(z)));
    if (length == 0) return 0;
    if (length > 33) return uint64_t{1} << 40;  // beyond any index or rank: the caller refuses it
    const int low_bits = static_cast<int>(length) - 1;
    const uint64_t low = z - (uint64_t{1} << low_bits);
    uint64_t got = 0;
    if (low_bits > 16) {
      got = uint64_t{con_->direct(static_cast<uint32_t>(low >> 16), low_bits - 16)} << 16;
      got |= con_->direct(static_cast<uint32_t>(low & 0xFFFFu), 16);
    } else {
      got = con_->direct(static_cast<uint32_t>(low), low_bits);
    }
    return (uint64_t{1} << low_bits) + got;
  }

  // The piece's seam vertices, for ranking them by distance (setSeams, or the encoder's source).
  void buildSeamGrid() {
    seam_pos_.assign(3 * size_t{seam_count_}, 0.0);
    if constexpr (kEncode) {
      const ScalarType ct = header_.coord_type;
      for (size_t v = 0; v < enc_->seam->size(); ++v) {
        const uint32_t k = (*enc_->seam)[v];
        if (k == kNoIndex) continue;
        for (int i = 0; i < 3; ++i) {
          uint8_t raw[8];
          storeCoordinate(ct, enc_->mesh->coords[3 * v + i], raw);
          seam_pos_[3 * size_t{k} + i] = doubleFromRaw(ct, raw);
        }
      }
    } else {
      std::copy(seams_->coords, seams_->coords + 3 * size_t{seam_count_}, seam_pos_.begin());
    }
    double lo[3], hi[3];
    for (int i = 0; i < 3; ++i) lo[i] = hi[i] = seam_pos_[i];
    for (uint32_t k = 0; k < seam_count_; ++k)
      for (int i = 0; i < 3; ++i) {
        lo[i] = std::min(lo[i], seam_pos_[3 * size_t{k} + i]);
        hi[i] = std::max(hi[i], seam_pos_[3 * size_t{k} + i]);
      }
    seam_grid_.build(lo, hi, seam_count_);
    seam_grid_.reserveSlots(seam_count_);
    for (uint32_t k = 0; k < seam_count_; ++k) seam_grid_.insert(k, &seam_pos_[3 * size_t{k}]);
  }

  // Whether the vertex is one of the piece's seam vertices (a bit in CONN), then which: by its rank
  // among the seam vertices not yet introduced in order of distance to `pred` (then index), or, when
  // that rank is kSeamRankLimit or more or `pred` is not finite, by its index's difference from the
  // one after the previous seam vertex's (zigzag). The seam vertex's values are the seam list's. The
  // models' context is how near `pred` the nearest seam vertex not yet introduced lies, against the
  // length of the stencil's first edge (fp.s[0], fp.s[1]): a vertex predicted onto one is likely it.
  Status codeSeamVertex(uint32_t src, const double pred[3], const FieldPrediction& fp, uint32_t s, bool* is_seam) {
    uint32_t index = kNoIndex;
    if constexpr (kEncode) index = (*enc_->seam)[src];
    const bool finite = std::isfinite(pred[0]) && std::isfinite(pred[1]) && std::isfinite(pred[2]);
    auto dist = [&](uint32_t k) {
      const double* q = &seam_pos_[3 * size_t{k}];
      const double dx = q[0] - pred[0], dy = q[1] - pred[1], dz = q[2] - pred[2];
      return dx * dx + dy * dy + dz * dz;
    };
    auto ok = [](uint32_t) { return true; };
    auto all = [&](auto fn) {
      for (uint32_t k = 0; k < seam_count_; ++k)
        if (!seam_seen_[k]) fn(k);
    };
    uint32_t ctx = 0;
    if (finite && fp.s[0] != kNoIndex && fp.s[1] != kNoIndex && seams_introduced_ < seam_count_) {
      if (seam_pos_.empty()) buildSeamGrid();
      const double* a = pool_.position(fp.s[0]);
      const double* b = pool_.position(fp.s[1]);
      const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
      const double e2 = dx * dx + dy * dy + dz * dz;
      // Only a seam vertex nearer than the edge's length can make the context (5 d2 < 2 e2).
      const double d2 = seam_grid_.nearestWithin(pred, e2, dist, all);
      ctx = 50 * d2 < e2 ? 3 : 10 * d2 < e2 ? 2 : 5 * d2 < 2 * e2 ? 1 : 0;
    }
    *is_seam = con_->bit(seam_flag_[boundary_done_ ? 1 : 0][ctx], index != kNoIndex) != 0;
    if (!*is_seam) return Status::ok();
    if (seam_pos_.empty()) buildSeamGrid();
    uint64_t rank = kSeamRankLimit;
    if constexpr (kEncode) {
      if (finite) rank = seam_grid_.rankOf(pred, dist(index), index, dist, ok, all);
    }
    const uint32_t near = finite ? con_->bit(seam_near_[ctx], rank < kSeamRankLimit) : 0;
    if (near) {
      rank = codeLength(seam_rank_[ctx], rank);
      if (rank >= kSeamRankLimit) return bad("a seam vertex rank beyond the limit");
      if constexpr (!kEncode) {
        index = seam_grid_.kth(pred, rank, dist, ok, all);
        if (index == kNoIndex) return bad("a seam vertex rank beyond the piece's seam list");
      }
    } else {
      const uint32_t expected = seam_last_ + 1;
      uint64_t z = 0;
      if constexpr (kEncode) {
        const int64_t d = int64_t{index} - int64_t{expected};
        z = d >= 0 ? uint64_t(d) * 2 : uint64_t(-d) * 2 - 1;
      }
      z = codeLength(seam_length_, z);
      const int64_t d = (z & 1) ? -int64_t((z + 1) / 2) : int64_t(z / 2);
      const int64_t at = int64_t{expected} + d;
      if (at < 0 || at >= int64_t{seam_count_}) return bad("a seam vertex index beyond the piece's seam list");
      index = static_cast<uint32_t>(at);
    }
    if (seam_seen_[index]) return bad("a seam vertex introduced twice");
    seam_seen_[index] = 1;
    seam_grid_.erase(index);
    seam_last_ = index;
    ++seams_introduced_;
    double* x = pool_.position(s);
    uint8_t* out = pool_.slot_bytes > 0 ? pool_.values(s) : nullptr;
    if constexpr (kEncode) {
      uint64_t actual[3];
      sourceCoordinateKeys(src, actual);
      const ScalarType ct = header_.coord_type;
      for (int i = 0; i < 3; ++i) {
        uint8_t raw[8];
        rawFromKey(ct, actual[i], raw);
        x[i] = doubleFromRaw(ct, raw);
      }
      for (size_t f = 0; f < header_.point_fields.size(); ++f) {
        const size_t ib = header_.point_fields[f].itemBytes();
        std::memcpy(out + slot_off_[f], enc_->mesh->point_fields[f].bytes.data() + size_t{src} * ib, ib);
      }
    } else {
      for (int i = 0; i < 3; ++i) x[i] = seams_->coords[3 * size_t{index} + i];
      const uint8_t* in = seams_->values ? seams_->values + size_t{index} * item_bytes_ : nullptr;
      if (!in && pool_.slot_bytes > 0) return bad("the seam vertices' values are missing");
      for (size_t f = 0; f < header_.point_fields.size(); ++f)
        if (!pf_skip_[f]) std::memcpy(out + slot_off_[f], in + pf_offset_[f], header_.point_fields[f].itemBytes());
      if (seams_->seam_of_id) seams_->seam_of_id->push_back(index);
    }
    for (int i = 0; i < 3; ++i) pool_.err[3 * size_t{s} + i] = 0.0f;
    if (pool_.slot_bytes > 0) std::memcpy(last_vals_.data(), out, pool_.slot_bytes);
    return emitVertex(src, s);
  }

  // The encoder's keys of source vertex src's coordinates, as stored in the file's coordinate type.
  void sourceCoordinateKeys(uint32_t src, uint64_t actual[3]) const {
    const ScalarType ct = header_.coord_type;
    for (uint32_t i = 0; i < 3; ++i) {
      uint8_t raw[8];
      storeCoordinate(ct, enc_->mesh->coords[3 * size_t{src} + i], raw);
      actual[i] = keyFromRaw(ct, raw);
    }
  }

  // A packed GEOM: the coordinates as stored, no rule, carry or copy.
  Status codePackedCoordinates(uint32_t src, uint32_t s) {
    const ScalarType ct = header_.coord_type;
    const size_t cs = scalarSize(ct);
    double* x = pool_.position(s);
    uint8_t item[24];
    if constexpr (kEncode) {
      uint64_t actual[3];
      sourceCoordinateKeys(src, actual);
      for (int i = 0; i < 3; ++i) rawFromKey(ct, actual[i], item + i * cs);
    } else {
      const uint8_t* in = geo_reader_->next();
      if (!in) return bad(geo_reader_->error());
      std::memcpy(item, in, 3 * cs);
    }
    for (int i = 0; i < 3; ++i) {
      x[i] = doubleFromRaw(ct, item + i * cs);
      if constexpr (!kEncode) {
        if (!std::isfinite(x[i])) return bad("decoded a non-finite coordinate");
      }
      pool_.err[3 * size_t{s} + i] = 0.0f;
    }
    return Status::ok();
  }

  // The coordinates predicted (section 10.5): behind a front face a rule and an error carry, then per
  // axis a copy of a copy source's coordinate or a residual against the prediction.
  Status codeCoordinates(uint32_t src, const double pred[3], const FieldPrediction& fp, uint32_t s) {
    const ScalarType ct = header_.coord_type;
    const bool choose = fp.kind == FieldPrediction::kInterpolate || fp.kind == FieldPrediction::kAverage;
    const bool has_d = fp.kind == FieldPrediction::kInterpolate;
    uint64_t actual[3] = {0, 0, 0};
    if constexpr (kEncode) sourceCoordinateKeys(src, actual);
    uint64_t pk[3];
    for (int i = 0; i < 3; ++i) pk[i] = keyFromPrediction(ct, pred[i]);
    // Copy sources: the stencil, then the apex candidates (front vertices around the gate), which
    // on extruded and sheared grids hold the vertex's neighbours along a grid line.
    uint32_t copy_src[4 + kMaxCandidates];
    uint32_t ncopy = 0;
    if (fp.kind != FieldPrediction::kLast) {
      for (int m = 0; m < 4; ++m)
        if (fp.s[m] != kNoIndex && (m < 3 || has_d)) copy_src[ncopy++] = fp.s[m];
      if (fp.kind != FieldPrediction::kEdge)
        for (int m = 0; m < n_near_; ++m) copy_src[ncopy++] = near_[m];
    }
    // The encoder's first copy source that has each axis's value, kNoIndex if none does: a copied
    // axis's residual does not count when the encoder chooses a prediction.
    uint32_t first_copy[3] = {kNoIndex, kNoIndex, kNoIndex};
    if constexpr (kEncode) {
      for (int i = 0; i < 3; ++i)
        for (uint32_t m = 0; m < ncopy && first_copy[i] == kNoIndex; ++m)
          if (keyFromPrediction(ct, P(copy_src[m])[i]) == actual[i]) first_copy[i] = m;
    }
    double base[3] = {pred[0], pred[1], pred[2]};  // the prediction before any carry (pool_.err)
    if (choose) GTN_RETURN_IF_ERROR(codeCoordinateRule(fp, pred, actual, first_copy, base, pk));
    double* x = pool_.position(s);
    GTN_RETURN_IF_ERROR(codeCoordinateAxes(copy_src, ncopy, first_copy, actual, pk, x));
    for (int i = 0; i < 3; ++i)
      pool_.err[3 * size_t{s} + i] = fp.kind == FieldPrediction::kLast ? 0.0f : static_cast<float>(x[i] - base[i]);
    return Status::ok();
  }

  // The rule and error carry of a vertex behind a front face (the encoder's choice, then coded):
  // sets base (the rule's prediction) and pk (its keys, with the carry added).
  Status codeCoordinateRule(const FieldPrediction& fp, const double pred[3], const uint64_t actual[3],
                            const uint32_t first_copy[3], double base[3], uint64_t pk[3]) {
    const ScalarType ct = header_.coord_type;
    const bool has_d = fp.kind == FieldPrediction::kInterpolate;
    uint32_t rule = 0, carry = 0;
    if constexpr (kEncode) chooseCoordinateRule(fp, pred, actual, first_copy, &rule, &carry);
    rule = geo_rule_[geo_last_rule_].code(*geo_, rule);
    if (!ruleAllowed(rule, has_d, kCoordRules)) return bad("invalid coordinate prediction rule");
    geo_last_rule_ = rule;
    carry = geo_carry_[geo_last_carry_].code(*geo_, carry);
    const uint32_t carry_src = carry == 0 ? kNoIndex : carrySource(carry, fp, has_d);
    if (carry != 0 && carry_src == kNoIndex) return bad("coordinate error carried from an unknown vertex");
    geo_last_carry_ = carry;
    for (int i = 0; i < 3; ++i) {
      if (rule != 0) {
        double stencil[4];
        coordStencil(fp, i, stencil);
        base[i] = kWeightedRule[rule](stencil);
      }
      if (carry != 0) {
        pk[i] = keyFromPrediction(ct, base[i] + static_cast<double>(pool_.err[3 * size_t{carry_src} + i]));
      } else if (rule != 0) {
        pk[i] = keyFromPrediction(ct, base[i]);
      }
    }
    return Status::ok();
  }

  // The encoder's rule and carry for the coordinates `actual`: the cheapest by signalling plus
  // residual bit lengths (axes that a copy codes do not count), the lowest carry and then the lowest
  // rule among equals; the previous rule is tried first, so that most others stop early.
  void chooseCoordinateRule(const FieldPrediction& fp, const double pred[3], const uint64_t actual[3],
                            const uint32_t first_copy[3], uint32_t* rule_out, uint32_t* carry_out) {
    const ScalarType ct = header_.coord_type;
    const uint64_t cmask = keyMask(scalarBits(ct));
    const bool has_d = fp.kind == FieldPrediction::kInterpolate;
    uint32_t rule = 0, carry = 0;
    const SymbolCosts<4> signal = symbolCosts(geo_rule_[geo_last_rule_]);
    const SymbolCosts<3> carry_signal = symbolCosts(geo_carry_[geo_last_carry_]);
    double predicted[3][kRules];  // every rule's prediction of each axis
    for (int i = 0; i < 3; ++i) {
      double stencil[4];
      coordStencil(fp, i, stencil);
      weightedRules(stencil, predicted[i], std::make_integer_sequence<uint32_t, kRules>());
      predicted[i][0] = pred[i];
    }
    // `type` is ct as a compile-time constant (coordinates are float32 or float64).
    auto search = [&](auto type) {
      int best = 1 << 30;
      // Whether rule r with carry m at `cost` would not replace the best so far: among equals
      // the lowest carry, then the lowest rule, wins.
      auto loses = [&](int cost, uint32_t r, uint32_t m) {
        return cost > best || (cost == best && (m > carry || (m == carry && r > rule)));
      };
      auto take = [&](int cost, uint32_t r, uint32_t m) {
        best = cost;
        rule = r;
        carry = m;
      };
      // The rules without a carry, each stopped as soon as it cannot win.
      for (uint32_t t = 0; t < kCoordRules; ++t) {
        const uint32_t r = triedRule(t, geo_last_rule_);
        if (!ruleAllowed(r, has_d, kCoordRules)) continue;
        int cost = signal[r] + carry_signal[0];
        for (int i = 0; i < 3 && !loses(cost, r, 0); ++i)
          if (first_copy[i] == kNoIndex)
            cost += 16 * residualBits(actual[i], keyFromPrediction(type, predicted[i][r]), cmask);
        if (!loses(cost, r, 0)) take(cost, r, 0);
      }
      // A carry costs at least the cheapest rule and carry symbols and the margin: when the best
      // without one costs no more, no carry can win (most vertices of grids with copied axes).
      int floor = 1 << 30;
      for (uint32_t r = 0; r < kCoordRules; ++r)
        if (ruleAllowed(r, has_d, kCoordRules)) floor = std::min(floor, signal[r]);
      int cheapest_carry = 1 << 30;
      for (uint32_t m = 1; m < kCarries; ++m) cheapest_carry = std::min(cheapest_carry, carry_signal[m]);
      if (best <= floor + cheapest_carry + kCarryMargin) return;
      // Each carry with every rule, four rules at a time (addRuleCosts), then taken in the same
      // order and with the same ties.
      constexpr uint32_t kPadded = (kCoordRules + 3) / 4 * 4;
      for (uint32_t m = 1; m < kCarries; ++m) {
        const uint32_t src = carrySource(m, fp, has_d);
        if (src == kNoIndex) continue;
        const float* e = &pool_.err[3 * size_t{src}];
        int cost[kPadded];
        for (uint32_t r = 0; r < kPadded; ++r)
          cost[r] = r < kCoordRules ? signal[r] + carry_signal[m] + kCarryMargin : 0;
        for (int i = 0; i < 3; ++i) {
          if (first_copy[i] != kNoIndex) continue;
          double v[kPadded] = {};
          for (uint32_t r = 0; r < kCoordRules; ++r) v[r] = predicted[i][r] + static_cast<double>(e[i]);
          addRuleCosts<kPadded>(type, actual[i], v, cost);
        }
        for (uint32_t t = 0; t < kCoordRules; ++t) {
          const uint32_t r = triedRule(t, geo_last_rule_);
          if (ruleAllowed(r, has_d, kCoordRules) && !loses(cost[r], r, m)) take(cost[r], r, m);
        }
      }
    };
    if (ct == ScalarType::kFloat32) {
      search(std::integral_constant<ScalarType, ScalarType::kFloat32>());
    } else {
      search(std::integral_constant<ScalarType, ScalarType::kFloat64>());
    }
    *rule_out = rule;
    *carry_out = carry;
  }

  // Each axis: a bit whether it copies a copy source's coordinate (which one: the previous axis's
  // source, one bit, else its index), else its residual against the prediction pk. Writes x.
  // first_copy: the encoder's first copy source of each axis (codeCoordinates).
  Status codeCoordinateAxes(const uint32_t* copy_src, uint32_t ncopy, const uint32_t first_copy[3],
                            const uint64_t actual[3], const uint64_t pk[3], double x[3]) {
    const ScalarType ct = header_.coord_type;
    uint32_t prev_which = kNoIndex;  // copy source of the previous coordinate of this vertex
    for (uint32_t i = 0; i < 3; ++i) {
      uint64_t key = 0;
      uint32_t hit = 0;
      if (ncopy > 0) {
        uint32_t which = 0;
        if constexpr (kEncode) {
          // Prefer the source the previous coordinate was copied from: one bit says so.
          if (prev_which != kNoIndex && keyFromPrediction(ct, P(copy_src[prev_which])[i]) == actual[i]) {
            hit = 1;
            which = prev_which;
          } else if (first_copy[i] != kNoIndex) {
            hit = 1;
            which = first_copy[i];
          }
        }
        hit = geo_->bit(copy_flag_[i][copy_last_[i] + 2 * (prev_which != kNoIndex)], hit);
        copy_last_[i] = hit;
        if (hit) {
          uint32_t same = prev_which != kNoIndex && which == prev_which;
          if (prev_which != kNoIndex) same = geo_->bit(copy_same_[i], same);
          if (same) {
            which = prev_which;
          } else {
            which = copy_which_[i].code(*geo_, which);
          }
          if (which >= ncopy) return bad("coordinate copied from an unknown vertex");
          key = keyFromPrediction(ct, P(copy_src[which])[i]);
          prev_which = which;
        } else {
          prev_which = kNoIndex;
        }
      }
      if (!hit) key = coord_vc_.code(*geo_, i, pk[i], actual[i]);
      uint8_t raw[8];
      rawFromKey(ct, key, raw);
      x[i] = doubleFromRaw(ct, raw);
      if constexpr (!kEncode) {
        if (!std::isfinite(x[i])) return bad("decoded a non-finite coordinate");
      }
    }
    return Status::ok();
  }

  // The point-field values of the vertex in slot s (section 10.5): per field a rule (behind a front
  // face or a boundary edge), then per component its residual against the rule's prediction; a
  // component that repeats another is copied, a packed field's item taken as stored.
  Status codeFieldValues(uint32_t src, const FieldPrediction& fp, uint32_t s) {
    const bool choose = fp.kind == FieldPrediction::kInterpolate || fp.kind == FieldPrediction::kAverage ||
                        fp.kind == FieldPrediction::kParallelogram;  // rule 0 is then the parallelogram
    const bool has_d = fp.kind == FieldPrediction::kInterpolate;
    computeFieldPrediction(fp, pool_.position(s));
    uint8_t* out = pool_.values(s);
    size_t k = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      const FieldDesc& d = header_.point_fields[f];
      const size_t vs = scalarSize(d.type);
      if (pf_skip_[f]) {
        k += d.components;
        continue;
      }
      const uint8_t* src_item = nullptr;
      if constexpr (kEncode) src_item = enc_->mesh->point_fields[f].bytes.data() + size_t{src} * d.itemBytes();
      if (pf_packed_[f]) {
        // Packed form: the item as stored, every component (none repeats another).
        if constexpr (!kEncode) {
          src_item = pf_readers_[f]->next();
          if (!src_item) return bad(pf_readers_[f]->error());
        }
        std::memcpy(out + slot_off_[f], src_item, d.itemBytes());
        k += d.components;
        continue;
      }
      uint32_t rule = 0;
      if (choose && field_coded_comps_[f] > 0) {
        if constexpr (kEncode) rule = chooseFieldRule(f, k, fp, has_d, src_item);
        rule = pf_rule_[f][pf_last_rule_[f]].code(*pf_[f], rule);
        if (!fieldRuleAllowed(rule, has_d)) return bad("invalid field prediction rule");
        pf_last_rule_[f] = rule;
      }
      for (uint32_t c = 0; c < d.components; ++c, ++k) {
        const size_t off = slot_off_[f] + c * vs;
        if (alias_[k] != kNoIndex) {
          std::memcpy(out + off, out + comp_slot_off_[alias_[k]], vs);
          continue;
        }
        uint64_t act = 0;
        if constexpr (kEncode) act = keyFromRaw(d.type, src_item + c * vs);
        const double pv = rule == 0 ? pred_vals_[k] : fieldRule(rule, fp, d.type, off);
        const uint64_t key = pf_vc_[f].code(*pf_[f], c, keyFromPrediction(d.type, pv), act);
        rawFromKey(d.type, key, out + off);
      }
    }
    std::memcpy(last_vals_.data(), out, pool_.slot_bytes);
    return Status::ok();
  }

  // The vertex in slot s (the encoder's source vertex src) is complete: it gets the next id and is
  // emitted (the decoder's sink) or recorded (the encoder's orders).
  Status emitVertex(uint32_t src, uint32_t s) {
    const double* x = P(s);
    const uint32_t id = static_cast<uint32_t>(next_id_++);
    pool_.ids[s] = id;
    if constexpr (kEncode) {
      enc_->vertex_order[src] = id;
      enc_->src_slot[src] = s;
      enc_->slot_src[s] = src;
    } else {
      GTN_RETURN_IF_ERROR(sink_->vertex(id, x, sinkValues(s)));
    }
    std::memcpy(last_pos_, x, sizeof(last_pos_));
    ++live_;
    if (peeling_.grid().built()) peeling_.grid().insert(s, x);
    peak_live_ = std::max<uint64_t>(peak_live_, live_);
    return Status::ok();
  }

  Status introduceFromLast(uint32_t src, uint32_t* slot) {
    FieldPrediction fp;
    fp.kind = FieldPrediction::kLast;
    return introduceVertex(src, last_pos_, fp, slot);
  }

  // ---- front faces -----------------------------------------------------------------------------
  // `tet`: the encoder's undecoded tetrahedron behind the face.
  void openFace(const uint32_t v[3], uint32_t d, uint32_t tet, uint32_t cell = kNoIndex) {
    if (cell != kNoIndex) cells_.hold(cell);
    const uint32_t face = front_.open(v, d, cell, pool_);
    if constexpr (kEncode) {
      if (face >= enc_->face_tet.size()) enc_->face_tet.resize(size_t{face} + 1);
      enc_->face_tet[face] = tet;
    }
  }
  // Closes the open face `index`, face k of the tetrahedron e that emitTet emits (Front::close).
  void closeFace(long index, int k, const uint32_t e[4], const long closes[4]) {
    const FrontFace f = front_.close(index, k, e, closes, pool_);
    if (f.cell != kNoIndex) cells_.release(f.cell);
  }

  // ---- boundary surface (boundary_phase.h) ------------------------------------------------------
  // Boundary triangle v (the encoder's triangle `tri`) is coded: the encoder marks it, the decoder
  // hands it to the sink.
  Status emitBoundaryTriangle(const uint32_t v[3], uint32_t tri) {
    if constexpr (kEncode) {
      enc_->btri_done[tri] = 1;
    } else {
      if (btris_done_ >= header_.boundary_triangles) return bad("more boundary triangles than the header announces");
      const uint32_t ids[3] = {pool_.ids[v[0]], pool_.ids[v[1]], pool_.ids[v[2]]};
      GTN_RETURN_IF_ERROR(sink_->boundaryTriangle(ids));
    }
    ++btris_done_;
    return Status::ok();
  }

  // Vertex of a seed (triangle or tetrahedron): an existing live slot or a new vertex.
  Status codeSeedVertex(Coder& c, uint32_t src, uint32_t* slot) {
    uint32_t existing = 0;
    if constexpr (kEncode) existing = enc_->src_slot[src] != kNoIndex;
    existing = c.bit(seed_existing_, existing);
    if (existing) {
      const uint32_t s = codeSlot(c, kEncode ? enc_->src_slot[src] : 0);
      if (!isLive(s)) return bad("seed refers to a vertex that is not live");
      *slot = s;
      return Status::ok();
    }
    return introduceFromLast(src, slot);
  }

  Status unusedPoints() {
    if constexpr (kEncode) {
      const size_t n = enc_->mesh->numPoints();
      for (size_t v = 0; v < n; ++v) {
        if (enc_->vertex_order[v] != kNoIndex) continue;
        uint32_t s;
        GTN_RETURN_IF_ERROR(introduceFromLast(static_cast<uint32_t>(v), &s));
        GTN_RETURN_IF_ERROR(retire(s));
      }
    } else {
      while (next_id_ < header_.points) {
        if (!geo_->ok()) return bad("geometry stream is truncated or corrupt");
        uint32_t s;
        GTN_RETURN_IF_ERROR(introduceFromLast(0, &s));
        GTN_RETURN_IF_ERROR(retire(s));
      }
    }
    return Status::ok();
  }

 private:
  friend class level::CellValues<LevelCoder>;
  friend class level::Peeling<LevelCoder>;

  const LevelHeader& header_;
  std::unique_ptr<Coder> bnd_, con_, geo_;
  std::vector<std::unique_ptr<Coder>> pf_, cf_;
  ValueCoder coord_vc_;
  std::vector<ValueCoder> pf_vc_, cf_vc_;
  // Streams in packed form, and the decoder's readers of them.
  bool geo_packed_ = false;
  std::vector<char> pf_packed_, cf_packed_, cf_split_;
  std::vector<std::vector<uint8_t>>* cf_escaped_ = nullptr;  // the encoder's escaped items of split streams
  std::unique_ptr<PackedReader> geo_reader_;
  std::vector<std::unique_ptr<PackedReader>> pf_readers_, cf_readers_;
  std::vector<size_t> pf_offset_;
  size_t item_bytes_ = 0;
  std::vector<size_t> slot_off_, comp_slot_off_;  // layOutSlotValues: offsets in a slot's values
  std::vector<uint8_t> sink_vals_;                // sinkValues' buffer, when fields are left out
  std::vector<char> pf_skip_, cf_skip_;           // fields whose values the decoder leaves out (setFields)
  const DecodeFields* fields_ = nullptr;

  EncoderSide* enc_ = nullptr;
  MeshSink* sink_ = nullptr;
  const std::string* what_ = nullptr;

  SlotPool pool_;

  Front front_;
  BoundaryPhase<LevelCoder> boundary_{*this};
  CellValues<LevelCoder> cells_{*this, header_};
  Peeling<LevelCoder> peeling_{*this};

  BitTree<4> geo_rule_[16];
  uint32_t geo_last_rule_ = 0;
  BitTree<3> geo_carry_[kCarries];  // [previous carry of this stream]
  uint32_t geo_last_carry_ = 0;
  std::vector<std::array<BitTree<4>, 16>> pf_rule_;
  std::vector<uint32_t> pf_last_rule_;
  BitModel seed_existing_;

  uint64_t next_id_ = 0, tets_done_ = 0, btris_done_ = 0, live_ = 0, peak_live_ = 0, boundary_points_ = 0;
  double last_pos_[3] = {0, 0, 0};
  std::vector<uint8_t> last_vals_;
  // Coordinates equal to a component of a stencil vertex (axis-aligned geometry).
  BitModel copy_flag_[3][4];  // [axis][hit of the previous vertex's axis + 2 * previous axis hit]
  BitModel copy_same_[3];
  // Point-field components: byte offset in a vertex's values, type, earlier identical component.
  std::vector<ScalarType> comp_type_;
  std::vector<uint32_t> alias_;
  std::vector<uint32_t> field_coded_comps_;  // per field: components not aliased
  BitModel alias_flag_;                      // a point-field component repeats an earlier one (codeAliases)
  ValueFormModels form_models_;              // the components' form declarations (codeValueForms)
  BitTree<5> copy_which_[3];
  const uint32_t* near_ = nullptr;  // apex candidates of the gate being decoded (copy sources)
  int n_near_ = 0;
  BitModel edge_points_flag_;
  BitModel delaunay_first_flag_;
  // Seam vertices (codeSeamVertex).
  const SeamValues* seams_ = nullptr;
  uint32_t seam_count_ = 0;
  int seam_bits_ = 0;
  std::vector<char> seam_seen_;
  uint32_t seams_introduced_ = 0;
  uint32_t seam_last_ = kNoIndex;  // the previous seam vertex's index (kNoIndex + 1 = 0 before the first)
  // [whether the boundary is done][context], [context]: codeSeamVertex.
  BitModel seam_flag_[2][4], seam_near_[4];
  bool boundary_done_ = false;
  BitTree<6> seam_length_, seam_rank_[4];
  std::vector<double> seam_pos_;  // 3 per seam vertex
  NearestGrid seam_grid_;         // the seam vertices not yet introduced
  static constexpr uint64_t kSeamRankLimit = 4096;
  uint32_t copy_last_[3] = {0, 0, 0};
  std::vector<double> pred_vals_;
};

// Whether the mesh looks like a Delaunay tetrahedralization, for the encoder's "Delaunay first" bit
// (section 10.4): over up to about 4096 tetrahedra spread through the mesh, at most 5% of their
// interior faces have the vertex across clearly inside the tetrahedron's circumsphere. Meshes from
// Delaunay meshers (TetGen, CGAL) pass, with no violation or a few; the levels that simplification
// leaves (its collapses break the empty-sphere property, about 30% of the faces) and curvilinear
// grids (20-35%) do not, and they rank better by count first. A floating-point test: the bit is the
// encoder's choice, which decoders only read.
bool looksDelaunay(const TetMesh& mesh, const FaceAdjacency& adj) {
  const size_t nt = mesh.numTets();
  const size_t step = std::max<size_t>(1, nt / 4096);
  size_t tested = 0, inside = 0;
  auto det3 = [](const double* a, const double* b, const double* c) {  // a . (b x c)
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  };
  for (size_t t = 0; t < nt; t += step) {
    const Tet& a = mesh.tets[t];
    for (int k = 0; k < 4; ++k) {
      const uint32_t u = adj.neighbor[4 * t + k];
      if (u >= nt) continue;
      uint32_t e = kNoIndex;
      for (uint32_t v : mesh.tets[u])
        if (v != a[0] && v != a[1] && v != a[2] && v != a[3]) e = v;
      if (e == kNoIndex) continue;
      // The insphere determinant relative to e (rows p_i - e, lifted by |p_i - e|^2), signed by the
      // tetrahedron's orientation; "clearly": beyond 1e-8 of the size of its terms.
      double m[4][3], l[4], scale = 0;
      for (int i = 0; i < 4; ++i) {
        const double* p = mesh.point(a[i]);
        const double* q = mesh.point(e);
        l[i] = 0;
        for (int d = 0; d < 3; ++d) {
          m[i][d] = p[d] - q[d];
          l[i] += m[i][d] * m[i][d];
        }
        scale = std::max(scale, l[i]);
      }
      const double ins = -l[0] * det3(m[1], m[2], m[3]) + l[1] * det3(m[0], m[2], m[3]) -
                         l[2] * det3(m[0], m[1], m[3]) + l[3] * det3(m[0], m[1], m[2]);
      const double o = signedVolume(mesh.point(a[0]), mesh.point(a[1]), mesh.point(a[2]), mesh.point(a[3]));
      if (!(o != 0) || !std::isfinite(ins)) continue;
      ++tested;
      if ((o > 0 ? -ins : ins) > 1e-8 * scale * scale * std::sqrt(scale)) ++inside;
    }
  }
  return tested > 0 && inside <= tested / 20;
}

}  // namespace

LevelHeader levelHeaderOf(const TetMesh& mesh) {
  LevelHeader h;
  const size_t np = mesh.numPoints();
  h.points = np;
  h.tets = mesh.numTets();
  h.coord_type = mesh.coord_type;
  for (const Field& f : mesh.point_fields) h.point_fields.push_back({f.name, f.components, f.type});
  for (const Field& f : mesh.cell_fields) h.cell_fields.push_back({f.name, f.components, f.type});
  h.metadata = mesh.metadata;
  if (np > 0) {
    for (int i = 0; i < 3; ++i) h.bbox_min[i] = h.bbox_max[i] = mesh.coords[i];
    for (size_t v = 0; v < np; ++v)
      for (int i = 0; i < 3; ++i) {
        h.bbox_min[i] = std::min(h.bbox_min[i], mesh.coords[3 * v + i]);
        h.bbox_max[i] = std::max(h.bbox_max[i], mesh.coords[3 * v + i]);
      }
  }
  return h;
}

StatusOr<EncodedLevel> encodeLevel(const TetMesh& mesh, const EncodeOptions& options) {
  if (options.keep_order) return unsupported("encodeLevel: keeping the source order is not implemented");
  GTN_RETURN_IF_ERROR(mesh.checkConsistency("encodeLevel"));
  if (mesh.coord_type != ScalarType::kFloat32 && mesh.coord_type != ScalarType::kFloat64)
    return unsupported("encodeLevel: coordinates must be float32 or float64");
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  if (np >= kNoIndex || nt >= kNoIndex) return unsupported("encodeLevel: more than 2^32-2 points or tetrahedra");
  for (size_t t = 0; t < nt; ++t) {
    const Tet& v = mesh.tets[t];
    if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3])
      return invalidData("encodeLevel: tetrahedron " + std::to_string(t) + " repeats a vertex");
  }
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  if (adj.non_manifold_faces > 0)
    return invalidData("encodeLevel: " + std::to_string(adj.non_manifold_faces) +
                       " faces are shared by three or more tetrahedra (non-manifold)");

  EncodedLevel out;
  LevelHeader& h = out.header;
  h = levelHeaderOf(mesh);

  if (!options.seam.empty() && options.seam.size() != np)
    return invalidData("encodeLevel: the seam list does not have one entry per point");
  {
    std::vector<char> named(options.seam_count, 0);
    uint32_t n = 0;
    for (uint32_t k : options.seam) {
      if (k == kNoIndex) continue;
      if (k >= options.seam_count || named[k]) return invalidData("encodeLevel: invalid or repeated seam index");
      named[k] = 1;
      ++n;
    }
    if (n != options.seam_count) return invalidData("encodeLevel: a seam index names no point");
  }
  EncoderSide enc;
  enc.mesh = &mesh;
  if (options.seam_count > 0) enc.seam = &options.seam;
  enc.delaunay_first = looksDelaunay(mesh, adj);
  enc.neighbor = &adj.neighbor;
  enc.src_slot.assign(np, kNoIndex);
  enc.remaining.assign(np, 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t) ++enc.remaining[v];
  enc.tet_done.assign(nt, 0);
  enc.btris.reserve(adj.boundary_faces);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      if (adj.neighbor[4 * t + k] != kNoNeighbor) continue;
      const Tet& v = mesh.tets[t];
      enc.btris.push_back({{v[kTetFace[k][0]], v[kTetFace[k][1]], v[kTetFace[k][2]]}, static_cast<uint32_t>(t)});
    }
  h.boundary_triangles = enc.btris.size();
  enc.btri_done.assign(enc.btris.size(), 0);
  enc.edge_start.assign(np + 1, 0);
  for (const EncoderSide::BoundaryTri& t : enc.btris)
    for (uint32_t v : t.v) ++enc.edge_start[v + 1];
  for (size_t v = 0; v < np; ++v) enc.edge_start[v + 1] += enc.edge_start[v];
  enc.bedges.resize(3 * enc.btris.size());
  {
    std::vector<size_t> next(enc.edge_start.begin(), enc.edge_start.end() - 1);
    for (size_t i = 0; i < enc.btris.size(); ++i)
      for (int j = 0; j < 3; ++j)
        enc.bedges[next[enc.btris[i].v[j]]++] = {enc.btris[i].v[(j + 1) % 3], static_cast<uint32_t>(i)};
  }
  enc.vertex_order.assign(np, kNoIndex);
  enc.tet_order.assign(nt, 0);
  if (options.edge_points) {
    enc.edge_points = findEdgePoints(mesh);
    std::sort(enc.edge_points.begin(), enc.edge_points.end(), [](const EdgePoint& x, const EdgePoint& y) {
      return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.point < y.point);
    });
    enc.edge_point_start.assign(np + 1, 0);
    for (const EdgePoint& p : enc.edge_points) ++enc.edge_point_start[p.a + 1];
    for (size_t v = 0; v < np; ++v) enc.edge_point_start[v + 1] += enc.edge_point_start[v];
  }
  {
    struct Comp {
      const uint8_t* base;
      size_t stride, size;
      ScalarType type;
    };
    std::vector<Comp> comps;
    for (const Field& f : mesh.point_fields)
      for (uint32_t c = 0; c < f.components; ++c)
        comps.push_back(
            {f.bytes.data() + c * scalarSize(f.type), f.components * scalarSize(f.type), scalarSize(f.type), f.type});
    enc.alias.assign(comps.size(), kNoIndex);
    constexpr size_t kMaxAliasScan = 64;  // components compared pairwise (quadratic)
    for (size_t k = 1; k < comps.size() && k < kMaxAliasScan; ++k)
      for (size_t j = 0; j < k; ++j) {
        if (enc.alias[j] != kNoIndex || comps[j].type != comps[k].type) continue;
        bool same = true;
        for (size_t v = 0; v < np && same; ++v)
          same =
              std::memcmp(comps[j].base + v * comps[j].stride, comps[k].base + v * comps[k].stride, comps[k].size) == 0;
        if (same && np > 0) {
          enc.alias[k] = static_cast<uint32_t>(j);
          break;
        }
      }
  }

  // One pass of the coder over a copy of the encoder's state. Streams marked packed code nothing
  // (their bytes are set afterwards); split cell-field streams code their symbols, and their escaped
  // values are collected in `escaped`, then packed behind them.
  using Enc = EntropyCoder<true>;
  struct Forms {
    bool geo = false;
    std::vector<char> pf, cf, cf_split;
  };
  auto pass = [&](EncodedLevel* level, const Forms& forms) -> Status {
    EncoderSide side = enc;
    level->header = h;
    level->boundary.clear();
    level->connectivity.clear();
    level->geometry.clear();
    level->point_fields.assign(h.point_fields.size(), {});
    level->cell_fields.assign(h.cell_fields.size(), {});
    std::vector<std::unique_ptr<Enc>> pf, cf;
    for (auto& s : level->point_fields) pf.push_back(std::make_unique<Enc>(&s));
    for (auto& s : level->cell_fields) cf.push_back(std::make_unique<Enc>(&s));
    LevelCoder<true> coder(h, std::make_unique<Enc>(&level->boundary), std::make_unique<Enc>(&level->connectivity),
                           std::make_unique<Enc>(&level->geometry), std::move(pf), std::move(cf));
    std::vector<std::vector<uint8_t>> escaped(h.cell_fields.size());
    coder.setEncoder(&side);
    coder.setSeamCount(options.seam_count);
    coder.setPacked(forms.geo, forms.pf, forms.cf, forms.cf_split, &escaped);
    GTN_RETURN_IF_ERROR(coder.run());
    for (size_t f = 0; f < h.cell_fields.size(); ++f) {
      if (!forms.cf_split[f]) continue;
      const FieldDesc& d = h.cell_fields[f];
      const std::vector<uint8_t> items =
          packValues(escaped[f].data(), escaped[f].size() / d.itemBytes(), d.itemBytes(), scalarSize(d.type), 0, true);
      level->cell_fields[f] = splitStream(level->cell_fields[f], items);
    }
    level->boundary_points = coder.boundaryPoints();
    level->vertex_order = std::move(side.vertex_order);
    level->tet_order = std::move(side.tet_order);
    return Status::ok();
  };
  Forms predicted{false, std::vector<char>(h.point_fields.size(), 0), std::vector<char>(h.cell_fields.size(), 0),
                  std::vector<char>(h.cell_fields.size(), 0)};
  GTN_RETURN_IF_ERROR(pass(&out, predicted));
  if (!options.packed_streams) return out;

  // The packed form (spec section 10.2.1) of each value stream, kept where it is smaller: the values
  // in decoding order (the same in every pass: the peeling does not depend on how values are coded).
  // GEOM is packed only in a level without edge points, which a packed GEOM cannot code.
  // A packed point stream holds the vertices coded here (not the seam vertices), in decoding order.
  std::vector<uint32_t> value_rank(np, kNoIndex);
  size_t coded_points = np;
  if (options.seam_count > 0) {
    std::vector<uint32_t> by_id(np);
    for (size_t v = 0; v < np; ++v) by_id[out.vertex_order[v]] = static_cast<uint32_t>(v);
    coded_points = 0;
    for (size_t id = 0; id < np; ++id)
      if (options.seam[by_id[id]] == kNoIndex) value_rank[by_id[id]] = static_cast<uint32_t>(coded_points++);
  } else {
    for (size_t v = 0; v < np; ++v) value_rank[v] = out.vertex_order[v];
  }
  std::vector<uint8_t> items;
  auto packed = [&](const uint8_t* src, size_t count, size_t item_bytes, size_t value_size, auto order,
                    const std::vector<uint8_t>& coded, size_t stored) {
    items.resize(stored * item_bytes);
    for (size_t i = 0; i < count; ++i) {
      const size_t at = order(i);
      if (at != kNoIndex) std::memcpy(&items[at * item_bytes], src + i * item_bytes, item_bytes);
    }
    std::vector<uint8_t> p = packValues(items.data(), stored, item_bytes, value_size, coded.size());
    return !p.empty() && p.size() < coded.size() ? p : std::vector<uint8_t>{};
  };
  auto by_vertex = [&](size_t v) { return value_rank[v] == kNoIndex ? size_t{kNoIndex} : size_t{value_rank[v]}; };
  auto by_tet = [&](size_t t) { return static_cast<size_t>(out.tet_order[t]); };
  Forms chosen = predicted;
  std::vector<uint8_t> geo;
  if (enc.edge_points.empty() && np > 0) {
    const size_t cs = scalarSize(mesh.coord_type);
    std::vector<uint8_t> coords(np * 3 * cs);
    for (size_t i = 0; i < 3 * np; ++i) storeCoordinate(mesh.coord_type, mesh.coords[i], &coords[i * cs]);
    geo = packed(coords.data(), np, 3 * cs, cs, by_vertex, out.geometry, coded_points);
    chosen.geo = !geo.empty();
  }
  std::vector<std::vector<uint8_t>> pfs(h.point_fields.size()), cfs(h.cell_fields.size());
  for (size_t f = 0; f < pfs.size(); ++f) {
    const Field& field = mesh.point_fields[f];
    pfs[f] = packed(field.bytes.data(), np, field.components * field.valueSize(), field.valueSize(), by_vertex,
                    out.point_fields[f], coded_points);
    chosen.pf[f] = !pfs[f].empty();
  }
  for (size_t f = 0; f < cfs.size(); ++f) {
    const Field& field = mesh.cell_fields[f];
    cfs[f] = packed(field.bytes.data(), nt, field.components * field.valueSize(), field.valueSize(), by_tet,
                    out.cell_fields[f], nt);
    chosen.cf[f] = !cfs[f].empty();
  }
  // Cell fields in split form: their symbols as predicted, the values they escape packed (the values
  // new to a split cell, which a table of levels shared by many cells repeats). Tried in a pass
  // of their own on the fields that cost more than a byte per 8 tetrahedra and whose values repeat.
  Forms trial = chosen;
  bool try_split = false;
  // Only where the values repeat: at most one distinct item (by a 64-bit hash) per 12 tetrahedra,
  // two hexahedra's worth.
  auto repeats = [&](const Field& field) {
    const size_t ib = field.components * field.valueSize();
    std::vector<uint64_t> hashes(nt);
    for (size_t t = 0; t < nt; ++t) {
      uint64_t hash = 0xCBF29CE484222325u;
      for (size_t b = 0; b < ib; ++b) hash = (hash ^ field.bytes[t * ib + b]) * 0x100000001B3u;
      hashes[t] = hash;
    }
    std::sort(hashes.begin(), hashes.end());
    return static_cast<size_t>(std::unique(hashes.begin(), hashes.end()) - hashes.begin()) * 12 <= nt;
  };
  for (size_t f = 0; f < cfs.size(); ++f) {
    trial.cf_split[f] = out.cell_fields[f].size() > nt / 8 && repeats(mesh.cell_fields[f]);
    trial.cf[f] = chosen.cf[f] && !trial.cf_split[f];
    try_split = try_split || trial.cf_split[f];
  }
  EncodedLevel split;
  if (try_split) {
    GTN_RETURN_IF_ERROR(pass(&split, trial));
    for (size_t f = 0; f < cfs.size(); ++f) {
      if (!trial.cf_split[f]) continue;
      const size_t best = cfs[f].empty() ? out.cell_fields[f].size() : cfs[f].size();
      chosen.cf_split[f] = split.cell_fields[f].size() < best;
      if (chosen.cf_split[f]) chosen.cf[f] = 0;
    }
  }
  const bool any = chosen.geo || std::find(chosen.pf.begin(), chosen.pf.end(), 1) != chosen.pf.end() ||
                   std::find(chosen.cf.begin(), chosen.cf.end(), 1) != chosen.cf.end() ||
                   std::find(chosen.cf_split.begin(), chosen.cf_split.end(), 1) != chosen.cf_split.end();
  if (!any) return out;
  // Another pass doubles the encoder's time: worth it when the other forms save a 64th of the
  // level's bytes, or a quarter of one stream's.
  size_t total = out.boundary.size() + out.connectivity.size() + out.geometry.size(), saved = 0;
  bool quarter = false;
  auto saving = [&](bool chosen_form, size_t form_size, size_t coded) {
    if (!chosen_form) return;
    saved += coded - std::min(coded, form_size);
    quarter = quarter || 4 * form_size <= 3 * coded;
  };
  saving(chosen.geo, geo.size(), out.geometry.size());
  for (size_t f = 0; f < pfs.size(); ++f) {
    total += out.point_fields[f].size();
    saving(chosen.pf[f], pfs[f].size(), out.point_fields[f].size());
  }
  for (size_t f = 0; f < cfs.size(); ++f) {
    total += out.cell_fields[f].size();
    saving(chosen.cf[f], cfs[f].size(), out.cell_fields[f].size());
    saving(chosen.cf_split[f], split.cell_fields.size() > f ? split.cell_fields[f].size() : 0,
           out.cell_fields[f].size());
  }
  if (!quarter && saved * 64 < total) return out;
  // Again with the chosen forms (the trial when it is that), since the streams share a few models.
  EncodedLevel again;
  if (try_split && chosen.cf == trial.cf && chosen.cf_split == trial.cf_split) {
    again = std::move(split);
  } else {
    GTN_RETURN_IF_ERROR(pass(&again, chosen));
  }
  if (chosen.geo) again.geometry = std::move(geo);
  for (size_t f = 0; f < pfs.size(); ++f)
    if (chosen.pf[f]) again.point_fields[f] = std::move(pfs[f]);
  for (size_t f = 0; f < cfs.size(); ++f)
    if (chosen.cf[f]) again.cell_fields[f] = std::move(cfs[f]);
  return again;
}

Status decodeLevel(const LevelHeader& header, const LevelPayload& payload, MeshSink& sink, DecodeStats* stats,
                   const std::string& what, const DecodeFields* fields, const SeamValues* seams) {
  if (header.coord_type != ScalarType::kFloat32 && header.coord_type != ScalarType::kFloat64)
    return invalidData(what + ": coordinates must be float32 or float64");
  if (header.points >= kNoIndex) return invalidData(what + ": too many points for one level");
  if (header.tets >= kNoIndex) return invalidData(what + ": too many tetrahedra for one level");
  if (payload.point_fields.size() != header.point_fields.size() ||
      payload.cell_fields.size() != header.cell_fields.size())
    return invalidData(what + ": field streams do not match the header's field list");
  for (const auto* list : {&header.point_fields, &header.cell_fields})
    for (const FieldDesc& d : *list) {
      if (static_cast<int>(d.type) >= kNumScalarTypes)
        return invalidData(what + ": field '" + d.name + "' has an unknown type");
      if (d.components == 0 || d.components > 4096)
        return invalidData(what + ": field '" + d.name + "' has an invalid component count");
    }
  const uint32_t seam_count = seams ? seams->count : 0;
  if (seam_count > header.points) return invalidData(what + ": more seam vertices than points");
  const uint64_t coded_points = header.points - seam_count;
  using Dec = EntropyCoder<false>;
  // A packed stream (section 10.2.1) is read by its PackedReader; its range decoder gets an empty
  // stream of its own, which nothing reads.
  static constexpr uint8_t kNoSymbols[6] = {0, 0, 0, 0, 0, 0};
  auto open = [&](std::span<const uint8_t> s, uint64_t count, const FieldDesc& d, const std::string& name,
                  std::unique_ptr<PackedReader>* reader) -> Status {
    if (!isPackedStream(s)) return Status::ok();
    *reader = std::make_unique<PackedReader>();
    const Status st = (*reader)->open(s, count, d.itemBytes(), scalarSize(d.type), name);
    return st.isOk() ? st : invalidData(what + ": " + st.message());
  };
  // A split CFLD stream (section 10.2.1): its range-coded part, and its packed part as a packed stream.
  std::vector<std::vector<uint8_t>> split_packed(header.cell_fields.size());
  std::vector<std::span<const uint8_t>> cell_streams(payload.cell_fields.begin(), payload.cell_fields.end());
  std::vector<char> cf_split(header.cell_fields.size(), 0);
  std::unique_ptr<PackedReader> geo_reader;
  std::vector<std::unique_ptr<PackedReader>> pf_readers(header.point_fields.size()),
      cf_readers(header.cell_fields.size());
  GTN_RETURN_IF_ERROR(
      open(payload.geometry, coded_points, FieldDesc{"", 3, header.coord_type}, "the geometry stream", &geo_reader));
  for (size_t f = 0; f < pf_readers.size(); ++f)
    GTN_RETURN_IF_ERROR(open(payload.point_fields[f], coded_points, header.point_fields[f],
                             "point field '" + header.point_fields[f].name + "'", &pf_readers[f]));
  for (size_t f = 0; f < cf_readers.size(); ++f) {
    const std::string name = "cell field '" + header.cell_fields[f].name + "'";
    if (isSplitStream(payload.cell_fields[f])) {
      if (!splitParts(payload.cell_fields[f], &cell_streams[f], &split_packed[f]))
        return invalidData(what + ": " + name + ": split stream's range-coded part is cut off or its length malformed");
      cf_split[f] = 1;
      cf_readers[f] = std::make_unique<PackedReader>();
      const Status st = cf_readers[f]->open(split_packed[f], header.tets, header.cell_fields[f].itemBytes(),
                                            scalarSize(header.cell_fields[f].type), name, false);
      if (!st.isOk()) return invalidData(what + ": " + st.message());
      continue;
    }
    GTN_RETURN_IF_ERROR(open(payload.cell_fields[f], header.tets, header.cell_fields[f], name, &cf_readers[f]));
  }
  auto symbols = [&](std::span<const uint8_t> s) {
    return std::make_unique<Dec>(isPackedStream(s) ? std::span<const uint8_t>(kNoSymbols) : s);
  };
  std::vector<std::unique_ptr<Dec>> pf, cf;
  for (auto s : payload.point_fields) pf.push_back(symbols(s));
  for (auto s : cell_streams) cf.push_back(symbols(s));
  GTN_RETURN_IF_ERROR(sink.beginLevel(header));
  LevelCoder<false> coder(header, std::make_unique<Dec>(payload.boundary), std::make_unique<Dec>(payload.connectivity),
                          symbols(payload.geometry), std::move(pf), std::move(cf));
  coder.setDecoder(&sink, &what);
  coder.setFields(fields);
  coder.setSeams(seams);
  coder.setPackedReaders(std::move(geo_reader), std::move(pf_readers), std::move(cf_readers), std::move(cf_split));
  const Status st = coder.run();
  if (stats) stats->peak_live_vertices = coder.peakLive();
  return st;
}

LevelPayload payloadOf(const EncodedLevel& encoded) {
  LevelPayload p;
  p.boundary = encoded.boundary;
  p.connectivity = encoded.connectivity;
  p.geometry = encoded.geometry;
  for (const auto& s : encoded.point_fields) p.point_fields.emplace_back(s);
  for (const auto& s : encoded.cell_fields) p.cell_fields.emplace_back(s);
  return p;
}

}  // namespace gtn
