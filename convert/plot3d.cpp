// PLOT3D importer: binary or ASCII curvilinear grids (with an optional Q file and function file, or a
// ParaView-style .p3d JSON meta-file naming them) into a tetrahedral mesh.
//
// PLOT3D files do not describe themselves, so every file is read by trying each interpretation
// (byte order, no / 4-byte / 8-byte Fortran record markers, single grid or multi-grid with a leading
// grid count, 2D or 3D, float32 or float64, IBLANK or not) and keeping those whose sizes match the
// file exactly. Values are in the whole layout (all X, then all Y, then all Z per grid, i fastest),
// cut into records three ways (below). When no interpretation fits exactly, one that fits with
// trailing zero bytes is accepted with a warning; trailing data that is not zero is an error. When
// several fit, the grid file's byte order and markers are preferred for its Q and function files, and
// readings that differ only in how their records are cut are told apart by their data (see pickOne);
// otherwise the import fails and lists them: guessing would silently produce a wrong mesh. A text file
// that no binary interpretation fits is read as ASCII PLOT3D, its layout decided the same way by its
// value count.
//
// Policies (README.md, "Inputs"):
// - Points keep grid order (i fastest, then j, then k), blocks concatenated, in source precision.
// - IBLANK: a cell with any hole vertex (IBLANK 0) is dropped and counted; fringe (negative) and wall
//   (2) points are ordinary points. All points are kept and IBLANK becomes the int32 field "iblank".
// - Blocks are never joined; --weld merges bit-identical points (across blocks too), keeps the first
//   point's field values, and drops the tetrahedra that collapse. With --weld each block's 5-split
//   parity is chosen so that welded seams conform wherever they can; the seams that cannot are
//   warned about (seamParities).
// - Records: one per grid (whole), one per k-plane holding all components of that plane (PLOT3D's
//   /PLANES), or one per component (Fortran's `write(u) x` / `write(u) y` / ...); with record markers
//   these are told apart by the record sizes, and where sizes coincide (a grid of 3 k-planes, a Q file
//   of 5) by the data. Without markers planes and whole always have the same size: a grid is read
//   plane by plane only when its cells come out more consistent so (else whole), and its Q and
//   function files as their data says.
//   Multi-grid dimensions may also come one record per grid.
// - Q files come in the classic layout (dimensions, then per grid four freestream reals and the five
//   conserved variables) and NASA OVERFLOW's (OVERFLOW's q-file description, and VTK's reader of it):
//   the dimension record ends with NQ and NQC, the number of variables and of species, and each grid's
//   freestream record holds FSMACH ALPHA REY TIME GAMINF BETA TINF, the integer IGAM, HTINF HT1 HT2,
//   RGAS(1:max(2,NQC)), FSMFR TVREF DTVREF, before its NQ variables. The first five variables are the
//   classic ones (density, momentum, stagnation energy); the others (species densities, turbulence
//   quantities) become the fields q6 .. qNQ.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "convert/cell_split.h"
#include "convert/import.h"
#include "convert/text_reader.h"
#include "format/file_io.h"
#include "format/gtn_bytes.h"
#include "mesh/fresh_memory.h"
#include "mesh/index.h"
#include "mesh/predicates.h"

static_assert(std::endian::native == std::endian::little,
              "Field holds little-endian bytes: a big-endian host would need byte swapping here");

namespace gtn {

namespace {

enum class Kind { kGrid, kQ, kFunction };

const char* kindName(Kind k) {
  switch (k) {
    case Kind::kGrid: return "grid";
    case Kind::kQ: return "Q";
    default: return "function";
  }
}

// One interpretation of a PLOT3D file.
struct Layout {
  bool big_endian = true;
  int marker = 0;  // Fortran record marker size in bytes: 0 (none), 4 or 8
  bool multi_grid = false;
  int ndim = 3;
  int precision = 4;  // bytes per real
  int int_bytes = 4;  // bytes per integer (dimensions, counts, IBLANK): 8 from 64-bit default integers
                      // (gfortran -fdefault-integer-8), tried with record markers only
  bool iblank = false;
  bool overflow = false;       // Q files: OVERFLOW's layout (NQ variables, a longer freestream record)
  bool planes = false;         // one record per k-plane (all components of the plane) instead of one per grid
  bool dims_per_grid = false;  // multi-grid: each grid's dimensions in a record of its own (found, not tried)
  // One record per component (x, y, z and IBLANK; each Q or function variable) instead of one per
  // grid, as Fortran writes `write(u) x` / `write(u) y` / ...; the records, in order, are the whole
  // layout.
  bool components = false;
  bool ascii = false;  // read from text (transcoded; the binary members then describe the transcoding)
};

std::string describeLayout(const Layout& l, Kind kind) {
  std::string s;
  if (l.ascii) {
    s = "ASCII";
  } else {
    s = l.big_endian ? "big-endian" : "little-endian";
    s += l.marker ? ", " + std::to_string(l.marker) + "-byte record markers" : ", no record markers";
  }
  s += l.multi_grid ? ", multi-grid" : ", single grid";
  if (kind == Kind::kGrid) s += l.ndim == 3 ? ", 3D" : ", 2D";
  if (!l.ascii) s += l.precision == 4 ? ", float32" : ", float64";
  if (kind == Kind::kGrid) s += l.iblank ? ", IBLANK" : ", no IBLANK";
  if (l.int_bytes == 8) s += ", 64-bit integers";
  if (kind == Kind::kQ && l.overflow) s += ", OVERFLOW";
  if (l.planes) s += ", planes";
  if (l.components) s += ", one record per variable";
  if (l.dims_per_grid) s += ", dimensions per grid";
  return s;
}

// What the .p3d meta-file (or nothing) says about the layout; unset members are detected.
struct Constraints {
  std::optional<bool> big_endian;
  std::optional<bool> fortran;  // record markers (of either size) or none
  std::optional<bool> multi_grid;
  std::optional<int> precision;
  std::optional<bool> iblank;
  std::optional<int> ndim;
  std::optional<bool> overflow;
  std::optional<bool> planes;
  std::optional<bool> components;

  bool allows(const Layout& l, Kind kind) const {
    if (planes && *planes != l.planes) return false;
    if (components && *components != l.components) return false;
    if (kind == Kind::kQ && overflow && *overflow != l.overflow) return false;
    if (big_endian && *big_endian != l.big_endian) return false;
    if (fortran && *fortran != (l.marker != 0)) return false;
    if (multi_grid && *multi_grid != l.multi_grid) return false;
    if (precision && *precision != l.precision) return false;
    if (kind == Kind::kGrid && iblank && *iblank != l.iblank) return false;
    if (kind == Kind::kGrid && ndim && *ndim != l.ndim) return false;
    return true;
  }
};

// What a .p3d meta-file fixed, in words ("" when nothing).
std::string describeConstraints(const Constraints& c) {
  std::vector<std::string> parts;
  if (c.big_endian) parts.push_back(*c.big_endian ? "big-endian" : "little-endian");
  if (c.fortran) parts.push_back(*c.fortran ? "record markers (Fortran)" : "no record markers (C)");
  if (c.multi_grid) parts.push_back(*c.multi_grid ? "multi-grid" : "single grid");
  if (c.precision) parts.push_back(*c.precision == 4 ? "float32" : "float64");
  if (c.iblank) parts.push_back(*c.iblank ? "IBLANK" : "no IBLANK");
  if (c.planes && *c.planes) parts.push_back("planes");
  if (c.components && *c.components) parts.push_back("one record per variable");
  std::string s;
  for (const std::string& p : parts) s += (s.empty() ? "" : ", ") + p;
  return s;
}

// A logical record: one piece, or several when it was written as Fortran subrecords.
struct Piece {
  uint64_t offset = 0, size = 0;
};
using Record = std::vector<Piece>;

struct BlockDims {
  int64_t n[3] = {1, 1, 1};
  int64_t nvar = 0;  // function files only
  uint64_t points() const { return static_cast<uint64_t>(n[0] * n[1] * n[2]); }
};

std::string dimsText(const BlockDims& b, int ndim = 3) {
  std::string s = std::to_string(b.n[0]);
  for (int a = 1; a < ndim; ++a) {
    s += 'x';
    s += std::to_string(b.n[a]);
  }
  return s;
}

std::string blocksText(const std::vector<BlockDims>& blocks) {
  std::string s;
  for (size_t g = 0; g < blocks.size() && g < 4; ++g) s += (g ? ", " : "") + dimsText(blocks[g]);
  if (blocks.size() > 4) s += ", ... (" + std::to_string(blocks.size()) + " grids)";
  return s;
}

// An interpretation that fits the file: where every block's records are.
struct Fit {
  Layout layout;
  std::vector<BlockDims> blocks;
  std::vector<Record> headers;  // Q files: the freestream record of each block
  std::vector<Record> data;     // one record per block
  int64_t nq = 5, nqc = 0;      // Q files: variables per point and species (OVERFLOW's NQ, NQC)
  uint64_t end = 0;             // first byte after the data
};

uint64_t loadUnsigned(const char* p, int size, bool big_endian) {
  uint64_t v = 0;
  for (int i = 0; i < size; ++i) {
    const uint64_t b = static_cast<unsigned char>(p[big_endian ? i : size - 1 - i]);
    v = (v << 8) | b;
  }
  return v;
}

int64_t loadSigned(const char* p, int size, bool big_endian) {
  const uint64_t u = loadUnsigned(p, size, big_endian);
  if (size == 4) return static_cast<int32_t>(static_cast<uint32_t>(u));
  return static_cast<int64_t>(u);
}

double loadReal(const char* p, int precision, bool big_endian) {
  const uint64_t u = loadUnsigned(p, precision, big_endian);
  if (precision == 4) return static_cast<double>(std::bit_cast<float>(static_cast<uint32_t>(u)));
  return std::bit_cast<double>(u);
}

// Copies one value of `size` bytes into little-endian order.
void storeLittle(const char* src, int size, bool big_endian, uint8_t* dst) {
  for (int i = 0; i < size; ++i) dst[i] = static_cast<uint8_t>(src[big_endian ? size - 1 - i : i]);
}

// Walks the records of one interpretation, checking every record marker against the file.
class RecordCursor {
 public:
  RecordCursor(std::string_view bytes, const Layout& layout) : bytes_(bytes), layout_(layout) {}

