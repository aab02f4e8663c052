#include "codec/grid_coder.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <optional>

#include "codec/range_coder.h"
#include "codec/value_coder.h"
#include "mesh/fresh_memory.h"
#include "mesh/index.h"
#include "mesh/longest_first.h"

namespace gtn {

namespace {

// Corner c of cell (i, j, k) in VTK order is node (i + dx, j + dy, k + dz).
constexpr uint8_t kCornerDx[8] = {0, 1, 1, 0, 0, 1, 1, 0};
constexpr uint8_t kCornerDy[8] = {0, 0, 1, 1, 0, 0, 1, 1};
constexpr uint8_t kCornerDz[8] = {0, 0, 0, 0, 1, 1, 1, 1};

// The tables of mesh/hex_split.cpp (the importers' grid splitter), as section 11.1 gives them.
constexpr std::array<uint8_t, 4> kSix[6] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                            {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
constexpr std::array<uint8_t, 4> kFiveEven[5] = {{0, 2, 7, 5}, {1, 0, 5, 2}, {3, 0, 2, 7}, {4, 0, 7, 5}, {6, 2, 5, 7}};
constexpr std::array<uint8_t, 4> kFiveOdd[5] = {{1, 3, 4, 6}, {0, 1, 3, 4}, {2, 1, 6, 3}, {5, 1, 4, 6}, {7, 3, 6, 4}};

constexpr uint64_t kPieceLimit = uint64_t{1} << 32;  // piece-local counts stay below (section 17)
constexpr int kMaxExplicitTets = 31;
constexpr int kMaxExtras = 8;
// A node costs at least a few hundredths of a bit in GEOM (three components, each at least a
// bucket symbol); a header whose nodes exceed this many per byte of its piece is corrupt, and is
// rejected before anything is allocated for them.
constexpr uint64_t kMaxNodesPerByte = 4096;

struct CellGeometry {
  uint64_t ni, nj, nk, ci, cj, ck;  // node and cell counts
  explicit CellGeometry(const GridLayout& l)
      : ni(l.dims[0]), nj(l.dims[1]), nk(l.dims[2]), ci(ni - 1), cj(nj - 1), ck(nk - 1) {}
  uint64_t cornerOffset(int c) const { return kCornerDx[c] + ni * (kCornerDy[c] + nj * kCornerDz[c]); }
  // The node of corner 0 of cell `cell`.
  uint64_t baseNode(uint64_t cell) const {
    const uint64_t i = cell % ci, j = (cell / ci) % cj, k = cell / (ci * cj);
    return i + ni * (j + nj * k);
  }
  bool odd(uint64_t cell, int parity) const {
    const uint64_t i = cell % ci, j = (cell / ci) % cj, k = cell / (ci * cj);
    return ((i + j + k + static_cast<uint64_t>(parity)) & 1) != 0;
  }
};

// node -> vertex (aliases: their target's vertex), or empty when the layout has no alias.
std::vector<uint32_t> nodeVertices(const GridLayout& l) {
  if (l.aliases.empty()) return {};
  std::vector<uint32_t> v(l.nodes());
  uint32_t next = 0;
  size_t a = 0;
  for (uint64_t n = 0; n < v.size(); ++n) {
    if (a < l.aliases.size() && l.aliases[a].first == n) {
      v[n] = v[l.aliases[a].second];
      ++a;
    } else {
      v[n] = next++;
    }
  }
  return v;
}

// ---- Byte helpers (the container's conventions: LEB128 varints, shortest form) -----------------

void putVarint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}

class Reader {
 public:
  Reader(std::span<const uint8_t> in, const std::string& what) : in_(in), what_(what) {}
  Status u8(uint8_t* v, const char* name) {
    if (pos_ >= in_.size()) return fail(name, "truncated");
    *v = in_[pos_++];
    return Status::ok();
  }
  Status varint(uint64_t* v, const char* name) {
    uint64_t r = 0;
    for (int shift = 0;; shift += 7) {
      if (pos_ >= in_.size()) return fail(name, "truncated");
      const uint8_t b = in_[pos_++];
      if (shift == 63 && b > 1) return fail(name, "a varint above 2^64 - 1");
      r |= uint64_t{b & 0x7Fu} << shift;
      if (!(b & 0x80)) {
        if (b == 0 && shift > 0) return fail(name, "a varint not in its shortest form");
        break;
      }
      if (shift == 63) return fail(name, "a varint longer than 10 bytes");
    }
    *v = r;
    return Status::ok();
  }
  Status varintBelow(uint64_t* v, uint64_t limit, const char* name) {
    GTN_RETURN_IF_ERROR(varint(v, name));
    if (*v >= limit) return fail(name, std::to_string(*v) + " is not below " + std::to_string(limit));
    return Status::ok();
  }
  size_t position() const { return pos_; }
  size_t remaining() const { return in_.size() - pos_; }
  Status fail(const char* name, const std::string& reason) const {
    return invalidData(what_ + ": structured piece, byte " + std::to_string(pos_) + ": " + name + ": " + reason);
  }

 private:
  std::span<const uint8_t> in_;
  size_t pos_ = 0;
  const std::string& what_;
};

// A count or difference v < 2^32 as its bit length (BitTree<6>) then the bits below its leading one.
template <class C>
uint64_t codeNumber(C& c, BitTree<6>& length, uint64_t v) {
  uint32_t b = C::kEncoding ? static_cast<uint32_t>(bitLength(v)) : 0;
  b = length.code(c, b);
  if (b > 32) {
    c.markCorrupt();
    return 0;
  }
  if (b <= 1) return b;
  const uint32_t low = c.direct(static_cast<uint32_t>(v & ((uint64_t{1} << (b - 1)) - 1)), static_cast<int>(b - 1));
  return (uint64_t{1} << (b - 1)) | low;
}

// ---- EXCP ------------------------------------------------------------------------------------------

struct ExcpModels {
  BitTree<6> alias_gap, alias_back, cell_gap;
  BitTree<2> kind;
  BitTree<4> extras;
  BitTree<5> count;
  BitTree<4> corner[4];  // by the corner's place in the tetrahedron
};

// The aliases and the exception records (section 11.4) of `layout` (the decoder's: counts set, lists
// filled). Checks as the decoder reads.
template <class C>
Status codeExceptions(C& c, GridLayout& layout, uint64_t n_aliases, uint64_t n_exceptions, uint64_t n_extra,
                      const std::string& what) {
  ExcpModels m;
  auto bad = [&](const std::string& reason) { return invalidData(what + ": EXCP stream: " + reason); };
  const uint64_t nodes = layout.nodes(), cells = layout.cells();
  uint64_t prev = 0;
  for (uint64_t a = 0; a < n_aliases; ++a) {
    uint64_t node = 0, target = 0;
    if constexpr (C::kEncoding) node = layout.aliases[a].first, target = layout.aliases[a].second;
    const uint64_t gap = codeNumber(c, m.alias_gap, node - (a ? prev + 1 : 0));
    const uint64_t back = codeNumber(c, m.alias_back, node - target);
    if constexpr (!C::kEncoding) {
      node = (a ? prev + 1 : 0) + gap;
      if (!c.ok() || node >= nodes || back == 0 || back > node)
        return bad("alias " + std::to_string(a) + " is corrupt (a node beyond the piece, or not after its target)");
      layout.aliases.emplace_back(static_cast<uint32_t>(node), static_cast<uint32_t>(node - back));
    }
    prev = node;
  }
  prev = 0;
  uint64_t extras = 0;
  for (uint64_t r = 0; r < n_exceptions; ++r) {
    GridException x;
    if constexpr (C::kEncoding) x = layout.exceptions[r];
    const uint64_t base = r ? prev + 1 : 0;
    const uint64_t cell = base + codeNumber(c, m.cell_gap, x.cell - base);
    x.kind = static_cast<uint8_t>(m.kind.code(c, x.kind));
    if constexpr (!C::kEncoding) {
      if (!c.ok() || cell >= cells) return bad("exception " + std::to_string(r) + " names a cell beyond the piece");
      if (x.kind > GridException::kExplicit)
        return bad("exception " + std::to_string(r) + " has the reserved kind " + std::to_string(x.kind));
      x.cell = static_cast<uint32_t>(cell);
    }
    prev = cell;
    if (x.kind == GridException::kExplicit) {
      x.extras = static_cast<uint8_t>(m.extras.code(c, x.extras));
      const uint32_t count = m.count.code(c, static_cast<uint32_t>(x.tets.size()));
      if constexpr (!C::kEncoding) {
        if (x.extras > kMaxExtras)
          return bad("exception " + std::to_string(r) + " adds " + std::to_string(x.extras) + " points (at most 8)");
        if (count == 0) return bad("explicit cell " + std::to_string(cell) + " has no tetrahedron");
        x.tets.resize(count);
      }
      for (auto& t : x.tets) {
        for (int q = 0; q < 4; ++q) t[q] = static_cast<uint8_t>(m.corner[q].code(c, t[q]));
        if constexpr (!C::kEncoding) {
          for (int q = 0; q < 4; ++q) {
            if (t[q] >= 8 + x.extras)
              return bad("explicit cell " + std::to_string(cell) + " names corner " + std::to_string(t[q]) +
                         " beyond its points");
            for (int p = 0; p < q; ++p)
              if (t[p] == t[q])
                return bad("explicit cell " + std::to_string(cell) + " has a tetrahedron that repeats a corner");
          }
        }
      }
      extras += x.extras;
    }
    if constexpr (!C::kEncoding) {
      if (!c.ok()) return bad("truncated or corrupt");
      layout.exceptions.push_back(std::move(x));
    }
  }
  if (!C::kEncoding && extras != n_extra)
    return bad("the records add " + std::to_string(extras) + " points, the header says " + std::to_string(n_extra));
  return Status::ok();
}

// ---- Values ----------------------------------------------------------------------------------------

// A component's value form (1.0 section 10.2) and predictor.
struct Form {
  int decimals = -1;
  int printed = 0;
  uint32_t shift = 0;
  bool exceptions = false;
  std::vector<uint64_t> table = {};
  uint8_t predictor = 0;

