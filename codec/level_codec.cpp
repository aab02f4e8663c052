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

#include "codec/edge_points.h"
#include "codec/flat_maps.h"
#include "codec/nearest_grid.h"
#include "codec/packed_values.h"
#include "codec/range_coder.h"
#include "codec/value_coder.h"
#include "mesh/faces.h"
#include "mesh/predicates.h"

namespace gtn {

namespace {

constexpr uint32_t kNoSlot = 0xFFFFFFFFu;
constexpr uint32_t kNone32 = 0xFFFFFFFFu;
constexpr uint32_t kSymNew = 0;
constexpr uint32_t kSymEscape = 15;
constexpr uint32_t kSymCellNeighbour = 9;  // cell values: 9..11 name a neighbour (spec section 10.7)

// The symbol that codes a vertex: new (not yet decoded), its 1-based place among the candidates, or
// escape (decoded but not a candidate).
inline uint32_t candidateSymbol(uint32_t slot, const uint32_t* cands, int nc) {
  if (slot == kNoSlot) return kSymNew;
  uint32_t sym = kSymEscape;
  for (int i = 0; i < nc; ++i)
    if (cands[i] == slot) sym = static_cast<uint32_t>(i + 1);
  return sym;
}
constexpr int kMaxCandidates = 14;  // symbols 1..14
constexpr int kMaxGather = 48;
constexpr int kFanSteps = 10;
constexpr uint64_t kEscapeScanBudget = 256;  // live vertices scanned per decoded element, at most, for ranked escapes
constexpr uint32_t kEscapeRankBits = 12;     // ranks below 2^12
constexpr int kTetContexts = 10 * 3 * 3;
constexpr int kBoundaryContexts = 2 * 4 * 4 * 2;
constexpr double kMaxKey = 1.7976931348623157e308;  // candidate distances beyond this (inf, NaN) tie here
constexpr double kPredictK = 0.6;  // new vertex at g + k (g - d) (spec section 10.5)
// Prediction rules for a vertex x behind the front face (a, b, c) whose decoded tetrahedron has
// fourth vertex d: weights of (a, b, c, d). Rule 0 is the default (coordinates: g + k (g - d);
// fields: the interpolant of (a, b, c, d) at x). Rules 1-8 are the parallelograms a structured
// grid makes exact, and two reflections; rules 9-12 repeat one stencil vertex, which is exact where a
// grid copies its boundary values to the next layer (blunt fin repeats two planes this way) and for
// coincident points.
constexpr uint32_t kRules = 13;
constexpr uint32_t kCoordRules = 9;  // coordinates have their own per-axis copies (spec section 10.5)
// Field rules 13-15 repeat the first three apex candidates (spec section 10.4's order).
constexpr uint32_t kFieldRules = 16;
constexpr uint32_t kCandidateRules = 3;
// Coordinate error carries (spec section 10.5): none, the stencil's a, b, c, d, the first three apex
// candidates.
constexpr uint32_t kCarries = 8;
// What a carry must save beyond its signalling for the encoder to choose it, in 1/16 bits: the
// residual-length estimate is coarse, and the smallest of 8 x 9 estimates is biased low (on meshes
// without grid structure a carry wins by chance; 3 bits keeps those files within 0.3%).
constexpr int kCarryMargin = 48;
constexpr double kRuleWeights[kRules][4] = {
    {0, 0, 0, 0},  {1, 1, 0, -1}, {0, 1, 1, -1}, {1, 0, 1, -1}, {1, 1, -1, 0},
    {-1, 1, 1, 0}, {1, -1, 1, 0}, {1, 1, 1, -2}, {2.0 / 3, 2.0 / 3, 2.0 / 3, -1},
    {1, 0, 0, 0},  {0, 1, 0, 0},  {0, 0, 1, 0},  {0, 0, 0, 1},
};

// The prediction of rule r (r < kRules) from the stencil values x = (a, b, c, d): the sum of
// kRuleWeights[r][j] * x[j] over the non-zero weights, in order, starting from +0 (spec section 10.5).
// The weights are compile-time constants, as the encoder tries every rule at every vertex; a stencil
// value whose weight is zero is never read.
template <uint32_t r>
inline double weightedRule(const double x[4]) {
  double v = 0;
  if constexpr (kRuleWeights[r][0] != 0.0) v += kRuleWeights[r][0] * x[0];
  if constexpr (kRuleWeights[r][1] != 0.0) v += kRuleWeights[r][1] * x[1];
  if constexpr (kRuleWeights[r][2] != 0.0) v += kRuleWeights[r][2] * x[2];
  if constexpr (kRuleWeights[r][3] != 0.0) v += kRuleWeights[r][3] * x[3];
  return v;
}
template <uint32_t... r>
constexpr std::array<double (*)(const double*), sizeof...(r)> weightedRuleTable(std::integer_sequence<uint32_t, r...>) {
  return {&weightedRule<r>...};
}
constexpr auto kWeightedRule = weightedRuleTable(std::make_integer_sequence<uint32_t, kRules>());
// Every rule's prediction at once, out[r] = weightedRule<r>(x) (out[0] = 0): straight-line code for
// the encoder, which tries them all.
template <uint32_t... r>
inline void weightedRules(const double x[4], double* out, std::integer_sequence<uint32_t, r...>) {
  ((out[r] = weightedRule<r>(x)), ...);
}

enum SlotState : uint8_t { kFree = 0, kLive = 1, kRetired = 2 };

// A source coordinate (held as double) stored as the file's coordinate type (float32 or float64).
inline void storeCoordinate(ScalarType ct, double v, uint8_t* raw) {
  if (ct == ScalarType::kFloat32) {
    const float f = static_cast<float>(v);
    std::memcpy(raw, &f, 4);
  } else {
    std::memcpy(raw, &v, 8);
  }
}

inline uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t{a} << 32) | b; }
// Whether two cell values' keys agree, compared in line: std::equal calls memcmp, which costs more
// than comparing the few components a cell value has.
inline bool sameKeys(const uint64_t* a, const uint64_t* b, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i)
    if (a[i] != b[i]) return false;
  return true;
}
// The i-th prediction rule the encoder tries when `last` was chosen before: `last` first (most
// others then stop early), then the rest in order.
inline uint32_t triedRule(uint32_t i, uint32_t last) { return i == 0 ? last : (i <= last ? i - 1 : i); }
// std::floor(y) for y < 1e18 without a library call (baseline x86-64 has no rounding instruction):
// from -2^52 up every value converts to int64 exactly or truncates toward zero; below, every double
// is an integer already. floor(-0.0) comes out +0.0, which compares equal: the order is the same.
inline double floorKey(double y) {
  if (!(y > -4503599627370496.0)) return y;
  const double d = static_cast<double>(static_cast<int64_t>(y));
  return d > y ? d - 1 : d;
}

// What coding each symbol through `tree` costs now, in 1/16 bits (the encoder weighs a prediction
// rule's signalling against the residual bits it saves). One walk over the nodes prices every
// symbol, as the encoder tries them all: a symbol's cost is the sum along its path from the root.
template <int kBits>
struct SymbolCosts {
  int path[2 << kBits];  // cost of reaching each node; the leaves are the symbols
  int operator[](uint32_t symbol) const { return path[(1 << kBits) + symbol]; }
};
template <int kBits>
SymbolCosts<kBits> symbolCosts(const BitTree<kBits>& tree) {
  static const std::array<uint16_t, 4096> kCost = [] {
    std::array<uint16_t, 4096> t{};
    for (size_t i = 0; i < t.size(); ++i) t[i] = static_cast<uint16_t>(std::lround(-16.0 * std::log2((i + 0.5) / 4096.0)));
    return t;
  }();
  SymbolCosts<kBits> c;
  c.path[1] = 0;
  for (uint32_t node = 1; node < (1u << kBits); ++node) {
    const uint32_t p0 = tree.m[node].p0();
    c.path[2 * node] = c.path[node] + kCost[p0 >> 4];
    c.path[2 * node + 1] = c.path[node] + kCost[(65536 - p0) >> 4];
  }
  return c;
}

// How the field values of a new vertex are predicted.
struct FieldPrediction {
  // kEdge: a point on the edge (s[0], s[1]), predicted at its midpoint (section 10.5).
  enum Kind { kLast, kParallelogram, kInterpolate, kAverage, kEdge } kind = kLast;
  uint32_t s[4] = {kNoSlot, kNoSlot, kNoSlot, kNoSlot};
};