  // The next record, which must hold exactly `expected` bytes; `what` names it in `*why`.
  bool next(uint64_t expected, const char* what, Record* out, std::string* why) {
    out->clear();
    const uint64_t size = bytes_.size();
    if (layout_.marker == 0) {
      if (expected > size - pos_) {
        *why = std::string(what) + " needs " + std::to_string(expected) + " bytes at byte " + std::to_string(pos_) +
               ", the file has " + std::to_string(size - pos_) + " left";
        return false;
      }
      if (expected) out->push_back({pos_, expected});
      pos_ += expected;
      return true;
    }
    const uint64_t m = static_cast<uint64_t>(layout_.marker);
    uint64_t p = pos_, total = 0;
    for (;;) {
      // Subrecords: a negative leading marker says the record continues in the next subrecord
      // (gfortran's scheme for records over 2 GiB); each trailing marker repeats the length.
      if (size - p < m) {
        *why = std::string(what) + ": the file ends inside the record marker at byte " + std::to_string(p);
        return false;
      }
      const int64_t head = loadSigned(bytes_.data() + p, layout_.marker, layout_.big_endian);
      const uint64_t len = head < 0 ? uint64_t{0} - static_cast<uint64_t>(head) : static_cast<uint64_t>(head);
      if (len > size - p - m || size - p - m - len < m) {
        *why = std::string(what) + ": the record marker at byte " + std::to_string(p) + " says " + std::to_string(len) +
               " bytes, past the end of the file";
        return false;
      }
      const int64_t tail = loadSigned(bytes_.data() + p + m + len, layout_.marker, layout_.big_endian);
      const uint64_t tail_len = tail < 0 ? uint64_t{0} - static_cast<uint64_t>(tail) : static_cast<uint64_t>(tail);
      if (tail_len != len) {
        *why = std::string(what) + ": the record marker at byte " + std::to_string(p) + " says " + std::to_string(len) +
               " bytes but the closing marker at byte " + std::to_string(p + m + len) + " says " +
               std::to_string(tail_len);
        return false;
      }
      if (len) out->push_back({p + m, len});
      total += len;
      p += 2 * m + len;
      if (total > expected) break;
      if (head >= 0) break;
    }
    if (total != expected) {
      *why = std::string(what) + ": the record at byte " + std::to_string(pos_) + " holds " + std::to_string(total) +
             " bytes" + (total > expected ? " or more" : "") + ", expected " + std::to_string(expected);
      return false;
    }
    pos_ = p;
    return true;
  }

  uint64_t pos() const { return pos_; }
  void seek(uint64_t pos) { pos_ = pos; }

 private:
  std::string_view bytes_;
  Layout layout_;
  uint64_t pos_ = 0;
};

// The bytes of a record, contiguous (copied into `scratch` only when it has several subrecords).
std::string_view recordBytes(std::string_view bytes, const Record& rec, std::string* scratch) {
  if (rec.empty()) return {};
  if (rec.size() == 1) return bytes.substr(rec[0].offset, rec[0].size);
  scratch->clear();
  for (const Piece& p : rec) scratch->append(bytes.substr(p.offset, p.size));
  return *scratch;
}

// The bytes of block `g` in the whole layout: each component for all points (i fastest, then j, then
// k), component after component. A planes file holds all components of k-plane 0, then of plane 1,
// ...; they are reordered into `*reordered`. `component_bytes` gives each component's value size.
std::string_view blockBytes(std::string_view bytes, const Fit& fit, size_t g,
                            const std::vector<size_t>& component_bytes, std::string* scratch, std::string* reordered) {
  const std::string_view v = recordBytes(bytes, fit.data[g], scratch);
  if (!fit.layout.planes) return v;
  const BlockDims& b = fit.blocks[g];
  const size_t plane = static_cast<size_t>(b.n[0] * b.n[1]), nk = static_cast<size_t>(b.n[2]), n = plane * nk;
  reordered->resize(v.size());
  size_t src = 0;
  for (size_t k = 0; k < nk; ++k) {
    size_t whole_offset = 0;  // where the component starts in the whole layout
    for (size_t cb : component_bytes) {
      std::memcpy(reordered->data() + whole_offset + k * plane * cb, v.data() + src, plane * cb);
      src += plane * cb;
      whole_offset += n * cb;
    }
  }
  return *reordered;
}

// The byte size of each component of a point of block g (X, Y, Z and IBLANK; the Q or function
// variables), as blockBytes takes them.
std::vector<size_t> componentBytes(const Fit& fit, size_t g, Kind kind) {
  const Layout& l = fit.layout;
  const size_t vb = static_cast<size_t>(l.precision);
  if (kind == Kind::kGrid) {
    std::vector<size_t> c(static_cast<size_t>(l.ndim), vb);
    if (l.iblank) c.push_back(static_cast<size_t>(l.int_bytes));
    return c;
  }
  return std::vector<size_t>(kind == Kind::kQ ? static_cast<size_t>(fit.nq) : static_cast<size_t>(fit.blocks[g].nvar),
                             vb);
}

// Tries one interpretation. On failure `*why` says what did not fit, `*header_ok` whether the grid
// count and dimensions at least made sense (or, with record markers, were read from records whose
// markers checked out: then an impossible value is the explanation) and `*progress` how far the
// records checked out (both for ranking the explanations).
bool tryLayout(std::string_view bytes, const Layout& l, Kind kind, Fit* fit, std::string* why, bool* header_ok,
               uint64_t* progress) {
  *header_ok = false;
  const uint64_t size = bytes.size();
  RecordCursor cursor(bytes, l);
  struct ProgressOnExit {
    const RecordCursor& c;
    uint64_t* out;
    ~ProgressOnExit() { *out = c.pos(); }
  } progress_on_exit{cursor, progress};
  Record rec;
  std::string scratch;
  int64_t ngrid = 1;
  const int ints = kind == Kind::kFunction ? 4 : (kind == Kind::kGrid ? l.ndim : 3);
  const uint64_t ib = static_cast<uint64_t>(l.int_bytes);
  if (l.multi_grid) {
    if (!cursor.next(ib, "grid count", &rec, why)) return false;
    const std::string_view v = recordBytes(bytes, rec, &scratch);
    ngrid = loadSigned(v.data(), l.int_bytes, l.big_endian);
    if (ngrid < 1 || static_cast<uint64_t>(ngrid) > size / (ib * static_cast<uint64_t>(ints))) {
      *why = "grid count " + std::to_string(ngrid) + " is impossible for a file of " + std::to_string(size) + " bytes";
      *header_ok = l.marker != 0;  // its record checked out: a real explanation
      return false;
    }
  }
  const bool overflow = kind == Kind::kQ && l.overflow;
  const uint64_t dims_bytes = static_cast<uint64_t>(ngrid) * ints * ib + (overflow ? 2 * ib : 0);
  const uint64_t dims_at = cursor.pos();
  std::string_view dv;
  std::string dims_scratch;
  bool dims_per_grid = false;
  if (cursor.next(dims_bytes, "dimensions", &rec, why)) {
    dv = recordBytes(bytes, rec, &scratch);
  } else {
    // Each grid's dimensions in a record of its own (`do g; write(u) ni(g), nj(g), nk(g); enddo`).
    if (!l.multi_grid || l.marker == 0 || ngrid < 2 || overflow) return false;
    const std::string why_whole = *why;
    cursor.seek(dims_at);
    for (int64_t g = 0; g < ngrid; ++g) {
      if (!cursor.next(static_cast<uint64_t>(ints) * ib, "dimensions", &rec, why)) {
        *why = why_whole;
        return false;
      }
      dims_scratch.append(recordBytes(bytes, rec, &scratch));
    }
    dv = dims_scratch;
    dims_per_grid = true;
  }
  fit->blocks.assign(static_cast<size_t>(ngrid), BlockDims());
  const uint64_t value_bytes = static_cast<uint64_t>(l.precision);
  fit->nq = 5;
  fit->nqc = 0;
  if (overflow) {
    // NQ and NQC follow the dimensions of all grids.
    const char* tail = dv.data() + ib * ngrid * ints;
    fit->nq = loadSigned(tail, l.int_bytes, l.big_endian);
    fit->nqc = loadSigned(tail + ib, l.int_bytes, l.big_endian);
    if (fit->nq < 1 || static_cast<uint64_t>(fit->nq) > size / value_bytes || fit->nqc < 0 ||
        static_cast<uint64_t>(fit->nqc) > size / value_bytes) {
      *why = "NQ " + std::to_string(fit->nq) + " and NQC " + std::to_string(fit->nqc) + " are impossible";
      *header_ok = l.marker != 0;
      return false;
    }
  }
  for (int64_t g = 0; g < ngrid; ++g) {
    BlockDims& b = fit->blocks[static_cast<size_t>(g)];
    uint64_t points = 1;
    for (int a = 0; a < ints; ++a) {
      const int64_t v = loadSigned(dv.data() + ib * (g * ints + a), l.int_bytes, l.big_endian);
      // Every point takes at least one real in the file: a larger count cannot fit.
      if (v < 1 || static_cast<uint64_t>(v) > size / value_bytes) {
        *why = "dimension " + std::to_string(a + 1) + " of grid " + std::to_string(g + 1) + " is " + std::to_string(v);
        *header_ok = l.marker != 0;
        return false;
      }
      if (a < 3 && a < l.ndim) {
        b.n[a] = v;
        points *= static_cast<uint64_t>(v);
        if (points > size / value_bytes) {
          *why = "grid " + std::to_string(g + 1) + " has more points than the file has bytes for";
          *header_ok = l.marker != 0;
          return false;
        }
      } else if (kind == Kind::kFunction) {
        b.nvar = v;
      }
    }
  }
  if (l.planes && std::all_of(fit->blocks.begin(), fit->blocks.end(), [](const BlockDims& b) { return b.n[2] == 1; })) {
    *why = "every grid has a single k-plane, so the planes layout is the whole layout";
    return false;
  }
  if (l.components && kind == Kind::kFunction &&
      std::all_of(fit->blocks.begin(), fit->blocks.end(), [](const BlockDims& b) { return b.nvar == 1; })) {
    *why = "every grid has a single variable, so one record per variable is the whole layout";
    return false;
  }
  *header_ok = true;
  fit->layout = l;
  fit->layout.dims_per_grid = dims_per_grid;
  fit->headers.clear();
  fit->data.assign(static_cast<size_t>(ngrid), Record());
  for (int64_t g = 0; g < ngrid; ++g) {
    const BlockDims& b = fit->blocks[static_cast<size_t>(g)];
    const uint64_t n = b.points();
    uint64_t per_point = 0;
    if (kind == Kind::kGrid) per_point = l.ndim * value_bytes + (l.iblank ? ib : 0);
    if (kind == Kind::kQ) {
      if (static_cast<uint64_t>(fit->nq) > size / value_bytes / n) {
        *why = "grid " + std::to_string(g + 1) + " (" + dimsText(b) + ", " + std::to_string(fit->nq) +
               " variables) needs more bytes than the file has";
        return false;
      }
      per_point = static_cast<uint64_t>(fit->nq) * value_bytes;
    }
    if (kind == Kind::kFunction) {
      if (static_cast<uint64_t>(b.nvar) > size / value_bytes / n) {
        *why = "grid " + std::to_string(g + 1) + " (" + dimsText(b) + ", " + std::to_string(b.nvar) +
               " variables) needs more bytes than the file has";
        return false;
      }
      per_point = static_cast<uint64_t>(b.nvar) * value_bytes;
    }
    // n * per_point cannot overflow: n and nvar were bounded by the file size above.
    const std::string block_name =
        "grid " + std::to_string(g + 1) + " (" + dimsText(b, kind == Kind::kGrid ? l.ndim : 3) + ") data";
    if (kind == Kind::kQ) {
      // OVERFLOW: 13 + max(2, NQC) reals and the integer IGAM (see the top of the file).
      const uint64_t header_bytes =
          overflow ? ib + (13 + static_cast<uint64_t>(std::max<int64_t>(2, fit->nqc))) * value_bytes : 4 * value_bytes;
      Record header;
      if (!cursor.next(header_bytes, ("grid " + std::to_string(g + 1) + " freestream header").c_str(), &header, why))
        return false;
      fit->headers.push_back(std::move(header));
    }
    if (l.components) {
      // One record per component; the block's record is their pieces in order, the whole layout.
      const std::vector<size_t> component_bytes = componentBytes(*fit, static_cast<size_t>(g), kind);
      if (component_bytes.size() < 2) {
        *why = "a single variable: one record per variable is the whole layout";
        return false;
      }
      Record& all = fit->data[static_cast<size_t>(g)];
      for (size_t c = 0; c < component_bytes.size(); ++c) {
        const std::string name = block_name + ", variable " + std::to_string(c + 1);
        if (!cursor.next(n * component_bytes[c], name.c_str(), &rec, why)) return false;
        all.insert(all.end(), rec.begin(), rec.end());
      }
    } else if (l.planes) {
      // One record per k-plane; the block's record is their pieces in order (blockBytes reorders).
      Record& all = fit->data[static_cast<size_t>(g)];
      const uint64_t plane_bytes = static_cast<uint64_t>(b.n[0] * b.n[1]) * per_point;
      for (int64_t k = 0; k < b.n[2]; ++k) {
        const std::string plane_name = block_name + ", plane " + std::to_string(k + 1);
        if (!cursor.next(plane_bytes, plane_name.c_str(), &rec, why)) return false;
        all.insert(all.end(), rec.begin(), rec.end());
      }
    } else if (!cursor.next(n * per_point, block_name.c_str(), &fit->data[static_cast<size_t>(g)], why)) {
      return false;
    }
  }
  fit->end = cursor.pos();
  return true;
}

struct Attempt {
  Layout layout;
  std::string why;
  uint64_t progress = 0;  // bytes whose records checked out before the failure
};

struct Detection {
  std::vector<Fit> exact;          // sizes match the file exactly
  std::vector<Fit> zero_tail;      // data followed by zero bytes only
  std::vector<Attempt> plausible;  // failed after a sensible header, or left non-zero trailing bytes
  size_t header_failures = 0;      // failed at the grid count, dimensions or record markers
};

bool allZero(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c == 0; });
}