  std::string describe() const {
    if (!table.empty()) return "table " + std::to_string(table.size());
    if (decimals >= 0) return "decimal " + std::to_string(decimals);
    if (printed > 0) return "printed " + std::to_string(printed);
    if (shift > 0) return "shift " + std::to_string(shift) + (exceptions ? " with exceptions" : "");
    return "plain";
  }
};

// The models of the form declarations, one set per stream.
struct DeclarationModels {
  BitTree<2> predictor;
  BitModel table, decimal, printed, shift, exceptions;
};

template <class C>
Status declareForm(C& c, DeclarationModels& dm, ValueCoder& vc, ScalarType type, uint32_t comp, Form& form,
                   uint64_t values, const std::string& what) {
  form.predictor = static_cast<uint8_t>(dm.predictor.code(c, form.predictor));
  if (!C::kEncoding && form.predictor > 2)
    return invalidData(what + " declares the reserved predictor 3 for component " + std::to_string(comp));
  if (c.bit(dm.table, !form.table.empty())) {
    std::vector<uint64_t> table = form.table;
    if (!vc.codeTable(c, comp, &table, values))
      return invalidData(what + " declares an invalid value table (longer than its values, or not ascending)");
    return Status::ok();
  }
  if (isFloatType(type)) {
    if (c.bit(dm.decimal, form.decimals >= 0)) {
      const uint32_t e = c.direct(static_cast<uint32_t>(std::max(form.decimals, 0)), 5);
      if (e > ValueCoder::kMaxDecimals)
        return invalidData(what + " declares " + std::to_string(e) + " decimal places (at most 22)");
      vc.setDecimals(comp, static_cast<int>(e));
      return Status::ok();
    }
    if (type == ScalarType::kFloat64 && c.bit(dm.printed, form.printed > 0)) {
      const uint32_t p = c.direct(static_cast<uint32_t>(form.printed), 5);
      if (p < 1 || p > ValueCoder::kMaxPrintedDigits)
        return invalidData(what + " declares " + std::to_string(p) + " printed digits (1 to 17)");
      vc.setPrinted(comp, static_cast<int>(p));
      return Status::ok();
    }
  }
  if (!c.bit(dm.shift, form.shift > 0)) return Status::ok();
  const uint32_t shift = c.direct(form.shift, 6);
  if (shift == 0 || shift >= static_cast<uint32_t>(vc.bits()))
    return invalidData(what + " declares an invalid shift of " + std::to_string(shift) + " bits");
  const uint32_t exceptions = c.bit(dm.exceptions, form.exceptions);
  vc.setShift(comp, static_cast<int>(shift), exceptions != 0);
  return Status::ok();
}

// How the value scan walks the piece: node counts, aliases, the cells of the extra points.
struct Scan {
  uint32_t ni, nj, nk;
  const std::vector<uint32_t>* alias_target;  // per node: the node it is, or kNoIndex; null: no alias
  std::vector<uint64_t> extra_cell_base;      // per extra point: corner 0's node of its cell
  uint64_t corner_offset[8];
  uint64_t vertices;
};

// The prediction of node (i, j, k) from the decoded values d (one per node and component, `stride`
// apart) by `predictor` (section 11.3).
[[gnu::always_inline]] inline double lorenzo(const double* p, uint32_t i, uint32_t j, uint32_t k, ptrdiff_t si,
                                             ptrdiff_t sj, ptrdiff_t sk) {
  if (i && j && k) return p[-si] + p[-sj] + p[-sk] - p[-si - sj] - p[-si - sk] - p[-sj - sk] + p[-si - sj - sk];
  if (i && j) return p[-si] + p[-sj] - p[-si - sj];
  if (i && k) return p[-si] + p[-sk] - p[-si - sk];
  if (j && k) return p[-sj] + p[-sk] - p[-sj - sk];
  if (i) return p[-si];
  if (j) return p[-sj];
  if (k) return p[-sk];
  return 0.0;
}

[[gnu::always_inline]] inline double predict(uint8_t predictor, const double* p, uint32_t i, uint32_t j, uint32_t k,
                                             ptrdiff_t si, ptrdiff_t sj, ptrdiff_t sk) {
  if (predictor == 1 && i) return p[-si];
  if (predictor == 2 && i) return i > 1 ? 2.0 * p[-si] - p[-2 * si] : p[-si];
  return lorenzo(p, i, j, k, si, sj, sk);
}

// Walks a value stream's values in coding order (section 11.3): the nodes in node order (aliases
// take their target's values), component by component, each predicted by its component's predictor
// from the decoded values d (per node and component), then the extra points, each predicted by the
// mean of its cell's corners. codeOne(component, vertex, prediction, &value) codes one value; `ok()`
// is asked after each k-plane and at the end, and false stops the walk (returned).
template <class F, class Ok>
bool scanValues(const Scan& scan, uint32_t comps, const std::vector<Form>& forms, std::vector<double>& d, F&& codeOne,
                Ok&& ok) {
  const uint64_t nodes = uint64_t{scan.ni} * scan.nj * scan.nk;
  const uint64_t plane = uint64_t{scan.ni} * scan.nj * comps;
  // A prediction reads the node's own k-plane and the one before it; aliases and extra points read
  // any earlier node. Without them d holds two planes, k's in half k % 2 (it stays in cache).
  const bool two_planes = !scan.alias_target && scan.extra_cell_base.empty();
  resizePopulated(d, two_planes ? std::min<uint64_t>(2, scan.nk) * plane : nodes * comps);
  uint8_t predictors[64];
  const bool uniform_lorenzo = std::all_of(forms.begin(), forms.end(), [](const Form& f) { return f.predictor == 0; });
  for (uint32_t cc = 0; cc < comps && cc < 64; ++cc) predictors[cc] = forms[cc].predictor;
  const ptrdiff_t si = comps, sj = si * scan.ni;
  uint64_t v = 0, n = 0;
  for (uint32_t k = 0; k < scan.nk; ++k) {
    // From plane k to plane k - 1.
    const ptrdiff_t sk = two_planes && (k & 1) == 0 ? -static_cast<ptrdiff_t>(plane) : static_cast<ptrdiff_t>(plane);
    double* const at_plane = two_planes ? &d[(k & 1) * plane] : &d[k * plane];
    for (uint32_t j = 0; j < scan.nj; ++j) {
      for (uint32_t i = 0; i < scan.ni; ++i, ++n) {
        double* p = at_plane + (uint64_t{j} * scan.ni + i) * comps;
        if (scan.alias_target) {
          const uint32_t t = (*scan.alias_target)[n];
          if (t != kNoIndex) {
            std::memcpy(p, &d[uint64_t{t} * comps], comps * sizeof(double));
            continue;
          }
        }
        if (uniform_lorenzo) {
          for (uint32_t cc = 0; cc < comps; ++cc) codeOne(cc, v, lorenzo(p + cc, i, j, k, si, sj, sk), p + cc);
        } else {
          for (uint32_t cc = 0; cc < comps; ++cc)
            codeOne(cc, v, predict(cc < 64 ? predictors[cc] : forms[cc].predictor, p + cc, i, j, k, si, sj, sk),
                    p + cc);
        }
        ++v;
      }
    }
    if (!ok()) return false;
  }
  for (uint64_t base : scan.extra_cell_base) {
    for (uint32_t cc = 0; cc < comps; ++cc) {
      double sum = d[(base + scan.corner_offset[0]) * comps + cc];
      for (int q = 1; q < 8; ++q) sum += d[(base + scan.corner_offset[q]) * comps + cc];
      double value;
      codeOne(cc, v, sum / 8.0, &value);
    }
    ++v;
  }
  return ok();
}

// One value stream (GEOM or a PFLD): the form declarations of its `comps` components, then every
// vertex's values, component by component (section 11.3). Encoder: `src` holds vertex v's component
// c at src + v * src_stride + c * size; decoder: `dst` gets them at dst + (v * comps + c) * size.
// `d`: scratch for the decoded values by node (scanValues).
template <class C>
Status codeValueStream(C& c, ScalarType type, uint32_t comps, const Scan& scan, std::vector<Form>& forms,
                       const uint8_t* src, size_t src_stride, uint8_t* dst, std::vector<double>& d,
                       const std::string& what) {
  ValueCoder vc(type, comps);
  DeclarationModels dm;
  if constexpr (!C::kEncoding) forms.assign(comps, Form{});
  for (uint32_t cc = 0; cc < comps; ++cc)
    GTN_RETURN_IF_ERROR(declareForm(c, dm, vc, type, cc, forms[cc], scan.vertices, what));
  if (!c.ok()) return invalidData(what + " is truncated or corrupt in its declarations");
  const size_t size = scalarSize(type);
  uint8_t tmp[8];
  auto codeOne = [&](uint32_t cc, uint64_t v, double pred, double* out) {
    const uint64_t pk = keyFromPrediction(type, pred);
    uint64_t actual = 0;
    if constexpr (C::kEncoding) actual = keyFromRaw(type, src + v * src_stride + cc * size);
    const uint64_t key = vc.code(c, cc, pk, actual);
    uint8_t* raw = C::kEncoding ? tmp : dst + (v * comps + cc) * size;
    rawFromKey(type, key, raw);
    *out = doubleFromRaw(type, raw);
  };
  if (!scanValues(scan, comps, forms, d, codeOne, [&] { return c.ok(); }))
    return invalidData(what + " is truncated or corrupt");
  return Status::ok();
}

// ---- Form 1: static canonical prefix codes (section 12.2) --------------------------------------------

// Bits least significant first, in 64-bit little-endian words (the stream is padded with zero bits
// to a whole word).
class BitWriter {
 public:
  explicit BitWriter(std::vector<uint8_t>* out) : out_(out) {}
  // n <= 64 bits of v.
  void put(uint64_t v, int n) {
    if (n > 32) {
      put(v & 0xFFFFFFFFu, 32);
      put(v >> 32, n - 32);
      return;
    }
    if (n == 0) return;
    acc_ |= (v & ((uint64_t{1} << n) - 1)) << fill_;
    fill_ += n;
    while (fill_ >= 8) {
      out_->push_back(static_cast<uint8_t>(acc_));
      acc_ >>= 8;
      fill_ -= 8;
    }
  }
  void finish() {
    if (fill_ > 0) out_->push_back(static_cast<uint8_t>(acc_));
    acc_ = 0;
    fill_ = 0;
    while (out_->size() % 8 != start_ % 8) out_->push_back(0);
  }

 private:
  std::vector<uint8_t>* out_;
  size_t start_ = out_->size();
  uint64_t acc_ = 0;
  int fill_ = 0;
};

class BitReader {
 public:
  explicit BitReader(std::span<const uint8_t> in) : p_(in.data()), size_(in.size()) {}
  // At least 56 bits in the buffer (zeros past the end, counted as an overrun).
  [[gnu::always_inline]] void refill() {
    if (pos_ + 8 <= size_) [[likely]] {
      uint64_t w;
      std::memcpy(&w, p_ + pos_, 8);
      buf_ |= w << avail_;
      pos_ += (63 - avail_) >> 3;
      avail_ |= 56;
      return;
    }
    while (avail_ <= 56) {
      const uint64_t b = pos_ < size_ ? p_[pos_] : 0;
      ++pos_;
      buf_ |= b << avail_;
      avail_ += 8;
    }
  }
  uint64_t peek() const { return buf_; }
  void skip(int n) {
    buf_ >>= n;
    avail_ -= n;
  }
  // n <= 56 bits (after a refill).
  [[gnu::always_inline]] uint64_t take(int n) {
    const uint64_t v = buf_ & ((uint64_t{1} << n) - 1);
    skip(n);
    return v;
  }
  uint64_t get(int n) {
    if (n > 32) {
      const uint64_t lo = get(32);
      return lo | (get(n - 32) << 32);
    }
    refill();
    return take(n);
  }
  // Bits consumed so far.
  uint64_t consumed() const { return uint64_t{pos_} * 8 - static_cast<uint64_t>(avail_); }
  // Every value read inside the stream, and what is left a zero padding of less than a word.
  bool finishedCleanly() {
    const uint64_t used = consumed(), total = uint64_t{size_} * 8;
    if (used > total || total - used >= 64 || size_ % 8 != 0) return false;
    const int rest = static_cast<int>(total - used);
    refill();
    return take(rest) == 0;
  }
  bool overrun() const { return consumed() > uint64_t{size_} * 8; }

 private:
  const uint8_t* p_;
  size_t size_, pos_ = 0;
  uint64_t buf_ = 0;
  int avail_ = 0;
};

constexpr int kMaxCodeLength = 15;
constexpr int kTableBits = 11;

// Huffman code lengths (at most kMaxCodeLength) of the symbols with nonzero frequency.
std::vector<uint8_t> codeLengths(std::vector<uint64_t> freq) {
  const size_t n = freq.size();
  std::vector<uint8_t> len(n, 0);
  std::vector<size_t> used;
  for (size_t s = 0; s < n; ++s)
    if (freq[s]) used.push_back(s);
  if (used.size() == 1) len[used[0]] = 1;
  if (used.size() <= 1) return len;
  for (;;) {
    // Two-queue Huffman over the used symbols sorted by frequency.
    std::vector<size_t> order = used;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return freq[a] < freq[b]; });
    struct Node {
      uint64_t w;
      int32_t left, right;  // children (node indices), or -1 - symbol for leaves
    };
    std::vector<Node> nodes;
    for (size_t s : order) nodes.push_back({freq[s], -1 - static_cast<int32_t>(s), 0});
    size_t leaf = 0, inner = order.size();
    auto take = [&]() {
      if (leaf < order.size() && (inner >= nodes.size() || nodes[leaf].w <= nodes[inner].w)) return leaf++;
      return inner++;
    };
    while ((order.size() - leaf) + (nodes.size() - inner) > 1) {
      const size_t a = take(), b = take();
      nodes.push_back({nodes[a].w + nodes[b].w, static_cast<int32_t>(a), static_cast<int32_t>(b)});
    }
    // Depths from the root (the last node).
    std::vector<uint8_t> depth(nodes.size(), 0);
    int deepest = 0;
    for (size_t x = nodes.size(); x-- > order.size();) {
      for (int32_t child : {nodes[x].left, nodes[x].right}) {
        depth[static_cast<size_t>(child)] = static_cast<uint8_t>(depth[x] + 1);
        deepest = std::max<int>(deepest, depth[x] + 1);
      }
    }
    if (deepest <= kMaxCodeLength) {
      for (size_t x = 0; x < order.size(); ++x) len[static_cast<size_t>(-1 - nodes[x].left)] = depth[x];
      return len;
    }
    for (size_t s : used) freq[s] = (freq[s] + 1) / 2;  // flatten and retry
  }
}