// What the encoder knows and the decoder does not.
struct EncoderSide {
  const TetMesh* mesh = nullptr;
  bool delaunay_first = false;  // the level's "Delaunay first" bit (looksDelaunay)
  const std::vector<uint32_t>* neighbor = nullptr;
  std::vector<uint32_t> src_slot;  // source vertex -> live slot
  std::vector<uint32_t> slot_src;  // slot -> source vertex
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
  // source vertex is a from edge_point_start[a] on; a coded point's entry becomes kNone32.
  std::vector<EdgePoint> edge_points;
  std::vector<uint32_t> edge_point_start;
  std::vector<uint32_t> face_tet;  // FaceMap index of an open face -> the undecoded tetrahedron behind it

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
    if (src_slot[x] == kNoSlot) {
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

template <bool kEncode>
class LevelCoder {
 public:
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
    for (const FieldDesc& d : header.cell_fields) {
      cf_vc_.emplace_back(d.type, d.components);
      cf_offset_.push_back(cell_bytes_);
      cell_bytes_ += d.itemBytes();
    }
    cell_buf_.assign(cell_bytes_, 0);
    last_cell_keys_.resize(header.cell_fields.size());
    for (size_t f = 0; f < header.cell_fields.size(); ++f) {
      // The first prediction is the key of zero.
      const FieldDesc& d = header.cell_fields[f];
      last_cell_keys_[f].assign(d.components, keyFromPrediction(d.type, 0.0));
      cell_comps_ += d.components;
    }
    cell_keys_.assign(cell_comps_, 0);
    uint32_t max_comps = 1;
    for (const FieldDesc& d : header.cell_fields) max_comps = std::max(max_comps, d.components);
    cell_pred_.assign(max_comps, 0);
    cell_act_.assign(max_comps, 0);
    cell_mtf_.resize(header.cell_fields.size());
    cell_sym_.resize(header.cell_fields.size());
    cell_last_sym_.assign(header.cell_fields.size(), 0);
    pred_vals_.resize(std::max<size_t>(1, item_bytes_));
    for (size_t f = 0; f < header.point_fields.size(); ++f)
      for (uint32_t c = 0; c < header.point_fields[f].components; ++c) comp_type_.push_back(header.point_fields[f].type);
    alias_.assign(comp_type_.size(), kNone32);
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
    edge_points_ = geo_packed_ ? 0 : geo_->bit(edge_points_flag_, edge_points);
    uint32_t delaunay_first = 0;
    if constexpr (kEncode) delaunay_first = enc_->delaunay_first;
    delaunay_first_ = con_->bit(delaunay_first_flag_, delaunay_first);
    GTN_RETURN_IF_ERROR(boundaryPhase());
    if constexpr (!kEncode) GTN_RETURN_IF_ERROR(sink_->endBoundary());
    GTN_RETURN_IF_ERROR(peelingPhase());
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
          return bad("point field stream '" + header_.point_fields[f].name + "' is corrupt, truncated or has trailing bytes");
        }
      }
      for (size_t f = 0; f < cf_.size(); ++f) {
        if (cf_skip_[f]) continue;
        if (!cf_packed_[f] && !cf_[f]->finishedCleanly())
          return bad("cell field stream '" + header_.cell_fields[f].name + "' is corrupt, truncated or has trailing bytes");
        if (cf_packed_[f] || cf_split_[f]) GTN_RETURN_IF_ERROR(packedEnd(*cf_readers_[f]));
      }
      GTN_RETURN_IF_ERROR(sink_->endLevel());
    }
    return Status::ok();
  }

  uint64_t peakLive() const { return peak_live_; }

  // Slot s's values as the sink takes them: every field at its offset, those left out zero.
  const uint8_t* sinkValues(uint32_t s) {
    if (item_bytes_ == 0) return nullptr;
    if (slot_bytes_ == item_bytes_) return &vals_[s * slot_bytes_];
    for (size_t f = 0; f < header_.point_fields.size(); ++f)
      if (!pf_skip_[f])
        std::memcpy(&sink_vals_[pf_offset_[f]], &vals_[s * slot_bytes_ + slot_off_[f]], header_.point_fields[f].itemBytes());
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
          is_alias = enc_->alias[k] != kNone32;
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
    slot_bytes_ = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      if (pf_skip_[f]) continue;
      slot_off_[f] = slot_bytes_;
      slot_bytes_ += header_.point_fields[f].itemBytes();
    }
    comp_slot_off_.clear();
    for (size_t f = 0; f < header_.point_fields.size(); ++f)
      for (uint32_t c = 0; c < header_.point_fields[f].components; ++c)
        comp_slot_off_.push_back(slot_off_[f] + c * scalarSize(header_.point_fields[f].type));
    last_vals_.assign(slot_bytes_, 0);
    if (slot_bytes_ != item_bytes_) sink_vals_.assign(item_bytes_, 0);
  }

  // A field left out of the decode is decoded after all when a kept field repeats one of its
  // components. A component repeats an earlier one, so one pass from the last field back takes
  // repeats of repeats along.
  void keepRepeatedFields() {
    std::vector<size_t> field_of;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) field_of.insert(field_of.end(), header_.point_fields[f].components, f);
    for (size_t k = field_of.size(); k-- > 0;)
      if (!pf_skip_[field_of[k]] && alias_[k] != kNone32) pf_skip_[field_of[alias_[k]]] = 0;
  }

  // Each value-coded component's form (section 10.2), at the start of its stream. For a float type a
  // bit (one model for the level) says whether it is coded in decimal form, then its decimal places
  // in 5 direct bits; otherwise, for float64, a bit (another model) whether it is in printed-single
  // form, then its digits in 5 direct bits; otherwise a bit (a third model) says whether it has a
  // shift, then the shift in 6 direct bits.
  Status codeValueForms() {
    struct Form {
      int decimals = -1;
      int printed = 0;
      uint32_t shift = 0;
      bool exceptions = false;  // of the shift
      std::vector<uint64_t> table = {};  // the distinct keys, ascending, of a table form
    };
    // `values`: how many values the stream holds, the most a table can need.
    auto declare = [&](Coder& c, ValueCoder& vc, ScalarType type, uint32_t comp, Form form, uint64_t values,
                       const std::string& what) -> Status {
      if (c.bit(table_flag_, !form.table.empty())) {
        if (!vc.codeTable(c, comp, &form.table, values))
          return bad(what + (c.ok() ? " declares an invalid value table (longer than its values, or not ascending)"
                                    : " is truncated or corrupt in its value table"));
        return Status::ok();
      }
      if (isFloatType(type)) {
        uint32_t decimal = form.decimals >= 0;
        decimal = c.bit(decimal_flag_, decimal);
        if (decimal) {
          const uint32_t e = c.direct(static_cast<uint32_t>(std::max(form.decimals, 0)), 5);
          if constexpr (!kEncode) {
            if (e > ValueCoder::kMaxDecimals)
              return bad(what + " declares " + std::to_string(e) + " decimal places (at most 22)");
          }
          vc.setDecimals(comp, static_cast<int>(e));
          return Status::ok();
        }
        if (type == ScalarType::kFloat64) {
          uint32_t printed = form.printed > 0;
          printed = c.bit(printed_flag_, printed);
          if (printed) {
            const uint32_t p = c.direct(static_cast<uint32_t>(form.printed), 5);
            if constexpr (!kEncode) {
              if (p < 1 || p > ValueCoder::kMaxPrintedDigits)
                return bad(what + " declares " + std::to_string(p) + " printed digits (1 to 17)");
            }
            vc.setPrinted(comp, static_cast<int>(p));
            return Status::ok();
          }
        }
      }
      uint32_t has = form.shift > 0;
      has = c.bit(shift_flag_, has);
      if (!has) return Status::ok();
      const uint32_t shift = c.direct(form.shift, 6);
      if constexpr (!kEncode) {
        if (shift == 0 || shift >= static_cast<uint32_t>(vc.bits()))
          return bad(what + " declares an invalid shift of " + std::to_string(shift) + " bits");
      }
      const uint32_t exceptions = c.bit(exceptions_flag_, form.exceptions);
      vc.setShift(comp, static_cast<int>(shift), exceptions != 0);
      return Status::ok();
    };
    // The encoder's choice for `n` values `stride` bytes apart: the shift, or whichever of the decimal
    // places, printed digits, larger shift with exceptions or value table costs least, when that saves
    // a twentieth. Costs are estimated on the differences of
    // consecutive values in the source's order (neighbours there are mostly neighbours in space), as
    // bit lengths: of the integers' differences, of the shifted keys' differences for floats and for
    // values without a decimal form; over every value, or a sample of 256 pairs (pseudo-random: a
    // regular stride can alias with a grid's layout) for more than 1024.
    auto choose = [](ScalarType type, const uint8_t* p, size_t n, size_t stride) {
      Form form;
      int z = scalarBits(type) - 1;
      for (size_t i = 0; i < n && z > 0; ++i) z = std::min(z, ValueCoder::trailingZeros(type, p + i * stride));
      form.shift = static_cast<uint32_t>(z);
      if (n < 2) return form;
      struct Pair {
        int places[2];
        double integer[2];
        float float_bits;  // bit length of the difference of the shifted keys
        uint64_t keys[2];
        int zeros[2];  // trailing zero bits of the stored patterns, at most the width - 1
      };
      struct Value {
        uint64_t key;
        int places;
        double integer;
        int zeros;
      };
      int lo = ValueCoder::kMaxDecimals + 1, hi = -1;
      auto valueAt = [&](size_t i) {
        Value v{keyFromRaw(type, p + i * stride), -1, 0, std::min(ValueCoder::trailingZeros(type, p + i * stride), scalarBits(type) - 1)};
        int64_t integer = 0;
        v.places = ValueCoder::decimalPlaces(type, v.key, &integer);
        v.integer = static_cast<double>(integer);
        if (v.places >= 0) lo = std::min(lo, v.places), hi = std::max(hi, v.places);
        return v;
      };
      std::vector<Pair> pairs;
      const bool sample = n > 1024;
      uint64_t state = 0x9E3779B97F4A7C15u;
      // Consecutive pairs share a value: its decimal places (a shortest-decimal conversion, most of
      // the cost) are found once.
      Value next = sample ? Value{} : valueAt(0);
      for (size_t k = 0; k < (sample ? 256 : n - 1); ++k) {
        state ^= state << 13, state ^= state >> 7, state ^= state << 17;
        const size_t i = sample ? state % (n - 1) : k;
        const Value a = sample ? valueAt(i) : next, b = valueAt(i + 1);
        next = b;
        Pair pair{{a.places, b.places}, {a.integer, b.integer}, 0, {a.key, b.key}, {a.zeros, b.zeros}};
        const uint64_t d = (b.key > a.key ? b.key - a.key : a.key - b.key) >> z;
        pair.float_bits = static_cast<float>(bitLength(d));
        pairs.push_back(pair);
      }
      double floats = 0;
      for (const Pair& pair : pairs) floats += pair.float_bits + 1;
      double best = 0.95 * floats;
      for (int e = lo; e <= hi; ++e) {
        double cost = 0;
        for (const Pair& pair : pairs) {
          double at_e[2];
          for (int j = 0; j < 2; ++j)
            at_e[j] = pair.places[j] >= 0 && pair.places[j] <= e ? pair.integer[j] * kPowersOfTen[e - pair.places[j]] : 1e300;
          const bool both = std::fabs(at_e[0]) < kDecimalLimit && std::fabs(at_e[1]) < kDecimalLimit;
          cost += both ? std::log2(std::fabs(at_e[1] - at_e[0]) + 1) + 1 : pair.float_bits + 4;
        }
        if (cost < best) best = cost, form = {e, 0, 0};
      }
      // Float64 values that are float32 values printed with p digits (0.200000002980232 for 0.2f): the
      // p that most of the pairs' first values have (values that are float32 values exactly have a
      // shift of 29 or more instead), costed like the decimal places, on the float32 keys.
      if (type == ScalarType::kFloat64 && form.shift < 29) {
        int count[ValueCoder::kMaxPrintedDigits] = {};
        uint64_t single = 0;
        // A printing with p digits reads back as v only if v's shortest decimal has at most p: a full
        // double (17) is never tried, so this costs one conversion per value where no form applies.
        for (const Pair& pair : pairs)
          for (int digits = std::max(1, shortestDigits(pair.keys[0])); digits < ValueCoder::kMaxPrintedDigits; ++digits)
            count[digits] += printedSingleKey(pair.keys[0], digits, &single);
        int digits = 0;
        for (int d = 1; d < ValueCoder::kMaxPrintedDigits; ++d)
          if (count[d] > count[digits]) digits = d;
        if (digits > 0) {
          double cost = 0;
          for (const Pair& pair : pairs) {
            uint64_t k32[2];
            const bool both = printedSingleKey(pair.keys[0], digits, &k32[0]) && printedSingleKey(pair.keys[1], digits, &k32[1]);
            cost += both ? bitLength(k32[1] > k32[0] ? k32[1] - k32[0] : k32[0] - k32[1]) + 1 : pair.float_bits + 4;
          }
          if (cost < best) best = cost, form = {-1, digits, 0};
        }
      }
      // A shift with exceptions: s low bits that most values have zero, but not all (sums of float32
      // values kept in doubles, with a few full doubles; exact zeros among computed values). Each s
      // that some sampled value has is costed like the decimal places, on the keys shifted by s; a pair's
      // second value is costed as predicted by the first, whose low bits the shift drops whatever they
      // are (a zero next to full doubles costs a few bits of exponent instead of a whole double). The
      // escape's models start cold: a few dozen bits, and no gain below some 64 values.
      if (n < 64) return form;
      constexpr double kColdModels = 32;
      bool tried[64] = {};
      for (const Pair& candidate : pairs) {
        for (const int sh : candidate.zeros) {
          if (sh <= z || tried[sh]) continue;
          tried[sh] = true;
          double cost = kColdModels;
          for (const Pair& pair : pairs) {
            const uint64_t d = pair.keys[1] > pair.keys[0] ? pair.keys[1] - pair.keys[0] : pair.keys[0] - pair.keys[1];
            cost += pair.zeros[1] >= sh ? bitLength(d >> sh) + 1 : pair.float_bits + 4;
          }
          if (cost < best) best = cost, form = {-1, 0, static_cast<uint32_t>(sh), true};
        }
      }
      // A value table: few distinct values (a lattice's coordinates, a field with a few levels) cost
      // their places in the table, plus the table. Only when the sampled values repeat (at most half
      // of them distinct) are all the values sorted, and the table is kept to a quarter of them. The
      // estimate takes neighbours in the source's order for predictions, which misses by more than the
      // table's own bits on small lattices (an MMG cube of 152 points would grow by a tenth): the table
      // is weighed only from 1024 values on.
      if (n < 1024) return form;
      std::vector<uint64_t> keys;
      for (const Pair& pair : pairs) keys.insert(keys.end(), pair.keys, pair.keys + 2);
      std::sort(keys.begin(), keys.end());
      const size_t sampled_distinct = static_cast<size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
      if (sampled_distinct > pairs.size()) return form;  // more than half of the 2 per pair
      keys.resize(n);
      for (size_t i = 0; i < n; ++i) keys[i] = keyFromRaw(type, p + i * stride);
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
      if (keys.size() * 4 > n) return form;
      double table_bits = 12;
      for (size_t i = 1; i < keys.size(); ++i) {
        const uint64_t pred = i == 1 ? keys[0] + 1 : 2 * keys[i - 1] - keys[i - 2];
        const int64_t r = static_cast<int64_t>(keys[i] - pred);
        table_bits += bitLength(static_cast<uint64_t>(r < 0 ? -r : r)) + 2;
      }
      double cost = table_bits * static_cast<double>(pairs.size()) / static_cast<double>(n - 1);
      for (const Pair& pair : pairs) {
        const auto a = std::lower_bound(keys.begin(), keys.end(), pair.keys[0]), b = std::lower_bound(keys.begin(), keys.end(), pair.keys[1]);
        cost += bitLength(static_cast<uint64_t>(a < b ? b - a : a - b)) + 1;
      }
      if (cost < best) form = {-1, 0, 0, false, std::move(keys)};
      return form;
    };
    const ScalarType ct = header_.coord_type;
    for (uint32_t i = 0; i < 3 && !geo_packed_; ++i) {
      Form form;
      if constexpr (kEncode) {
        const std::vector<double>& xyz = enc_->mesh->coords;
        const size_t n = xyz.size() / 3;
        std::vector<uint8_t> raw(n * scalarSize(ct));
        for (size_t v = 0; v < n; ++v) storeCoordinate(ct, xyz[3 * v + i], &raw[v * scalarSize(ct)]);
        form = choose(ct, raw.data(), n, scalarSize(ct));
      }
      GTN_RETURN_IF_ERROR(declare(*geo_, coord_vc_, ct, i, std::move(form), header_.points, "the geometry stream"));
    }
    size_t k = 0;
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      const FieldDesc& d = header_.point_fields[f];
      for (uint32_t c = 0; c < d.components; ++c, ++k) {
        if (alias_[k] != kNone32 || pf_packed_[f]) continue;
        Form form;
        if constexpr (kEncode) {
          const Field& src = enc_->mesh->point_fields[f];
          form = choose(d.type, src.bytes.data() + c * scalarSize(d.type), src.itemCount(), d.itemBytes());
        }
        GTN_RETURN_IF_ERROR(declare(*pf_[f], pf_vc_[f], d.type, c, std::move(form), header_.points, "point field '" + d.name + "'"));
      }
    }
    for (size_t f = 0; f < header_.cell_fields.size(); ++f) {
      const FieldDesc& d = header_.cell_fields[f];
      for (uint32_t c = 0; c < d.components && !cf_packed_[f] && !cf_split_[f]; ++c) {
        Form form;
        if constexpr (kEncode) {
          const Field& src = enc_->mesh->cell_fields[f];
          form = choose(d.type, src.bytes.data() + c * scalarSize(d.type), src.itemCount(), d.itemBytes());
        }
        GTN_RETURN_IF_ERROR(declare(*cf_[f], cf_vc_[f], d.type, c, std::move(form), header_.tets, "cell field '" + d.name + "'"));
      }
    }
    return Status::ok();
  }

 private:
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
  Status internal(const std::string& reason) const {
    return invalidData("encodeLevel: inconsistent mesh: " + reason);
  }

  // ---- slot pool -------------------------------------------------------------------------------
  uint32_t allocSlot() {
    uint32_t s;
    if (!free_.empty()) {
      s = free_.back();
      free_.pop_back();
    } else {
      s = static_cast<uint32_t>(state_.size());
      if (s == state_.capacity()) reserveSlots(s + s / 4 + 64);
      state_.push_back(kFree);
      pos_.resize(pos_.size() + 3);
      err_.resize(err_.size() + 3);
      vals_.resize(vals_.size() + slot_bytes_);
      open_.push_back(0);
      pins_.push_back(0);
      ids_.push_back(0);
      gather_mark_.push_back(0);
      if (!boundary_done_) {
        nxt_.push_back(kNoSlot);
        prv_.push_back(kNoSlot);
        corner_sum_.push_back(0.0);
        corner_count_.push_back(0);
      }
      if constexpr (kEncode) enc_->slot_src.push_back(kNone32);
    }
    state_[s] = kLive;
    open_[s] = 0;
    pins_[s] = 0;
    if (!boundary_done_) {
      nxt_[s] = kNoSlot;
      prv_[s] = kNoSlot;
      corner_sum_[s] = 0.0;
      corner_count_[s] = 0;
    }
    return s;
  }
  // Room for n slots in every per-slot array. The pool grows by a quarter, not the vectors' own
  // doubling: these arrays are most of the decoder's memory after the edge buckets (64 bytes a slot,
  // grown a chunk at a time), and doubling left up to half of them unused (blunt fin's 9748 slots
  // had room for 16384).
  void reserveSlots(size_t n) {
    state_.reserve(n);
    pos_.reserve(3 * n);
    err_.reserve(3 * n);
    vals_.reserve(slot_bytes_ * n);
    open_.reserve(n);
    pins_.reserve(n);
    ids_.reserve(n);
    gather_mark_.reserve(n);
    if (!boundary_done_) {
      nxt_.reserve(n);
      prv_.reserve(n);
      corner_sum_.reserve(n);
      corner_count_.reserve(n);
    }
    faces_.reserveSlots(n);
    if (grid_.built()) grid_.reserveSlots(n);
  }
  void freeSlot(uint32_t s) {
    state_[s] = kFree;
    free_.push_back(s);
  }
  bool isLive(uint32_t s) const { return s < state_.size() && state_[s] == kLive; }
  const double* P(uint32_t s) const { return &pos_[3 * size_t{s}]; }

  Status retire(uint32_t s) {
    state_[s] = kRetired;
    --live_;
    if (grid_.built()) grid_.erase(s);
    if constexpr (kEncode) {
      enc_->src_slot[enc_->slot_src[s]] = kNoSlot;
    } else {
      GTN_RETURN_IF_ERROR(sink_->retireVertex(ids_[s]));
    }
    if (pins_[s] == 0) freeSlot(s);
    return Status::ok();
  }
  void unpin(uint32_t s) {
    if (--pins_[s] == 0 && state_[s] == kRetired) freeSlot(s);
  }

  // Slot index coded uniformly over the pool size.
  uint32_t codeSlot(Coder& c, uint32_t s) {
    const int n = bitLength(state_.size() > 1 ? state_.size() - 1 : 0);
    return c.direct(kEncode ? s : 0, n);
  }

  // ---- values ----------------------------------------------------------------------------------
  // Coordinate i of the stencil vertices (0 where there is none): the values rules weigh.
  void coordStencil(const FieldPrediction& fp, int i, double x[4]) const {
    for (int j = 0; j < 4; ++j) x[j] = fp.s[j] != kNoSlot ? P(fp.s[j])[i] : 0.0;
  }
  double fieldRule(uint32_t r, const FieldPrediction& fp, ScalarType type, size_t off) const {
    if (r >= kRules) return doubleFromRaw(type, &vals_[near_[r - kRules] * slot_bytes_ + off]);
    double x[4];
    for (int j = 0; j < 4; ++j) x[j] = fp.s[j] != kNoSlot ? doubleFromRaw(type, &vals_[fp.s[j] * slot_bytes_ + off]) : 0.0;
    return kWeightedRule[r](x);
  }

  void computeFieldPrediction(const FieldPrediction& fp, const double* x) {
    size_t k = 0;
    double lambda[4] = {1, 0, 0, 0};
    int n = 1;
    FieldPrediction::Kind kind = fp.kind;
    if (kind == FieldPrediction::kInterpolate) {
      const double *a = P(fp.s[0]), *b = P(fp.s[1]), *c = P(fp.s[2]), *d = P(fp.s[3]);
      double e1[3], e2[3], e3[3], r[3];
      for (int i = 0; i < 3; ++i) {
        e1[i] = b[i] - a[i];
        e2[i] = c[i] - a[i];
        e3[i] = d[i] - a[i];
        r[i] = x[i] - a[i];
      }
      auto det = [](const double* u, const double* v, const double* w) {
        return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
               u[2] * (v[0] * w[1] - v[1] * w[0]);
      };
      const double vol = det(e1, e2, e3);
      bool ok = vol != 0.0 && std::isfinite(vol);
      if (ok) {
        lambda[1] = det(r, e2, e3) / vol;
        lambda[2] = det(e1, r, e3) / vol;
        lambda[3] = det(e1, e2, r) / vol;
        lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
        for (double l : lambda)
          if (!(std::fabs(l) <= 8.0)) ok = false;
      }
      if (ok) {
        n = 4;
      } else {
        kind = FieldPrediction::kAverage;
      }
    }
    if (kind == FieldPrediction::kAverage) {
      lambda[0] = lambda[1] = lambda[2] = 1.0 / 3.0;
      n = 3;
    } else if (kind == FieldPrediction::kParallelogram) {
      lambda[0] = 1;
      lambda[1] = 1;
      lambda[2] = -1;
      n = 3;
    } else if (kind == FieldPrediction::kEdge) {
      lambda[0] = lambda[1] = 0.5;
      n = 2;
    }
    for (size_t f = 0; f < header_.point_fields.size(); ++f) {
      const FieldDesc& d = header_.point_fields[f];
      const size_t vs = scalarSize(d.type);
      if (pf_skip_[f]) {
        k += d.components;
        continue;
      }
      for (uint32_t c = 0; c < d.components; ++c, ++k) {
        const size_t off = slot_off_[f] + c * vs;
        if (kind == FieldPrediction::kLast) {
          pred_vals_[k] = doubleFromRaw(d.type, &last_vals_[off]);
          continue;
        }
        double v = 0;
        for (int i = 0; i < n; ++i) v += lambda[i] * doubleFromRaw(d.type, &vals_[fp.s[i] * slot_bytes_ + off]);
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
        if (alias_[k + c] != kNone32) continue;
        const size_t off = slot_off_[f] + c * vs;
        const uint64_t actual = keyFromRaw(type, src_item + c * vs);
        double x[4], v[kFieldRules] = {};
        for (int j = 0; j < 4; ++j) x[j] = fp.s[j] != kNoSlot ? doubleFromRaw(type, &vals_[fp.s[j] * slot_bytes_ + off]) : 0.0;
        weightedRules(x, v, std::make_integer_sequence<uint32_t, kRules>());
        v[0] = pred_vals_[k + c];
        for (uint32_t j = 0; j < n_cand; ++j) v[kRules + j] = doubleFromRaw(type, &vals_[near_[j] * slot_bytes_ + off]);
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

  // The keys of a `bits`-wide type are its low `bits` bits.
  static uint64_t keyMask(int bits) { return bits == 64 ? ~uint64_t{0} : ((uint64_t{1} << bits) - 1); }
  // Magnitude class of the residual between two keys (`mask`: their type's keyMask), the encoder's cost.
  static int residualBits(uint64_t actual, uint64_t pred, uint64_t mask) {
    const uint64_t r = (actual - pred) & mask, n = (~r + 1) & mask;
    return bitLength(r < n ? r : n);
  }
  // Adds to cost[r] the residual cost of prediction v[r], 16 * residualBits, for r < kCount (a multiple
  // of 4): the rules of one component whose actual key is `actual`.
  template <uint32_t kCount, class Type>
  static void addRuleCosts(Type type, uint64_t actual, const double* v, int* cost) {
    static_assert(kCount % 4 == 0);
#if defined(__SSE2__)
    // Four rules at a time for float32, the usual field type: the same arithmetic as
    // keyFromPrediction (the range check, the float conversion) and residualBits (the smaller of the
    // residual and its negation, modulo 2^32), whose bit length is the exponent of its exact
    // conversion to double.
    if constexpr (std::is_same_v<Type, std::integral_constant<ScalarType, ScalarType::kFloat32>>) {
      const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7FFFFFFFFFFFFFFF));
      const __m128d max_float = _mm_set1_pd(3.4028234663852886e38);
      const __m128i sign = _mm_set1_epi32(static_cast<int>(0x80000000u));
      const __m128i act = _mm_set1_epi32(static_cast<int>(actual));
      for (uint32_t r = 0; r < kCount; r += 4) {
        __m128 f[2];
        for (int h = 0; h < 2; ++h) {
          const __m128d d = _mm_loadu_pd(v + r + 2 * h);
          const __m128d in_range = _mm_cmple_pd(_mm_and_pd(d, abs_mask), max_float);  // not NaN or infinite
          f[h] = _mm_cvtpd_ps(_mm_and_pd(d, in_range));
        }
        const __m128i bits = _mm_castps_si128(_mm_movelh_ps(f[0], f[1]));
        const __m128i key = _mm_xor_si128(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), sign));
        const __m128i res = _mm_sub_epi32(act, key), neg = _mm_sub_epi32(_mm_setzero_si128(), res);
        const __m128i less = _mm_cmplt_epi32(_mm_xor_si128(res, sign), _mm_xor_si128(neg, sign));
        const __m128i mag = _mm_or_si128(_mm_and_si128(less, res), _mm_andnot_si128(less, neg));
        // As int32 the largest magnitude, 2^31, is -2^31: the exponent is the same.
        auto lengths = [&](__m128i two) {
          const __m128i e = _mm_and_si128(_mm_srli_epi64(_mm_castpd_si128(_mm_cvtepi32_pd(two)), 52), _mm_set1_epi64x(0x7FF));
          return _mm_subs_epu16(e, _mm_set1_epi16(1022));  // 0 (exponent 0) stays 0
        };
        const __m128i lo = lengths(mag), hi = lengths(_mm_shuffle_epi32(mag, _MM_SHUFFLE(3, 2, 3, 2)));
        const __m128i len = _mm_castps_si128(_mm_shuffle_ps(_mm_castsi128_ps(lo), _mm_castsi128_ps(hi), _MM_SHUFFLE(2, 0, 2, 0)));
        __m128i* c = reinterpret_cast<__m128i*>(cost + r);
        _mm_storeu_si128(c, _mm_add_epi32(_mm_loadu_si128(c), _mm_slli_epi32(len, 4)));
      }
      return;
    }