Detection detect(std::string_view bytes, Kind kind, const Constraints& constraints) {
  Detection d;
  for (int be = 1; be >= 0; --be) {
    for (int marker : {0, 4, 8}) {
      for (int multi = 0; multi < 2; ++multi) {
        for (int ndim : {3, 2}) {
          if (ndim == 2 && kind != Kind::kGrid) continue;
          for (int precision : {4, 8}) {
            for (int int_bytes : {4, 8}) {
              if (int_bytes == 8 && marker == 0) continue;  // sizes alone cannot vouch for it
              for (int variant = 0; variant < 8; ++variant) {
                // Bit 0: with IBLANK for grids, OVERFLOW's layout for Q files; bit 1: written plane
                // by plane (told apart by record markers only, 3D only); bit 2: one record per
                // variable (record markers only).
                if ((variant & 1) && kind == Kind::kFunction) continue;
                if ((variant & 2) && ndim != 3) continue;
                if ((variant & 4) && (marker == 0 || (variant & 2))) continue;
                Layout l;
                l.big_endian = be != 0;
                l.marker = marker;
                l.multi_grid = multi != 0;
                l.ndim = ndim;
                l.precision = precision;
                l.iblank = (variant & 1) != 0 && kind == Kind::kGrid;
                l.overflow = (variant & 1) != 0 && kind == Kind::kQ;
                l.planes = (variant & 2) != 0;
                l.components = (variant & 4) != 0;
                l.int_bytes = int_bytes;
                if (!constraints.allows(l, kind)) continue;
                Fit fit;
                std::string why;
                bool header_ok = false;
                uint64_t progress = 0;
                if (!tryLayout(bytes, l, kind, &fit, &why, &header_ok, &progress)) {
                  if (header_ok) {
                    d.plausible.push_back({l, why, progress});
                  } else {
                    ++d.header_failures;
                  }
                  continue;
                }
                if (fit.end == bytes.size()) {
                  d.exact.push_back(std::move(fit));
                } else if (allZero(bytes.substr(fit.end))) {
                  d.zero_tail.push_back(std::move(fit));
                } else {
                  d.plausible.push_back({l,
                                         "grids " + blocksText(fit.blocks) + " end at byte " + std::to_string(fit.end) +
                                             ", followed by " + std::to_string(bytes.size() - fit.end) +
                                             " bytes that are not all zero",
                                         fit.end});
                }
              }
            }  // int_bytes
          }
        }
      }
    }
  }
  // The interpretations that got furthest explain the failure best; those with record markers first:
  // they got past a header whose markers checked out, which a marker-less reading of the same bytes
  // (the marker taken for a dimension) gets past by chance.
  // Without markers the planes reading is the rarer one: it explains a failure only after the others
  // (it gets further in a truncated whole file, plane by plane).
  std::stable_sort(d.plausible.begin(), d.plausible.end(), [](const Attempt& a, const Attempt& b) {
    if ((a.layout.marker != 0) != (b.layout.marker != 0)) return a.layout.marker != 0;
    const bool pa = a.layout.marker == 0 && a.layout.planes, pb = b.layout.marker == 0 && b.layout.planes;
    if (pa != pb) return pb;
    return a.progress > b.progress;
  });
  return d;
}

std::string triedText(const Detection& d, Kind kind) {
  std::string s =
      "tried big- and little-endian, no/4-byte/8-byte record markers, whole, planes and one record per "
      "variable, single and multi-grid, ";
  s += "32-bit integers (and 64-bit ones with record markers), ";
  s += kind == Kind::kGrid
           ? "2D and 3D, float32 and float64, with and without IBLANK"
           : (kind == Kind::kQ ? "float32 and float64, classic and OVERFLOW layouts" : "float32 and float64");
  s += " (binary; text files are read as ASCII PLOT3D)";
  const size_t shown = std::min<size_t>(d.plausible.size(), 8);
  for (size_t i = 0; i < shown; ++i)
    s += "; [" + std::to_string(i + 1) + "] " + describeLayout(d.plausible[i].layout, kind) + ": " + d.plausible[i].why;
  if (d.plausible.size() > shown) s += "; ... and " + std::to_string(d.plausible.size() - shown) + " more";
  if (d.header_failures)
    s += "; " + std::to_string(d.header_failures) +
         " other interpretations fail at once (impossible grid count, dimensions or record markers)";
  return s;
}

bool looksLikeText(std::string_view bytes) {
  const std::string_view head = bytes.substr(0, 512);
  return !head.empty() && std::all_of(head.begin(), head.end(), [](char c) {
    const unsigned char u = static_cast<unsigned char>(c);
    return u == '\n' || u == '\r' || u == '\t' || (u >= 32 && u < 127);
  });
}

bool sameDims(const std::vector<BlockDims>& a, const std::vector<BlockDims>& b) {
  if (a.size() != b.size()) return false;
  for (size_t g = 0; g < a.size(); ++g) {
    for (int k = 0; k < 3; ++k)
      if (a[g].n[k] != b[g].n[k]) return false;
  }
  return true;
}

// The values of one block read with a fit, found in place (no copy of the block): component c of
// point p, in the whole layout's terms, wherever the fit's records put it (whole, planes or one
// record per variable; a record may be in several pieces).
class BlockValues {
 public:
  BlockValues(std::string_view bytes, const Fit& fit, size_t g, const std::vector<size_t>& component_bytes)
      : bytes_(bytes), rec_(fit.data[g]), l_(fit.layout), cb_(component_bytes) {
    const BlockDims& b = fit.blocks[g];
    n_ = b.points();
    plane_ = static_cast<uint64_t>(b.n[0] * b.n[1]);
    uint64_t at = 0;
    for (const Piece& piece : rec_) {
      starts_.push_back(at);
      at += piece.size;
    }
    before_.assign(cb_.size() + 1, 0);
    for (size_t c = 0; c < cb_.size(); ++c) before_[c + 1] = before_[c] + cb_[c];
  }
  double real(size_t c, uint64_t p) const {
    char buf[8];
    read(offset(c, p), static_cast<size_t>(l_.precision), buf);
    return loadReal(buf, l_.precision, l_.big_endian);
  }

 private:
  uint64_t offset(size_t c, uint64_t p) const {
    if (!l_.planes) return before_[c] * n_ + p * cb_[c];
    const uint64_t k = p / plane_, in_plane = p % plane_;
    return k * plane_ * before_.back() + before_[c] * plane_ + in_plane * cb_[c];
  }
  void read(uint64_t at, size_t size, char* out) const {
    size_t i = static_cast<size_t>(std::upper_bound(starts_.begin(), starts_.end(), at) - starts_.begin()) - 1;
    for (size_t done = 0; done < size; ++i) {  // a value may straddle two pieces (subrecords)
      const uint64_t off = at + done - starts_[i];
      const size_t take = static_cast<size_t>(std::min<uint64_t>(size - done, rec_[i].size - off));
      std::memcpy(out + done, bytes_.data() + rec_[i].offset + off, take);
      done += take;
    }
  }
  std::string_view bytes_;
  const Record& rec_;
  const Layout& l_;
  std::vector<size_t> cb_;
  std::vector<uint64_t> starts_, before_;
  uint64_t n_ = 0, plane_ = 1;
};

// The data checks below look at a sample: enough to tell a right reading from a wrong one, at a cost
// that does not grow with the grid (every marker-less 3D file has two readings to compare).
constexpr uint64_t kSampleSize = 20000;
uint64_t sampleStride(uint64_t count) { return std::max<uint64_t>(1, count / kSampleSize) | 1; }

// How many sampled cells of a grid fit read with `fit` have the orientation most of them have: the
// sign of the corner at (i, j, k) spanned by its three neighbours (exact). A grid read with its own
// layout is consistent (its cells all right- or all left-handed); read with another layout whose
// records happen to have the same sizes, its points land in the wrong places and its cells go flat
// or turn both ways.
uint64_t consistentCells(std::string_view bytes, const Fit& fit) {
  const Layout& l = fit.layout;
  uint64_t positive = 0, negative = 0;
  for (size_t g = 0; g < fit.blocks.size(); ++g) {
    const BlockDims& b = fit.blocks[g];
    if (l.ndim != 3 || b.n[0] < 2 || b.n[1] < 2 || b.n[2] < 2) continue;
    const BlockValues v(bytes, fit, g, componentBytes(fit, g, Kind::kGrid));
    const uint64_t ci = static_cast<uint64_t>(b.n[0] - 1), cj = static_cast<uint64_t>(b.n[1] - 1),
                   cells = ci * cj * static_cast<uint64_t>(b.n[2] - 1);
    auto point = [&](uint64_t i, uint64_t j, uint64_t k, double out[3]) {
      const uint64_t at = i + static_cast<uint64_t>(b.n[0]) * (j + static_cast<uint64_t>(b.n[1]) * k);
      for (int a = 0; a < 3; ++a) out[a] = v.real(static_cast<size_t>(a), at);
    };
    for (uint64_t t = 0; t < cells; t += sampleStride(cells)) {
      const uint64_t i = t % ci, j = (t / ci) % cj, k = t / (ci * cj);
      double p[4][3];
      point(i, j, k, p[0]);
      point(i + 1, j, k, p[1]);
      point(i, j + 1, k, p[2]);
      point(i, j, k + 1, p[3]);
      bool finite = true;  // the exact predicate wants finite input; addGrid reports the others
      for (const auto& q : p) finite &= std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]);
      if (!finite) continue;
      const int o = orient3d(p[0], p[1], p[2], p[3]);
      positive += o > 0;
      negative += o < 0;
    }
  }
  return std::max(positive, negative);
}