// A canonical prefix code: codes (bit-reversed, for least-significant-first reading) and the
// decoder's table of kTableBits bits with a slow path for longer codes.
struct PrefixCode {
  std::vector<uint8_t> len;
  std::vector<uint32_t> code;   // reversed
  int single = -1;              // the only symbol, coded in no bits
  std::vector<uint16_t> table;  // entry: symbol << 4 | length, 0 = longer than kTableBits
  uint16_t count[kMaxCodeLength + 1] = {};
  std::vector<uint16_t> sorted;  // symbols by (length, symbol)

  // False for lengths that are not a complete code (or a single symbol).
  bool build(bool decoder) {
    const size_t n = len.size();
    std::fill(std::begin(count), std::end(count), 0);
    size_t used = 0;
    for (size_t s = 0; s < n; ++s) {
      if (len[s] > kMaxCodeLength) return false;
      if (len[s]) ++count[len[s]], ++used, single = static_cast<int>(s);
    }
    if (used == 0) return false;
    if (used == 1) return len[static_cast<size_t>(single)] == 1;  // a single symbol: length 1, coded in no bits
    single = -1;
    uint64_t kraft = 0;
    for (int l = 1; l <= kMaxCodeLength; ++l) kraft += uint64_t{count[l]} << (kMaxCodeLength - l);
    if (kraft != (uint64_t{1} << kMaxCodeLength)) return false;
    uint32_t next[kMaxCodeLength + 2] = {};
    for (int l = 1; l <= kMaxCodeLength; ++l) next[l + 1] = (next[l] + count[l]) << 1;
    code.assign(n, 0);
    sorted.clear();
    for (int l = 1; l <= kMaxCodeLength; ++l)
      for (size_t s = 0; s < n; ++s)
        if (len[s] == l) sorted.push_back(static_cast<uint16_t>(s));
    for (size_t s = 0; s < n; ++s) {
      if (!len[s]) continue;
      const uint32_t c = next[len[s]]++;
      uint32_t r = 0;
      for (int b = 0; b < len[s]; ++b) r |= ((c >> b) & 1) << (len[s] - 1 - b);
      code[s] = r;
    }
    if (decoder) {
      table.assign(size_t{1} << kTableBits, 0);
      for (size_t s = 0; s < n; ++s) {
        if (!len[s] || len[s] > kTableBits) continue;
        const uint16_t entry = static_cast<uint16_t>(s << 4 | len[s]);
        for (uint32_t x = code[s]; x < table.size(); x += 1u << len[s]) table[x] = entry;
      }
    }
    return true;
  }
  // Reads one symbol (the reader refilled).
  [[gnu::always_inline]] uint32_t read(BitReader& r) const {
    if (single >= 0) return static_cast<uint32_t>(single);
    const uint16_t e = table[r.peek() & ((1u << kTableBits) - 1)];
    if (e) [[likely]] {
      r.skip(e & 15);
      return e >> 4;
    }
    // Canonical decoding, one bit at a time (codes longer than the table).
    uint32_t c = 0, first = 0, index = 0;
    for (int l = 1; l <= kMaxCodeLength; ++l) {
      c |= static_cast<uint32_t>(r.take(1));
      if (c - first < count[l]) return sorted[index + (c - first)];
      index += count[l];
      first = (first + count[l]) << 1;
      c <<= 1;
    }
    return 0;  // unreachable for a complete code
  }
};

// A component's coding domain in form 1: the width of its residuals, how keys map to it, and its
// alphabet: the 4w − 1 value symbols (valueSymbol), an escape (decimal form), then kRunSymbols run
// symbols.
constexpr int kRunSymbols = 31;  // runs of 2^(b - 1) .. 2^b - 1 zero residuals, b = 2..32
struct Form1Domain {
  int w = 0;  // residual width
  int shift = 0;
  bool escape = false;  // decimal: an escape symbol 2w + 1, then the value's residual at the full width
  uint32_t escapeSymbol() const { return 4 * static_cast<uint32_t>(w) - 1; }
  uint32_t runBase() const { return escapeSymbol() + (escape ? 1 : 0); }
  size_t symbols() const { return runBase() + kRunSymbols; }
};

// Whether form 1 can code `f` (it has no per-value escape bit for printed-single values or a shift
// with exceptions), and its domain.
bool form1Domain(ScalarType type, const Form& f, Form1Domain* d) {
  if (f.printed > 0 || f.exceptions) return false;
  if (!f.table.empty()) {
    d->w = std::max(1, bitLength(f.table.size() - 1));
  } else if (f.decimals >= 0) {
    d->w = 64;
    d->escape = true;
  } else {
    d->shift = static_cast<int>(f.shift);
    d->w = scalarBits(type) - d->shift;
  }
  return true;
}

// A residual's value symbol, from its bucket s of 12.1 and magnitude: s for s <= 2 (zero, +1, −1),
// else 3 + 4 (b − 2) + 2 (1 if negative) + the bit below the leading one, b = bitlen(|r|) >= 2.
[[gnu::always_inline]] inline uint32_t valueSymbol(uint32_t s, uint64_t mag) {
  if (s <= 2) return s;
  const uint32_t b = (s + 1) >> 1, negative = (s & 1) ^ 1;
  return 3 + 4 * (b - 2) + 2 * negative + static_cast<uint32_t>((mag >> (b - 2)) & 1);
}

// The bit length of the residual a value symbol codes (w + 1 for the escape).
[[gnu::always_inline]] inline uint32_t symbolBits(uint32_t symbol) {
  return symbol < 3 ? (symbol + 1) >> 1 : ((symbol - 3) >> 2) + 2;
}

// The context class of a component's next value: ⌊(b′ + b″) / 4⌋ capped at 15, b′ the bit length of
// the previous value's residual and b″ that of the value ni values before it in the component's
// order (0 where there is none or it was in a run), or kRunClass right after a run.
constexpr uint32_t kAfterRun = 0xFF;  // `last` after a run
constexpr uint32_t kRunClass = 16;
constexpr uint32_t kEscapeClass = 17;  // the code of an escaped value's full-width residual
constexpr int kForm1Classes = 18;
[[gnu::always_inline]] inline uint32_t form1Class(uint32_t last, uint32_t up) {
  return last == kAfterRun ? kRunClass : std::min((last + up) >> 2, 15u);
}

// The residual of key `k` against `p` (both w bits wide) as its symbol and raw bits.
[[gnu::always_inline]] inline uint32_t residualSymbol(uint64_t k, uint64_t p, int w, uint64_t* mag_out) {
  const uint64_t mask = w == 64 ? ~uint64_t{0} : (uint64_t{1} << w) - 1;
  const uint64_t r = (k - p) & mask;
  if (r == 0) return *mag_out = 0, 0;
  const uint64_t half = uint64_t{1} << (w - 1);
  const bool negative = r >= half;
  const uint64_t mag = negative ? ((~r + 1) & mask) : r;
  *mag_out = mag;
  const uint32_t b = static_cast<uint32_t>(bitLength(mag == 0 ? half : mag));
  return 2 * b - (negative ? 0 : 1);
}

// The prediction in a component's form-1 domain.
[[gnu::always_inline]] inline uint64_t domainPrediction(ScalarType type, const Form& f, const Form1Domain& dom,
                                                        uint64_t pred_key) {
  if (!f.table.empty()) {
    const std::vector<uint64_t>& t = f.table;
    size_t at = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), pred_key) - t.begin());
    if (at == t.size() || (at > 0 && pred_key - t[at - 1] <= t[at] - pred_key)) --at;
    return at;
  }
  if (f.decimals >= 0) {
    uint8_t raw[8];
    rawFromKey(type, pred_key, raw);
    const double np =
        value_detail::clampRound(doubleFromRaw(type, raw) * kPowersOfTen[f.decimals], -kDecimalLimit, kDecimalLimit);
    return static_cast<uint64_t>(static_cast<int64_t>(np)) ^ (uint64_t{1} << 63);
  }
  return pred_key >> dom.shift;
}

// One value of a component as the encoder sees it: its symbol (bucket or escape) and raw bits (the
// magnitude; for an escape, the full-width residual's bucket and magnitude).
struct Form1Token {
  uint64_t mag = 0;
  uint16_t symbol = 0;
  uint16_t escape_symbol = 0;  // the value symbol of an escaped value's residual at the full width
};

// The runs of a component's tokens (per value: the length of the run of zero residuals that starts
// there and is coded as one run symbol, else 0) when every run of at least `min_run` zeros is one.
void markRuns(const std::vector<Form1Token>& tokens, uint64_t min_run, std::vector<uint32_t>* runs) {
  runs->assign(tokens.size(), 0);
  for (size_t v = 0; v < tokens.size();) {
    if (tokens[v].symbol != 0) {
      ++v;
      continue;
    }
    size_t end = v;
    while (end < tokens.size() && tokens[end].symbol == 0 && end - v < 0xFFFFFFFFu) ++end;
    if (end - v >= min_run) (*runs)[v] = static_cast<uint32_t>(end - v);
    v = end;
  }
}

// The symbol frequencies per class of a component's tokens with `runs`.
std::vector<std::vector<uint64_t>> form1Frequencies(const std::vector<Form1Token>& tokens,
                                                    const std::vector<uint32_t>& runs, const Form1Domain& dom,
                                                    size_t ni, uint64_t* run_bits) {
  std::vector<std::vector<uint64_t>> freq(kForm1Classes, std::vector<uint64_t>(dom.symbols(), 0));
  uint32_t last = 0;
  *run_bits = 0;
  for (size_t v = 0; v < tokens.size();) {
    if (runs[v]) {
      const int b = bitLength(runs[v]);
      ++freq[form1Class(last, v >= ni ? symbolBits(tokens[v - ni].symbol) : 0)]
            [dom.runBase() + static_cast<uint32_t>(b - 2)];
      *run_bits += static_cast<uint64_t>(b - 1);
      last = kAfterRun;
      v += runs[v];
      continue;
    }
    ++freq[form1Class(last, v >= ni ? symbolBits(tokens[v - ni].symbol) : 0)][tokens[v].symbol];
    if (dom.escape && tokens[v].symbol == dom.escapeSymbol()) ++freq[kEscapeClass][tokens[v].escape_symbol];
    last = symbolBits(tokens[v].symbol);
    ++v;
  }
  return freq;
}

// The bits of a component's code length lists and symbol codes (raw bits of the buckets aside).
uint64_t form1CodeBits(const std::vector<std::vector<uint64_t>>& freq, uint64_t run_bits) {
  uint64_t total = run_bits;
  for (const auto& f : freq) {
    total += 1;
    const std::vector<uint8_t> len = codeLengths(f);
    size_t listed = len.size();
    while (listed > 0 && len[listed - 1] == 0) --listed;
    if (listed == 0) continue;
    total += 9;
    for (size_t s = 0; s < listed;) {
      size_t step = 1;
      if (!len[s])
        while (s + step < listed && !len[s + step] && step < 32) ++step;
      total += len[s] ? 5 : 6;
      s += step;
    }
    size_t used = 0;
    for (size_t s = 0; s < f.size(); ++s) used += f[s] != 0;
    if (used > 1)
      for (size_t s = 0; s < f.size(); ++s) total += f[s] * len[s];
  }
  return total;
}

