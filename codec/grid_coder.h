// The structured-piece coder of format 2.0 (spec/gtn-format-2.0-draft.md section 11): a box of
// cells of a structured block whose tetrahedra follow a split rule (5 with a parity, or 6; optionally
// left-handed), except the cells an exception list names (blanked cells, explicit cells with Steiner
// points), with welded node aliases. Connectivity costs the header and the exceptions; coordinates
// and point fields are predicted along the grid (Lorenzo, the previous node along i or linear along
// i, chosen per component by measurement) and coded with 1.0's value coder and value forms (decimal,
// printed-single, shift, table), each chosen by measurement; cell fields with 1.0's cell-field
// symbols over grid neighbours.
//
// This unit codes one piece as a byte string: the structured header of section 11.1, a stream table
// and the streams EXCP, GRID, GEOM, PFLD per point field, CFLD per cell field (section 9). It codes a
// piece with nothing known and no seams (a whole block as one piece of the coarsest level): its GRID
// stream is empty. The container (pieces, seams, levels) is not part of it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mesh/mesh_stream.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// A cell that the split rule does not give (section 11.4).
struct GridException {
  enum Kind : uint8_t { kBlanked = 0, kExplicit = 1 };
  uint32_t cell = 0;  // i + (ni - 1) * (j + (nj - 1) * k)
  uint8_t kind = kBlanked;
  uint8_t extras = 0;  // Steiner points the record adds (0..8), numbered after every earlier record's
  // Explicit cells: the tetrahedra (1..31), corners 0..7 of the cell (VTK order) and 8 + e for the
  // record's e-th extra point.
  std::vector<std::array<uint8_t, 4>> tets;
};

// What a structured piece's connectivity is: the block's node counts, the split rule, the aliases
// and the exceptions. Its vertices are the nodes that are not aliases, in node order, then the extra
// points of the exceptions in record order; its tetrahedra those of gridTets.
struct GridLayout {
  uint32_t dims[3] = {2, 2, 2};       // node counts ni, nj, nk, each >= 2
  uint8_t split = 5;                  // 5 or 6
  uint8_t parity = 0;                 // 5-split: cell (i, j, k) is odd when (i + j + k + parity) is
  bool left_handed = false;           // every rule tetrahedron has its last two corners exchanged
  bool cell_values_per_cell = false;  // cell fields coded once per cell (every tetrahedron of a cell alike)
  std::vector<std::pair<uint32_t, uint32_t>> aliases;  // (node a, node t it is), t < a, a increasing
  std::vector<GridException> exceptions;               // in increasing cell order

  uint64_t nodes() const { return uint64_t{dims[0]} * dims[1] * dims[2]; }
  uint64_t cells() const { return uint64_t{dims[0] - 1} * (dims[1] - 1) * (dims[2] - 1); }
  uint64_t extras() const;
  uint64_t vertices() const { return nodes() - aliases.size() + extras(); }
  uint64_t tets() const;
};

// Checks a layout's own consistency (dims, split, increasing aliases and exceptions, corner symbols,
// counts below 2^32); the message starts with `what`.
Status checkGridLayout(const GridLayout& layout, const std::string& what);

// The layout's tetrahedra in the spec's order (cell order, i fastest; within a cell the rule's table
// order, or an explicit cell's list), with vertex numbers as the decoder gives them. The layout must
// pass checkGridLayout.
std::vector<Tet> gridTets(const GridLayout& layout);

// The tetrahedra of a layout of rule cells alone (no alias, no exception; one that passes
// checkGridLayout), each made from its index as gridTets makes it, in about as long as a read of a
// tetrahedron held in memory: for a caller that releases a grid's tetrahedra (16 bytes each) while
// it reads them in an order of its own (simplify/ranking.h's RankingOptions::grid_tets).
class RuleGridTets {
 public:
  explicit RuleGridTets(const GridLayout& layout);
  uint64_t size() const { return tets_; }
  // The points they name: the block's nodes, 0 .. points() - 1.
  uint64_t points() const { return ni_ * nj_ * nk_; }
  // Tetrahedron t (t < size()), as gridTets(layout)[t].
  Tet operator[](uint64_t t) const {
    const uint64_t cell = divide(t, per_magic_);
    const uint64_t r = t - cell * per_;
    const uint64_t q = divide(cell, ci_magic_);  // cell = i + ci * (j + cj * k)
    const uint64_t i = cell - q * ci_;
    const uint64_t k = divide(q, cj_magic_);
    const uint64_t j = q - k * cj_;
    const uint32_t base = static_cast<uint32_t>(i + ni_ * (j + nj_ * k));
    const uint32_t* o = offsets_[((i + j + k + parity_) & 1) * 6 + r].data();
    return {base + o[0], base + o[1], base + o[2], base + o[3]};
  }
  // Whether `tets` are exactly these.
  bool sameAs(const std::vector<Tet>& tets) const;