// How far apart the values of grid neighbours lie when the file is read with `fit`: the mean over
// blocks, components and sampled neighbour pairs along i, j and k of |difference|. Coordinates
// (grids) or variables (Q and function files) vary smoothly over a grid; read with another layout
// whose records happen to have the same sizes, one array's values land in another's places and the
// seams jump (from density to energy, say). The readings being compared hold the same values in
// other places, so their sums are on one scale. Non-finite values are left out.
double roughness(std::string_view bytes, const Fit& fit, Kind kind) {
  double sum = 0;
  uint64_t pairs = 0;
  for (size_t g = 0; g < fit.blocks.size(); ++g) {
    const BlockDims& b = fit.blocks[g];
    const uint64_t n = b.points(), ni = static_cast<uint64_t>(b.n[0]), nj = static_cast<uint64_t>(b.n[1]);
    const std::vector<size_t> cb = componentBytes(fit, g, kind);
    const size_t count = kind == Kind::kGrid ? static_cast<size_t>(fit.layout.ndim) : cb.size();  // not IBLANK
    const BlockValues v(bytes, fit, g, cb);
    const uint64_t step[3] = {1, ni, ni * nj};
    for (uint64_t p = 0; p < n; p += sampleStride(n)) {
      const uint64_t i = p % ni, j = (p / ni) % nj;
      for (int a = 0; a < 3; ++a) {
        if ((a == 0 && i + 1 >= ni) || (a == 1 && j + 1 >= nj) || p + step[a] >= n) continue;
        for (size_t c = 0; c < count; ++c) {
          const double d = std::fabs(v.real(c, p + step[a]) - v.real(c, p));
          if (!std::isfinite(d)) continue;
          sum += d;
          ++pairs;
        }
      }
    }
  }
  return pairs ? sum / static_cast<double>(pairs) : 0.0;
}

// Picks the one fit among `fits` that `accept` takes, preferring the grid file's byte order and
// record markers when several remain, then fits with record markers over fits without. Readings that
// differ only in their records (whole, planes, one per variable: the planes of a grid of 3 k-planes
// have the sizes of its x, y and z records, and a Q file of 5 k-planes likewise) are told apart by
// their data: for grids the consistency of their cells first, then for every kind the roughness of
// their values; only when the data cannot tell (the readings give the same values) does the grid's
// own records decide. Empty when none; an error when still ambiguous.
StatusOr<std::optional<Fit>> pickOne(const std::string& path, std::string_view bytes, Kind kind, std::vector<Fit> fits,
                                     const std::function<bool(const Fit&)>& accept, const Layout* prefer) {
  std::vector<Fit> ok;
  for (Fit& f : fits)
    if (accept(f)) ok.push_back(std::move(f));
  if (ok.size() > 1 && prefer) {
    std::vector<Fit> same;
    for (const Fit& f : ok)
      if (f.layout.big_endian == prefer->big_endian && f.layout.marker == prefer->marker) same.push_back(f);
    if (!same.empty()) ok = std::move(same);
  }
  if (ok.size() > 1) {
    // Readings alike but for their records: the data decides.
    auto alike = [](const Layout& a, const Layout& b) {
      return a.big_endian == b.big_endian && a.marker == b.marker && a.multi_grid == b.multi_grid && a.ndim == b.ndim &&
             a.precision == b.precision && a.iblank == b.iblank && a.overflow == b.overflow;
    };
    std::vector<uint64_t> consistent(ok.size(), 0);
    std::vector<double> rough(ok.size(), 0.0);
    for (size_t i = 0; i < ok.size(); ++i) {
      if (kind == Kind::kGrid) consistent[i] = consistentCells(bytes, ok[i]);
      rough[i] = roughness(bytes, ok[i], kind);
    }
    auto sameRecords = [&](const Fit& f) {
      return prefer && f.layout.planes == prefer->planes && f.layout.components == prefer->components;
    };
    // j beats i: more consistent cells; else values clearly smoother (a wrong reading's seams make
    // it rougher by far; 1% keeps rounding noise out); else, the data agreeing, the grid's records.
    // Without record markers every 3D file also fits plane by plane: there a grid leaves the whole
    // layout only for cells that are more consistent, never for smoothness alone.
    auto whole = [](const Fit& f) { return !f.layout.planes && !f.layout.components; };
    auto beats = [&](size_t j, size_t i) {
      if (consistent[j] != consistent[i]) return consistent[j] > consistent[i];
      if (!(kind == Kind::kGrid && ok[i].layout.marker == 0)) {
        if (rough[j] < 0.99 * rough[i]) return true;
        if (rough[i] < 0.99 * rough[j]) return false;
      }
      if (sameRecords(ok[j]) != sameRecords(ok[i])) return sameRecords(ok[j]);
      return whole(ok[j]) && !whole(ok[i]);
    };
    std::vector<Fit> kept;
    for (size_t i = 0; i < ok.size(); ++i) {
      bool beaten = false;
      for (size_t j = 0; j < ok.size() && !beaten; ++j)
        beaten = j != i && alike(ok[i].layout, ok[j].layout) && beats(j, i);
      if (!beaten) kept.push_back(ok[i]);
    }
    ok = std::move(kept);
  }
  if (ok.size() > 1) {
    // A fit whose record markers all check out carries a signature that a marker-less fit of the
    // same size (the bytes merely adding up) does not: it wins.
    std::vector<Fit> marked;
    for (const Fit& f : ok)
      if (f.layout.marker != 0) marked.push_back(f);
    if (!marked.empty() && marked.size() < ok.size()) ok = std::move(marked);
  }
  if (ok.empty()) return std::optional<Fit>();
  if (ok.size() == 1) return std::optional<Fit>(std::move(ok[0]));
  std::string msg = path + ": ambiguous PLOT3D " + kindName(kind) + " file: " + std::to_string(ok.size()) +
                    " interpretations fit it; name the layout in a .p3d meta-file (keys \"byte-order\", \"precision\", "
                    "\"multi-grid\", \"blanking\", \"language\", and gtn's \"records\": \"whole\", \"planes\" or "
                    "\"variables\"):";
  for (size_t i = 0; i < ok.size(); ++i)
    msg += " [" + std::to_string(i + 1) + "] " + describeLayout(ok[i].layout, kind) + ": grids " +
           blocksText(ok[i].blocks) + (i + 1 < ok.size() ? ";" : "");
  return invalidData(msg);
}

struct Selected {
  Fit fit;
  bool found = false;
};

// Chooses the interpretation of one file: exact fits first, then fits followed by zero bytes
// (with a warning). `accept` filters (Q and function files must match the grid).
StatusOr<Selected> selectFit(const std::string& path, std::string_view bytes, Kind kind, const Detection& d,
                             const std::function<bool(const Fit&)>& accept, const Layout* prefer,
                             std::vector<std::string>* warnings) {
  Selected s;
  GTN_ASSIGN_OR_RETURN(std::optional<Fit> exact, pickOne(path, bytes, kind, d.exact, accept, prefer));
  if (exact) {
    s.fit = std::move(*exact);
    s.found = true;
    return s;
  }
  GTN_ASSIGN_OR_RETURN(std::optional<Fit> padded, pickOne(path, bytes, kind, d.zero_tail, accept, prefer));
  if (padded) {
    s.fit = std::move(*padded);
    s.found = true;
    warnings->push_back(std::string("PLOT3D ") + kindName(kind) + " file " + path + ": ignored " +
                        std::to_string(bytes.size() - s.fit.end) + " trailing zero bytes after its data (from byte " +
                        std::to_string(s.fit.end) + ")");
  }
  return s;
}

StatusOr<std::string> readInput(const std::string& path, Kind kind) {
  GTN_ASSIGN_OR_RETURN(std::string bytes, readWholeFile(path));
  if (bytes.empty()) return invalidData(path + ": PLOT3D " + kindName(kind) + " file is empty (0 bytes)");
  return bytes;
}

Status noFitError(const std::string& path, std::string_view bytes, Kind kind, const Detection& d) {
  std::string msg = path + ": not a PLOT3D " + kindName(kind) + " file this reader understands (" +
                    std::to_string(bytes.size()) + " bytes): no interpretation fits its size exactly";
  if (looksLikeText(bytes)) msg += "; it looks like text, but not like ASCII PLOT3D either";
  return invalidData(msg + "; " + triedText(d, kind));
}

// How a Q or function file fails when read with its grid's byte order, record markers, precision
// and layout (files written together share them): the likeliest explanation, named first. Empty
// for a grid read from text, or when that reading fits.
std::string gridLayoutReading(std::string_view bytes, Kind kind, const Layout& grid) {
  if (grid.ascii) return "";
  Layout l = grid;
  l.ndim = 3;
  l.iblank = false;
  l.overflow = false;
  Fit fit;
  std::string why;
  bool header_ok = false;
  uint64_t progress = 0;
  if (tryLayout(bytes, l, kind, &fit, &why, &header_ok, &progress)) return "";
  return "read like its grid (" + describeLayout(l, kind) + "): " + why;
}

// Why no interpretation of a Q or function file goes with the grid: its dimensions disagree with
// the grid's, or nothing fits at all.
Status noMatchError(const std::string& path, std::string_view bytes, Kind kind, const Detection& d,
                    const std::vector<BlockDims>& grid_blocks, const std::string& grid_path,
                    const Layout& grid_layout) {
  const std::vector<Fit>& fits = d.exact.empty() ? d.zero_tail : d.exact;
  if (fits.empty()) {
    const std::string likely = gridLayoutReading(bytes, kind, grid_layout);
    if (likely.empty()) return noFitError(path, bytes, kind, d);
    const Status all = noFitError(path, bytes, kind, d);
    const std::string prefix = path + ": ";
    return invalidData(prefix + likely + "; " +
                       all.message().substr(all.message().rfind(prefix, 0) == 0 ? prefix.size() : 0));
  }
  return invalidData(path + ": PLOT3D " + kindName(kind) + " file dimensions " + blocksText(fits[0].blocks) + " (" +
                     describeLayout(fits[0].layout, kind) + ") disagree with the grid's " + blocksText(grid_blocks) +
                     " (" + grid_path + ")");
}

// ---------------------------------------------------------------------------------------------
// ASCII PLOT3D: the same records as text (Fortran list-directed or C printf output; commas may
// separate values, exponents may be written with D). Which layout the text holds is decided by its
// value count, as the size decides it for binary files; the chosen layout is then transcoded into a
// binary file (little-endian, no record markers, int32 integers, float64 reals) that the binary
// reader reads with that layout imposed.

struct AsciiValues {
  std::vector<double> v;
  std::vector<uint64_t> line;  // 1-based line of each value
};

StatusOr<AsciiValues> readAsciiValues(const std::string& path, std::string_view text) {
  AsciiValues out;
  uint64_t line = 1;
  size_t i = 0;
  std::string token;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ',') {
      ++i;
      continue;
    }
    size_t e = i;
    while (e < text.size() && !std::strchr(" \t\r\n,", text[e])) ++e;
    token.assign(text.substr(i, e - i));
    for (char& ch : token)
      if (ch == 'D' || ch == 'd') ch = 'E';
    if (token.find_first_not_of('*') == std::string::npos)
      return invalidData(path + ":" + std::to_string(line) + ": ASCII PLOT3D: '" + token.substr(0, 40) +
                         "' is a Fortran field that overflowed its format (the value did not fit its width)");
    if (token.find('*') != std::string::npos)
      return unsupported(path + ":" + std::to_string(line) + ": Fortran repeat counts ('" + token.substr(0, 40) +
                         "') are not supported in ASCII PLOT3D");
    double v;
    if (!parseDouble(token, &v))
      return invalidData(path + ":" + std::to_string(line) + ": ASCII PLOT3D: '" + token.substr(0, 40) +
                         "' is not a number");
    out.v.push_back(v);
    out.line.push_back(line);
    i = e;
  }
  return out;
}

