// The cell values of the level codec (spec section 10.7): each tetrahedron's cell-field values, coded
// when it is emitted. Per field a symbol says "as the neighbour behind the gate face" (else the
// previous tetrahedron), "as the i-th other decoded neighbour", "as the i-th most recent distinct
// value", or "coded as a residual"; packed and split streams take their items as stored. The values
// of a tetrahedron that still has open faces stay in a record, as the prediction of the tetrahedra
// behind those faces. Host is the level coder: it owns the streams, the header and the front.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "codec/flat_maps.h"
#include "codec/prediction.h"
#include "codec/range_coder.h"
#include "codec/symbols.h"
#include "codec/value_coder.h"
#include "mesh/index.h"
#include "mesh/mesh_stream.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gtn::level {

inline constexpr uint32_t kSymCellNeighbour = 9;  // cell values: 9..11 name a neighbour (spec section 10.7)

// Whether two cell values' keys agree, compared in line: std::equal calls memcmp, which costs more
// than comparing the few components a cell value has.
inline bool sameKeys(const uint64_t* a, const uint64_t* b, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i)
    if (a[i] != b[i]) return false;
  return true;
}

template <class Host>
class CellValues {
 public:
  static constexpr bool kEncode = Host::kEncode;

  CellValues(Host& host, const LevelHeader& header) : h_(host) {
    for (const FieldDesc& d : header.cell_fields) {
      offset_.push_back(bytes_);
      bytes_ += d.itemBytes();
    }
    buf_.assign(bytes_, 0);
    last_keys_.resize(header.cell_fields.size());
    for (size_t f = 0; f < header.cell_fields.size(); ++f) {
      // The first prediction is the key of zero.
      const FieldDesc& d = header.cell_fields[f];
      last_keys_[f].assign(d.components, keyFromPrediction(d.type, 0.0));
      comps_ += d.components;
    }
    keys_.assign(comps_, 0);
    uint32_t max_comps = 1;
    for (const FieldDesc& d : header.cell_fields) max_comps = std::max(max_comps, d.components);
    pred_.assign(max_comps, 0);
    act_.assign(max_comps, 0);
    mtf_.resize(header.cell_fields.size());
    sym_.resize(header.cell_fields.size());
    last_sym_.assign(header.cell_fields.size(), 0);
  }