#endif
    const uint64_t mask = keyMask(scalarBits(type));
    for (uint32_t r = 0; r < kCount; ++r) cost[r] += 16 * residualBits(actual, keyFromPrediction(type, v[r]), mask);
  }
  // The vertex whose error carry m (1 to kCarries - 1) names, or kNoSlot if there is none: the
  // stencil's a, b, c, d (d only with has_d), then the first three apex candidates.
  uint32_t carrySource(uint32_t m, const FieldPrediction& fp, bool has_d) const {
    if (m >= 1 && m <= 3) return fp.s[m - 1];
    if (m == 4) return has_d ? fp.s[3] : kNoSlot;
    if (m >= 5 && m < kCarries && static_cast<int>(m - 5) < n_near_) return near_[m - 5];
    return kNoSlot;
  }
  static bool ruleAllowed(uint32_t rule, bool has_d, uint32_t rules) {
    return rule < rules && (has_d || kRuleWeights[rule][3] == 0.0);
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
    double* x = &pos_[3 * size_t{s}];
    const ScalarType ct = header_.coord_type;
    const uint64_t cmask = keyMask(scalarBits(ct));
    const bool choose = fp.kind == FieldPrediction::kInterpolate || fp.kind == FieldPrediction::kAverage;
    // Fields also choose behind a boundary edge (rule 0 is then the parallelogram).
    const bool choose_fields = choose || fp.kind == FieldPrediction::kParallelogram;
    const bool has_d = fp.kind == FieldPrediction::kInterpolate;
    uint64_t actual[3] = {0, 0, 0};
    if constexpr (kEncode) {
      for (uint32_t i = 0; i < 3; ++i) {
        uint8_t raw[8];
        storeCoordinate(ct, enc_->mesh->coords[3 * size_t{src} + i], raw);
        actual[i] = keyFromRaw(ct, raw);
      }
    }
    if (geo_packed_) {
      // Packed form: the coordinates as stored, no rule, carry or copy.
      const size_t cs = scalarSize(ct);
      uint8_t item[24];
      if constexpr (kEncode) {
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
        err_[3 * size_t{s} + i] = 0.0f;
      }
    } else {
      uint64_t pk[3];
      for (int i = 0; i < 3; ++i) pk[i] = keyFromPrediction(ct, pred[i]);
      // Copy sources: the stencil, then the apex candidates (front vertices around the gate), which
      // on extruded and sheared grids hold the vertex's neighbours along a grid line.
      uint32_t copy_src[4 + kMaxCandidates];
      uint32_t ncopy = 0;
      if (fp.kind != FieldPrediction::kLast) {
        for (int m = 0; m < 4; ++m)
          if (fp.s[m] != kNoSlot && (m < 3 || has_d)) copy_src[ncopy++] = fp.s[m];
        if (fp.kind != FieldPrediction::kEdge)
          for (int m = 0; m < n_near_; ++m) copy_src[ncopy++] = near_[m];
      }
      // The encoder's first copy source that has each axis's value, kNone32 if none does: a copied
      // axis's residual does not count when the encoder chooses a prediction.
      uint32_t first_copy[3] = {kNone32, kNone32, kNone32};
      if constexpr (kEncode) {
        for (int i = 0; i < 3; ++i)
          for (uint32_t m = 0; m < ncopy && first_copy[i] == kNone32; ++m)
            if (keyFromPrediction(ct, P(copy_src[m])[i]) == actual[i]) first_copy[i] = m;
      }
      double base[3] = {pred[0], pred[1], pred[2]};  // the prediction before any carry (err_)
      if (choose) {
        uint32_t rule = 0, carry = 0;
        if constexpr (kEncode) {
          // The cheapest rule, the lowest among equals; the previous rule first, so that most others
          // stop early.
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
                if (first_copy[i] == kNone32)
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
              if (src == kNoSlot) continue;
              const float* e = &err_[3 * size_t{src}];
              int cost[kPadded];
              for (uint32_t r = 0; r < kPadded; ++r) cost[r] = r < kCoordRules ? signal[r] + carry_signal[m] + kCarryMargin : 0;
              for (int i = 0; i < 3; ++i) {
                if (first_copy[i] != kNone32) continue;
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
        }
        rule = geo_rule_[geo_last_rule_].code(*geo_, rule);
        if (!ruleAllowed(rule, has_d, kCoordRules)) return bad("invalid coordinate prediction rule");
        geo_last_rule_ = rule;
        carry = geo_carry_[geo_last_carry_].code(*geo_, carry);
        const uint32_t carry_src = carry == 0 ? kNoSlot : carrySource(carry, fp, has_d);
        if (carry != 0 && carry_src == kNoSlot) return bad("coordinate error carried from an unknown vertex");
        geo_last_carry_ = carry;
        for (int i = 0; i < 3; ++i) {
          if (rule != 0) {
            double stencil[4];
            coordStencil(fp, i, stencil);
            base[i] = kWeightedRule[rule](stencil);
          }
          if (carry != 0) {
            pk[i] = keyFromPrediction(ct, base[i] + static_cast<double>(err_[3 * size_t{carry_src} + i]));
          } else if (rule != 0) {
            pk[i] = keyFromPrediction(ct, base[i]);
          }
        }
      }
      uint32_t prev_which = kNone32;  // copy source of the previous coordinate of this vertex
      for (uint32_t i = 0; i < 3; ++i) {
        uint64_t key = 0;
        uint32_t hit = 0;
        if (ncopy > 0) {
          uint32_t which = 0;
          if constexpr (kEncode) {
            // Prefer the source the previous coordinate was copied from: one bit says so.
            if (prev_which != kNone32 && keyFromPrediction(ct, P(copy_src[prev_which])[i]) == actual[i]) {
              hit = 1;
              which = prev_which;
            } else if (first_copy[i] != kNone32) {
              hit = 1;
              which = first_copy[i];
            }
          }
          hit = geo_->bit(copy_flag_[i][copy_last_[i] + 2 * (prev_which != kNone32)], hit);
          copy_last_[i] = hit;
          if (hit) {
            uint32_t same = prev_which != kNone32 && which == prev_which;
            if (prev_which != kNone32) same = geo_->bit(copy_same_[i], same);
            if (same) {
              which = prev_which;
            } else {
              which = copy_which_[i].code(*geo_, which);
            }
            if (which >= ncopy) return bad("coordinate copied from an unknown vertex");
            key = keyFromPrediction(ct, P(copy_src[which])[i]);
            prev_which = which;
          } else {
            prev_which = kNone32;
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
      for (int i = 0; i < 3; ++i)
        err_[3 * size_t{s} + i] = fp.kind == FieldPrediction::kLast ? 0.0f : static_cast<float>(x[i] - base[i]);
    }
    if (slot_bytes_ > 0) {
      computeFieldPrediction(fp, x);
      uint8_t* out = &vals_[s * slot_bytes_];
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
        if (choose_fields && field_coded_comps_[f] > 0) {
          if constexpr (kEncode) rule = chooseFieldRule(f, k, fp, has_d, src_item);
          rule = pf_rule_[f][pf_last_rule_[f]].code(*pf_[f], rule);
          if (!fieldRuleAllowed(rule, has_d)) return bad("invalid field prediction rule");
          pf_last_rule_[f] = rule;
        }
        for (uint32_t c = 0; c < d.components; ++c, ++k) {
          const size_t off = slot_off_[f] + c * vs;
          if (alias_[k] != kNone32) {
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
      std::memcpy(last_vals_.data(), out, slot_bytes_);
    }
    const uint32_t id = static_cast<uint32_t>(next_id_++);
    ids_[s] = id;
    if constexpr (kEncode) {
      enc_->vertex_order[src] = id;
      enc_->src_slot[src] = s;
      enc_->slot_src[s] = src;
    } else {
      GTN_RETURN_IF_ERROR(sink_->vertex(id, x, sinkValues(s)));
    }
    std::memcpy(last_pos_, x, sizeof(last_pos_));
    ++live_;
    if (grid_.built()) grid_.insert(s, P(s));
    peak_live_ = std::max<uint64_t>(peak_live_, live_);
    *slot_out = s;
    return Status::ok();
  }

  Status introduceFromLast(uint32_t src, uint32_t* slot) {
    FieldPrediction fp;
    fp.kind = FieldPrediction::kLast;
    return introduceVertex(src, last_pos_, fp, slot);
  }

  // ---- front faces -----------------------------------------------------------------------------
  // `tet`: the encoder's undecoded tetrahedron behind the face.
  void openFace(const uint32_t v[3], uint32_t d, uint32_t tet, uint32_t cell = kNone32) {
    FrontFace f;
    for (int i = 0; i < 3; ++i) f.v[i] = v[i];
    f.d = d;
    f.cell = cell;
    if (cell != kNone32) ++cell_ref_[cell];
    const uint32_t face = static_cast<uint32_t>(faces_.insert(f));
    if constexpr (kEncode) {
      if (face >= enc_->face_tet.size()) enc_->face_tet.resize(size_t{face} + 1);
      enc_->face_tet[face] = tet;
    }
    for (int i = 0; i < 3; ++i) {
      ++open_[v[i]];
      edges_.put(v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
    }
    if (d != kNoSlot) ++pins_[d];
    QueuedFace q;
    FaceMap::sortedKey(v, q.key);
    queue_.push_back(q);
  }
  // Closes the open face `index`, face k of the tetrahedron e that emitTet emits, which opens its
  // faces j with closes[j] < 0. An edge that such a face puts again, in the same direction, is not
  // erased: the eraseIf would find the new value and do nothing, whether before the put or after.
  // The opened faces run their edges against face k's order in kTetFace (t0, t1, t2): the closed
  // face shares their directions when it is the reverse of that order, and then its edge (t0, t2) is
  // put again by face t1 if opened, and so on.
  void closeFace(long index, int k, const uint32_t e[4], const long closes[4]) {
    const FrontFace f = faces_.at(index);
    faces_.eraseAt(index);
    for (int i = 0; i < 3; ++i) --open_[f.v[i]];
    const int* t = kTetFace[k];
    const uint32_t o0 = e[t[0]], o1 = e[t[1]], o2 = e[t[2]];
    const bool reversed = f.v[0] == o0 ? f.v[1] == o2 : (f.v[1] == o0 ? f.v[2] == o2 : f.v[0] == o2);
    if (reversed) {
      if (closes[t[1]] >= 0) edges_.eraseIf(o0, o2, o1);
      if (closes[t[0]] >= 0) edges_.eraseIf(o2, o1, o0);
      if (closes[t[2]] >= 0) edges_.eraseIf(o1, o0, o2);
    } else {
      edges_.eraseIf(o0, o1, o2);
      edges_.eraseIf(o1, o2, o0);
      edges_.eraseIf(o2, o0, o1);
    }
    if (f.d != kNoSlot) unpin(f.d);
    if (f.cell != kNone32) releaseCell(f.cell);
  }
  void releaseCell(uint32_t r) {
    if (--cell_ref_[r] == 0) cell_free_.push_back(r);
  }

  // ---- boundary surface ------------------------------------------------------------------------
  void openHalf(uint32_t s, uint32_t t, uint32_t r) {
    half_.put(edgeKey(s, t), r);
    nxt_[s] = t;
    prv_[t] = s;
    hqueue_.push_back(edgeKey(s, t));
  }
  void closeHalf(uint32_t s, uint32_t t, uint32_t r) {
    half_.eraseIf(edgeKey(s, t), r);
    if (nxt_[s] == t) nxt_[s] = kNoSlot;
    if (prv_[t] == s) prv_[t] = kNoSlot;
  }

  Status addTriangle(const uint32_t v[3], uint32_t tri) {
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return bad("boundary triangle with a repeated vertex");
    if constexpr (kEncode) {
      enc_->btri_done[tri] = 1;
    } else {
      if (btris_done_ >= header_.boundary_triangles) return bad("more boundary triangles than the header announces");
      const uint32_t ids[3] = {ids_[v[0]], ids_[v[1]], ids_[v[2]]};
      GTN_RETURN_IF_ERROR(sink_->boundaryTriangle(ids));
    }
    ++btris_done_;
    for (int i = 0; i < 3; ++i) {
      corner_sum_[v[i]] += cornerAngle(P(v[i]), P(v[(i + 1) % 3]), P(v[(i + 2) % 3]));
      ++corner_count_[v[i]];
    }
    for (int i = 0; i < 3; ++i) {
      const uint32_t s = v[i], t = v[(i + 1) % 3], r = v[(i + 2) % 3];
      const uint32_t w = half_.find(edgeKey(t, s), kNone32);
      if (w != kNone32) {
        closeHalf(t, s, w);
      } else {
        openHalf(s, t, r);
      }
    }
    const uint32_t inward[3] = {v[0], v[2], v[1]};
    uint32_t key[3];
    FaceMap::sortedKey(inward, key);
    if (faces_.find(key) >= 0) return bad("boundary triangle repeated");
    openFace(inward, kNoSlot, kEncode ? enc_->btris[tri].tet : 0);
    return Status::ok();
  }

  // Vertex of a seed (triangle or tetrahedron): an existing live slot or a new vertex.
  Status codeSeedVertex(Coder& c, uint32_t src, uint32_t* slot) {
    uint32_t existing = 0;
    if constexpr (kEncode) existing = enc_->src_slot[src] != kNoSlot;
    existing = c.bit(seed_existing_, existing);
    if (existing) {
      const uint32_t s = codeSlot(c, kEncode ? enc_->src_slot[src] : 0);
      if (!isLive(s)) return bad("seed refers to a vertex that is not live");
      *slot = s;
      return Status::ok();
    }
    return introduceFromLast(src, slot);
  }

  Status boundaryPhase() {
    while (true) {
      if (hqueue_.empty()) {
        uint32_t more = 0;
        uint32_t tri = 0;
        if constexpr (kEncode) {
          while (enc_->next_seed_tri < enc_->btris.size() && enc_->btri_done[enc_->next_seed_tri]) ++enc_->next_seed_tri;
          more = enc_->next_seed_tri < enc_->btris.size();
          tri = static_cast<uint32_t>(enc_->next_seed_tri);
        }
        more = bnd_->bit(bseed_more_, more);
        if (!more) break;
        uint32_t v[3];
        for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(codeSeedVertex(*bnd_, kEncode ? enc_->btris[tri].v[i] : 0, &v[i]));
        GTN_RETURN_IF_ERROR(addTriangle(v, tri));
        continue;
      }
      if constexpr (!kEncode) {
        if (!bnd_->ok()) return bad("boundary stream is truncated or corrupt");
      }
      const uint64_t hk = hqueue_.front();
      hqueue_.pop_front();
      const uint32_t p = static_cast<uint32_t>(hk >> 32), q = static_cast<uint32_t>(hk);
      const uint32_t w = half_.find(hk, kNone32);
      if (w == kNone32) continue;
      uint32_t has = 0, tri = 0, x_src = 0;
      if constexpr (kEncode) {
        const uint32_t sp = enc_->slot_src[p], sq = enc_->slot_src[q];
        for (size_t i = enc_->edge_start[sq]; i < enc_->edge_start[sq + 1]; ++i) {
          const EncoderSide::DirectedEdge& e = enc_->bedges[i];
          if (e.b == sp && !enc_->btri_done[e.tri]) {
            has = 1;
            tri = e.tri;
            break;
          }
        }
        if (has) {
          const auto& bt = enc_->btris[tri];
          for (int i = 0; i < 3; ++i)
            if (bt.v[i] != sp && bt.v[i] != sq) x_src = bt.v[i];
        }
      }
      has = bnd_->bit(bpartner_, has);
      if (!has) continue;
      // Candidates: walk the open loop forward from q and backward from p.
      uint32_t cands[8];
      int nc = 0;
      auto add = [&](uint32_t s) {
        if (s == kNoSlot || s == p || s == q || !isLive(s)) return;
        for (int i = 0; i < nc; ++i)
          if (cands[i] == s) return;
        cands[nc++] = s;
      };
      uint32_t fwd = nxt_[q], bwd = prv_[p];
      const uint32_t closes = (fwd != kNoSlot && fwd == bwd) ? 1 : 0;
      for (int step = 0; step < 4; ++step) {
        add(fwd);
        add(bwd);
        if (fwd != kNoSlot) fwd = nxt_[fwd];
        if (bwd != kNoSlot) bwd = prv_[bwd];
      }
      // The first two candidates (usually the two ears, prev(p) and next(q)): the ear at the vertex
      // whose triangles so far leave the smaller angle open comes first (it is the likelier to
      // close), then the one nearer the parallelogram prediction. The context: the angle that
      // candidate's triangle would open at its vertex, the angle left open there and whether the
      // vertex has four triangles already.
      uint32_t ear_ctx = (3 * 4 + 3) * 2;  // no ear first
      if (nc > 0) {
        double pr[3];
        for (int i = 0; i < 3; ++i) pr[i] = P(p)[i] + P(q)[i] - P(w)[i];
        auto earOf = [&](uint32_t c) { return c == prv_[p] ? p : (c == nxt_[q] ? q : kNoSlot); };
        if (nc > 1) {
          const uint32_t e0 = earOf(cands[0]), e1 = earOf(cands[1]);
          const double s0 = e0 != kNoSlot ? corner_sum_[e0] : -1.0, s1 = e1 != kNoSlot ? corner_sum_[e1] : -1.0;
          if (s1 > s0 || (!(s1 < s0) && apexDistance(P(cands[1]), pr) < apexDistance(P(cands[0]), pr)))
            std::swap(cands[0], cands[1]);
        }
        const uint32_t e = earOf(cands[0]);
        if (e != kNoSlot) {
          const uint32_t other = e == p ? q : p;
          ear_ctx = (openingClass(P(e), P(other), P(cands[0])) * 4 + roomClass(corner_sum_[e])) * 2 +
                    (corner_count_[e] >= 4 ? 1 : 0);
        }
      }
      uint32_t sym = 0;
      if constexpr (kEncode) {
        sym = candidateSymbol(enc_->src_slot[x_src], cands, nc);
      }
      sym = bsym_[closes * 32 + ear_ctx].code(*bnd_, sym);
      uint32_t x;
      if (sym == kSymNew) {
        double pred[3];
        for (int i = 0; i < 3; ++i) pred[i] = P(p)[i] + P(q)[i] - P(w)[i];
        FieldPrediction fp;
        fp.kind = FieldPrediction::kParallelogram;
        fp.s[0] = p;
        fp.s[1] = q;
        fp.s[2] = w;
        GTN_RETURN_IF_ERROR(introduceVertex(x_src, pred, fp, &x));
      } else if (sym == kSymEscape) {
        x = codeSlot(*bnd_, kEncode ? enc_->src_slot[x_src] : 0);
        if (!isLive(x)) return bad("boundary triangle refers to a vertex that is not live");
      } else {
        if (sym > static_cast<uint32_t>(nc)) return bad("boundary candidate rank out of range");
        x = cands[sym - 1];
      }
      const uint32_t v[3] = {q, p, x};
      GTN_RETURN_IF_ERROR(addTriangle(v, tri));
    }
    // Freed, not just emptied: the decoder's memory should follow the peeling front from here on.
    // The boundary loop and the corner angles are not needed either, nor kept for new slots.
    half_ = EdgeMap();
    hqueue_ = RingQueue<uint64_t>();
    nxt_ = std::vector<uint32_t>();
    prv_ = std::vector<uint32_t>();
    corner_sum_ = std::vector<double>();
    corner_count_ = std::vector<uint32_t>();
    boundary_done_ = true;
    return Status::ok();
  }

  // ---- peeling ---------------------------------------------------------------------------------
  void predictApex(const FrontFace& g, double p[3]) const {
    const double *a = P(g.v[0]), *b = P(g.v[1]), *c = P(g.v[2]);
    double gc[3];
    for (int i = 0; i < 3; ++i) gc[i] = (a[i] + b[i] + c[i]) / 3.0;
    if (g.d != kNoSlot) {
      const double* d = P(g.d);
      for (int i = 0; i < 3; ++i) p[i] = gc[i] + kPredictK * (gc[i] - d[i]);
      return;
    }
    double e1[3], e2[3];
    for (int i = 0; i < 3; ++i) {
      e1[i] = b[i] - a[i];
      e2[i] = c[i] - a[i];
    }
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    auto len = [](const double* u, const double* v) {
      return std::sqrt((u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]) + (u[2] - v[2]) * (u[2] - v[2]));
    };
    const double edge = (len(a, b) + len(b, c) + len(c, a)) / 3.0;
    const double scale = nl > 0 && std::isfinite(nl) ? 0.8 * edge / nl : 0.0;
    for (int i = 0; i < 3; ++i) p[i] = gc[i] + n[i] * scale;
  }

  struct Candidate {
    uint32_t s;
    uint32_t w;
    double dist;  // squared distance to the predicted apex
    double key;   // sort key: Delaunay sweep parameter, else dist
  };

  // Front vertices around the gate face, with the coding context. `side`: the orientation filter of
  // the gate face (a, b, c). The candidates are only gathered here, with their multiplicities; both
  // orders rank by multiplicity first, so a group of equal multiplicity is filtered and keyed only
  // when a rank, the context or a new vertex's list reaches it (evaluateGroups): usually only the
  // first group is. The result is the same as keying every candidate.
  void gatherCandidates(const FrontFace& g, const Orient3dFilter& side, const double p[3], uint32_t* ctx) {
    RawCandidate* c = raw_;
    int n = 0;
    uint32_t across[3] = {kNone32, kNone32, kNone32};  // the apex of the front face across each gate edge (c, a), (a, b), (b, c)
    if (++gather_epoch_ == kGatherEpochs) {
      std::fill(gather_mark_.begin(), gather_mark_.end(), 0);
      gather_epoch_ = 1;
    }
    const uint32_t tag = gather_epoch_ << kGatherIndexBits;
    for (uint32_t s : g.v) gather_mark_[s] = tag | kGateMark;
    auto add = [&](uint32_t s) {
      const uint32_t m = gather_mark_[s];
      if ((m & ~kGateMark) == tag) {
        if (m != (tag | kGateMark)) ++c[m & kGateMark].w;
        return;
      }
      if (n < kMaxGather) {
        gather_mark_[s] = tag | static_cast<uint32_t>(n);
        c[n++] = {s, 1};
      }
    };
    for (int j = 0; j < 3; ++j) {
      const uint32_t a = g.v[j], b = g.v[(j + 1) % 3], cc = g.v[(j + 2) % 3];
      // Forward around a: across edge (c, a), then on.
      const EdgeMap::From around = edges_.from(a);
      uint32_t v = cc;
      bool closed = false;
      for (int step = 0; step < kFanSteps; ++step) {
        const uint32_t w = around.find(v, kNone32);
        if (step == 0) across[j] = w;
        if (w == kNone32) break;
        if (w == b) {
          closed = true;
          break;
        }
        add(w);
        v = w;
      }
      if (closed) continue;
      v = b;
      for (int step = 0; step < kFanSteps; ++step) {
        const uint32_t w = edges_.find(edgeKey(v, a), kNone32);
        if (w == kNone32 || w == cc) break;
        add(w);
        v = w;
      }
    }
    raw_n_ = n;
    cand_n_ = 0;
    first_ = -1;
    gate_ = &g;
    side_ = &side;
    pred_ = p;
    // The apex lies on the far side of the gate face from the decoded tetrahedron (a, b, c, d),
    // whatever the mesh's orientation convention; behind a boundary face, on the side where the
    // apexes decoded so far mostly lay. Candidates on the other side are dropped (the escape still
    // reaches them). Only signs a floating-point filter proves count (near-flat cases drop nothing):
    // exact arithmetic would cost more than it saves, and the filter is reproducible everywhere.
    wrong_ = g.d != kNoSlot ? side.sign(P(g.d)) : (apex_votes_ > 0 ? -1 : (apex_votes_ < 0 ? 1 : 0));
    // Delaunay order: the spheres through a, b and c, swept into the undecoded side, meet the
    // apex of a Delaunay tetrahedron first. key = the sweep parameter at which a candidate is met.
    delaunay_ = wrong_ != 0;
    swept_ready_ = false;
    // Two orders compete: by distance to the predicted apex (right on structured grids) and by the
    // Delaunay sweep (right on Delaunay meshes). The one that has ranked the true apexes better so
    // far is used; both sides keep the same score. Both orders are total (slots differ), so a
    // candidate's place is the number of candidates before it: nothing is sorted unless the whole
    // list is needed (a new vertex's copy sources), and the list's prefix is the same either way.
    by_key_chosen_ = delaunay_ && order_score_ > 0;
    // Ranking by key first needs every candidate keyed.
    if (by_key_chosen_ && delaunay_first_) evaluateAllGroups();
    // The context: the best multiplicity, how many share it (up to 3), how close the nearest of
    // those lies to the predicted apex, and across how many gate edges (up to 2) the front face's
    // apex is the first candidate (then the tetrahedron closes that face).
    evaluateGroups(1);
    uint32_t k = 0;
    uint32_t near = 2;
    uint32_t adjacent = 0;
    if (cand_n_ > 0) {
      // Over the best multiplicity's group: the only one evaluated so far, unless the Delaunay order
      // is chosen.
      uint32_t best_w = 0, top = 0;
      double best_dist = 0;
      for (int i = 0; i < cand_n_; ++i) best_w = std::max(best_w, cand_[i].w);
      for (int i = 0; i < cand_n_; ++i) {
        if (cand_[i].w != best_w) continue;
        best_dist = top == 0 ? cand_[i].dist : std::min(best_dist, cand_[i].dist);
        ++top;
      }
      k = 1 + (std::min<uint32_t>(best_w, 3) - 1) * 3 + std::min<uint32_t>(top, 3) - 1;
      const double *a = P(g.v[0]), *b = P(g.v[1]), *cc = P(g.v[2]);
      double e2 = 0;
      for (int i = 0; i < 3; ++i)
        e2 += (a[i] - b[i]) * (a[i] - b[i]) + (b[i] - cc[i]) * (b[i] - cc[i]) + (cc[i] - a[i]) * (cc[i] - a[i]);
      e2 /= 3.0;
      near = best_dist < 0.25 * e2 ? 0 : (best_dist < e2 ? 1 : 2);
      const uint32_t first = candidateAt(0);
      for (int j = 0; j < 3; ++j) adjacent += across[j] == first ? 1 : 0;
    }
    *ctx = (k * 3 + near) * 3 + std::min<uint32_t>(adjacent, 2);
  }

  // Moves whole groups of equal multiplicity, best first, from raw_ to cand_ (dropping those on the
  // wrong side, keying the rest) until cand_ holds at least `want` candidates or raw_ is empty.
  void evaluateGroups(int want) {
    while (cand_n_ < want && raw_n_ > 0) {
      uint32_t w = 0;
      for (int i = 0; i < raw_n_; ++i) w = std::max(w, raw_[i].w);
      for (int i = 0; i < raw_n_;) {
        if (raw_[i].w != w) {
          ++i;
          continue;
        }
        const uint32_t s = raw_[i].s;
        raw_[i] = raw_[--raw_n_];
        evaluate(s, w);
      }
    }
  }
  // The same for every group at once (ranking by key first needs every candidate keyed).
  void evaluateAllGroups() {
    for (int i = 0; i < raw_n_; ++i) evaluate(raw_[i].s, raw_[i].w);
    raw_n_ = 0;
  }
  // Drops candidate s if it is on the wrong side, else keys it into cand_.
  void evaluate(uint32_t s, uint32_t w) {
    const double* q = P(s);
    if (wrong_ != 0 && side_->sign(q) == wrong_) return;
    Candidate& x = cand_[cand_n_++];
    x.s = s;
    x.w = w;
    // Sort keys must be ordered values: overflowing coordinates (NaN or infinite distances) sort
    // last, so that the comparison stays a strict weak order.
    x.dist = apexDistance(q, pred_);
    x.key = x.dist;
    if (delaunay_) {
      if (!swept_ready_) prepareSweep();
      x.key = sweepKey(q);
    }
  }
  // The Delaunay order's key of q (prepareSweep first): the sweep parameter at which q is met, in
  // units of 1/64 of the face's circumradius, so that nearly cospherical candidates (every cell of
  // a structured grid) tie and fall back to the distance order.
  double sweepKey(const double* q) const {
    const double e[3] = {q[0] - cc0_[0], q[1] - cc0_[1], q[2] - cc0_[2]};
    const double h = nn_[0] * e[0] + nn_[1] * e[1] + nn_[2] * e[2];
    const double t = h > 0 ? (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] - r2_) / (2 * h) : 1e300;
    const double y = t * key_scale_;
    return y < 1e18 ? floorKey(y) : 1e18;  // NaN too
  }
  // The circumcentre and radius of the gate face and its normal into the undecoded side.
  void prepareSweep() {
    const FrontFace& g = *gate_;
    const double *a = P(g.v[0]), *b = P(g.v[1]), *c3 = P(g.v[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c3[0] - a[0], c3[1] - a[1], c3[2] - a[2]};
    const double N[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    const double NN = N[0] * N[0] + N[1] * N[1] + N[2] * N[2];
    const double w[3] = {uu * v[0] - vv * u[0], uu * v[1] - vv * u[1], uu * v[2] - vv * u[2]};
    const double wx[3] = {w[1] * N[2] - w[2] * N[1], w[2] * N[0] - w[0] * N[2], w[0] * N[1] - w[1] * N[0]};
    r2_ = 0;
    for (int i = 0; i < 3; ++i) {
      cc0_[i] = NN > 0 ? a[i] + wx[i] / (2 * NN) : a[i];
      nn_[i] = -wrong_ * N[i];
      r2_ += (cc0_[i] - a[i]) * (cc0_[i] - a[i]);
    }
    const double nl = std::sqrt(NN);
    key_scale_ = r2_ > 0 && nl > 0 ? 64.0 * nl / std::sqrt(r2_) : 0.0;
    swept_ready_ = true;
  }

  static bool beforeByDistance(const Candidate& x, const Candidate& y) {
    if (x.w != y.w) return x.w > y.w;
    if (x.dist != y.dist) return x.dist < y.dist;
    return x.s < y.s;
  }
  // The Delaunay order: by key, then count, in a level that sets "Delaunay first"; by count, then
  // key, in others.
  static bool beforeByKey(const Candidate& x, const Candidate& y, bool key_first) {
    if (key_first && x.key != y.key) return x.key < y.key;
    if (x.w != y.w) return x.w > y.w;
    if (x.key != y.key) return x.key < y.key;
    if (x.dist != y.dist) return x.dist < y.dist;
    return x.s < y.s;
  }
  // The two orders as function objects, so that the sorts inline them.
  struct ByDistance {
    bool operator()(const Candidate& x, const Candidate& y) const { return beforeByDistance(x, y); }
  };
  struct ByKey {
    bool key_first;
    bool operator()(const Candidate& x, const Candidate& y) const { return beforeByKey(x, y, key_first); }
  };
  // Place of the candidate at index i in one order (0 = first).
  int placeOf(int i, bool by_key) const {
    int place = 0;
    const Candidate& x = cand_[i];
    if (by_key) {
      for (int j = 0; j < cand_n_; ++j) place += beforeByKey(cand_[j], x, delaunay_first_);
    } else {
      for (int j = 0; j < cand_n_; ++j) place += beforeByDistance(cand_[j], x);
    }
    return place;
  }
  // Index of `slot` in cand_, evaluating groups until it is there; -1 if it is no candidate (or was
  // dropped).
  int candidateIndex(uint32_t slot) {
    for (;;) {
      for (int i = 0; i < cand_n_; ++i)
        if (cand_[i].s == slot) return i;
      bool pending = false;
      for (int i = 0; i < raw_n_; ++i) pending |= raw_[i].s == slot;
      if (!pending) return -1;
      evaluateGroups(cand_n_ + 1);
    }
  }
  // The coded symbol of `slot` (kNoSlot: a new vertex): new, 1 + its place in the chosen order among
  // the first kMaxCandidates, or escape.
  uint32_t candidateSymbolOf(uint32_t slot) {
    if (slot == kNoSlot) return kSymNew;
    const int i = candidateIndex(slot);
    if (i < 0) return kSymEscape;
    const int place = placeOf(i, by_key_chosen_);
    return place < kMaxCandidates ? static_cast<uint32_t>(place + 1) : kSymEscape;
  }
  // The slot at `place` of the chosen order, kNoSlot if there are not that many candidates.
  uint32_t candidateAt(int place) {
    evaluateGroups(place + 1);
    if (place >= cand_n_) return kNoSlot;
    if (place == 0) return cand_[firstIndex()].s;
    return by_key_chosen_ ? candidateAt(place, ByKey{delaunay_first_}) : candidateAt(place, ByDistance());
  }
  // Index in cand_ of the first candidate of the chosen order (cand_ not empty), found once per
  // gate: the groups evaluated later have smaller multiplicities and come after it in both orders.
  int firstIndex() {
    if (first_ < 0) first_ = by_key_chosen_ ? firstIndex(ByKey{delaunay_first_}) : firstIndex(ByDistance());
    return first_;
  }
  template <class Before>
  int firstIndex(Before before) const {
    int best = 0;
    for (int i = 1; i < cand_n_; ++i)
      if (before(cand_[i], cand_[best])) best = i;
    return best;
  }
  template <class Before>
  uint32_t candidateAt(int place, Before before) const {
    Candidate tmp[kMaxGather];
    std::copy(cand_, cand_ + cand_n_, tmp);
    std::nth_element(tmp, tmp + place, tmp + cand_n_, before);
    return tmp[place].s;
  }
  // The first kMaxCandidates candidates in the chosen order; returns their count.
  int orderedCandidates(uint32_t* out) {
    evaluateAllGroups();
    if (by_key_chosen_) return orderedCandidates(out, ByKey{delaunay_first_});
    return orderedCandidates(out, ByDistance());
  }
  template <class Before>
  int orderedCandidates(uint32_t* out, Before before) const {
    Candidate tmp[kMaxGather];
    std::copy(cand_, cand_ + cand_n_, tmp);
    std::sort(tmp, tmp + cand_n_, before);
    const int m = std::min(cand_n_, kMaxCandidates);
    for (int i = 0; i < m; ++i) out[i] = tmp[i].s;
    return m;
  }
  // After a tetrahedron's apex x is known: the order that placed it earlier (among the first
  // kMaxCandidates; later or absent counts as kMaxCandidates) scores a point. Without the Delaunay
  // order (no side to sweep into) both orders are the same.
  void scoreOrders(uint32_t x) {
    if (!delaunay_) return;
    // The usual apex is the first candidate, whose place in the chosen order is 0.
    const bool first = first_ >= 0 && cand_[first_].s == x;
    const int i = first ? first_ : candidateIndex(x);
    if (i < 0) return;
    const int rk = first && by_key_chosen_ ? 0 : std::min(placeOf(i, true), kMaxCandidates);
    const int rd = first && !by_key_chosen_ ? 0 : std::min(placeOf(i, false), kMaxCandidates);
    if (rk < rd && order_score_ < kOrderScoreLimit) ++order_score_;
    if (rd < rk && order_score_ > -kOrderScoreLimit) --order_score_;
  }

  // `pred_cell`: the cell-value record of the decoded neighbour behind the gate face, or kNone32.
  // `gate`: the index in faces_ of the open face (e[0], e[2], e[1]) (face 3), or -1 to look it up;
  // `fresh_apex`: e[3] was just introduced, so no open face holds it.
  Status emitTet(const uint32_t e[4], uint32_t src_tet, uint32_t pred_cell, long gate = -1, bool fresh_apex = false) {
    if (e[0] == e[1] || e[0] == e[2] || e[0] == e[3] || e[1] == e[2] || e[1] == e[3] || e[2] == e[3])
      return bad("tetrahedron with a repeated vertex");
    if constexpr (!kEncode) {
      if (tets_done_ >= header_.tets) return bad("more tetrahedra than the header announces");
    }
    // The open faces the tetrahedron closes, -1 for those it opens: the answers faces_.find gives,
    // where the caller does not know them already. Nothing below changes them before the faces are
    // closed (pool indices stay valid until their face is erased, and the faces differ).
    long closes[4];
    for (int k = 0; k < 4; ++k) {
      closes[k] = -1;
      if (k == 3 && gate >= 0) {
        closes[k] = gate;
      } else if (k == 3 || !fresh_apex) {
        const uint32_t f[3] = {e[kTetFace[k][0]], e[kTetFace[k][1]], e[kTetFace[k][2]]};
        uint32_t key[3];
        FaceMap::sortedKey(f, key);
        closes[k] = faces_.find(key);
      }
    }
    // Cell values: per field, a symbol says "as the neighbour behind the gate face" (else the
    // previous tetrahedron), "as the i-th other decoded neighbour", "as the i-th most recent
    // distinct value", or "coded as a residual". The other neighbours are those across the faces it
    // closes besides the gate: importers give every tetrahedron of a split hexahedron, wedge or
    // pyramid its cell's value, and those siblings are seldom behind the gate face.
    size_t j = 0;
    for (size_t f = 0; f < header_.cell_fields.size(); ++f) {
      const FieldDesc& d = header_.cell_fields[f];
      const size_t vs = scalarSize(d.type);
      const uint32_t nc = d.components;
      if (cf_skip_[f]) {
        j += nc;
        continue;
      }
      if (cf_packed_[f]) {
        // Packed form: the item as stored.
        const uint8_t* item = nullptr;
        if constexpr (kEncode) {
          item = enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes();
        } else {
          item = cf_readers_[f]->next();
          if (!item) return bad(cf_readers_[f]->error());
        }
        for (uint32_t c = 0; c < nc; ++c) {
          cell_keys_[j + c] = last_cell_keys_[f][c] = keyFromRaw(d.type, item + c * vs);
        }
        std::memcpy(&cell_buf_[cf_offset_[f]], item, d.itemBytes());
        j += nc;
        continue;
      }
      uint64_t* pred = &cell_pred_[0];
      uint64_t* act = &cell_act_[0];
      for (uint32_t c = 0; c < nc; ++c) {
        pred[c] = pred_cell != kNone32 ? cell_rec_[pred_cell * cell_comps_ + j + c] : last_cell_keys_[f][c];
        if constexpr (kEncode)
          act[c] = keyFromRaw(d.type, enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes() + c * vs);
      }
      // The distinct values, other than P, of the neighbours across faces 0, 1 and 2, in that order.
      const uint64_t* nbr[3];
      uint32_t n_nbr = 0;
      for (int k = 0; k < 3; ++k) {
        if (closes[k] < 0) continue;
        const uint32_t r = faces_.at(closes[k]).cell;
        if (r == kNone32) continue;
        const uint64_t* v = &cell_rec_[size_t{r} * cell_comps_ + j];
        bool seen = sameKeys(v, pred, nc);
        for (uint32_t i = 0; i < n_nbr && !seen; ++i) seen = sameKeys(v, nbr[i], nc);
        if (!seen) nbr[n_nbr++] = v;
      }
      std::vector<std::vector<uint64_t>>& mtf = cell_mtf_[f];
      BitTree<4>& tree = cell_sym_[f][cell_last_sym_[f] * 3 + std::min<uint32_t>(n_nbr, 2)];
      uint32_t sym = kSymEscape;
      if constexpr (kEncode) {
        // P when it is right; else a neighbour's or a recent value, whichever the model makes
        // cheaper now (the neighbour on a tie; std::min takes the one found, the escape being the
        // largest symbol); else the escape. Neither fixed order does as well: neighbours first cost
        // the cornell box's face markers 5% more (they equal a neighbour's by coincidence), recent
        // values first AngularSector's cell ids 24% more.
        uint32_t by_nbr = kSymEscape, by_mtf = kSymEscape;
        for (uint32_t i = 0; i < n_nbr && by_nbr == kSymEscape; ++i)
          if (sameKeys(act, nbr[i], nc)) by_nbr = kSymCellNeighbour + i;
        for (size_t i = 0; i < mtf.size() && by_mtf == kSymEscape; ++i)
          if (sameKeys(act, mtf[i].data(), nc)) by_mtf = static_cast<uint32_t>(i + 1);
        if (sameKeys(act, pred, nc)) {
          sym = 0;
        } else if (by_nbr != kSymEscape && by_mtf != kSymEscape) {
          const SymbolCosts<4> cost = symbolCosts(tree);
          sym = cost[by_mtf] < cost[by_nbr] ? by_mtf : by_nbr;
        } else {
          sym = std::min(by_nbr, by_mtf);
        }
      }
      sym = tree.code(*cf_[f], sym);
      cell_last_sym_[f] = std::min<uint32_t>(sym, 2);
      uint64_t* keys = &cell_keys_[j];
      if (sym == 0) {
        std::copy(pred, pred + nc, keys);
      } else if (sym == kSymEscape && cf_split_[f]) {
        // Split form: the escaped values are the packed part's next item.
        const uint8_t* item = nullptr;
        if constexpr (kEncode) {
          item = enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes();
          (*cf_escaped_)[f].insert((*cf_escaped_)[f].end(), item, item + d.itemBytes());
        } else {
          item = cf_readers_[f]->next();
          if (!item) return bad(cf_readers_[f]->error());
        }
        for (uint32_t c = 0; c < nc; ++c) keys[c] = keyFromRaw(d.type, item + c * vs);
      } else if (sym == kSymEscape) {
        for (uint32_t c = 0; c < nc; ++c) keys[c] = cf_vc_[f].code(*cf_[f], c, pred[c], act[c]);
      } else if (sym >= kSymCellNeighbour) {
        if (sym - kSymCellNeighbour >= n_nbr) return bad("cell value refers to a neighbour that does not exist");
        std::copy(nbr[sym - kSymCellNeighbour], nbr[sym - kSymCellNeighbour] + nc, keys);
      } else {
        if (sym > mtf.size()) return bad("cell value refers to an unknown recent value");
        std::copy(mtf[sym - 1].begin(), mtf[sym - 1].end(), keys);
      }
      // Move to front.
      size_t at = mtf.size();
      for (size_t i = 0; i < mtf.size(); ++i)
        if (sameKeys(keys, mtf[i].data(), nc)) at = i;
      if (at == mtf.size()) {
        if (mtf.size() < kRecentCellValues) {
          mtf.emplace_back(nc);
        }
        at = mtf.size() - 1;
      }
      for (size_t i = at; i > 0; --i) mtf[i].swap(mtf[i - 1]);
      std::copy(keys, keys + nc, mtf[0].begin());
      for (uint32_t c = 0; c < nc; ++c) {
        last_cell_keys_[f][c] = keys[c];
        rawFromKey(d.type, keys[c], &cell_buf_[cf_offset_[f] + c * vs]);
      }
      j += nc;
    }
    if constexpr (kEncode) {
      enc_->tet_order[src_tet] = tets_done_;
      enc_->tet_done[src_tet] = 1;
      for (uint32_t v : enc_->mesh->tets[src_tet]) --enc_->remaining[v];
    } else {
      const uint32_t ids[4] = {ids_[e[0]], ids_[e[1]], ids_[e[2]], ids_[e[3]]};
      GTN_RETURN_IF_ERROR(sink_->tet(ids, cell_bytes_ ? cell_buf_.data() : nullptr));
    }
    ++tets_done_;
    if (edge_points_) GTN_RETURN_IF_ERROR(codeEdgePoints(e, gate, fresh_apex));
    uint32_t rec = kNone32;
    if (cell_comps_ > 0) {
      if (!cell_free_.empty()) {
        rec = cell_free_.back();
        cell_free_.pop_back();
      } else {
        rec = static_cast<uint32_t>(cell_ref_.size());
        cell_ref_.push_back(0);
        cell_rec_.resize(cell_rec_.size() + cell_comps_);
      }
      cell_ref_[rec] = 1;  // held until the faces are opened
      std::copy(cell_keys_.begin(), cell_keys_.end(), cell_rec_.begin() + size_t{rec} * cell_comps_);
    }
    for (int k = 0; k < 4; ++k) {
      if (closes[k] >= 0) {
        closeFace(closes[k], k, e, closes);
        continue;
      }
      const uint32_t f[3] = {e[kTetFace[k][0]], e[kTetFace[k][1]], e[kTetFace[k][2]]};
      uint32_t nb = 0;
      if constexpr (kEncode) {
        const uint32_t sv = enc_->slot_src[e[k]];
        const Tet& t = enc_->mesh->tets[src_tet];
        int j = 0;
        while (j < 4 && t[j] != sv) ++j;
        if (j == 4) return internal("tetrahedron vertex lost");
        nb = (*enc_->neighbor)[4 * size_t{src_tet} + j];
        if (nb == kNoNeighbor || nb == kNonManifold || enc_->tet_done[nb]) return internal("front face without a tetrahedron behind it");
      }
      openFace(f, e[k], nb, rec);
    }
    if (rec != kNone32) releaseCell(rec);
    for (int k = 0; k < 4; ++k) {
      const uint32_t s = e[k];
      if (open_[s] != 0 || state_[s] != kLive) continue;
      uint32_t done = 0;
      if constexpr (kEncode) done = enc_->remaining[enc_->slot_src[s]] == 0;
      done = con_->bit(retire_, done);
      if (done) GTN_RETURN_IF_ERROR(retire(s));
    }
    return Status::ok();
  }

  // The points on the edges of the tetrahedron (e, closing `gate`, -1 for a seed) that are coded now,
  // while both ends are live (section 10.5): per edge, a bit per point and a final clear bit. An
  // edge's points are coded with the first tetrahedron that has the edge, so the edges of a gate face
  // rarely have any left (only behind a boundary face), and those to a new apex always do on a
  // quadratic mesh: the bits' contexts tell these apart.
  Status codeEdgePoints(const uint32_t e[4], long gate, bool fresh_apex) {
    const bool boundary_gate = gate >= 0 && faces_.at(gate).d == kNoSlot;
    for (int k = 0; k < 6; ++k) {
      const uint32_t a = e[kTetEdge[k][0]], b = e[kTetEdge[k][1]];
      const uint32_t kind = gate < 0 || (k >= 3 && fresh_apex) ? 0 : (k >= 3 ? 1 : (boundary_gate ? 2 : 3));
      EdgePoint *next = nullptr, *end = nullptr;  // the encoder's entries of the edge
      uint32_t hi = 0;
      if constexpr (kEncode) {
        const uint32_t sa = enc_->slot_src[a], sb = enc_->slot_src[b], lo = std::min(sa, sb);
        hi = std::max(sa, sb);
        next = enc_->edge_points.data() + enc_->edge_point_start[lo];
        end = enc_->edge_points.data() + enc_->edge_point_start[lo + 1];
        while (next != end && next->b < hi) ++next;
      }
      for (uint32_t more = 0;; more = 1) {
        uint32_t bit = 0;
        if constexpr (kEncode) bit = next != end && next->b == hi && next->point != kNone32;
        bit = geo_->bit(edge_point_[kind][more], bit);
        if (!bit) break;
        if constexpr (!kEncode) {
          if (!geo_->ok()) return bad("geometry stream is truncated or corrupt");
        }
        uint32_t src = 0;
        if constexpr (kEncode) {
          src = next->point;
          next->point = kNone32;
          ++next;
        }
        FieldPrediction fp;
        fp.kind = FieldPrediction::kEdge;
        fp.s[0] = a;
        fp.s[1] = b;
        const double *pa = P(a), *pb = P(b);
        const double mid[3] = {(pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5, (pa[2] + pb[2]) * 0.5};
        uint32_t s;
        GTN_RETURN_IF_ERROR(introduceVertex(src, mid, fp, &s));
        GTN_RETURN_IF_ERROR(retire(s));
      }
    }
    return Status::ok();
  }

  Status seedTet() {
    uint32_t src_tet = 0;
    Tet src{};
    if constexpr (kEncode) {
      src_tet = static_cast<uint32_t>(enc_->next_seed_tet);
      src = enc_->mesh->tets[src_tet];
    }
    uint32_t e[4];
    for (int i = 0; i < 4; ++i) GTN_RETURN_IF_ERROR(codeSeedVertex(*con_, src[i], &e[i]));
    return emitTet(e, src_tet, kNone32);
  }

  // Starts loading the front data of the likely next gate face while this one is coded.
  void prefetchGate(const uint32_t key[3]) const {
    faces_.prefetch(key);
    for (int i = 0; i < 3; ++i) {
      edges_.prefetch(key[i]);
      if (key[i] < state_.size()) __builtin_prefetch(P(key[i]));
    }
  }

  // The dot products of u = a - o and v = b - o (sums over the axes in order): u.u, v.v, u.v.
  struct CornerDots {
    double uu, vv, uv;
  };
  static CornerDots cornerDots(const double* o, const double* a, const double* b) {
    const double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]}, v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
    return {u[0] * u[0] + u[1] * u[1] + u[2] * u[2], v[0] * v[0] + v[1] * v[1] + v[2] * v[2],
            u[0] * v[0] + u[1] * v[1] + u[2] * v[2]};
  }
  // The angle at o of the triangle (o, a, b) in radians, from the polynomial arccosine of
  // Abramowitz and Stegun 4.4.45 (error below 1e-4): basic operations only, so that every platform
  // gets the same bits. 0 for a degenerate or non-finite corner (section 10.3).
  static double cornerAngle(const double* o, const double* a, const double* b) {
    const CornerDots c = cornerDots(o, a, b);
    const double n = std::sqrt(c.uu * c.vv);
    if (!(n > 0 && n <= kMaxKey)) return 0.0;
    double x = c.uv / n;
    const bool obtuse = x < 0;
    if (obtuse) x = -x;
    if (x > 1) x = 1;
    const double acute = std::sqrt(1 - x) * (1.5707288 + x * (-0.2121144 + x * (0.0742610 + x * -0.0187293)));
    return obtuse ? 3.141592653589793 - acute : acute;
  }
  // The angle at o between a and b: 0 below 60 degrees, 1 below 90, 2 otherwise, 3 degenerate.
  static uint32_t openingClass(const double* o, const double* a, const double* b) {
    const CornerDots c = cornerDots(o, a, b);
    if (!(c.uu > 0 && c.vv > 0)) return 3;
    if (!(c.uv > 0)) return 2;
    return 4 * c.uv * c.uv > c.uu * c.vv ? 0 : 1;
  }
  // The angle left open around a vertex whose corner angles sum to `sum`: 0 below 70 degrees
  // (1.2217304763960306 radians), 1 below 130 (2.2689280275926285), 2 otherwise.
  static uint32_t roomClass(double sum) {
    const double room = 6.283185307179586 - sum;
    return room < 1.2217304763960306 ? 0 : (room < 2.2689280275926285 ? 1 : 2);
  }

  // Squared distance from q to a predicted position p (apex or parallelogram), a NaN or overflow
  // counting as the largest finite double (sections 10.3 and 10.4).
  static double apexDistance(const double* q, const double p[3]) {
    const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
    const double d = dx * dx + dy * dy + dz * dz;
    return d <= kMaxKey ? d : kMaxKey;
  }

  // An apex outside the candidate list: its rank among the live vertices not on the wrong side of
  // the gate face, or its slot. The rank is by sweep key (then distance to the predicted apex) in a
  // "Delaunay first" level while the Delaunay order is in use, else by distance: the apex of a
  // Delaunay tetrahedron is the first vertex the sweep meets, whichever fan it lies on, and in a
  // thin shell the apex lies across the shell, near the prediction but far along the front. A rank
  // may cost a scan of every live vertex, so it is allowed only while the live counts of the ranked
  // escapes so far stay within kEscapeScanBudget per tetrahedron and boundary triangle decoded so
  // far: the decoder's work stays linear in what it outputs, whatever the stream (or the header's
  // counts) says.
  Status codeEscape(const FrontFace& g, const Orient3dFilter& side, const double p[3], uint32_t xs, uint32_t* x) {
    const bool allowed = escape_scan_ + live_ <= kEscapeScanBudget * (tets_done_ + btris_done_ + 1);
    uint32_t by_rank = 0;
    uint64_t rank = 0;
    auto eligible = [&](uint32_t t) {
      return state_[t] == kLive && t != g.v[0] && t != g.v[1] && t != g.v[2] && !(wrong_ != 0 && side.sign(P(t)) == wrong_);
    };
    auto dist = [&](uint32_t t) { return apexDistance(P(t), p); };
    auto all = [&](auto fn) {
      for (uint32_t t = 0; t < state_.size(); ++t)
        if (state_[t] == kLive) fn(t);
    };
    const bool by_key = by_key_chosen_ && delaunay_first_;
    if (by_key && !swept_ready_) prepareSweep();
    const bool swept = by_key && key_scale_ > 0 && std::isfinite(key_scale_) &&
                       std::isfinite(r2_) && std::isfinite(cc0_[0]) && std::isfinite(cc0_[1]) && std::isfinite(cc0_[2]);
    auto key = [&](uint32_t t) { return NearestGrid::Key{sweepKey(P(t)), apexDistance(P(t), p)}; };
    // Every vertex with a key below the bound lies within sqrt(safe2) of the circumcentre C: one
    // at sweep parameter tau (a length along the normal) lies in the sphere of centre C + tau n
    // through a, b and c, so within |tau| + sqrt(R^2 + tau^2) of C when tau >= 0, and within R of C
    // when tau < 0. Margins keep rounding on the safe side.
    auto bound = [&](double safe2) {
      const double s = std::sqrt(safe2) * (1 - 1e-9), r = std::sqrt(r2_);
      if (!(s > r * (1 + 1e-6))) return -std::numeric_limits<double>::infinity();
      const double tau = (s - r) * (s + r) / (2 * s) - 1e-9 * (s + r);
      const double y = 64.0 * tau / r;
      return y < 1e18 ? floorKey(y) - 1 : 1e18;
    };
    if (allowed && !grid_.built()) buildGrid();
    if constexpr (kEncode) {
      if (allowed && isLive(xs) && eligible(xs)) {
        rank = swept ? grid_.rankOfBy(cc0_, key(xs), xs, key, bound, eligible, all)
                     : grid_.rankOf(p, dist(xs), xs, dist, eligible, all);
        by_rank = rank < (uint64_t{1} << kEscapeRankBits);
      }
    }
    if (allowed) by_rank = con_->bit(esc_by_rank_, by_rank);
    if (!by_rank) {
      *x = codeSlot(*con_, xs);
      if (!isLive(*x)) return bad("tetrahedron refers to a vertex that is not live");
      return Status::ok();
    }
    escape_scan_ += live_;
    // Rank: its bit length b (BitTree<4>), then the b - 1 bits below the leading one.
    const uint32_t b = esc_bits_.code(*con_, kEncode ? static_cast<uint32_t>(bitLength(rank)) : 0);
    if (b > kEscapeRankBits) return bad("escape rank out of range");
    if (b > 1) rank = (uint64_t{1} << (b - 1)) | con_->direct(kEncode ? static_cast<uint32_t>(rank) & ((1u << (b - 1)) - 1) : 0, static_cast<int>(b) - 1);
    else rank = b;
    if constexpr (kEncode) {
      *x = xs;
      return Status::ok();
    }
    // The rank-th eligible live vertex in that order.
    *x = swept ? grid_.kthBy(cc0_, rank, key, bound, eligible, all) : grid_.kth(p, rank, dist, eligible, all);
    if (*x == NearestGrid::kNone) return bad("escape rank beyond the live vertices");
    return Status::ok();
  }

  // The rank queries' grid over the live vertices, built at the first ranked escape and kept up
  // to date from then on (it changes no answer, only how soon it is found).
  void buildGrid() {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t t = 0; t < state_.size(); ++t) {
      if (state_[t] != kLive) continue;
      for (int i = 0; i < 3; ++i) {
        const double v = P(t)[i];
        if (!std::isfinite(v)) continue;
        lo[i] = std::min(lo[i], v);
        hi[i] = std::max(hi[i], v);
      }
    }
    grid_.build(lo, hi, live_);
    grid_.reserveSlots(state_.capacity());
    for (uint32_t t = 0; t < state_.size(); ++t)
      if (state_[t] == kLive) grid_.insert(t, P(t));
  }

  Status peelingPhase() {
    while (true) {
      long idx = -1;
      while (!queue_.empty()) {
        const QueuedFace q = queue_.front();
        queue_.pop_front();
        // The face opened with this entry, or else one opened later on the same vertices.
        idx = faces_.find(q.key);
        if (idx >= 0) break;
      }
      if (!queue_.empty()) prefetchGate(queue_.front().key);
      if constexpr (!kEncode) {
        if (!con_->ok()) return bad("connectivity stream is truncated or corrupt");
        if (!geo_->ok()) return bad("geometry stream is truncated or corrupt");
      }
      if (idx < 0) {
        uint32_t more = 0;
        if constexpr (kEncode) {
          while (enc_->next_seed_tet < enc_->tet_done.size() && enc_->tet_done[enc_->next_seed_tet]) ++enc_->next_seed_tet;
          more = enc_->next_seed_tet < enc_->tet_done.size();
        }
        more = con_->bit(seed_more_, more);
        if (!more) break;
        GTN_RETURN_IF_ERROR(seedTet());
        continue;
      }
      const FrontFace g = faces_.at(idx);
      double p[3];
      predictApex(g, p);
      uint32_t ctx = 0;
      const Orient3dFilter side(P(g.v[0]), P(g.v[1]), P(g.v[2]));
      gatherCandidates(g, side, p, &ctx);
      uint32_t sym = 0, x_src = 0, flip = 0;
      if constexpr (kEncode) {
        const Tet& t = enc_->mesh->tets[enc_->face_tet[idx]];
        const uint32_t ga = enc_->slot_src[g.v[0]], gb = enc_->slot_src[g.v[1]], gcv = enc_->slot_src[g.v[2]];
        int xi = -1;
        for (int i = 0; i < 4; ++i)
          if (t[i] != ga && t[i] != gb && t[i] != gcv) xi = i;
        if (xi < 0) return internal("gate face does not belong to its tetrahedron");
        x_src = t[xi];
        enc_->prefetchCoding(enc_->face_tet[idx], t, x_src);
        // Parity of (a, b, c, x) as a permutation of the stored order: its inversions are the 3 - xi
        // stored vertices after x's place and those among the places of a, b and c.
        auto place = [&](uint32_t v) { return int{t[1] == v} + 2 * int{t[2] == v} + 3 * int{t[3] == v}; };
        const int pa = place(ga), pb = place(gb), pc = place(gcv);
        flip = (3 - xi + (pa > pb) + (pa > pc) + (pb > pc)) & 1;
        sym = candidateSymbolOf(enc_->src_slot[x_src]);
      }
      sym = tsym_[ctx].code(*con_, sym);
      uint32_t x;
      if (sym == kSymNew) {
        FieldPrediction fp;
        fp.kind = g.d != kNoSlot ? FieldPrediction::kInterpolate : FieldPrediction::kAverage;
        fp.s[0] = g.v[0];
        fp.s[1] = g.v[1];
        fp.s[2] = g.v[2];
        fp.s[3] = g.d;
        uint32_t cands[kMaxCandidates];
        near_ = cands;
        n_near_ = orderedCandidates(cands);
        GTN_RETURN_IF_ERROR(introduceVertex(x_src, p, fp, &x));
        n_near_ = 0;
      } else if (sym == kSymEscape) {
        GTN_RETURN_IF_ERROR(codeEscape(g, side, p, kEncode ? enc_->src_slot[x_src] : 0, &x));
      } else {
        x = candidateAt(static_cast<int>(sym) - 1);
        if (x == kNoSlot) return bad("candidate rank out of range");
      }
      apex_votes_ += side.sign(P(x));
      scoreOrders(x);
      flip = con_->bit(flip_, flip);
      if constexpr (kEncode) {
        // The next gate's face record was prefetched at the start of this one.
        if (!queue_.empty())
          if (const long next = faces_.find(queue_.front().key); next >= 0) enc_->prefetchTet(enc_->face_tet[next]);
      }
      const uint32_t e[4] = {g.v[0], flip ? g.v[2] : g.v[1], flip ? g.v[1] : g.v[2], x};
      GTN_RETURN_IF_ERROR(emitTet(e, kEncode ? enc_->face_tet[idx] : 0, g.cell, idx, sym == kSymNew));
    }
    return Status::ok();
  }

  Status unusedPoints() {
    if constexpr (kEncode) {
      const size_t n = enc_->mesh->numPoints();
      for (size_t v = 0; v < n; ++v) {
        if (enc_->vertex_order[v] != kNone32) continue;
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
  std::vector<size_t> pf_offset_, cf_offset_;
  size_t item_bytes_ = 0, cell_bytes_ = 0;
  std::vector<size_t> slot_off_, comp_slot_off_;  // layOutSlotValues: offsets in a slot's values
  size_t slot_bytes_ = 0;                         // a slot's values (item_bytes_ when nothing is left out)
  std::vector<uint8_t> sink_vals_;                // sinkValues' buffer, when fields are left out
  std::vector<char> pf_skip_, cf_skip_;  // fields whose values the decoder leaves out (setFields)
  const DecodeFields* fields_ = nullptr;

  EncoderSide* enc_ = nullptr;
  MeshSink* sink_ = nullptr;
  const std::string* what_ = nullptr;

  // Slot pool.
  std::vector<uint8_t> state_;
  std::vector<double> pos_;
  // Per slot, per axis: the vertex's coordinate minus its prediction before any carry (the
  // prediction rule's, or the boundary's or edge's prediction; 0 for seeds), which later vertices
  // may carry over (spec section 10.5).
  std::vector<float> err_;
  std::vector<uint8_t> vals_;
  std::vector<uint32_t> open_, pins_, ids_, free_;
  // Per slot while the boundary phase lasts: the open boundary loop (nxt_, prv_) and, over the
  // boundary triangles added so far, the sum of their corner angles at the vertex (cornerAngle) and
  // their count (section 10.3).
  std::vector<uint32_t> nxt_, prv_;
  std::vector<double> corner_sum_;
  std::vector<uint32_t> corner_count_;
  bool boundary_done_ = false;

  FaceMap faces_;
  EdgeMap edges_;  // directed edge of an open face -> its third vertex
  EdgeMap half_;   // open boundary half-edge -> third vertex of its triangle
  // The sorted key of a face when it was opened: the face is found again by its key (at most one
  // open face has it), which is also how a face opened later on the same vertices is taken at this
  // entry. 12 bytes: the queue keeps the entries of faces closed since (23332 at once on blunt fin).
  struct QueuedFace {
    uint32_t key[3];
  };
  RingQueue<QueuedFace> queue_;
  RingQueue<uint64_t> hqueue_;

  BitTree<4> tsym_[kTetContexts];
  BitModel esc_by_rank_;
  BitTree<4> esc_bits_;
  int wrong_ = 0;                  // the gate's wrong side (gatherCandidates)
  uint64_t escape_scan_ = 0;       // live counts of the ranked escapes so far
  NearestGrid grid_;
  BitTree<4> bsym_[kBoundaryContexts];
  BitTree<4> geo_rule_[16];
  uint32_t geo_last_rule_ = 0;
  BitTree<3> geo_carry_[kCarries];  // [previous carry of this stream]
  uint32_t geo_last_carry_ = 0;
  std::vector<std::array<BitTree<4>, 16>> pf_rule_;
  std::vector<uint32_t> pf_last_rule_;
  BitModel flip_, retire_, seed_more_, bseed_more_, bpartner_, seed_existing_;

  int64_t apex_votes_ = 0;  // sum of orient3dCertain(a, b, c, apex) over the tetrahedra decoded so far
  // Apex candidates in both orders (section 10.4 of the spec) and which order has ranked better.
  static constexpr int kOrderScoreLimit = 32;
  struct RawCandidate {
    uint32_t s;
    uint32_t w;  // how many fan walks reached it
  };
  RawCandidate raw_[kMaxGather];  // the gate's candidates not evaluated yet, unordered
  // Per slot, while gatherCandidates runs: gather_epoch_ above kGatherIndexBits bits that hold the
  // slot's index in raw_, or kGateMark for the gate's own vertices (an older epoch: neither). Finding
  // a fan vertex among the candidates so far is then one load, not a scan of them all.
  static constexpr uint32_t kGatherIndexBits = 6;
  static constexpr uint32_t kGateMark = (1u << kGatherIndexBits) - 1;
  static constexpr uint32_t kGatherEpochs = 1u << (32 - kGatherIndexBits);
  static_assert(kMaxGather < kGateMark);
  std::vector<uint32_t> gather_mark_;
  uint32_t gather_epoch_ = 0;
  int raw_n_ = 0;
  Candidate cand_[kMaxGather];  // the evaluated ones (whole groups, best multiplicities), unordered
  int cand_n_ = 0;
  int first_ = -1;  // firstIndex(), -1 until found
  const FrontFace* gate_ = nullptr;  // the gate face, its side filter and predicted apex, while
  const Orient3dFilter* side_ = nullptr;  // its candidates are evaluated
  const double* pred_ = nullptr;
  bool delaunay_ = false, swept_ready_ = false, by_key_chosen_ = false;
  double cc0_[3] = {0, 0, 0}, nn_[3] = {0, 0, 0}, r2_ = 0, key_scale_ = 0;  // prepareSweep
  int order_score_ = 0;
  uint64_t next_id_ = 0, tets_done_ = 0, btris_done_ = 0, live_ = 0, peak_live_ = 0;
  double last_pos_[3] = {0, 0, 0};
  std::vector<uint8_t> last_vals_, cell_buf_;
  std::vector<std::vector<uint64_t>> last_cell_keys_;
  // Cell values of decoded tetrahedra that still have open faces, as prediction sources.
  size_t cell_comps_ = 0;
  std::vector<uint64_t> cell_rec_, cell_keys_;
  std::vector<uint32_t> cell_ref_, cell_free_;
  static constexpr size_t kRecentCellValues = 8;
  std::vector<uint64_t> cell_pred_, cell_act_;
  std::vector<std::vector<std::vector<uint64_t>>> cell_mtf_;  // [field][recency][component]
  std::vector<std::array<BitTree<4>, 9>> cell_sym_;  // [min(previous symbol, 2) * 3 + min(neighbours, 2)]
  std::vector<uint32_t> cell_last_sym_;
  // Coordinates equal to a component of a stencil vertex (axis-aligned geometry).
  BitModel copy_flag_[3][4];  // [axis][hit of the previous vertex's axis + 2 * previous axis hit]
  BitModel copy_same_[3];
  // Point-field components: byte offset in a vertex's values, type, earlier identical component.
  std::vector<ScalarType> comp_type_;
  std::vector<uint32_t> alias_;
  std::vector<uint32_t> field_coded_comps_;  // per field: components not aliased
  BitModel alias_flag_;     // a point-field component repeats an earlier one (codeAliases)
  BitModel shift_flag_;     // a component declares a shift (codeValueForms)
  BitModel exceptions_flag_;  // a component's shift has exceptions (codeValueForms)
  BitModel table_flag_;     // a component is coded in table form (codeValueForms)
  BitModel decimal_flag_;   // a float component is coded in decimal form (codeValueForms)
  BitModel printed_flag_;   // a float64 component is coded in printed-single form (codeValueForms)
  BitTree<5> copy_which_[3];
  const uint32_t* near_ = nullptr;  // apex candidates of the gate being decoded (copy sources)
  int n_near_ = 0;
  bool edge_points_ = false;  // the level codes points on edges (section 10.5)
  BitModel edge_points_flag_;
  bool delaunay_first_ = false;  // the Delaunay order ranks by key before count (section 10.4)
  BitModel delaunay_first_flag_;
  BitModel edge_point_[4][2];  // [edge kind (codeEdgePoints)][after a point on the same edge]
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
      uint32_t e = kNone32;
      for (uint32_t v : mesh.tets[u])
        if (v != a[0] && v != a[1] && v != a[2] && v != a[3]) e = v;
      if (e == kNone32) continue;
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
      const double ins = -l[0] * det3(m[1], m[2], m[3]) + l[1] * det3(m[0], m[2], m[3]) - l[2] * det3(m[0], m[1], m[3]) +
                         l[3] * det3(m[0], m[1], m[2]);
      const double o = signedVolume(mesh.point(a[0]), mesh.point(a[1]), mesh.point(a[2]), mesh.point(a[3]));
      if (!(o != 0) || !std::isfinite(ins)) continue;
      ++tested;
      if ((o > 0 ? -ins : ins) > 1e-8 * scale * scale * std::sqrt(scale)) ++inside;
    }
  }
  return tested > 0 && inside <= tested / 20;
}

}  // namespace

StatusOr<EncodedLevel> encodeLevel(const TetMesh& mesh, const EncodeOptions& options) {
  if (options.keep_order) return unsupported("encodeLevel: keeping the source order is not implemented");
  GTN_RETURN_IF_ERROR(mesh.checkConsistency("encodeLevel"));
  if (mesh.coord_type != ScalarType::kFloat32 && mesh.coord_type != ScalarType::kFloat64)
    return unsupported("encodeLevel: coordinates must be float32 or float64");
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  if (np >= kNone32 || nt >= kNone32) return unsupported("encodeLevel: more than 2^32-2 points or tetrahedra");
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
  h.points = np;
  h.tets = nt;
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

  EncoderSide enc;
  enc.mesh = &mesh;
  enc.delaunay_first = looksDelaunay(mesh, adj);
  enc.neighbor = &adj.neighbor;
  enc.src_slot.assign(np, kNoSlot);
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
  enc.vertex_order.assign(np, kNone32);
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
        comps.push_back({f.bytes.data() + c * scalarSize(f.type), f.components * scalarSize(f.type), scalarSize(f.type), f.type});
    enc.alias.assign(comps.size(), kNone32);
    constexpr size_t kMaxAliasScan = 64;  // components compared pairwise (quadratic)
    for (size_t k = 1; k < comps.size() && k < kMaxAliasScan; ++k)
      for (size_t j = 0; j < k; ++j) {
        if (enc.alias[j] != kNone32 || comps[j].type != comps[k].type) continue;
        bool same = true;
        for (size_t v = 0; v < np && same; ++v)
          same = std::memcmp(comps[j].base + v * comps[j].stride, comps[k].base + v * comps[k].stride, comps[k].size) == 0;
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
    coder.setPacked(forms.geo, forms.pf, forms.cf, forms.cf_split, &escaped);
    GTN_RETURN_IF_ERROR(coder.run());
    for (size_t f = 0; f < h.cell_fields.size(); ++f) {
      if (!forms.cf_split[f]) continue;
      const FieldDesc& d = h.cell_fields[f];
      const std::vector<uint8_t> items = packValues(escaped[f].data(), escaped[f].size() / d.itemBytes(), d.itemBytes(),
                                                    scalarSize(d.type), 0, true);
      level->cell_fields[f] = splitStream(level->cell_fields[f], items);
    }
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
  std::vector<uint8_t> items;
  auto packed = [&](const uint8_t* src, size_t count, size_t item_bytes, size_t value_size, auto order,
                    const std::vector<uint8_t>& coded) {
    items.resize(count * item_bytes);
    for (size_t i = 0; i < count; ++i) std::memcpy(&items[order(i) * item_bytes], src + i * item_bytes, item_bytes);
    std::vector<uint8_t> p = packValues(items.data(), count, item_bytes, value_size, coded.size());
    return !p.empty() && p.size() < coded.size() ? p : std::vector<uint8_t>{};
  };
  auto by_vertex = [&](size_t v) { return size_t{out.vertex_order[v]}; };
  auto by_tet = [&](size_t t) { return static_cast<size_t>(out.tet_order[t]); };
  Forms chosen = predicted;
  std::vector<uint8_t> geo;
  if (enc.edge_points.empty() && np > 0) {
    const size_t cs = scalarSize(mesh.coord_type);
    std::vector<uint8_t> coords(np * 3 * cs);
    for (size_t i = 0; i < 3 * np; ++i) storeCoordinate(mesh.coord_type, mesh.coords[i], &coords[i * cs]);
    geo = packed(coords.data(), np, 3 * cs, cs, by_vertex, out.geometry);
    chosen.geo = !geo.empty();
  }
  std::vector<std::vector<uint8_t>> pfs(h.point_fields.size()), cfs(h.cell_fields.size());
  for (size_t f = 0; f < pfs.size(); ++f) {
    const Field& field = mesh.point_fields[f];
    pfs[f] = packed(field.bytes.data(), np, field.components * field.valueSize(), field.valueSize(), by_vertex, out.point_fields[f]);
    chosen.pf[f] = !pfs[f].empty();
  }
  for (size_t f = 0; f < cfs.size(); ++f) {
    const Field& field = mesh.cell_fields[f];
    cfs[f] = packed(field.bytes.data(), nt, field.components * field.valueSize(), field.valueSize(), by_tet, out.cell_fields[f]);
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
    saving(chosen.cf_split[f], split.cell_fields.size() > f ? split.cell_fields[f].size() : 0, out.cell_fields[f].size());
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
                   const std::string& what, const DecodeFields* fields) {
  if (header.coord_type != ScalarType::kFloat32 && header.coord_type != ScalarType::kFloat64)
    return invalidData(what + ": coordinates must be float32 or float64");
  if (header.points >= kNone32) return invalidData(what + ": too many points for one level");
  if (header.tets >= kNone32) return invalidData(what + ": too many tetrahedra for one level");
  if (payload.point_fields.size() != header.point_fields.size() ||
      payload.cell_fields.size() != header.cell_fields.size())
    return invalidData(what + ": field streams do not match the header's field list");
  for (const auto* list : {&header.point_fields, &header.cell_fields})
    for (const FieldDesc& d : *list) {
      if (static_cast<int>(d.type) >= kNumScalarTypes) return invalidData(what + ": field '" + d.name + "' has an unknown type");
      if (d.components == 0 || d.components > 4096)
        return invalidData(what + ": field '" + d.name + "' has an invalid component count");
    }
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
  std::vector<std::unique_ptr<PackedReader>> pf_readers(header.point_fields.size()), cf_readers(header.cell_fields.size());
  GTN_RETURN_IF_ERROR(open(payload.geometry, header.points, FieldDesc{"", 3, header.coord_type}, "the geometry stream",
                           &geo_reader));
  for (size_t f = 0; f < pf_readers.size(); ++f)
    GTN_RETURN_IF_ERROR(open(payload.point_fields[f], header.points, header.point_fields[f],
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