// Form 1's value stream: declarations, code lengths and values (see encodeForm1 / decodeForm1).
// False when a component's form has no form-1 coding.
bool encodeForm1(ScalarType type, uint32_t comps, const Scan& scan, const std::vector<Form>& forms, const uint8_t* src,
                 size_t stride, std::vector<double>& d, std::vector<uint8_t>* out) {
  const size_t size = scalarSize(type);
  const int width = scalarBits(type);
  std::vector<Form1Domain> dom(comps);
  for (uint32_t cc = 0; cc < comps; ++cc)
    if (!form1Domain(type, forms[cc], &dom[cc])) return false;
  // Pass 1: every value's token, per component in value order.
  std::vector<std::vector<Form1Token>> tokens(comps);
  for (auto& t : tokens) t.reserve(scan.vertices);
  auto tokenize = [&](uint32_t cc, uint64_t v, double pred, double* value) {
    const Form& f = forms[cc];
    const uint64_t key = keyFromRaw(type, src + v * stride + cc * size);
    const uint64_t pk = keyFromPrediction(type, pred);
    const uint64_t p = domainPrediction(type, f, dom[cc], pk);
    Form1Token t;
    uint64_t k;
    if (!f.table.empty()) {
      k = static_cast<uint64_t>(std::lower_bound(f.table.begin(), f.table.end(), key) - f.table.begin());
    } else if (f.decimals >= 0) {
      int64_t n = 0;
      if (!decimalInteger(type, key, f.decimals, &n)) {
        t.symbol = static_cast<uint16_t>(dom[cc].escapeSymbol());
        const uint32_t bucket = residualSymbol(key, pk, width, &t.mag);
        t.escape_symbol = static_cast<uint16_t>(valueSymbol(bucket, t.mag));
        tokens[cc].push_back(t);
        *value = doubleFromRaw(type, src + v * stride + cc * size);
        return;
      }
      k = static_cast<uint64_t>(n) ^ (uint64_t{1} << 63);
    } else {
      k = key >> dom[cc].shift;
    }
    const uint32_t bucket = residualSymbol(k, p, dom[cc].w, &t.mag);
    t.symbol = static_cast<uint16_t>(valueSymbol(bucket, t.mag));
    tokens[cc].push_back(t);
    *value = doubleFromRaw(type, src + v * stride + cc * size);
  };
  scanValues(scan, comps, forms, d, tokenize, [] { return true; });
  // Per component, the shortest run threshold by measurement (none: no run symbol).
  std::vector<std::vector<uint32_t>> runs(comps);
  std::vector<PrefixCode> codes(size_t{comps} * kForm1Classes);
  for (uint32_t cc = 0; cc < comps; ++cc) {
    uint64_t best = std::numeric_limits<uint64_t>::max();
    std::vector<uint32_t> trial;
    for (uint64_t min_run :
         {uint64_t{2}, uint64_t{3}, uint64_t{4}, uint64_t{8}, uint64_t{16}, uint64_t{32}, uint64_t{1} << 32}) {
      markRuns(tokens[cc], min_run, &trial);
      uint64_t run_bits = 0;
      const uint64_t bits = form1CodeBits(form1Frequencies(tokens[cc], trial, dom[cc], scan.ni, &run_bits), run_bits);
      if (bits < best) best = bits, runs[cc] = trial;
    }
    uint64_t run_bits = 0;
    const auto freq = form1Frequencies(tokens[cc], runs[cc], dom[cc], scan.ni, &run_bits);
    for (int k = 0; k < kForm1Classes; ++k) {
      PrefixCode& pc = codes[cc * kForm1Classes + k];
      pc.len = codeLengths(freq[k]);
      if (std::any_of(pc.len.begin(), pc.len.end(), [](uint8_t l) { return l != 0; })) pc.build(false);
    }
  }
  // Pass 2: the stream.
  BitWriter w(out);
  for (uint32_t cc = 0; cc < comps; ++cc) {
    const Form& f = forms[cc];
    w.put(f.predictor, 2);
    w.put(!f.table.empty(), 1);
    if (!f.table.empty()) {
      const uint64_t last = f.table.size() - 1;
      w.put(static_cast<uint64_t>(bitLength(last)), 6);
      w.put(last, bitLength(last));
      for (uint64_t key : f.table) w.put(key, width);
    } else {
      if (isFloatType(type)) {
        w.put(f.decimals >= 0, 1);
        if (f.decimals >= 0) w.put(static_cast<uint64_t>(f.decimals), 5);
        if (type == ScalarType::kFloat64 && f.decimals < 0) w.put(0, 1);  // printed: never in form 1
      }
      if (f.decimals < 0) {
        w.put(f.shift > 0, 1);
        if (f.shift > 0) w.put(f.shift, 6), w.put(0, 1);  // no exceptions in form 1
      }
    }
    for (int k = 0; k < kForm1Classes; ++k) {
      const PrefixCode& pc = codes[cc * kForm1Classes + k];
      size_t listed = pc.len.size();
      while (listed > 0 && pc.len[listed - 1] == 0) --listed;
      w.put(listed > 0, 1);
      if (listed == 0) continue;
      w.put(listed, 9);
      for (size_t s = 0; s < listed;) {
        w.put(pc.len[s] != 0, 1);
        if (pc.len[s]) {
          w.put(pc.len[s++], 4);
          continue;
        }
        size_t unused = 1;  // up to 32 unused symbols in 5 bits
        while (s + unused < listed && !pc.len[s + unused] && unused < 32) ++unused;
        w.put(unused - 1, 5);
        s += unused;
      }
    }
  }
  std::vector<uint32_t> last(comps, 0);
  std::vector<uint64_t> skip(comps, 0);
  auto write = [&](uint32_t cc, uint64_t v, double, double* value) {
    *value = doubleFromRaw(type, src + v * stride + cc * size);
    if (skip[cc] > 0) {
      --skip[cc];
      return;
    }
    const uint32_t up = v >= scan.ni ? symbolBits(tokens[cc][v - scan.ni].symbol) : 0;
    const PrefixCode& pc = codes[cc * kForm1Classes + form1Class(last[cc], up)];
    if (const uint32_t run = runs[cc][v]) {
      const int b = bitLength(run);
      const uint32_t s = dom[cc].runBase() + static_cast<uint32_t>(b - 2);
      if (pc.single < 0) w.put(pc.code[s], pc.len[s]);
      w.put(run, b - 1);  // below the leading one
      skip[cc] = run - 1;
      last[cc] = kAfterRun;
      return;
    }
    const Form1Token& t = tokens[cc][v];
    const uint32_t s = t.symbol;
    if (pc.single < 0) w.put(pc.code[s], pc.len[s]);
    last[cc] = symbolBits(s);
    uint32_t raw_symbol = s;
    if (dom[cc].escape && s == dom[cc].escapeSymbol()) {
      const PrefixCode& ec = codes[cc * kForm1Classes + kEscapeClass];
      raw_symbol = t.escape_symbol;
      if (ec.single < 0) w.put(ec.code[raw_symbol], ec.len[raw_symbol]);
    }
    if (raw_symbol >= 3)
      w.put(t.mag, static_cast<int>((raw_symbol - 3) >> 2));  // below the leading one and the next (put masks them off)
  };
  scanValues(scan, comps, forms, d, write, [] { return true; });
  w.finish();
  return true;
}

Status decodeForm1(std::span<const uint8_t> in, ScalarType type, uint32_t comps, const Scan& scan, uint8_t* dst,
                   std::vector<double>& d, const std::string& what) {
  BitReader r(in);
  const size_t size = scalarSize(type);
  const int width = scalarBits(type);
  const uint64_t width_mask = width == 64 ? ~uint64_t{0} : (uint64_t{1} << width) - 1;
  std::vector<Form> forms(comps);
  std::vector<Form1Domain> dom(comps);
  std::vector<PrefixCode> codes(size_t{comps} * kForm1Classes);
  auto bad = [&](const std::string& reason) { return invalidData(what + " (form 1): " + reason); };
  for (uint32_t cc = 0; cc < comps; ++cc) {
    Form& f = forms[cc];
    const std::string comp = "component " + std::to_string(cc);
    f.predictor = static_cast<uint8_t>(r.get(2));
    if (f.predictor > 2) return bad(comp + " declares the reserved predictor 3");
    if (r.get(1)) {
      const int length = static_cast<int>(r.get(6));
      if (length > 32) return bad(comp + " declares a table of more than 2^32 values");
      const uint64_t entries = r.get(length) + 1;
      if (entries > scan.vertices || entries * static_cast<uint64_t>(width) > in.size() * 8)
        return bad(comp + " declares a value table longer than its values or its stream");
      f.table.resize(entries);
      for (uint64_t x = 0; x < entries; ++x) {
        f.table[x] = r.get(width);
        if (x > 0 && f.table[x] <= f.table[x - 1]) return bad(comp + " declares a value table that is not ascending");
      }
    } else {
      if (isFloatType(type)) {
        if (r.get(1)) {
          f.decimals = static_cast<int>(r.get(5));
          if (f.decimals > ValueCoder::kMaxDecimals) return bad(comp + " declares more than 22 decimal places");
        } else if (type == ScalarType::kFloat64 && r.get(1)) {
          return bad(comp + " declares the printed-single form, which form 1 does not code");
        }
      }
      if (f.decimals < 0 && r.get(1)) {
        f.shift = static_cast<uint32_t>(r.get(6));
        if (f.shift == 0 || f.shift >= static_cast<uint32_t>(width)) return bad(comp + " declares an invalid shift");
        if (r.get(1)) return bad(comp + " declares a shift with exceptions, which form 1 does not code");
      }
    }
    form1Domain(type, f, &dom[cc]);
    for (int k = 0; k < kForm1Classes; ++k) {
      PrefixCode& pc = codes[cc * kForm1Classes + k];
      if (!r.get(1)) continue;
      const size_t listed = static_cast<size_t>(r.get(9));
      if (listed == 0 || listed > dom[cc].symbols())
        return bad(comp + " lists " + std::to_string(listed) + " code lengths in class " + std::to_string(k) +
                   " (1 to " + std::to_string(dom[cc].symbols()) + ")");
      pc.len.assign(dom[cc].symbols(), 0);
      for (size_t s = 0; s < listed;) {
        if (!r.get(1)) {
          s += static_cast<size_t>(r.get(5)) + 1;  // unused symbols
          if (s >= listed)
            return bad(comp + " lists code lengths in class " + std::to_string(k) + " that end with an unused symbol");
          continue;
        }
        pc.len[s] = static_cast<uint8_t>(r.get(4));
        if (pc.len[s] == 0) return bad(comp + " gives a used symbol the code length 0 in class " + std::to_string(k));
        ++s;
      }
      if (!pc.build(true)) return bad(comp + " declares code lengths that are not a complete prefix code");
    }
    if (r.overrun()) return bad("truncated in its declarations");
  }
  std::vector<uint32_t> last(comps, 0);
  std::vector<uint64_t> run(comps, 0);  // zero residuals still to come in the current run
  // Per component, the bit lengths of its last ni residuals (a ring; `at` the oldest).
  const size_t ni = scan.ni;
  std::vector<uint8_t> ring(size_t{comps} * ni, 0);
  std::vector<size_t> at(comps, 0);
  bool corrupt = false;
  // The scan for the value type `type_c` (a std::integral_constant for the common float types, so
  // that the conversions' switches on the type fold away; the runtime type otherwise).
  auto scanAs = [&](auto type_c) -> bool {
    const ScalarType type = type_c;
    const size_t vsize = type == ScalarType::kFloat32 ? 4 : type == ScalarType::kFloat64 ? 8 : size;
    // Inlined into the scan's loop: GCC leaves it a call per value otherwise (about a seventh of the decode).
    auto decodeOne = [&](uint32_t cc, uint64_t v, double pred, double* value) __attribute__((always_inline)) {
      const Form& f = forms[cc];
      const Form1Domain& dm = dom[cc];
      uint8_t* raw = dst + (v * comps + cc) * vsize;
      uint64_t k;
      uint8_t& up = ring[cc * ni + at[cc]];
      at[cc] = at[cc] + 1 == ni ? 0 : at[cc] + 1;
      if (run[cc] > 0) {
        --run[cc];
        up = 0;
        k = domainPrediction(type, f, dm, keyFromPrediction(type, pred));
      } else {
        const PrefixCode& pc = codes[cc * kForm1Classes + form1Class(last[cc], up)];
        r.refill();
        if (pc.len.empty()) [[unlikely]] {
          corrupt = true;
          std::memset(raw, 0, size);
          *value = 0;
          return;
        }
        const uint32_t s = pc.read(r);
        const uint64_t pk = keyFromPrediction(type, pred);
        k = domainPrediction(type, f, dm, pk);
        if (s >= dm.runBase()) {
          const int b = static_cast<int>(s - dm.runBase()) + 2;
          run[cc] = ((uint64_t{1} << (b - 1)) | r.take(b - 1)) - 1;
          last[cc] = kAfterRun;
          up = 0;
        } else {
          last[cc] = symbolBits(s);
          up = static_cast<uint8_t>(last[cc]);
          if (dm.escape && s == dm.escapeSymbol()) {
            // The value's key as a residual against the prediction's at the full width, its value
            // symbol in the escape class's code.
            const PrefixCode& ec = codes[cc * kForm1Classes + kEscapeClass];
            uint64_t key = pk;
            r.refill();
            const uint32_t e = ec.len.empty() ? 0 : ec.read(r);
            if (ec.len.empty() || e >= 4 * static_cast<uint32_t>(width) - 1) {
              corrupt = true;
            } else if (e > 0) {
              uint64_t mag = 1;
              bool negative = e == 2;
              if (e >= 3) {
                const int below = static_cast<int>((e - 3) >> 2);
                negative = ((e - 3) >> 1) & 1;
                mag = (uint64_t{2 | ((e - 3) & 1)} << below) | r.get(below);
              }
              key = (negative ? pk - mag : pk + mag) & width_mask;
            }
            rawFromKey(type, key, raw);
            *value = doubleFromRaw(type, raw);
            return;
          }
          if (s > 0) {
            uint64_t mag = 1;
            bool negative = s == 2;
            if (s >= 3) {
              const uint32_t x = s - 3;
              const int below = static_cast<int>(x >> 2);  // b − 2 raw bits
              negative = (x >> 1) & 1;
              mag = (uint64_t{2 | (x & 1)} << below) | (below <= 40 ? r.take(below) : r.get(below));
            }
            k = negative ? k - mag : k + mag;
            if (dm.w < 64) k &= (uint64_t{1} << dm.w) - 1;
          }
        }
      }
      uint64_t key;
      if (!f.table.empty()) {
        if (k >= f.table.size()) corrupt = true, k = 0;
        key = f.table[k];
      } else if (f.decimals >= 0) {
        decimalValue(type, static_cast<int64_t>(k ^ (uint64_t{1} << 63)), f.decimals, raw);
        key = keyFromRaw(type, raw);
      } else {
        const int z = dm.shift;
        const bool ones = z > 0 && isFloatType(type) && ((k >> (dm.w - 1)) & 1) == 0;
        key = (k << z) | (ones ? (uint64_t{1} << z) - 1 : 0);
      }
      rawFromKey(type, key, raw);
      *value = doubleFromRaw(type, raw);
    };
    return scanValues(scan, comps, forms, d, decodeOne, [&] { return !corrupt && !r.overrun(); });
  };
  struct RuntimeType {
    ScalarType t;
    operator ScalarType() const { return t; }
  };
  const bool scanned = type == ScalarType::kFloat32 ? scanAs(std::integral_constant<ScalarType, ScalarType::kFloat32>{})
                       : type == ScalarType::kFloat64
                           ? scanAs(std::integral_constant<ScalarType, ScalarType::kFloat64>{})
                           : scanAs(RuntimeType{type});
  if (!scanned) return bad("truncated or corrupt (a value beyond its code or its table, or past the end)");
  for (uint32_t cc = 0; cc < comps; ++cc)
    if (run[cc] > 0)
      return bad("component " + std::to_string(cc) + " has a run of zero residuals " + std::to_string(run[cc]) +
                 " values longer than its values");
  if (!r.finishedCleanly()) return bad("corrupt, truncated or has trailing bytes");
  return Status::ok();
}