  // The values of the tetrahedron being emitted (the encoder's source tetrahedron src_tet), whose
  // faces closes[k] >= 0 close open faces (their records are the neighbours' values); pred_cell is
  // the record of the neighbour behind the gate face, or kNoIndex.
  Status code(const long closes[4], uint32_t src_tet, uint32_t pred_cell) {
    // Cell values: per field, a symbol says "as the neighbour behind the gate face" (else the
    // previous tetrahedron), "as the i-th other decoded neighbour", "as the i-th most recent
    // distinct value", or "coded as a residual". The other neighbours are those across the faces it
    // closes besides the gate: importers give every tetrahedron of a split hexahedron, wedge or
    // pyramid its cell's value, and those siblings are seldom behind the gate face.
    size_t j = 0;
    for (size_t f = 0; f < h_.header_.cell_fields.size(); ++f) {
      const FieldDesc& d = h_.header_.cell_fields[f];
      const size_t vs = scalarSize(d.type);
      const uint32_t nc = d.components;
      if (h_.cf_skip_[f]) {
        j += nc;
        continue;
      }
      if (h_.cf_packed_[f]) {
        // Packed form: the item as stored.
        const uint8_t* item = nullptr;
        if constexpr (kEncode) {
          item = h_.enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes();
        } else {
          item = h_.cf_readers_[f]->next();
          if (!item) return h_.bad(h_.cf_readers_[f]->error());
        }
        for (uint32_t c = 0; c < nc; ++c) {
          keys_[j + c] = last_keys_[f][c] = keyFromRaw(d.type, item + c * vs);
        }
        std::memcpy(&buf_[offset_[f]], item, d.itemBytes());
        j += nc;
        continue;
      }
      uint64_t* pred = &pred_[0];
      uint64_t* act = &act_[0];
      for (uint32_t c = 0; c < nc; ++c) {
        pred[c] = pred_cell != kNoIndex ? rec_[pred_cell * comps_ + j + c] : last_keys_[f][c];
        if constexpr (kEncode)
          act[c] =
              keyFromRaw(d.type, h_.enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes() + c * vs);
      }
      // The distinct values, other than P, of the neighbours across faces 0, 1 and 2, in that order.
      const uint64_t* nbr[3];
      uint32_t n_nbr = 0;
      for (int k = 0; k < 3; ++k) {
        if (closes[k] < 0) continue;
        const uint32_t r = h_.front_.faces.at(closes[k]).cell;
        if (r == kNoIndex) continue;
        const uint64_t* v = &rec_[size_t{r} * comps_ + j];
        bool seen = sameKeys(v, pred, nc);
        for (uint32_t i = 0; i < n_nbr && !seen; ++i) seen = sameKeys(v, nbr[i], nc);
        if (!seen) nbr[n_nbr++] = v;
      }
      std::vector<std::vector<uint64_t>>& mtf = mtf_[f];
      BitTree<4>& tree = sym_[f][last_sym_[f] * 3 + std::min<uint32_t>(n_nbr, 2)];
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
      sym = tree.code(*h_.cf_[f], sym);
      last_sym_[f] = std::min<uint32_t>(sym, 2);
      uint64_t* keys = &keys_[j];
      if (sym == 0) {
        std::copy(pred, pred + nc, keys);
      } else if (sym == kSymEscape && h_.cf_split_[f]) {
        // Split form: the escaped values are the packed part's next item.
        const uint8_t* item = nullptr;
        if constexpr (kEncode) {
          item = h_.enc_->mesh->cell_fields[f].bytes.data() + size_t{src_tet} * d.itemBytes();
          (*h_.cf_escaped_)[f].insert((*h_.cf_escaped_)[f].end(), item, item + d.itemBytes());
        } else {
          item = h_.cf_readers_[f]->next();
          if (!item) return h_.bad(h_.cf_readers_[f]->error());
        }
        for (uint32_t c = 0; c < nc; ++c) keys[c] = keyFromRaw(d.type, item + c * vs);
      } else if (sym == kSymEscape) {
        for (uint32_t c = 0; c < nc; ++c) keys[c] = h_.cf_vc_[f].code(*h_.cf_[f], c, pred[c], act[c]);
      } else if (sym >= kSymCellNeighbour) {
        if (sym - kSymCellNeighbour >= n_nbr) return h_.bad("cell value refers to a neighbour that does not exist");
        std::copy(nbr[sym - kSymCellNeighbour], nbr[sym - kSymCellNeighbour] + nc, keys);
      } else {
        if (sym > mtf.size()) return h_.bad("cell value refers to an unknown recent value");
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
        last_keys_[f][c] = keys[c];
        rawFromKey(d.type, keys[c], &buf_[offset_[f] + c * vs]);
      }
      j += nc;
    }
    return Status::ok();
  }

  // The emitted tetrahedron's values as the sink takes them (null without cell fields).
  const uint8_t* values() const { return bytes_ ? buf_.data() : nullptr; }
  size_t itemBytes() const { return bytes_; }

  // A record of the emitted tetrahedron's values, held once until the faces it opens hold it
  // (hold); kNoIndex without cell fields.
  uint32_t record() {
    if (comps_ == 0) return kNoIndex;
    uint32_t rec;
    if (!free_.empty()) {
      rec = free_.back();
      free_.pop_back();
    } else {
      rec = static_cast<uint32_t>(ref_.size());
      ref_.push_back(0);
      rec_.resize(rec_.size() + comps_);
    }
    ref_[rec] = 1;  // held until the faces are opened
    std::copy(keys_.begin(), keys_.end(), rec_.begin() + size_t{rec} * comps_);
    return rec;
  }
  void hold(uint32_t rec) { ++ref_[rec]; }
  void release(uint32_t rec) {
    if (--ref_[rec] == 0) free_.push_back(rec);
  }

 private:
  static constexpr size_t kRecentCellValues = 8;

  Host& h_;
  std::vector<size_t> offset_;                    // per field: its bytes' offset in an item
  size_t bytes_ = 0;                              // an item: every field's values
  std::vector<uint8_t> buf_;                      // the emitted tetrahedron's item
  std::vector<std::vector<uint64_t>> last_keys_;  // per field: the previous tetrahedron's keys
  // Cell values of decoded tetrahedra that still have open faces, as prediction sources.
  size_t comps_ = 0;
  std::vector<uint64_t> rec_, keys_;
  std::vector<uint32_t> ref_, free_;
  std::vector<uint64_t> pred_, act_;
  std::vector<std::vector<std::vector<uint64_t>>> mtf_;  // [field][recency][component]
  std::vector<std::array<BitTree<4>, 9>> sym_;           // [min(previous symbol, 2) * 3 + min(neighbours, 2)]
  std::vector<uint32_t> last_sym_;
};

}  // namespace gtn::level