bool asciiInt(double v, int64_t* out) {
  if (!(v >= -2147483648.0 && v <= 2147483647.0) || v != std::floor(v)) return false;
  *out = static_cast<int64_t>(v);
  return true;
}

// Transcodes the values as `l` lays them out, or says why they do not fit it.
bool transcodeAscii(const AsciiValues& a, const Layout& l, Kind kind, ByteWriter* bin, std::string* why) {
  const std::vector<double>& v = a.v;
  const uint64_t n = v.size();
  uint64_t pos = 0;
  auto take_int = [&](const char* what, int64_t* out) {
    if (pos >= n) {
      *why = std::string("the text ends before the ") + what;
      return false;
    }
    if (!asciiInt(v[pos], out)) {
      *why = std::string("the ") + what + " on line " + std::to_string(a.line[pos]) + " is not an integer";
      return false;
    }
    ++pos;
    return true;
  };
  int64_t ngrid = 1;
  if (l.multi_grid) {
    if (!take_int("grid count", &ngrid)) return false;
    if (ngrid < 1 || static_cast<uint64_t>(ngrid) > n) {
      *why = "grid count " + std::to_string(ngrid) + " is impossible";
      return false;
    }
    bin->u32(static_cast<uint32_t>(ngrid));
  }
  const int ints = kind == Kind::kFunction ? 4 : (kind == Kind::kGrid ? l.ndim : 3);
  std::vector<uint64_t> points(static_cast<size_t>(ngrid), 1), nvar(static_cast<size_t>(ngrid), 0);
  for (int64_t g = 0; g < ngrid; ++g) {
    for (int k = 0; k < ints; ++k) {
      int64_t d;
      if (!take_int("grid dimensions", &d)) return false;
      if (d < 1 || static_cast<uint64_t>(d) > n) {
        *why = "dimension " + std::to_string(k + 1) + " of grid " + std::to_string(g + 1) + " is " + std::to_string(d);
        return false;
      }
      if (k < 3) {
        points[g] *= static_cast<uint64_t>(d);
        if (points[g] > n) {
          *why = "grid " + std::to_string(g + 1) + " has more points than the text has values";
          return false;
        }
      } else {
        nvar[g] = static_cast<uint64_t>(d);
      }
      bin->u32(static_cast<uint32_t>(d));
    }
  }
  // The value count must match exactly (checked before transcoding the bulk of the file).
  uint64_t need = pos;
  for (int64_t g = 0; g < ngrid; ++g) {
    uint64_t per_point =
        kind == Kind::kGrid ? static_cast<uint64_t>(l.ndim + (l.iblank ? 1 : 0)) : (kind == Kind::kQ ? 5 : nvar[g]);
    if (per_point != 0 && points[g] > (n + 4) / per_point) {
      *why = "grid " + std::to_string(g + 1) + " needs more values than the text has";
      return false;
    }
    need += points[g] * per_point + (kind == Kind::kQ ? 4 : 0);
  }
  if (need != n) {
    *why = "the header announces " + std::to_string(need) + " values, the text has " + std::to_string(n);
    return false;
  }
  for (int64_t g = 0; g < ngrid; ++g) {
    if (kind == Kind::kQ)
      for (int k = 0; k < 4; ++k) bin->f64(v[pos++]);
    const uint64_t reals = kind == Kind::kGrid ? points[g] * l.ndim : points[g] * (kind == Kind::kQ ? 5 : nvar[g]);
    for (uint64_t k = 0; k < reals; ++k) bin->f64(v[pos++]);
    if (kind == Kind::kGrid && l.iblank) {
      for (uint64_t k = 0; k < points[g]; ++k) {
        int64_t b;
        if (!take_int("IBLANK value", &b)) return false;
        bin->u32(static_cast<uint32_t>(static_cast<int32_t>(b)));
      }
    }
  }
  return true;
}

// An ASCII file as the binary file of its one fitting layout; `*layout` receives that layout (the
// binary reader must be held to it). Fails when none or several layouts fit.
StatusOr<std::string> asciiAsBinary(const std::string& path, std::string_view text, Kind kind,
                                    const Constraints& constraints, Layout* layout) {
  GTN_ASSIGN_OR_RETURN(const AsciiValues values, readAsciiValues(path, text));
  if (values.v.empty())
    return invalidData(path + ": ASCII PLOT3D " + std::string(kindName(kind)) + " file holds no values");
  std::vector<std::pair<Layout, std::string>> fits;
  std::string tried;
  for (int multi = 0; multi < 2; ++multi) {
    for (int ndim : {3, 2}) {
      if (ndim == 2 && kind != Kind::kGrid) continue;
      for (int iblank = 0; iblank < 2; ++iblank) {
        if (iblank && kind != Kind::kGrid) continue;
        Layout l;
        l.big_endian = false;
        l.marker = 0;
        l.multi_grid = multi != 0;
        l.ndim = ndim;
        l.precision = 8;
        l.iblank = iblank != 0;
        l.ascii = true;
        if (constraints.multi_grid && *constraints.multi_grid != l.multi_grid) continue;
        if (kind == Kind::kGrid && constraints.iblank && *constraints.iblank != l.iblank) continue;
        if (kind == Kind::kGrid && constraints.ndim && *constraints.ndim != l.ndim) continue;
        ByteWriter bin;
        std::string why;
        if (transcodeAscii(values, l, kind, &bin, &why)) {
          fits.emplace_back(l, std::string(bin.bytes().begin(), bin.bytes().end()));
        } else {
          tried += "; " + describeLayout(l, kind) + ": " + why;
        }
      }
    }
  }
  if (fits.empty())
    return invalidData(path + ": not a PLOT3D " + std::string(kindName(kind)) +
                       " file this reader understands: it is text (" + std::to_string(values.v.size()) +
                       " values) and no ASCII PLOT3D layout fits its value count" + tried);
  if (fits.size() > 1) {
    std::string msg = path + ": ambiguous ASCII PLOT3D " + std::string(kindName(kind)) +
                      " file: " + std::to_string(fits.size()) + " layouts fit its " + std::to_string(values.v.size()) +
                      " values; name the layout in a .p3d meta-file:";
    for (size_t i = 0; i < fits.size(); ++i)
      msg += " [" + std::to_string(i + 1) + "] " + describeLayout(fits[i].first, kind);
    return invalidData(msg);
  }
  *layout = fits[0].first;
  return std::move(fits[0].second);
}

// The constraints that hold the binary reader to a transcoded layout.
Constraints imposed(const Layout& l) {
  Constraints c;
  c.big_endian = l.big_endian;
  c.fortran = l.marker != 0;
  c.multi_grid = l.multi_grid;
  c.precision = l.precision;
  c.iblank = l.iblank;
  c.ndim = l.ndim;
  c.overflow = l.overflow;
  c.planes = l.planes;
  c.components = l.components;
  return c;
}

// Text is read as ASCII PLOT3D when no binary interpretation fits it exactly: *bytes becomes the
// transcoded binary and *d its detection under the layout the text fits.
Status asciiFallback(const std::string& path, Kind kind, const Constraints& constraints, std::string* bytes,
                     Detection* d) {
  if (!d->exact.empty() || !looksLikeText(*bytes)) return Status::ok();
  Layout l;
  GTN_ASSIGN_OR_RETURN(std::string bin, asciiAsBinary(path, *bytes, kind, constraints, &l));
  *d = detect(bin, kind, imposed(l));
  for (Fit& f : d->exact) f.layout.ascii = true;
  *bytes = std::move(bin);
  return Status::ok();
}

// ---------------------------------------------------------------------------------------------
// The .p3d meta-file.

struct P3dFiles {
  std::string xyz, q, function;
  std::vector<std::string> function_names;  // "function-names": the function file's variables
  Constraints constraints;
  std::vector<std::string> warnings;
};

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

// A .json file, or a .p3d file that is JSON text: many .p3d files are PLOT3D grids themselves (gmsh's
// -format p3d writes an ASCII grid so, and CFD grids are often so named), read as grid files. A file
// that cannot be read is taken by its name, for readP3dMeta to say why.
bool isP3dMeta(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return false;
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "json") return true;
  if (ext != "p3d") return false;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return true;
  char head[64];
  const size_t n = std::fread(head, 1, sizeof head, f);
  std::fclose(f);
  const std::string_view h(head, n);
  if (h.find('\0') != std::string_view::npos) return false;  // binary: a grid
  const size_t first = h.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  return first != std::string_view::npos && (h[first] == '{' || h[first] == '[');
}

StatusOr<P3dFiles> readP3dMeta(const std::string& path) {
  // A meta-file is a few hundred bytes; a large one is not a meta-file.
  GTN_ASSIGN_OR_RETURN(std::string text, readWholeFile(path, 16u << 20));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    return invalidData(path + ": not a valid .p3d JSON meta-file: byte " + std::to_string(e.byte) + ": " + e.what());
  }
  if (!j.is_object()) return invalidData(path + ": a .p3d meta-file must hold one JSON object");
  P3dFiles out;
  const std::string dir = directoryOf(path);
  auto bad = [&](const std::string& key, const std::string& expected) {
    return invalidData(path + ": key \"" + key + "\" must be " + expected + ", not " + j[key].dump());
  };
  bool auto_detect = false;
  if (j.contains("auto-detect-format")) {
    if (!j["auto-detect-format"].is_boolean()) return bad("auto-detect-format", "true or false");
    auto_detect = j["auto-detect-format"].get<bool>();
  }
  nlohmann::json files;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    const nlohmann::json& v = it.value();
    if (key == "auto-detect-format") continue;
    if (key == "filenames") {
      files = v;
      continue;
    }
    if (key == "format") {
      if (!v.is_string() || (v != "binary" && v != "ascii")) return bad(key, "\"binary\" or \"ascii\"");
      continue;  // text is recognised by its content
    }
    // ParaView ignores the layout keys when auto-detection is on; so do we.
    if (key == "byte-order") {
      if (!v.is_string() || (v != "big" && v != "little")) return bad(key, "\"big\" or \"little\"");
      if (!auto_detect) out.constraints.big_endian = v == "big";
    } else if (key == "precision") {
      if (!v.is_number_integer() || (v != 32 && v != 64)) return bad(key, "32 or 64");
      if (!auto_detect) out.constraints.precision = v.get<int>() / 8;
    } else if (key == "multi-grid") {
      if (!v.is_boolean()) return bad(key, "true or false");
      if (!auto_detect) out.constraints.multi_grid = v.get<bool>();
    } else if (key == "blanking") {
      if (!v.is_boolean()) return bad(key, "true or false");
      if (!auto_detect) out.constraints.iblank = v.get<bool>();
    } else if (key == "language") {
      // ParaView's reader spells them "C" and "fortran" (and nothing else); "Fortran" is read too.
      if (!v.is_string() || (v != "C" && v != "fortran" && v != "Fortran")) return bad(key, "\"C\" or \"fortran\"");
      if (!auto_detect) out.constraints.fortran = v != "C";
    } else if (key == "records") {
      // gtn's own key (ParaView has none for this): how the data records are cut. Always obeyed.
      if (!v.is_string() || (v != "whole" && v != "planes" && v != "variables"))
        return bad(key, "\"whole\", \"planes\" or \"variables\"");
      out.constraints.planes = v == "planes";
      out.constraints.components = v == "variables";
    } else if (key == "function-names") {
      // ParaView's names for the function file's variables, in order.
      if (!v.is_array()) return bad(key, "a list of names");
      for (const nlohmann::json& name : v) {
        if (!name.is_string() || name.get<std::string>().empty()) return bad(key, "a list of non-empty names");
        const std::string n = name.get<std::string>();
        if (std::find(out.function_names.begin(), out.function_names.end(), n) != out.function_names.end())
          return invalidData(path + ": key \"function-names\" lists \"" + n + "\" twice");
        out.function_names.push_back(n);
      }
    } else if (key == "2D") {
      if (!v.is_boolean()) return bad(key, "true or false");
      if (v.get<bool>()) return unsupported(path + ": \"2D\": true: 2D grids cannot become tetrahedra");
      if (!auto_detect) out.constraints.ndim = 3;
    } else {
      out.warnings.push_back(path + ": ignored key \"" + key + "\"");
    }
  }
  if (files.is_string() || files.is_object()) files = nlohmann::json::array({files});
  if (!files.is_array() || files.empty())
    return invalidData(path + ": \"filenames\" must list at least one entry with an \"xyz\" file");
  // The first time step: the smallest "time", or the first entry when none has one.
  size_t chosen = 0;
  for (size_t i = 0; i < files.size(); ++i) {
    const nlohmann::json& e = files[i];
    if (!e.is_object() && !e.is_string())
      return invalidData(path + ": \"filenames\"[" + std::to_string(i) + "] must be an object");
    if (e.is_object() && e.contains("time") && !e["time"].is_number())
      return invalidData(path + ": \"filenames\"[" + std::to_string(i) + "].time must be a number");
    auto time_of = [](const nlohmann::json& x) {
      return x.is_object() && x.contains("time") ? x["time"].get<double>() : 0.0;
    };
    if (time_of(e) < time_of(files[chosen])) chosen = i;
  }
  if (files.size() > 1)
    out.warnings.push_back(path + ": " + std::to_string(files.size()) +
                           " time steps listed; imported only the first (entry " + std::to_string(chosen + 1) + ")");
  const nlohmann::json& e = files[chosen];
  auto resolve = [&](const std::string& name) { return !name.empty() && name[0] == '/' ? name : dir + name; };
  if (e.is_string()) {
    out.xyz = resolve(e.get<std::string>());
    return out;
  }
  for (const char* key : {"xyz", "q", "function"}) {
    if (!e.contains(key)) continue;
    if (!e[key].is_string() || e[key].get<std::string>().empty())
      return invalidData(path + ": \"filenames\"[" + std::to_string(chosen) + "]." + key + " must be a file name");
    const std::string p = resolve(e[key].get<std::string>());
    if (std::string(key) == "xyz") out.xyz = p;
    if (std::string(key) == "q") out.q = p;
    if (std::string(key) == "function") out.function = p;
  }
  if (out.xyz.empty())
    return invalidData(path + ": \"filenames\"[" + std::to_string(chosen) + "] names no \"xyz\" grid file");
  return out;
}