// Candidate forms of one component (vertex values `n`, `stride` bytes apart): the shift of its
// trailing zeros, and where a sample suggests them, a decimal, printed-single, shift-with-exceptions
// or table form. The encoder measures each.
std::vector<Form> candidateForms(ScalarType type, const uint8_t* p, size_t n, size_t stride) {
  std::vector<Form> out;
  const int width = scalarBits(type);
  int z = width - 1;
  std::vector<int> zeros_hist(65, 0);
  for (size_t i = 0; i < n; ++i) {
    const int t = std::min(ValueCoder::trailingZeros(type, p + i * stride), width - 1);
    z = std::min(z, t);
    ++zeros_hist[t];
  }
  out.push_back(Form{-1, 0, static_cast<uint32_t>(n ? z : 0)});
  if (n < 16) return out;
  // A larger shift that at least 90% of the values allow.
  {
    size_t at_least = 0;
    for (int s = width - 1; s > z; --s) {
      at_least += zeros_hist[s];
      if (at_least * 10 >= n * 9) {
        out.push_back(Form{-1, 0, static_cast<uint32_t>(s), true});
        break;
      }
    }
  }
  const size_t samples = std::min<size_t>(n, 512);
  auto sampleAt = [&](size_t s) { return n <= 512 ? s : (s * 2654435761u) % n; };
  if (isFloatType(type)) {
    int hist[ValueCoder::kMaxDecimals + 1] = {};
    size_t decimal = 0;
    for (size_t s = 0; s < samples; ++s) {
      int64_t integer = 0;
      const int e = ValueCoder::decimalPlaces(type, keyFromRaw(type, p + sampleAt(s) * stride), &integer);
      if (e >= 0) ++hist[e], ++decimal;
    }
    if (decimal * 2 >= samples) {
      size_t acc = 0;
      for (int e = 0; e <= ValueCoder::kMaxDecimals; ++e) {
        acc += hist[e];
        if (acc * 10 >= decimal * 9) {
          out.push_back(Form{e, 0, 0});
          break;
        }
      }
    }
    if (type == ScalarType::kFloat64 && z < 29) {
      int count[ValueCoder::kMaxPrintedDigits] = {};
      uint64_t single = 0;
      for (size_t s = 0; s < samples; ++s) {
        const uint64_t key = keyFromRaw(type, p + sampleAt(s) * stride);
        for (int digits = std::max(1, shortestDigits(key)); digits < ValueCoder::kMaxPrintedDigits; ++digits)
          if (printedSingleKey(key, digits, &single)) {
            ++count[digits];
            break;
          }
      }
      int best = 0;
      for (int dgt = 1; dgt < ValueCoder::kMaxPrintedDigits; ++dgt)
        if (count[dgt] > count[best]) best = dgt;
      if (best > 0 && static_cast<size_t>(count[best]) * 2 >= samples) out.push_back(Form{-1, best, 0});
    }
  }
  // Few distinct values: a table.
  std::vector<uint64_t> keys;
  for (size_t s = 0; s < samples; ++s) keys.push_back(keyFromRaw(type, p + sampleAt(s) * stride));
  std::sort(keys.begin(), keys.end());
  if (static_cast<size_t>(std::unique(keys.begin(), keys.end()) - keys.begin()) * 2 <= samples) {
    keys.resize(n);
    for (size_t i = 0; i < n; ++i) keys[i] = keyFromRaw(type, p + i * stride);
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    if (keys.size() * 4 <= n) {
      Form f;
      f.table = std::move(keys);
      out.push_back(std::move(f));
    }
  }
  return out;
}

// ---- Cell fields -------------------------------------------------------------------------------------

struct CellScan {
  uint64_t ci, cj, ck;
  std::vector<uint32_t> first;  // per cell: its first tetrahedron; one more entry: the total
  bool per_cell;
};

// One cell field (section 11.5): the shift declarations of its components, then per item (cell or
// tetrahedron) 1.0 section 10.7's symbol over P, the move-to-front list and the grid neighbours.
// Values are per tetrahedron in `src` (encoder) and `dst` (decoder; the decoder fills every
// tetrahedron of a cell in per-cell mode).
template <class C>
Status codeCellField(C& c, const FieldDesc& desc, const CellScan& scan, const uint8_t* src, uint8_t* dst,
                     std::vector<Form>& forms, const std::string& what) {
  const ScalarType type = desc.type;
  const uint32_t comps = desc.components;
  const size_t size = scalarSize(type), item = desc.itemBytes();
  ValueCoder vc(type, comps);
  DeclarationModels dm;
  if constexpr (!C::kEncoding) forms.assign(comps, Form{});
  const uint64_t tets = scan.first.back();
  for (uint32_t cc = 0; cc < comps; ++cc) GTN_RETURN_IF_ERROR(declareForm(c, dm, vc, type, cc, forms[cc], tets, what));
  const uint8_t* vals = C::kEncoding ? src : dst;
  BitTree<4> symbol[9];
  uint32_t last_symbol = 0;
  std::vector<uint8_t> mtf(8 * item);
  uint32_t mtf_size = 0;
  std::vector<uint8_t> zero(item, 0);
  const uint8_t* prev_item = zero.data();
  const uint64_t cells = scan.ci * scan.cj * scan.ck;
  for (uint64_t cell = 0; cell < cells; ++cell) {
    const uint32_t begin = scan.first[cell], end = scan.first[cell + 1];
    if (begin == end) continue;
    const uint64_t i = cell % scan.ci, j = (cell / scan.ci) % scan.cj, k = cell / (scan.ci * scan.cj);
    const uint32_t places = scan.per_cell ? 1 : end - begin;
    for (uint32_t q = 0; q < places; ++q) {
      const uint64_t t = begin + q;
      // P and the neighbours.
      const uint8_t* P = prev_item;
      const uint8_t* nb[3];
      uint32_t n_nb = 0;
      auto cellItem = [&](bool exists, uint64_t other) -> const uint8_t* {
        if (!exists) return nullptr;
        const uint32_t b = scan.first[other], e = scan.first[other + 1];
        if (b + q >= e) return nullptr;
        return vals + (b + q) * item;
      };
      const uint8_t* cand[3];
      if (scan.per_cell) {
        if (const uint8_t* x = cellItem(i > 0, cell - 1)) P = x;
        cand[0] = cellItem(j > 0, cell - scan.ci);
        cand[1] = cellItem(k > 0, cell - scan.ci * scan.cj);
        cand[2] = cellItem(i > 0 && j > 0, cell - 1 - scan.ci);
      } else {
        cand[0] = cellItem(i > 0, cell - 1);
        cand[1] = cellItem(j > 0, cell - scan.ci);
        cand[2] = cellItem(k > 0, cell - scan.ci * scan.cj);
      }
      for (const uint8_t* x : cand) {
        if (!x || std::memcmp(x, P, item) == 0) continue;
        bool seen = false;
        for (uint32_t s = 0; s < n_nb; ++s) seen |= std::memcmp(x, nb[s], item) == 0;
        if (!seen) nb[n_nb++] = x;
      }
      const uint32_t ctx = 3 * std::min(last_symbol, 2u) + std::min(n_nb, 2u);
      uint32_t s = 15;
      if constexpr (C::kEncoding) {
        const uint8_t* value = src + t * item;
        if (std::memcmp(value, P, item) == 0) {
          s = 0;
        } else {
          for (uint32_t x = 0; x < n_nb && s == 15; ++x)
            if (std::memcmp(value, nb[x], item) == 0) s = 9 + x;
          for (uint32_t x = 0; x < mtf_size && s == 15; ++x)
            if (std::memcmp(value, &mtf[x * item], item) == 0) s = 1 + x;
        }
      }
      s = symbol[ctx].code(c, s);
      last_symbol = s;
      uint8_t* out = C::kEncoding ? nullptr : dst + t * item;
      uint8_t value_buf[64];
      uint8_t* value = C::kEncoding ? value_buf : out;
      if (item > sizeof value_buf && C::kEncoding)
        return invalidData(what + ": a cell field item of more than 64 bytes");
      if (s == 0) {
        std::memcpy(value, P, item);
      } else if (s <= 8) {
        if (s > mtf_size)
          return invalidData(what + " names entry " + std::to_string(s) + " of a shorter recent-value list");
        std::memcpy(value, &mtf[(s - 1) * item], item);
      } else if (s <= 11) {
        if (s - 9 >= n_nb) return invalidData(what + " names a grid neighbour the cell does not have");
        std::memcpy(value, nb[s - 9], item);
      } else if (s == 15) {
        for (uint32_t cc = 0; cc < comps; ++cc) {
          const uint64_t pk = keyFromRaw(type, P + cc * size);
          const uint64_t actual = C::kEncoding ? keyFromRaw(type, src + t * item + cc * size) : 0;
          rawFromKey(type, vc.code(c, cc, pk, actual), value + cc * size);
        }
      } else {
        return invalidData(what + " holds the reserved symbol " + std::to_string(s));
      }
      if constexpr (C::kEncoding) std::memcpy(value, src + t * item, item);
      // Move to front.
      uint32_t at = mtf_size;
      for (uint32_t x = 0; x < mtf_size; ++x)
        if (std::memcmp(&mtf[x * item], value, item) == 0) at = x;
      if (at == mtf_size && mtf_size < 8) ++mtf_size;
      if (at == 8) at = 7;
      std::memmove(&mtf[item], &mtf[0], at * item);
      std::memcpy(&mtf[0], value, item);
      if constexpr (!C::kEncoding) {
        if (scan.per_cell)
          for (uint64_t u = begin + 1; u < end; ++u) std::memcpy(dst + u * item, out, item);
      }
      prev_item = vals + t * item;
    }
    if (!c.ok()) return invalidData(what + " is truncated or corrupt");
  }
  if (!c.ok()) return invalidData(what + " is truncated or corrupt");
  return Status::ok();
}