 private:
  // n / d for n and d below 2^32, by a multiplication (Lemire, Kaser and Kurz: the magic number is
  // 2^64 / d rounded up; 0 stands for d = 1, whose 2^64 does not fit).
  static uint64_t magic(uint64_t d) { return UINT64_MAX / d + 1; }
  static uint64_t divide(uint64_t n, uint64_t m) {
    return m == 0 ? n : static_cast<uint64_t>((static_cast<unsigned __int128>(m) * n) >> 64);
  }
  uint64_t tets_ = 0, per_ = 6, ci_ = 1, cj_ = 1, ni_ = 2, nj_ = 2, nk_ = 2, parity_ = 0;
  uint64_t per_magic_ = 0, ci_magic_ = 0, cj_magic_ = 0;
  // Per parity (even, odd) and rule tetrahedron: its corners' node offsets from the cell's corner 0.
  std::array<std::array<uint32_t, 4>, 12> offsets_{};
};

// The split rule's tetrahedra of a cell, as corner numbers 0..7 (split 5 or 6, odd: the 5-split's
// odd cells), before the left-handed exchange.
std::span<const std::array<uint8_t, 4>> gridRuleTets(int split, bool odd);

// The layout of a mesh whose first points are a block's ni x nj x nk nodes in node order (i fastest)
// followed only by extra points, with tetrahedra in cell order as a structured importer writes them
// (PLOT3D, VTK structured datasets): the split, parity and handedness that leave the fewest cells
// as exceptions, and those cells (blanked, or explicit: flipped, split around a Steiner point, or
// otherwise not the rule's). `aliases` (the layout's: (node, earlier node it is), node increasing)
// are nodes that have no point of their own (welded into an earlier node): the nodes' points are
// then those of the other nodes, in node order. Fails when the tetrahedra do not come cell by cell.
StatusOr<GridLayout> matchGridLayout(const TetMesh& mesh, const uint32_t dims[3],
                                     std::span<const std::pair<uint32_t, uint32_t>> aliases = {});

// The predictors of section 11.3.
enum class GridPredictor : uint8_t { kLorenzo = 0, kPreviousI = 1, kLinearI = 2 };

struct GridEncodeOptions {
  // -1: each component's predictor chosen by measurement; 0..2: that predictor for every component.
  int predictor = -1;
  // GEOM and PFLD streams: -1 form 1 (static prefix codes, faster to decode) where it is at most 2%
  // larger than form 0 (adaptive range coding), else form 0 (section 12); 0 or 1: that form (1 where
  // every component's value form allows it: not printed-single, no shift with exceptions).
  int value_form = -1;
};

// What the encoder chose and how large each part came out, in bytes.
struct GridEncodeReport {
  size_t header = 0;  // the structured header and the stream table
  size_t excp = 0, grid = 0, geom = 0;
  std::vector<size_t> point_fields, cell_fields;
  // Per coordinate axis, then per point-field component: the predictor (0..2) and the value form
  // ("plain", "shift s", "decimal e", "printed p", "table D").
  std::vector<uint8_t> predictors;
  std::vector<std::string> forms;
  std::vector<uint8_t> stream_forms;  // GEOM, then each PFLD: 0 or 1
};

// What the decoder must be told (in the format, the file header holds it).
struct GridSchema {
  ScalarType coord_type = ScalarType::kFloat32;
  std::vector<FieldDesc> point_fields, cell_fields;
};
GridSchema gridSchemaOf(const TetMesh& mesh);

// Encodes `mesh` as the structured piece `layout`: its points must be the layout's vertices (nodes
// that are not aliases in node order, then the extra points in record order), its tetrahedra exactly
// gridTets(layout), its cell fields one value per tetrahedron. Fails (kUsage; kInvalidData for a layout
// that fails checkGridLayout) otherwise.
StatusOr<std::vector<uint8_t>> encodeGridPiece(const GridLayout& layout, const TetMesh& mesh,
                                               const GridEncodeOptions& options = {},
                                               GridEncodeReport* report = nullptr);

struct DecodedGridPiece {
  GridLayout layout;
  TetMesh mesh;  // vertices and tetrahedra in the layout's order, values bit for bit
};

// Which fields decodeGridPiece decodes: point[f], cell[f] false leaves schema field f out (its
// stream is not read; its values come out zero). Empty vectors (or no selection) decode every field.
// `tets` false leaves DecodedGridPiece::mesh.tets empty (for a caller that makes them from the layout).
// `beside`, when set, runs once the layout is read, in parallel with the streams' decoding (a caller's
// own work from the layout, such as the boundary triangles); its failure fails the decode after any
// stream's.
struct GridFieldSelection {
  std::vector<bool> point, cell;
  bool tets = true;
  std::function<Status(const GridLayout&)> beside;
};

// Decodes a piece written by encodeGridPiece. Fails with kInvalidData, naming `what`, the part and
// the reason, on any corrupt or truncated input; allocations are bounded by the input's size.
StatusOr<DecodedGridPiece> decodeGridPiece(std::span<const uint8_t> bytes, const GridSchema& schema,
                                           const std::string& what, const GridFieldSelection* fields = nullptr);

}  // namespace gtn