// ---------------------------------------------------------------------------------------------
// Building the mesh.

std::string realText(double v, int precision) {
  char buf[40];
  std::snprintf(buf, sizeof buf, precision == 4 ? "%.9g" : "%.17g", v);
  return buf;
}

// Copies `count` values of `size` bytes from a source record into field bytes (little-endian),
// `stride` values apart in the field starting at value index `first`.
void copyValues(const char* src, size_t count, int size, bool big_endian, Field* f, size_t first, size_t stride) {
  uint8_t* dst = f->bytes.data();
  for (size_t i = 0; i < count; ++i)
    storeLittle(src + i * size, size, big_endian, dst + (first + i * stride) * static_cast<size_t>(size));
}

Status addGrid(const std::string& path, std::string_view bytes, const Fit& fit, TetMesh& mesh,
               std::vector<int32_t>* iblank) {
  const Layout& l = fit.layout;
  uint64_t total = 0;
  for (const BlockDims& b : fit.blocks) total += b.points();
  if (total > UINT32_MAX)
    return unsupported(path + ": " + std::to_string(total) + " points exceed the 2^32 limit of a mesh");
  mesh.coord_type = l.precision == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  resizePopulated(mesh.coords, 3 * total);
  if (l.iblank) iblank->resize(total);
  std::string scratch, reordered;
  size_t base = 0;
  for (size_t g = 0; g < fit.blocks.size(); ++g) {
    const size_t n = fit.blocks[g].points();
    const std::string_view v = blockBytes(bytes, fit, g, componentBytes(fit, g, Kind::kGrid), &scratch, &reordered);
    for (int a = 0; a < 3; ++a) {
      const char* src = v.data() + a * n * l.precision;
      for (size_t i = 0; i < n; ++i) {
        const double x = loadReal(src + i * l.precision, l.precision, l.big_endian);
        if (!std::isfinite(x)) {
          const uint64_t offset = fit.data[g].size() == 1 ? fit.data[g][0].offset + (a * n + i) * l.precision : 0;
          return invalidData(path + ": grid " + std::to_string(g + 1) + " point " + std::to_string(i) + ": " +
                             "xyz"[a] + " coordinate is not finite" +
                             (offset ? " (byte " + std::to_string(offset) + ")" : std::string()));
        }
        mesh.coords[3 * (base + i) + a] = x;
      }
    }
    if (l.iblank) {
      const char* src = v.data() + 3 * n * l.precision;
      for (size_t i = 0; i < n; ++i)
        (*iblank)[base + i] = static_cast<int32_t>(loadSigned(src + l.int_bytes * i, l.int_bytes, l.big_endian));
    }
    base += n;
  }
  return Status::ok();
}

void addQ(std::string_view bytes, const Fit& fit, TetMesh& mesh, std::vector<std::string>* warnings,
          const std::string& path) {
  const Layout& l = fit.layout;
  const size_t total = mesh.numPoints();
  const ScalarType type = l.precision == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  // The classic five variables under their names; an OVERFLOW file's further ones (or all of them
  // when it has fewer than five) as q1 .. qNQ.
  const size_t nq = static_cast<size_t>(fit.nq);
  const bool classic = nq >= 5;
  std::vector<Field> fields;
  auto addField = [&](std::string name, uint32_t components) {  // its pages mapped in one call
    fields.emplace_back(std::move(name), components, type, 0);
    resizePopulated(fields.back().bytes, total * components * scalarSize(type));
  };
  if (classic) {
    addField("density", 1);
    addField("momentum", 3);
    addField("stagnation_energy", 1);
  }
  for (size_t k = classic ? 5 : 0; k < nq; ++k) addField("q" + std::to_string(k + 1), 1);
  // The freestream reals before OVERFLOW's IGAM: FSMACH ALPHA REY TIME, then GAMINF BETA TINF.
  const int header_reals = l.overflow ? 7 : 4;
  std::string scratch, reordered;
  size_t base = 0;
  double first_header[7] = {0, 0, 0, 0, 0, 0, 0};
  for (size_t g = 0; g < fit.blocks.size(); ++g) {
    const size_t n = fit.blocks[g].points();
    const std::string_view h = recordBytes(bytes, fit.headers[g], &scratch);
    double header[7];
    for (int k = 0; k < header_reals; ++k) header[k] = loadReal(h.data() + k * l.precision, l.precision, l.big_endian);
    if (g == 0) {
      std::copy(header, header + header_reals, first_header);
    } else if (!std::equal(header, header + header_reals, first_header) && warnings->size() < 100) {
      warnings->push_back(path + ": grid " + std::to_string(g + 1) +
                          " has other freestream values than grid 1; metadata keeps grid 1's");
    }
    const std::string_view v = blockBytes(bytes, fit, g, componentBytes(fit, g, Kind::kQ), &scratch, &reordered);
    const size_t p = static_cast<size_t>(l.precision);
    for (size_t q = 0; q < nq; ++q) {
      const char* src = v.data() + q * n * p;
      if (!classic || q >= 5) {
        copyValues(src, n, l.precision, l.big_endian, &fields[classic ? q - 2 : q], base, 1);
      } else if (q == 0) {
        copyValues(src, n, l.precision, l.big_endian, &fields[0], base, 1);
      } else if (q <= 3) {
        copyValues(src, n, l.precision, l.big_endian, &fields[1], 3 * base + (q - 1), 3);
      } else {
        copyValues(src, n, l.precision, l.big_endian, &fields[2], base, 1);
      }
    }
    base += n;
  }
  for (Field& f : fields) mesh.point_fields.push_back(std::move(f));
  static const char* kKeys[7] = {"plot3d.fsmach", "plot3d.alpha", "plot3d.re",  "plot3d.time",
                                 "plot3d.gaminf", "plot3d.beta",  "plot3d.tinf"};
  for (int k = 0; k < header_reals; ++k) mesh.setMetadata(kKeys[k], realText(first_header[k], l.precision));
  if (l.overflow) {
    mesh.setMetadata("plot3d.nq", std::to_string(fit.nq));
    mesh.setMetadata("plot3d.nqc", std::to_string(fit.nqc));
  }
}

// The function file's variables become point fields named `names` (a .p3d meta-file's
// "function-names", `meta` naming it), then function_k for the variables beyond them.
Status addFunction(const std::string& path, std::string_view bytes, const Fit& fit, TetMesh& mesh,
                   const std::vector<std::string>& names = {}, const std::string& meta = "") {
  const Layout& l = fit.layout;
  const int64_t nvar = fit.blocks[0].nvar;
  for (size_t g = 1; g < fit.blocks.size(); ++g) {
    if (fit.blocks[g].nvar != nvar)
      return unsupported(path + ": grid " + std::to_string(g + 1) + " has " + std::to_string(fit.blocks[g].nvar) +
                         " function variables, grid 1 has " + std::to_string(nvar) +
                         ": fields need the same on every grid");
  }
  const size_t total = mesh.numPoints();
  const ScalarType type = l.precision == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  const size_t first = mesh.point_fields.size();
  for (int64_t k = 0; k < nvar; ++k) {
    const std::string name = static_cast<size_t>(k) < names.size() ? names[k] : "function_" + std::to_string(k);
    for (const Field& f : mesh.point_fields) {
      if (f.name == name)
        return invalidData(meta + ": key \"function-names\": \"" + name +
                           "\" names a field of the Q file or another "
                           "function variable already");
    }
    mesh.point_fields.emplace_back(name, 1, type, total);
  }
  std::string scratch, reordered;
  size_t base = 0;
  for (size_t g = 0; g < fit.blocks.size(); ++g) {
    const size_t n = fit.blocks[g].points();
    const std::string_view v = blockBytes(bytes, fit, g, componentBytes(fit, g, Kind::kFunction), &scratch, &reordered);
    for (int64_t k = 0; k < nvar; ++k)
      copyValues(v.data() + k * n * l.precision, n, l.precision, l.big_endian, &mesh.point_fields[first + k], base, 1);
    base += n;
  }
  return Status::ok();
}