CellScan cellScan(const GridLayout& layout) {
  const CellGeometry g(layout);
  CellScan s{g.ci, g.cj, g.ck, {}, layout.cell_values_per_cell};
  const uint64_t cells = layout.cells();
  s.first.resize(cells + 1);
  const uint32_t rule = layout.split;
  uint32_t t = 0;
  size_t x = 0;
  for (uint64_t cell = 0; cell < cells; ++cell) {
    s.first[cell] = t;
    if (x < layout.exceptions.size() && layout.exceptions[x].cell == cell) {
      t += static_cast<uint32_t>(layout.exceptions[x].tets.size());
      ++x;
    } else {
      t += rule;
    }
  }
  s.first[cells] = t;
  return s;
}

Scan valueScan(const GridLayout& layout, const std::vector<uint32_t>* alias_target) {
  const CellGeometry g(layout);
  Scan s{layout.dims[0], layout.dims[1], layout.dims[2], alias_target, {}, {}, layout.vertices()};
  for (int q = 0; q < 8; ++q) s.corner_offset[q] = g.cornerOffset(q);
  for (const GridException& x : layout.exceptions)
    for (int e = 0; e < x.extras; ++e) s.extra_cell_base.push_back(g.baseNode(x.cell));
  return s;
}

std::vector<uint32_t> aliasTargets(const GridLayout& layout) {
  std::vector<uint32_t> t;
  if (layout.aliases.empty()) return t;
  t.assign(layout.nodes(), kNoIndex);
  for (const auto& [a, target] : layout.aliases) t[a] = target;
  return t;
}

uint8_t flagsOf(const GridLayout& l) {
  return static_cast<uint8_t>((l.split == 5 ? (l.parity & 1) : 0) | (l.left_handed ? 2 : 0) |
                              (l.cell_values_per_cell ? 4 : 0));
}

void storeCoordinate(ScalarType type, double v, uint8_t* out) {
  if (type == ScalarType::kFloat32) {
    const float f = static_cast<float>(v);
    std::memcpy(out, &f, 4);
  } else {
    std::memcpy(out, &v, 8);
  }
}

}  // namespace

uint64_t GridLayout::extras() const {
  uint64_t n = 0;
  for (const GridException& x : exceptions) n += x.extras;
  return n;
}

uint64_t GridLayout::tets() const {
  uint64_t n = cells() * split;
  for (const GridException& x : exceptions) n = n - split + x.tets.size();
  return n;
}

std::span<const std::array<uint8_t, 4>> gridRuleTets(int split, bool odd) {
  if (split == 6) return kSix;
  return odd ? std::span<const std::array<uint8_t, 4>>(kFiveOdd) : std::span<const std::array<uint8_t, 4>>(kFiveEven);
}

Status checkGridLayout(const GridLayout& l, const std::string& what) {
  auto bad = [&](const std::string& reason) { return invalidData(what + ": " + reason); };
  for (int a = 0; a < 3; ++a)
    if (l.dims[a] < 2) return bad("a node count below 2");
  if (l.nodes() >= kPieceLimit) return bad("2^32 nodes or more");
  if (l.split != 5 && l.split != 6) return bad("split " + std::to_string(l.split) + " (5 or 6)");
  if (l.parity > 1 || (l.split == 6 && l.parity != 0)) return bad("a parity other than 0 or 1 (0 for split 6)");
  for (size_t a = 0; a < l.aliases.size(); ++a) {
    const auto [node, target] = l.aliases[a];
    if (node >= l.nodes() || target >= node || (a > 0 && node <= l.aliases[a - 1].first))
      return bad("alias " + std::to_string(a) + " is not (node, earlier node) in increasing node order");
  }
  for (size_t x = 0; x < l.exceptions.size(); ++x) {
    const GridException& e = l.exceptions[x];
    if (e.cell >= l.cells() || (x > 0 && e.cell <= l.exceptions[x - 1].cell))
      return bad("exception " + std::to_string(x) + " is not in increasing cell order inside the block");
    if (e.kind == GridException::kBlanked) {
      if (!e.tets.empty() || e.extras)
        return bad("blanked cell " + std::to_string(e.cell) + " lists tetrahedra or points");
      continue;
    }
    if (e.kind != GridException::kExplicit) return bad("exception " + std::to_string(x) + " of an unknown kind");
    if (e.tets.empty() || e.tets.size() > kMaxExplicitTets)
      return bad("explicit cell " + std::to_string(e.cell) + " with 0 or more than 31 tetrahedra");
    if (e.extras > kMaxExtras) return bad("explicit cell " + std::to_string(e.cell) + " adds more than 8 points");
    for (const auto& t : e.tets)
      for (int q = 0; q < 4; ++q) {
        if (t[q] >= 8 + e.extras)
          return bad("explicit cell " + std::to_string(e.cell) + " names a corner beyond its points");
        for (int p = 0; p < q; ++p)
          if (t[p] == t[q])
            return bad("explicit cell " + std::to_string(e.cell) + " has a tetrahedron that repeats a corner");
      }
  }
  if (l.tets() >= kPieceLimit) return bad("2^32 tetrahedra or more");
  return Status::ok();
}

namespace {
// Calls emit(tet) for each tetrahedron of the layout, in gridTets's order, until emit returns false;
// returns whether every call returned true.
template <class Emit>
bool forEachGridTet(const GridLayout& l, Emit&& emit) {
  const CellGeometry g(l);
  const std::vector<uint32_t> nv = nodeVertices(l);
  uint64_t off[8];
  for (int q = 0; q < 8; ++q) off[q] = g.cornerOffset(q);
  const int a2 = l.left_handed ? 3 : 2, a3 = l.left_handed ? 2 : 3;
  uint32_t next_extra = static_cast<uint32_t>(l.nodes() - l.aliases.size());
  size_t x = 0;
  uint64_t cell = 0;
  for (uint64_t k = 0; k < g.ck; ++k)
    for (uint64_t j = 0; j < g.cj; ++j)
      for (uint64_t i = 0; i < g.ci; ++i, ++cell) {
        const uint64_t base = i + g.ni * (j + g.nj * k);
        uint32_t corner[16];
        for (int q = 0; q < 8; ++q) corner[q] = nv.empty() ? static_cast<uint32_t>(base + off[q]) : nv[base + off[q]];
        if (x < l.exceptions.size() && l.exceptions[x].cell == cell) {
          const GridException& e = l.exceptions[x++];
          for (int q = 0; q < e.extras; ++q) corner[8 + q] = next_extra++;
          for (const auto& t : e.tets)
            if (!emit(Tet{corner[t[0]], corner[t[1]], corner[t[2]], corner[t[3]]})) return false;
          continue;
        }
        const bool odd = ((i + j + k + l.parity) & 1) != 0;
        for (const auto& t : gridRuleTets(l.split, odd))
          if (!emit(Tet{corner[t[0]], corner[t[1]], corner[t[a2]], corner[t[a3]]})) return false;
      }
  return true;
}

// Whether `tets` are the layout's, in its order (compared as they are made: nothing is held).
bool isGridTets(const GridLayout& l, const std::vector<Tet>& tets) {
  if (tets.size() != l.tets()) return false;
  size_t n = 0;
  return forEachGridTet(l, [&](const Tet& t) { return tets[n++] == t; });
}
}  // namespace

RuleGridTets::RuleGridTets(const GridLayout& l) {
  const CellGeometry g(l);
  tets_ = l.cells() * l.split;
  per_ = l.split;
  ci_ = g.ci;
  cj_ = g.cj;
  ni_ = g.ni;
  nj_ = g.nj;
  nk_ = g.nk;
  parity_ = l.parity;
  per_magic_ = magic(per_);
  ci_magic_ = magic(ci_);
  cj_magic_ = magic(cj_);
  const int a2 = l.left_handed ? 3 : 2, a3 = l.left_handed ? 2 : 3;
  for (int odd = 0; odd < 2; ++odd) {
    const auto rule = gridRuleTets(l.split, odd != 0);
    for (size_t r = 0; r < rule.size(); ++r) {
      const auto& t = rule[r];
      offsets_[odd * 6 + r] = {static_cast<uint32_t>(g.cornerOffset(t[0])), static_cast<uint32_t>(g.cornerOffset(t[1])),
                               static_cast<uint32_t>(g.cornerOffset(t[a2])),
                               static_cast<uint32_t>(g.cornerOffset(t[a3]))};
    }
  }
}

bool RuleGridTets::sameAs(const std::vector<Tet>& tets) const {
  if (tets.size() != tets_) return false;
  for (uint64_t t = 0; t < tets_; ++t)
    if (tets[t] != (*this)[t]) return false;
  return true;
}

std::vector<Tet> gridTets(const GridLayout& l) {
  std::vector<Tet> out;
  reservePopulated(out, l.tets());
  forEachGridTet(l, [&](const Tet& t) {
    out.push_back(t);
    return true;
  });
  return out;
}