// --weld: where cell faces of blocks weld together (the faces on the sides of blocks whose four
// corners are bit-identical to another side face's), the tetrahedra on both sides must cut the face
// along the same diagonal, or the seam stays as boundary triangles inside the volume. The 5-split
// cuts every face along the diagonal joining its two corners of even (i + j + k + parity) (hex_split),
// so each block's parity (0 or 1, added to i + j + k) can be chosen: a welded face asks for the two
// blocks' parities to be equal or to differ, whatever the directions of their index axes there. The
// demands are met block pair by block pair, the pairs sharing the most faces first (a union-find
// that keeps each block's parity relative to its root; the first block keeps parity 0); a demand
// that contradicts those already met (an odd cycle of seams, a block meeting itself after an odd
// number of cells, faces whose corners pair up differently on the two sides) cannot be met. The
// 6-split cuts every face along the diagonal of increasing indices, which has no choice: faces where
// the two blocks' index directions disagree cannot conform. Warnings name the blocks of every seam
// that does not conform, with its number of faces. Returns each block's parity.
std::vector<uint8_t> seamParities(const std::vector<BlockDims>& blocks, const std::vector<int32_t>& iblank, int split,
                                  const TetMesh& mesh, std::vector<std::string>* warnings) {
  const size_t nb = blocks.size();
  std::vector<uint8_t> parity(nb, 0);
  std::vector<uint64_t> first(nb + 1, 0);
  for (size_t b = 0; b < nb; ++b) first[b + 1] = first[b] + blocks[b].points();
  auto hasCells = [&](size_t b) { return blocks[b].n[0] >= 2 && blocks[b].n[1] >= 2 && blocks[b].n[2] >= 2; };
  auto id = [&](size_t b, const int64_t x[3]) {
    const int64_t* n = blocks[b].n;
    return static_cast<uint32_t>(first[b] + static_cast<uint64_t>(x[0] + n[0] * (x[1] + n[1] * x[2])));
  };
  // Calls f(b, a, x) for every side face of every block: the face of the cell at the side of axis a,
  // corner x (x[a] the side's index), spanning the other two axes.
  auto forSideFaces = [&](auto&& f) {
    for (size_t b = 0; b < nb; ++b) {
      if (!hasCells(b)) continue;
      const int64_t* n = blocks[b].n;
      for (int a = 0; a < 3; ++a) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        for (const int64_t side : {int64_t{0}, n[a] - 1}) {
          int64_t x[3];
          x[a] = side;
          for (x[v] = 0; x[v] + 1 < n[v]; ++x[v])
            for (x[u] = 0; x[u] + 1 < n[u]; ++x[u]) f(b, a, x);
        }
      }
    }
  };
  // The welded identity of every side point: the first side point bit-identical to it.
  std::vector<uint32_t> rep(mesh.numPoints());
  std::iota(rep.begin(), rep.end(), 0u);
  {
    std::vector<uint32_t> side;
    forSideFaces([&](size_t b, int a, const int64_t x[3]) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      for (int c = 0; c < 4; ++c) {
        int64_t y[3] = {x[0], x[1], x[2]};
        y[u] += c & 1;
        y[v] += c >> 1;
        side.push_back(id(b, y));
      }
    });
    std::sort(side.begin(), side.end());
    side.erase(std::unique(side.begin(), side.end()), side.end());
    auto bits = [&](uint32_t p) {
      return std::array<uint64_t, 3>{std::bit_cast<uint64_t>(mesh.coords[3 * size_t{p}]),
                                     std::bit_cast<uint64_t>(mesh.coords[3 * size_t{p} + 1]),
                                     std::bit_cast<uint64_t>(mesh.coords[3 * size_t{p} + 2])};
    };
    std::stable_sort(side.begin(), side.end(), [&](uint32_t p, uint32_t q) { return bits(p) < bits(q); });
    for (size_t i = 1; i < side.size(); ++i)
      if (bits(side[i]) == bits(side[i - 1])) rep[side[i]] = rep[side[i - 1]];
  }
  // Every side face whose cell is kept and whose corners are four welded points: its corners' welded
  // identities (sorted) and the diagonal its cell's split cuts along at parity 0.
  struct SideFace {
    std::array<uint32_t, 4> key;
    uint32_t block;
    std::array<uint32_t, 2> diagonal;
    bool operator<(const SideFace& o) const { return key != o.key ? key < o.key : block < o.block; }
  };
  std::vector<SideFace> faces;
  forSideFaces([&](size_t b, int a, const int64_t x[3]) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    const int64_t* n = blocks[b].n;
    int64_t cell[3] = {x[0], x[1], x[2]};
    if (cell[a] == n[a] - 1) --cell[a];
    if (!iblank.empty()) {
      for (int c = 0; c < 8; ++c) {
        const int64_t y[3] = {cell[0] + (c & 1), cell[1] + ((c >> 1) & 1), cell[2] + (c >> 2)};
        if (iblank[id(b, y)] == 0) return;
      }
    }
    uint32_t r[4];  // around the face: (0, 0), (1, 0), (1, 1), (0, 1) along (u, v)
    for (int c = 0; c < 4; ++c) {
      int64_t y[3] = {x[0], x[1], x[2]};
      y[u] += c == 1 || c == 2;
      y[v] += c >= 2;
      r[c] = rep[id(b, y)];
    }
    SideFace f{{r[0], r[1], r[2], r[3]}, static_cast<uint32_t>(b), {}};
    std::sort(f.key.begin(), f.key.end());
    if (std::adjacent_find(f.key.begin(), f.key.end()) != f.key.end()) return;  // collapsed
    // Corner (0, 0) has even i + j + k: the 5-split's diagonal at parity 0 runs through it, as the
    // 6-split's always does; otherwise the 5-split's runs through the other two.
    const bool even = (x[0] + x[1] + x[2]) % 2 == 0;
    f.diagonal = split == 6 || even ? std::array<uint32_t, 2>{r[0], r[2]} : std::array<uint32_t, 2>{r[1], r[3]};
    std::sort(f.diagonal.begin(), f.diagonal.end());
    faces.push_back(f);
  });
  std::sort(faces.begin(), faces.end());
  // Per pair of blocks (smaller first; a block may meet itself): faces asking for equal parities,
  // for different ones, and faces whose corners pair up differently on the two sides.
  struct Demand {
    uint64_t same = 0, differ = 0, twisted = 0;
  };
  std::map<std::pair<uint32_t, uint32_t>, Demand> demands;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    for (size_t k = i + 1; k < j; ++k) {
      const SideFace &f = faces[i], &g = faces[k];
      std::array<uint32_t, 2> other;
      std::set_difference(f.key.begin(), f.key.end(), f.diagonal.begin(), f.diagonal.end(), other.begin());
      Demand& d = demands[{f.block, g.block}];
      if (g.diagonal == f.diagonal) ++d.same;
      else if (g.diagonal == other) ++d.differ;
      else ++d.twisted;
    }
    i = j;
  }
  if (demands.empty()) return parity;
  if (split == 5) {
    std::vector<uint32_t> parent(nb);
    std::iota(parent.begin(), parent.end(), 0u);
    std::vector<uint8_t> relative(nb, 0);  // parity relative to the parent
    auto find = [&](uint32_t x) {
      uint8_t p = 0;
      uint32_t root = x;
      while (parent[root] != root) {
        p ^= relative[root];
        root = parent[root];
      }
      // Path compression: every block on the way points at the root.
      for (uint8_t q = p; parent[x] != x;) {
        const uint32_t next = parent[x];
        const uint8_t r = relative[x];
        parent[x] = root;
        relative[x] = q;
        q ^= r;
        x = next;
      }
      return std::make_pair(root, p);
    };
    std::vector<std::pair<std::pair<uint32_t, uint32_t>, Demand>> order(demands.begin(), demands.end());
    std::stable_sort(order.begin(), order.end(), [](const auto& x, const auto& y) {
      return std::max(x.second.same, x.second.differ) > std::max(y.second.same, y.second.differ);
    });
    for (const auto& [blocks_pair, d] : order) {
      if (blocks_pair.first == blocks_pair.second || d.same + d.differ == 0) continue;
      const auto [ra, pa] = find(blocks_pair.first);
      const auto [rb, pb] = find(blocks_pair.second);
      if (ra == rb) continue;
      const uint8_t want = d.differ > d.same ? 1 : 0;
      const uint32_t root = std::min(ra, rb), child = std::max(ra, rb);
      parent[child] = root;
      relative[child] = pa ^ pb ^ want;
    }
    for (uint32_t b = 0; b < nb; ++b) parity[b] = find(b).second;
  }
  size_t told = 0, untold = 0;
  const std::string how = split == 5 ? "(no choice of the grids' split parities makes every seam agree)"
                                     : "(their index lines run in other directions there; --split 5 may conform)";
  for (const auto& [pair, d] : demands) {
    const bool equal = split == 6 || parity[pair.first] == parity[pair.second];
    const uint64_t bad = (equal ? d.differ : d.same) + d.twisted;
    if (bad == 0) continue;
    if (told == 20) {
      ++untold;
      continue;
    }
    ++told;
    const std::string who = pair.first == pair.second ? "grid " + std::to_string(pair.first + 1) + " meets itself"
                                                      : "grids " + std::to_string(pair.first + 1) + " and " +
                                                            std::to_string(pair.second + 1) + " meet";
    warnings->push_back("--weld: " + who + " at " + std::to_string(d.same + d.differ + d.twisted) + " cell faces, " +
                        std::to_string(bad) + " of which --split " + std::to_string(split) +
                        " cuts along different diagonals on the two sides " + how +
                        ": those faces stay as boundary triangles inside the volume, a non-conforming interface "
                        "(gtn validate: NONCONFORMING_INTERFACE)");
  }
  if (untold > 0) warnings->push_back("--weld: " + std::to_string(untold) + " more seams that do not conform");
  return parity;
}

// Hexahedral cells into tetrahedra, block by block; cells with a hole vertex are dropped, and warped
// cells are split around an added point (GridHexSplitter). The 5-split of block b alternates with
// (i + j + k + parity[b]) % 2.
void splitCells(const std::vector<BlockDims>& blocks, const std::vector<int32_t>& iblank, int split,
                const std::vector<uint8_t>& parity, TetMesh& mesh, ImportReport& report) {
  uint64_t cells = 0;
  for (const BlockDims& b : blocks) cells += static_cast<uint64_t>((b.n[0] - 1) * (b.n[1] - 1) * (b.n[2] - 1));
  reservePopulated(mesh.tets, cells * static_cast<uint64_t>(split));
  GridHexSplitter grid(&mesh);
  uint64_t base = 0;
  for (size_t g = 0; g < blocks.size(); ++g) {
    const BlockDims& b = blocks[g];
    const uint64_t ni = b.n[0], nj = b.n[1], nk = b.n[2];
    auto id = [&](uint64_t i, uint64_t j, uint64_t k) { return static_cast<uint32_t>(base + i + ni * (j + nj * k)); };
    for (uint64_t k = 0; k + 1 < nk; ++k) {
      for (uint64_t j = 0; j + 1 < nj; ++j) {
        for (uint64_t i = 0; i + 1 < ni; ++i) {
          const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                                 id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
          if (!iblank.empty() && std::any_of(h, h + 8, [&](uint32_t v) { return iblank[v] == 0; })) {
            ++report.dropped_cells;
            continue;
          }
          grid.split(h, split, (i + j + k + parity[g]) % 2 == 1);
        }
      }
    }
    base += b.points();
  }
  grid.finish(&report);
}

}  // namespace

// What the errors of a Q file given before its grid advise.
constexpr const char* kGridFirst =
    "give the grid file first, then the Q file (gtn convert GRID.xyz SOLUTION.q -o OUT.gtn)";