StatusOr<GridLayout> matchGridLayout(const TetMesh& mesh, const uint32_t dims[3],
                                     std::span<const std::pair<uint32_t, uint32_t>> aliases) {
  GridLayout probe;
  for (int a = 0; a < 3; ++a) probe.dims[a] = dims[a];
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 2) return invalidData("a grid dimension below 2");
  if (probe.nodes() >= kPieceLimit || mesh.numPoints() >= kPieceLimit)
    return invalidData("a piece of 2^32 points or more");
  probe.aliases.assign(aliases.begin(), aliases.end());
  for (size_t a = 0; a < aliases.size(); ++a)
    if (aliases[a].first >= probe.nodes() || aliases[a].second >= aliases[a].first ||
        (a > 0 && aliases[a].first <= aliases[a - 1].first))
      return invalidData("alias " + std::to_string(a) + " is not (node, earlier node) in increasing node order");
  // The vertex of each node; `nodes` counts the nodes' own points (the extra points follow them).
  const std::vector<uint32_t> nv = nodeVertices(probe);
  const uint64_t nodes = probe.nodes() - aliases.size();
  if (nodes > mesh.numPoints()) return invalidData("the mesh has fewer points than the grid has nodes");
  const CellGeometry g(probe);
  const uint64_t points = mesh.numPoints(), T = mesh.tets.size();
  uint64_t off[8];
  for (int q = 0; q < 8; ++q) off[q] = g.cornerOffset(q);
  struct Candidate {
    uint8_t split, parity;
    bool left;
  };
  const Candidate candidates[6] = {{5, 0, false}, {5, 1, false}, {6, 0, false},
                                   {5, 0, true},  {5, 1, true},  {6, 0, true}};
  std::optional<GridLayout> best;
  std::string failure = "the tetrahedra do not come cell by cell";
  // A first round gives up on a candidate at more than `limit` exceptions (a rule that is not the
  // mesh's makes nearly every cell one, each with its tetrahedra listed); a candidate within it has
  // fewer than every one given up. Only when none is within it, a second round has no limit.
  const uint64_t cells = probe.cells();
  const uint64_t first_limit = std::max<uint64_t>(64, cells / 16);
  for (int round = 0; round < 2 && !best; ++round)
    for (const Candidate& cand : candidates) {
      const uint64_t limit = round == 0 ? first_limit : cells;
      GridLayout l = probe;
      l.split = cand.split;
      l.parity = cand.parity;
      l.left_handed = cand.left;
      const int a2 = cand.left ? 3 : 2, a3 = cand.left ? 2 : 3;
      uint64_t t = 0, cell = 0, next_extra = nodes;
      bool ok = true;
      for (uint64_t k = 0; k < g.ck && ok; ++k)
        for (uint64_t j = 0; j < g.cj && ok; ++j)
          for (uint64_t i = 0; i < g.ci && ok; ++i, ++cell) {
            const uint64_t base = i + g.ni * (j + g.nj * k);
            uint32_t corner[8];
            for (int q = 0; q < 8; ++q)
              corner[q] = nv.empty() ? static_cast<uint32_t>(base + off[q]) : nv[base + off[q]];
            const auto rule = gridRuleTets(cand.split, ((i + j + k + cand.parity) & 1) != 0);
            bool regular = t + rule.size() <= T;
            for (size_t r = 0; r < rule.size() && regular; ++r) {
              const auto& q = rule[r];
              const Tet want = {corner[q[0]], corner[q[1]], corner[q[a2]], corner[q[a3]]};
              regular = mesh.tets[t + r] == want;
            }
            if (regular) {
              t += rule.size();
              continue;
            }
            // The tetrahedra at t whose vertices are all corners of this cell or extra points.
            GridException x;
            x.cell = static_cast<uint32_t>(cell);
            uint32_t extra_ids[kMaxExtras];
            while (t < T && ok) {
              std::array<uint8_t, 4> sym{};
              bool belongs = true;
              for (int q = 0; q < 4 && belongs; ++q) {
                const uint32_t v = mesh.tets[t][q];
                const uint8_t* at = nullptr;
                for (int c = 0; c < 8 && !at; ++c)
                  if (corner[c] == v) sym[q] = static_cast<uint8_t>(c), at = &sym[q];
                if (at) continue;
                if (v < nodes || v >= points) {
                  belongs = false;
                  break;
                }
                int e = 0;
                while (e < x.extras && extra_ids[e] != v) ++e;
                if (e == x.extras) {
                  // A new extra point of this record: the next in the mesh's order, or not this grid.
                  if (v != next_extra || x.extras == kMaxExtras) {
                    ok = false;
                    failure = "extra point " + std::to_string(v) + " is not introduced in cell order";
                    break;
                  }
                  extra_ids[x.extras++] = v;
                  ++next_extra;
                }
                sym[q] = static_cast<uint8_t>(8 + e);
              }
              if (!ok || !belongs) break;
              x.tets.push_back(sym);
              ++t;
            }
            if (!ok) break;
            if (x.tets.size() > kMaxExplicitTets) {
              ok = false;
              failure = "cell " + std::to_string(cell) + " has more than 31 tetrahedra";
              break;
            }
            x.kind = x.tets.empty() ? GridException::kBlanked : GridException::kExplicit;
            l.exceptions.push_back(std::move(x));
            if (best && l.exceptions.size() >= best->exceptions.size()) ok = false;  // no better than the best
            if (l.exceptions.size() > limit) ok = false;
          }
      if (!ok) continue;
      if (t != T) {
        failure = "tetrahedron " + std::to_string(t) + " belongs to no cell in order";
        continue;
      }
      if (next_extra != points) {
        failure = "points " + std::to_string(next_extra) + " and after are used by no cell";
        continue;
      }
      best = std::move(l);
    }
  if (!best)
    return invalidData("the mesh is not this " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                       std::to_string(dims[2]) + " grid: " + failure);
  return std::move(*best);
}

GridSchema gridSchemaOf(const TetMesh& mesh) {
  GridSchema s;
  s.coord_type = mesh.coord_type;
  for (const Field& f : mesh.point_fields) s.point_fields.push_back({f.name, f.components, f.type});
  for (const Field& f : mesh.cell_fields) s.cell_fields.push_back({f.name, f.components, f.type});
  return s;
}

StatusOr<std::vector<uint8_t>> encodeGridPiece(const GridLayout& layout, const TetMesh& mesh,
                                               const GridEncodeOptions& options, GridEncodeReport* report) {
  GTN_RETURN_IF_ERROR(checkGridLayout(layout, "structured piece"));
  if (options.predictor > 2)
    return usageError("structured piece: predictor " + std::to_string(options.predictor) + " (0 to 2)");
  const uint64_t V = layout.vertices();
  if (mesh.numPoints() != V)
    return usageError("structured piece: the mesh has " + std::to_string(mesh.numPoints()) + " points, the layout " +
                      std::to_string(V));
  if (!isGridTets(layout, mesh.tets)) return usageError("structured piece: the mesh's tetrahedra are not the layout's");
  if (mesh.coord_type != ScalarType::kFloat32 && mesh.coord_type != ScalarType::kFloat64)
    return usageError("structured piece: coordinates must be float32 or float64");
  for (const Field& f : mesh.point_fields)
    if (f.itemCount() != V || f.components == 0 || f.components > 64)
      return usageError("structured piece: point field '" + f.name +
                        "' has not one item per point (of 1..64 components)");
  for (const Field& f : mesh.cell_fields)
    if (f.itemCount() != mesh.tets.size() || f.components == 0 || (f.components * f.valueSize()) > 64)
      return usageError("structured piece: cell field '" + f.name +
                        "' has not one item per tetrahedron (of at most 64 bytes)");
  const CellScan cscan = cellScan(layout);
  if (layout.cell_values_per_cell) {
    for (const Field& f : mesh.cell_fields)
      for (uint64_t cell = 0; cell + 1 < cscan.first.size(); ++cell)
        for (uint32_t t = cscan.first[cell] + 1; t < cscan.first[cell + 1]; ++t)
          if (std::memcmp(&f.bytes[t * (f.components * f.valueSize())],
                          &f.bytes[cscan.first[cell] * (f.components * f.valueSize())],
                          (f.components * f.valueSize())) != 0)
            return usageError("structured piece: cell field '" + f.name + "' differs within cell " +
                              std::to_string(cell) + ", but the layout codes cell values per cell");
  }
  const std::vector<uint32_t> targets = aliasTargets(layout);
  const Scan scan = valueScan(layout, targets.empty() ? nullptr : &targets);
  GridEncodeReport rep;
  const std::string what = "structured piece";

  // EXCP.
  std::vector<uint8_t> excp;
  if (!layout.aliases.empty() || !layout.exceptions.empty()) {
    EntropyCoder<true> c(&excp);
    GridLayout copy = layout;
    GTN_RETURN_IF_ERROR(
        codeExceptions(c, copy, layout.aliases.size(), layout.exceptions.size(), layout.extras(), what));
    c.finish();
  }

  // A value stream with each component's form and predictor measured: each candidate coded alone,
  // the smallest kept (a component's models are its own, so it costs in the stream what it costs
  // alone, but for the declarations' models).
  std::vector<double> scratch;
  auto valueStream = [&](ScalarType type, uint32_t comps, const uint8_t* src, size_t stride,
                         const std::string& name) -> StatusOr<std::pair<uint8_t, std::vector<uint8_t>>> {
    std::vector<Form> chosen(comps);
    const size_t size = scalarSize(type);
    for (uint32_t cc = 0; cc < comps; ++cc) {
      auto measure = [&](Form f) -> StatusOr<size_t> {
        std::vector<uint8_t> out;
        EntropyCoder<true> c(&out);
        std::vector<Form> one{std::move(f)};
        GTN_RETURN_IF_ERROR(codeValueStream(c, type, 1, scan, one, src + cc * size, stride, nullptr, scratch, name));
        c.finish();
        return out.size();
      };
      std::vector<Form> forms = candidateForms(type, src + cc * size, V, stride);
      const int first_predictor = options.predictor >= 0 ? options.predictor : 0;
      size_t best = std::numeric_limits<size_t>::max();
      for (Form& f : forms) {
        f.predictor = static_cast<uint8_t>(first_predictor);
        GTN_ASSIGN_OR_RETURN(const size_t bytes, measure(f));
        if (bytes < best) best = bytes, chosen[cc] = f;
      }
      if (options.predictor < 0) {
        for (uint8_t p = 1; p <= 2; ++p) {
          Form f = chosen[cc];
          f.predictor = p;
          GTN_ASSIGN_OR_RETURN(const size_t bytes, measure(f));
          if (bytes < best) best = bytes, chosen[cc] = f;
        }
      }
      rep.predictors.push_back(chosen[cc].predictor);
      rep.forms.push_back(chosen[cc].describe());
    }
    std::vector<uint8_t> out;
    EntropyCoder<true> c(&out);
    GTN_RETURN_IF_ERROR(codeValueStream(c, type, comps, scan, chosen, src, stride, nullptr, scratch, name));
    c.finish();
    // Form 1 (static prefix codes, faster to decode) where it applies: kept when asked for, or by
    // default when at most 2% larger (section 12).
    uint8_t form = 0;
    if (options.value_form != 0) {
      std::vector<uint8_t> fast;
      if (encodeForm1(type, comps, scan, chosen, src, stride, scratch, &fast) &&
          (options.value_form == 1 || fast.size() * 100 <= out.size() * 102)) {
        out = std::move(fast);
        form = 1;
      }
    }
    rep.stream_forms.push_back(form);
    return std::make_pair(form, std::move(out));
  };

  std::vector<uint8_t> coords(V * 3 * scalarSize(mesh.coord_type));
  for (uint64_t i = 0; i < V * 3; ++i)
    storeCoordinate(mesh.coord_type, mesh.coords[i], &coords[i * scalarSize(mesh.coord_type)]);
  GTN_ASSIGN_OR_RETURN(auto geom_stream,
                       valueStream(mesh.coord_type, 3, coords.data(), 3 * scalarSize(mesh.coord_type), "GEOM"));
  std::vector<uint8_t> geom = std::move(geom_stream.second);
  std::vector<uint8_t> forms{0, 0, geom_stream.first};  // EXCP, GRID, GEOM, then the fields'
  std::vector<std::vector<uint8_t>> pfld, cfld;
  for (const Field& f : mesh.point_fields) {
    GTN_ASSIGN_OR_RETURN(auto s,
                         valueStream(f.type, f.components, f.bytes.data(), (f.components * f.valueSize()), "PFLD"));
    forms.push_back(s.first);
    pfld.push_back(std::move(s.second));
  }
  forms.resize(3 + pfld.size() + mesh.cell_fields.size(), 0);
  for (const Field& f : mesh.cell_fields) {
    std::vector<Form> forms(f.components);
    for (uint32_t cc = 0; cc < f.components; ++cc) {
      int z = scalarBits(f.type) - 1;
      for (size_t t = 0; t < mesh.tets.size() && z > 0; ++t)
        z = std::min(
            z, ValueCoder::trailingZeros(f.type, &f.bytes[t * (f.components * f.valueSize()) + cc * f.valueSize()]));
      forms[cc].shift = mesh.tets.empty() ? 0 : static_cast<uint32_t>(z);
    }
    std::vector<uint8_t> out;
    EntropyCoder<true> c(&out);
    const FieldDesc desc{f.name, f.components, f.type};
    GTN_RETURN_IF_ERROR(codeCellField(c, desc, cscan, f.bytes.data(), nullptr, forms, "CFLD"));
    c.finish();
    cfld.push_back(std::move(out));
  }

  // The piece: structured header, stream table, streams.
  std::vector<uint8_t> piece;
  putVarint(piece, 0);                              // block
  for (int a = 0; a < 3; ++a) putVarint(piece, 0);  // origin
  for (int a = 0; a < 3; ++a) putVarint(piece, layout.dims[a]);
  piece.push_back(layout.split);
  piece.push_back(flagsOf(layout));
  putVarint(piece, layout.exceptions.size());
  putVarint(piece, layout.extras());
  putVarint(piece, layout.aliases.size());
  std::vector<const std::vector<uint8_t>*> streams;
  const std::vector<uint8_t> grid;  // nothing known: empty (section 11.2)
  streams.push_back(&excp);
  streams.push_back(&grid);
  streams.push_back(&geom);
  for (const auto& s : pfld) streams.push_back(&s);
  for (const auto& s : cfld) streams.push_back(&s);
  putVarint(piece, streams.size());
  for (size_t x = 0; x < streams.size(); ++x) {
    piece.push_back(forms[x]);  // section 12
    putVarint(piece, streams[x]->size());
  }
  rep.header = piece.size();
  for (const auto* s : streams) piece.insert(piece.end(), s->begin(), s->end());
  rep.excp = excp.size();
  rep.grid = 0;
  rep.geom = geom.size();
  for (const auto& s : pfld) rep.point_fields.push_back(s.size());
  for (const auto& s : cfld) rep.cell_fields.push_back(s.size());
  if (report) *report = std::move(rep);
  return piece;
}

// What making the tetrahedra from the layout costs, in the units of the streams' decoding (their
// bytes): one stream byte takes about as long to decode as 26 tetrahedra take to make (the 64^3
// grid's 1.5 million tetrahedra about as long as its 67 KB energy stream). Counted as nothing, the
// tetrahedra were the last job, however long writing them took.
constexpr uint64_t kTetsPerStreamByte = 26;

StatusOr<DecodedGridPiece> decodeGridPiece(std::span<const uint8_t> bytes, const GridSchema& schema,
                                           const std::string& what, const GridFieldSelection* fields) {
  auto wanted = [](const std::vector<bool>* chosen, size_t f) {
    return !chosen || chosen->empty() || (f < chosen->size() && (*chosen)[f]);
  };
  Reader r(bytes, what);
  DecodedGridPiece out;
  GridLayout& l = out.layout;
  uint64_t v = 0;
  GTN_RETURN_IF_ERROR(r.varint(&v, "block"));
  if (v != 0) return r.fail("block", "block " + std::to_string(v) + " of a piece decoded on its own (0 expected)");
  for (int a = 0; a < 3; ++a) {
    GTN_RETURN_IF_ERROR(r.varint(&v, "origin"));
    if (v != 0) return r.fail("origin", "a piece decoded on its own starts at node (0, 0, 0)");
  }
  for (int a = 0; a < 3; ++a) {
    GTN_RETURN_IF_ERROR(r.varintBelow(&v, kPieceLimit, "dims"));
    if (v < 2) return r.fail("dims", "a node count of " + std::to_string(v) + " (at least 2)");
    l.dims[a] = static_cast<uint32_t>(v);
  }
  if (l.nodes() >= kPieceLimit) return r.fail("dims", "2^32 nodes or more");
  if (l.nodes() > kMaxNodesPerByte * bytes.size())
    return r.fail("dims",
                  std::to_string(l.nodes()) + " nodes in a piece of " + std::to_string(bytes.size()) + " bytes");
  uint8_t split = 0, flags = 0;
  GTN_RETURN_IF_ERROR(r.u8(&split, "split"));
  if (split != 5 && split != 6) return r.fail("split", "split " + std::to_string(split) + " (5 or 6)");
  GTN_RETURN_IF_ERROR(r.u8(&flags, "flags"));
  if (flags & 0xF8) return r.fail("flags", "reserved bits set");
  if (split == 6 && (flags & 1)) return r.fail("flags", "a parity with split 6");
  l.split = split;
  l.parity = flags & 1;
  l.left_handed = (flags & 2) != 0;
  l.cell_values_per_cell = (flags & 4) != 0;
  uint64_t n_exceptions = 0, n_extra = 0, n_aliases = 0;
  GTN_RETURN_IF_ERROR(r.varint(&n_exceptions, "n_exceptions"));
  if (n_exceptions > l.cells())
    return r.fail("n_exceptions",
                  std::to_string(n_exceptions) + " exceptions in " + std::to_string(l.cells()) + " cells");
  GTN_RETURN_IF_ERROR(r.varint(&n_extra, "n_extra"));
  if (n_extra > kMaxExtras * n_exceptions)
    return r.fail("n_extra",
                  std::to_string(n_extra) + " extra points in " + std::to_string(n_exceptions) + " exceptions");
  GTN_RETURN_IF_ERROR(r.varint(&n_aliases, "n_aliases"));
  if (n_aliases >= l.nodes())
    return r.fail("n_aliases", std::to_string(n_aliases) + " aliases of " + std::to_string(l.nodes()) + " nodes");
  uint64_t n_streams = 0;
  const uint64_t want_streams = 3 + schema.point_fields.size() + schema.cell_fields.size();
  GTN_RETURN_IF_ERROR(r.varint(&n_streams, "n_streams"));
  if (n_streams != want_streams)
    return r.fail("n_streams", std::to_string(n_streams) + " streams, the schema has " + std::to_string(want_streams));
  std::vector<uint64_t> sizes(n_streams);
  std::vector<uint8_t> forms(n_streams);
  uint64_t total = 0;
  for (uint64_t s = 0; s < n_streams; ++s) {
    uint8_t& form = forms[s];
    GTN_RETURN_IF_ERROR(r.u8(&form, "stream form"));
    const bool values = s >= 2 && s < 3 + schema.point_fields.size();
    if (form > (values ? 1 : 0))
      return r.fail("stream form",
                    "form " + std::to_string(form) + " for stream " + std::to_string(s) +
                        (values ? " (GEOM and PFLD use form 0 or 1 here)" : " (EXCP, GRID and CFLD use form 0)"));
    GTN_RETURN_IF_ERROR(r.varint(&sizes[s], "stream size"));
    if (sizes[s] > r.remaining()) return r.fail("stream size", "a stream larger than the piece");
    total += sizes[s];
  }
  if (total != r.remaining())
    return r.fail("stream table", "the streams add up to " + std::to_string(total) + " bytes, the piece holds " +
                                      std::to_string(r.remaining()));
  std::vector<std::span<const uint8_t>> streams;
  size_t at = r.position();
  for (uint64_t s = 0; s < n_streams; ++s) {
    streams.push_back(bytes.subspan(at, sizes[s]));
    at += sizes[s];
  }
  // EXCP and the layout.
  if (n_aliases + n_exceptions == 0) {
    if (!streams[0].empty()) return invalidData(what + ": EXCP stream: bytes where there is nothing to code");
  } else {
    if (n_aliases + n_exceptions > kMaxNodesPerByte * streams[0].size())
      return invalidData(what + ": EXCP stream: " + std::to_string(n_aliases + n_exceptions) + " records in " +
                         std::to_string(streams[0].size()) + " bytes");
    EntropyCoder<false> c(streams[0]);
    GTN_RETURN_IF_ERROR(codeExceptions(c, l, n_aliases, n_exceptions, n_extra, what));
    if (!c.finishedCleanly()) return invalidData(what + ": EXCP stream is corrupt, truncated or has trailing bytes");
  }
  GTN_RETURN_IF_ERROR(checkGridLayout(l, what));
  if (!streams[1].empty()) return invalidData(what + ": GRID stream: known nodes in a piece that has none");
  const uint64_t V = l.vertices();
  TetMesh& m = out.mesh;
  m.coord_type = schema.coord_type;
  if (m.coord_type != ScalarType::kFloat32 && m.coord_type != ScalarType::kFloat64)
    return usageError(what + ": coordinates must be float32 or float64");
  const std::vector<uint32_t> targets = aliasTargets(l);
  const Scan scan = valueScan(l, targets.empty() ? nullptr : &targets);
  // The streams are independent: each one (and the tetrahedra made from the layout) is decoded into its
  // own output by a task of its own. The first failure in stream order is returned, as one thread
  // decoding them in turn would.
  std::vector<std::function<Status()>> jobs;
  std::vector<Status> failed;  // per job, a failure found before it runs
  std::vector<uint64_t> cost;  // per job, its stream's bytes: what its decoding takes, about
  cost.push_back(streams[2].size());
  jobs.push_back([&]() -> Status {
    std::vector<double> d;
    const size_t cs = scalarSize(m.coord_type);
    std::vector<uint8_t> raw;
    resizePopulated(raw, V * 3 * cs);
    if (forms[2] == 1) {
      GTN_RETURN_IF_ERROR(decodeForm1(streams[2], m.coord_type, 3, scan, raw.data(), d, what + ": GEOM stream"));
    } else {
      EntropyCoder<false> c(streams[2]);
      std::vector<Form> declared;
      GTN_RETURN_IF_ERROR(
          codeValueStream(c, m.coord_type, 3, scan, declared, nullptr, 0, raw.data(), d, what + ": GEOM stream"));
      if (!c.finishedCleanly()) return invalidData(what + ": GEOM stream is corrupt, truncated or has trailing bytes");
    }
    resizePopulated(m.coords, V * 3);
    for (uint64_t i = 0; i < V * 3; ++i) m.coords[i] = doubleFromRaw(m.coord_type, &raw[i * cs]);
    return Status::ok();
  });
  failed.push_back(Status::ok());
  // A field's job: its description is checked here (a bad one ends the jobs there, as it would end one
  // thread's decoding), its values are decoded by the job into the field it adds to `to`.
  auto addField = [&](std::vector<Field>& to, const FieldDesc& desc, bool bad, const std::string& why, size_t stream,
                      std::function<Status(Field&)> decode) {
    cost.push_back(stream < streams.size() ? streams[stream].size() : 0);
    if (bad) {
      failed.push_back(usageError(what + why));
      jobs.push_back(nullptr);
      return;
    }
    to.emplace_back(desc.name, desc.components, desc.type, 0);
    failed.push_back(Status::ok());
    jobs.push_back([decode = std::move(decode), &field = to.back()] { return decode(field); });
  };
  m.point_fields.reserve(schema.point_fields.size());  // the jobs keep references to the fields
  for (size_t f = 0; f < schema.point_fields.size(); ++f) {
    const FieldDesc& desc = schema.point_fields[f];
    addField(m.point_fields, desc, desc.components == 0 || desc.components > 64,
             ": point field '" + desc.name + "' of 0 or more than 64 components", 3 + f,
             [&, f, &desc = desc](Field& field) {
               resizePopulated(field.bytes, V * desc.itemBytes());
               if (!wanted(fields ? &fields->point : nullptr, f)) return Status::ok();  // left out: zero values
               const std::string name = what + ": PFLD stream '" + desc.name + "'";
               std::vector<double> d;
               if (forms[3 + f] == 1)
                 return decodeForm1(streams[3 + f], desc.type, desc.components, scan, field.bytes.data(), d, name);
               EntropyCoder<false> c(streams[3 + f]);
               std::vector<Form> declared;
               GTN_RETURN_IF_ERROR(codeValueStream(c, desc.type, desc.components, scan, declared, nullptr, 0,
                                                   field.bytes.data(), d, name));
               if (!c.finishedCleanly()) return invalidData(name + " is corrupt, truncated or has trailing bytes");
               return Status::ok();
             });
  }
  if (!fields || fields->tets) {
    cost.push_back(l.tets() / kTetsPerStreamByte);
    jobs.push_back([&]() -> Status {
      m.tets = gridTets(l);
      return Status::ok();
    });
    failed.push_back(Status::ok());
  }
  std::optional<CellScan> cscan;
  if (!schema.cell_fields.empty()) cscan = cellScan(l);
  m.cell_fields.reserve(schema.cell_fields.size());
  for (size_t f = 0; f < schema.cell_fields.size(); ++f) {
    const FieldDesc& desc = schema.cell_fields[f];
    addField(m.cell_fields, desc, desc.components == 0 || desc.itemBytes() > 64,
             ": cell field '" + desc.name + "' of 0 components or more than 64 bytes",
             3 + schema.point_fields.size() + f, [&, f, &desc = desc](Field& field) {
               resizePopulated(field.bytes, cscan->first.back() * desc.itemBytes());
               if (!wanted(fields ? &fields->cell : nullptr, f)) return Status::ok();  // left out: zero values
               const std::string name = what + ": CFLD stream '" + desc.name + "'";
               EntropyCoder<false> c(streams[3 + schema.point_fields.size() + f]);
               std::vector<Form> declared;
               GTN_RETURN_IF_ERROR(codeCellField(c, desc, *cscan, nullptr, field.bytes.data(), declared, name));
               if (!c.finishedCleanly()) return invalidData(name + " is corrupt, truncated or has trailing bytes");
               return Status::ok();
             });
  }
  if (fields && fields->beside) {
    cost.push_back(0);
    jobs.push_back([&]() -> Status { return fields->beside(l); });
    failed.push_back(Status::ok());
  }
  // Jobs after a field that fails its description are not needed: one thread would stop there.
  size_t run = jobs.size();
  for (size_t j = 0; j < jobs.size(); ++j)
    if (!failed[j].isOk()) {
      run = j;
      break;
    }
  // Each thread takes the costliest job left (the largest streams start at once, the small ones fill
  // in); the results are still read in job order.
  cost.resize(run);
  std::vector<Status> results(run, Status::ok());
  forEachLongestFirst(cost, [&](size_t j) { results[j] = jobs[j](); });
  for (size_t j = 0; j < run; ++j)
    if (!results[j].isOk()) return results[j];
  if (run < jobs.size()) return failed[run];
  return out;
}

}  // namespace gtn