StatusOr<ImportResult> importPlot3d(const std::vector<std::string>& inputs, const ImportOptions& options) {
  if (inputs.empty()) return usageError("no PLOT3D input given");
  if (options.split != 5 && options.split != 6)
    return usageError("--split must be 5 or 6, not " + std::to_string(options.split));
  ImportResult result;
  std::vector<std::string>& warnings = result.report.warnings;

  std::string grid_path, second_path, function_path;
  std::vector<std::string> function_names;
  Constraints constraints;
  const bool meta = isP3dMeta(inputs[0]);
  for (size_t i = 1; i < inputs.size(); ++i) {
    if (isP3dMeta(inputs[i]) || meta)
      return usageError(inputs[i] + ": a .p3d meta-file names all the PLOT3D files; give it alone");
  }
  if (meta) {
    GTN_ASSIGN_OR_RETURN(P3dFiles files, readP3dMeta(inputs[0]));
    grid_path = files.xyz;
    constraints = files.constraints;
    warnings = files.warnings;
    if (!files.q.empty()) second_path = files.q;
    function_path = files.function;
    function_names = files.function_names;
    if (!function_names.empty() && function_path.empty())
      warnings.push_back(inputs[0] + ": \"function-names\" given, but the time step read names no function file");
  } else {
    if (inputs.size() > 3)
      return usageError("PLOT3D takes a grid file, an optional Q file and an optional function file; got " +
                        std::to_string(inputs.size()) + " inputs");
    grid_path = inputs[0];
    if (inputs.size() > 1) second_path = inputs[1];
    if (inputs.size() > 2) function_path = inputs[2];
  }

  // The grid.
  GTN_ASSIGN_OR_RETURN(std::string grid_bytes, readInput(grid_path, Kind::kGrid));
  Detection grid_detection = detect(grid_bytes, Kind::kGrid, constraints);
  GTN_RETURN_IF_ERROR(asciiFallback(grid_path, Kind::kGrid, constraints, &grid_bytes, &grid_detection));
  GTN_ASSIGN_OR_RETURN(Selected grid, selectFit(
                                          grid_path, grid_bytes, Kind::kGrid, grid_detection,
                                          [](const Fit&) { return true; }, nullptr, &warnings));
  if (!grid.found) {
    // A Q (solution) file given first, where the grid belongs.
    if (!meta) {
      const Detection as_q = detect(grid_bytes, Kind::kQ, constraints);
      const std::vector<Fit>& fits = as_q.exact.empty() ? as_q.zero_tail : as_q.exact;
      if (!fits.empty())
        return invalidData(grid_path + ": a PLOT3D Q (solution) file (" +
                           describeLayout(fits.front().layout, Kind::kQ) + ", grids " +
                           blocksText(fits.front().blocks) + "), not a grid file: " + kGridFirst);
    }
    const Status st = noFitError(grid_path, grid_bytes, Kind::kGrid, grid_detection);
    const std::string fixed = meta ? describeConstraints(constraints) : "";
    if (fixed.empty()) return st;
    return Status(st.code(), st.message() + "; only readings that the meta-file " + inputs[0] + " allows were tried (" +
                                 fixed + "): check its keys against the file");
  }
  if (grid.fit.layout.ndim == 2)
    return unsupported(grid_path + ": a 2D PLOT3D grid (" + dimsText(grid.fit.blocks[0], 2) +
                       (grid.fit.blocks.size() > 1 ? " and more" : "") + "; " +
                       describeLayout(grid.fit.layout, Kind::kGrid) + "): only 3D grids can be split into tetrahedra");
  // A block with a dimension below 2 is a surface, line or point: it has no cells. Among blocks that
  // have cells it is kept as points no tetrahedron uses (multi-block files carry such blocks); a file
  // of them only has nothing to convert.
  {
    std::vector<size_t> flat;
    for (size_t g = 0; g < grid.fit.blocks.size(); ++g) {
      const BlockDims& b = grid.fit.blocks[g];
      if (b.n[0] < 2 || b.n[1] < 2 || b.n[2] < 2) flat.push_back(g);
    }
    if (flat.size() == grid.fit.blocks.size())
      return unsupported(
          grid_path + ": grid " + std::to_string(flat[0] + 1) + " is " + dimsText(grid.fit.blocks[flat[0]]) +
          ": a dimension below 2 makes it a 2D (or 1D) grid, which has no cells to split into tetrahedra" +
          (flat.size() > 1 ? " (and so are the other " + std::to_string(flat.size() - 1) + " grids)" : ""));
    for (size_t i = 0; i < flat.size() && i < 20; ++i) {
      const BlockDims& b = grid.fit.blocks[flat[i]];
      warnings.push_back(grid_path + ": grid " + std::to_string(flat[i] + 1) + " is " + dimsText(b) +
                         ": a dimension below 2, so it has no cells; its " + std::to_string(b.points()) +
                         " points stay as points no tetrahedron uses");
    }
    if (flat.size() > 20)
      warnings.push_back(grid_path + ": " + std::to_string(flat.size() - 20) + " more grids without cells");
  }
  TetMesh& mesh = result.mesh;
  std::vector<int32_t> iblank;
  GTN_RETURN_IF_ERROR(addGrid(grid_path, grid_bytes, grid.fit, mesh, &iblank));
  grid_bytes = std::string();  // free before reading the solution
  const std::vector<BlockDims>& blocks = grid.fit.blocks;
  auto matches_grid = [&](const Fit& f) { return sameDims(f.blocks, blocks); };

  // Detects `*bytes` as `kind` (text transcoded from ASCII: then *text_status says whether that
  // worked) and picks the interpretation that goes with the grid.
  auto for_grid = [&](const std::string& path, std::string* bytes, Kind kind, Detection* d,
                      Status* text_status) -> StatusOr<Selected> {
    *d = detect(*bytes, kind, constraints);
    *text_status = asciiFallback(path, kind, constraints, bytes, d);
    if (!text_status->isOk()) return Selected();
    return selectFit(path, *bytes, kind, *d, matches_grid, &grid.fit.layout, &warnings);
  };
  auto no_match = [&](const std::string& path, std::string_view bytes, Kind kind, const Detection& d) {
    return noMatchError(path, bytes, kind, d, blocks, grid_path, grid.fit.layout);
  };
  if (!second_path.empty()) {
    // Read as a Q file in place (its bytes transcoded where it is text); read again, as a function
    // file, only where it is no Q file for the grid (a copy of a large file costs more than its use).
    GTN_ASSIGN_OR_RETURN(std::string bytes, readInput(second_path, Kind::kQ));
    Detection dq, df;
    Status q_text, f_text;
    GTN_ASSIGN_OR_RETURN(Selected q, for_grid(second_path, &bytes, Kind::kQ, &dq, &q_text));
    if (q.found) {
      addQ(bytes, q.fit, mesh, &warnings, second_path);
    } else if (meta || !function_path.empty()) {
      // Named as the Q file, or followed by the function file: it must be a Q file.
      if (!q_text.isOk()) return q_text;
      return no_match(second_path, bytes, Kind::kQ, dq);
    } else {
      GTN_ASSIGN_OR_RETURN(const std::string raw, readInput(second_path, Kind::kFunction));
      std::string fbytes = raw;
      GTN_ASSIGN_OR_RETURN(Selected f, for_grid(second_path, &fbytes, Kind::kFunction, &df, &f_text));
      if (!f.found) {
        // The grid given second: a file that reads as a grid of the same dimensions.
        const Detection as_grid = detect(raw, Kind::kGrid, constraints);
        for (const Fit& g : as_grid.exact) {
          if (g.blocks.size() != blocks.size() ||
              !std::equal(blocks.begin(), blocks.end(), g.blocks.begin(),
                          [](const BlockDims& a, const BlockDims& b) { return std::equal(a.n, a.n + 3, b.n); }))
            continue;
          return invalidData(second_path + ": a PLOT3D grid file (" + describeLayout(g.layout, Kind::kGrid) +
                             ", grids " + blocksText(g.blocks) + "), not a Q or function file for the grid " +
                             grid_path + ", which may be the Q file: " + kGridFirst);
        }
        if (!q_text.isOk() && !f_text.isOk())
          return invalidData(second_path + ": neither an ASCII PLOT3D Q file nor a function file for the grid " +
                             grid_path + " (" + blocksText(blocks) + "); as a Q file: " + q_text.message() +
                             "; as a function file: " + f_text.message());
        if (!dq.exact.empty() || !dq.zero_tail.empty()) return no_match(second_path, bytes, Kind::kQ, dq);
        if (!df.exact.empty() || !df.zero_tail.empty()) return no_match(second_path, fbytes, Kind::kFunction, df);
        const std::string likely = gridLayoutReading(bytes, Kind::kQ, grid.fit.layout);
        const std::string likely_f = gridLayoutReading(fbytes, Kind::kFunction, grid.fit.layout);
        return invalidData(second_path + ": neither a PLOT3D Q file nor a function file for the grid " + grid_path +
                           " (" + blocksText(blocks) + ")" +
                           (looksLikeText(raw) ? "; it looks like text, but not like ASCII PLOT3D either" : "") +
                           (likely.empty() ? "" : "; as a Q file " + likely) + "; as a Q file: " +
                           triedText(dq, Kind::kQ) + (likely_f.empty() ? "" : "; as a function file " + likely_f) +
                           "; as a function file: " + triedText(df, Kind::kFunction));
      }
      GTN_RETURN_IF_ERROR(addFunction(second_path, fbytes, f.fit, mesh));
    }
  }
  if (!function_path.empty()) {
    GTN_ASSIGN_OR_RETURN(std::string bytes, readInput(function_path, Kind::kFunction));
    Detection df;
    Status f_text;
    GTN_ASSIGN_OR_RETURN(Selected f, for_grid(function_path, &bytes, Kind::kFunction, &df, &f_text));
    if (!f_text.isOk()) return f_text;
    if (!f.found) return no_match(function_path, bytes, Kind::kFunction, df);
    GTN_RETURN_IF_ERROR(addFunction(function_path, bytes, f.fit, mesh, function_names, inputs[0]));
    const size_t nvar = static_cast<size_t>(f.fit.blocks[0].nvar);
    if (function_names.size() > nvar)
      warnings.push_back(inputs[0] + ": \"function-names\" lists " + std::to_string(function_names.size()) +
                         " names for the " + std::to_string(nvar) + " variables of " + function_path + "; the last " +
                         std::to_string(function_names.size() - nvar) + " name nothing");
  }

  if (!iblank.empty()) {
    if (mesh.findPointField("iblank"))
      return invalidData(inputs[0] + ": key \"function-names\": \"iblank\" names the grid's IBLANK field already");
    Field field("iblank", 1, ScalarType::kInt32, iblank.size());
    std::memcpy(field.bytes.data(), iblank.data(), iblank.size() * sizeof(int32_t));
    mesh.point_fields.push_back(std::move(field));
  }
  const std::vector<uint8_t> parity = options.weld ? seamParities(blocks, iblank, options.split, mesh, &warnings)
                                                   : std::vector<uint8_t>(blocks.size(), 0);
  splitCells(blocks, iblank, options.split, parity, mesh, result.report);
  // One block: the structured encoder may code it as such (importMesh keeps it when the mesh is it).
  if (blocks.size() == 1 && blocks[0].n[0] >= 2 && blocks[0].n[1] >= 2 && blocks[0].n[2] >= 2 &&
      blocks[0].points() < kNoIndex) {
    StructuredBlock b;
    for (int a = 0; a < 3; ++a) b.dims[a] = static_cast<uint32_t>(blocks[0].n[a]);
    mesh.blocks.push_back(std::move(b));
  }
  if (options.weld) weldPoints(mesh, result.report);

  mesh.setMetadata("source.format", "plot3d");
  mesh.setMetadata("plot3d.grids", std::to_string(blocks.size()));
  mesh.setMetadata("plot3d.layout", describeLayout(grid.fit.layout, Kind::kGrid));
  finishImport(result);
  return result;
}

}  // namespace gtn
