#include "codec/structured_piece.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include "mesh/faces.h"
#include "mesh/fresh_memory.h"
#include "mesh/index.h"

namespace gtn {

namespace {

// Corner c of a cell in VTK order is node (i + dx, j + dy, k + dz) (as in grid_coder.cpp).
constexpr uint8_t kDx[8] = {0, 1, 1, 0, 0, 1, 1, 0};
constexpr uint8_t kDy[8] = {0, 0, 1, 1, 0, 0, 1, 1};
constexpr uint8_t kDz[8] = {0, 0, 0, 0, 1, 1, 1, 1};

// The cell face (0: -i, 1: +i, 2: -j, 3: +j, 4: -k, 5: +k) that holds the three corner symbols, or
// -1 (a face inside the cell, or one with an extra point).
int cellFaceOf(uint8_t a, uint8_t b, uint8_t c) {
  if (a >= 8 || b >= 8 || c >= 8) return -1;
  if (kDx[a] == kDx[b] && kDx[b] == kDx[c]) return kDx[a];
  if (kDy[a] == kDy[b] && kDy[b] == kDy[c]) return 2 + kDy[a];
  if (kDz[a] == kDz[b] && kDz[b] == kDz[c]) return 4 + kDz[a];
  return -1;
}

// A candidate boundary triangle: its vertices sorted (the key) and as its tetrahedron lists it.
struct Candidate {
  std::array<uint32_t, 3> key;
  std::array<uint32_t, 3> tri;
  bool operator<(const Candidate& o) const { return key < o.key; }
};

void addCandidate(const Tet& t, int k, std::vector<Candidate>& out) {
  Candidate c;
  c.tri = {t[kTetFace[k][0]], t[kTetFace[k][1]], t[kTetFace[k][2]]};
  c.key = c.tri;
  std::sort(c.key.begin(), c.key.end());
  out.push_back(c);
}

// The tetrahedra of a layout, cell by cell, made from the layout alone (as gridTets makes them,
// without holding them all): the rule's (with its handedness) in rule cells, an explicit cell's list.
class CellTets {
 public:
  explicit CellTets(const GridLayout& l) : l_(l), ni_(l.dims[0]), nj_(l.dims[1]), nv_(nodeVertexMap(l)) {
    for (int q = 0; q < 8; ++q) off_[q] = kDx[q] + ni_ * (kDy[q] + nj_ * kDz[q]);
    uint64_t next = l.nodes() - l.aliases.size();
    for (const GridException& x : l.exceptions) {
      first_extra_.push_back(static_cast<uint32_t>(next));
      next += x.extras;
    }
    for (int odd = 0; odd < 2; ++odd) {
      const auto rule = gridRuleTets(l.split, odd != 0);
      for (size_t r = 0; r < rule.size(); ++r) {
        rule_[odd][r] = rule[r];
        if (l.left_handed) std::swap(rule_[odd][r][2], rule_[odd][r][3]);
        for (int q = 0; q < 4; ++q) last_in_rule_[odd][rule_[odd][r][q]] = static_cast<uint8_t>(r);
        for (int k = 0; k < 4; ++k) {
          const auto& s = rule_[odd][r];
          const int f = cellFaceOf(s[kTetFace[k][0]], s[kTetFace[k][1]], s[kTetFace[k][2]]);
          if (f >= 0) faces_[odd][f].push_back({static_cast<uint8_t>(r), static_cast<uint8_t>(k)});
        }
      }
    }
  }
  // The tetrahedra of cell (i, j, k) (`x`: its exception's index, or exceptions().size() for a rule
  // cell) into out[0 .. 31); returns how many.
  [[gnu::always_inline]] uint32_t tets(uint64_t i, uint64_t j, uint64_t k, size_t x, Tet* out) const {
    const uint64_t base = i + ni_ * (j + nj_ * k);
    uint32_t c[16];
    if (nv_.empty()) {
      for (int q = 0; q < 8; ++q) c[q] = static_cast<uint32_t>(base + off_[q]);
    } else {
      for (int q = 0; q < 8; ++q) c[q] = nv_[base + off_[q]];
    }
    if (x < l_.exceptions.size()) {
      const GridException& e = l_.exceptions[x];
      for (int q = 0; q < e.extras; ++q) c[8 + q] = first_extra_[x] + static_cast<uint32_t>(q);
      uint32_t n = 0;
      for (const auto& t : e.tets) out[n++] = {c[t[0]], c[t[1]], c[t[2]], c[t[3]]};
      return n;
    }
    const auto& rule = rule_[(i + j + k + l_.parity) & 1];
    for (uint32_t r = 0; r < l_.split; ++r) out[r] = {c[rule[r][0]], c[rule[r][1]], c[rule[r][2]], c[rule[r][3]]};
    return l_.split;
  }
  // Of a rule cell (odd: its parity class), the (tetrahedron, local face) pairs on cell face f.
  const std::vector<std::array<uint8_t, 2>>& ruleFaces(int odd, int f) const { return faces_[odd][f]; }
  // Of a rule cell, the corners whose last rule tetrahedron is r (a bit per corner).
  uint8_t lastInRule(int odd, uint32_t r) const {
    uint8_t m = 0;
    for (int q = 0; q < 8; ++q) m |= static_cast<uint8_t>((last_in_rule_[odd][q] == r) << q);
    return m;
  }
  uint64_t cornerOffset(int q) const { return off_[q]; }
  // The vertex of exception x's first extra point.
  uint32_t firstExtra(size_t x) const { return first_extra_[x]; }

 private:
  static std::vector<uint32_t> nodeVertexMap(const GridLayout& l) {
    if (l.aliases.empty()) return {};
    std::vector<uint32_t> v(l.nodes());
    uint32_t next = 0;
    size_t a = 0;
    for (uint64_t n = 0; n < v.size(); ++n) {
      if (a < l.aliases.size() && l.aliases[a].first == n) v[n] = v[l.aliases[a++].second];
      else v[n] = next++;
    }
    return v;
  }
  const GridLayout& l_;
  uint64_t ni_, nj_;
  std::vector<uint32_t> nv_;
  uint64_t off_[8];
  std::vector<uint32_t> first_extra_;
  std::array<uint8_t, 4> rule_[2][6] = {};
  uint8_t last_in_rule_[2][8] = {};
  std::vector<std::array<uint8_t, 2>> faces_[2][6];
};

// Copies the items of `fields` (item `index`) one after another into `out`.
struct ItemGather {
  std::vector<const uint8_t*> data;
  std::vector<size_t> size;
  std::vector<uint8_t> buffer;
  explicit ItemGather(const std::vector<Field>& fields) {
    size_t total = 0;
    for (const Field& f : fields) {
      data.push_back(f.bytes.data());
      size.push_back(f.components * f.valueSize());
      total += size.back();
    }
    buffer.assign(std::max<size_t>(total, 1), 0);
  }
  const uint8_t* item(uint64_t index) {
    uint8_t* p = buffer.data();
    for (size_t f = 0; f < data.size(); ++f) {
      std::memcpy(p, data[f] + index * size[f], size[f]);
      p += size[f];
    }
    return buffer.data();
  }
};

}  // namespace

StatusOr<std::vector<std::array<uint32_t, 3>>> gridBoundary(const GridLayout& l, const std::string& what) {
  const uint64_t ci = l.dims[0] - 1, cj = l.dims[1] - 1, ck = l.dims[2] - 1;
  const CellTets gen(l);
  const size_t nx = l.exceptions.size();
  auto exceptionAt = [&](uint64_t cell) -> size_t {  // its index, or nx
    auto it = std::lower_bound(l.exceptions.begin(), l.exceptions.end(), cell,
                               [](const GridException& e, uint64_t c) { return e.cell < c; });
    return it != l.exceptions.end() && it->cell == cell ? static_cast<size_t>(it - l.exceptions.begin()) : nx;
  };
  // The outer box's rule faces give two triangles each; exceptions add a few more. Mapped at once:
  // growing by appends would fault its pages in one at a time.
  std::vector<Candidate> cand;
  reservePopulated(cand, 4 * (ci * cj + cj * ck + ci * ck) + 64);
  Tet tets[32];
  // A rule cell's triangles on its face f.
  auto ruleFace = [&](uint64_t i, uint64_t j, uint64_t k, int f) {
    gen.tets(i, j, k, nx, tets);
    for (const auto& [r, face] : gen.ruleFaces(static_cast<int>((i + j + k + l.parity) & 1), f))
      addCandidate(tets[r], face, cand);
  };
  // The outer box: each side's rule cells (exception cells give all their faces below).
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const uint64_t n[3] = {ci, cj, ck};
    const uint64_t fixed = (f & 1) ? n[axis] - 1 : 0;
    const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
    for (uint64_t v = 0; v < n[a2]; ++v)
      for (uint64_t u = 0; u < n[a1]; ++u) {
        uint64_t c[3];
        c[axis] = fixed, c[a1] = u, c[a2] = v;
        if (nx && exceptionAt(c[0] + ci * (c[1] + cj * c[2])) != nx) continue;
        ruleFace(c[0], c[1], c[2], f);
      }
  }
  // Each exception: every face of its tetrahedra, and the faces its rule neighbours turn to it.
  for (size_t x = 0; x < nx; ++x) {
    const GridException& e = l.exceptions[x];
    const uint64_t i = e.cell % ci, j = (e.cell / ci) % cj, k = e.cell / (ci * cj);
    const uint32_t count = gen.tets(i, j, k, x, tets);
    for (uint32_t t = 0; t < count; ++t)
      for (int q = 0; q < 4; ++q) addCandidate(tets[t], q, cand);
    const uint64_t c[3] = {i, j, k}, n[3] = {ci, cj, ck};
    const uint64_t stride[3] = {1, ci, ci * cj};
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      const bool up = f & 1;
      if (up ? c[axis] + 1 >= n[axis] : c[axis] == 0) continue;
      const uint64_t other = up ? e.cell + stride[axis] : e.cell - stride[axis];
      if (exceptionAt(other) != nx) continue;  // that exception lists its own faces
      uint64_t o[3] = {i, j, k};
      o[axis] = up ? o[axis] + 1 : o[axis] - 1;
      ruleFace(o[0], o[1], o[2], f ^ 1);
    }
  }
  // The faces met once. Without aliases and exceptions every candidate is a face of the outer box,
  // each met once.
  if (l.aliases.empty() && nx == 0) {
    std::vector<std::array<uint32_t, 3>> out;
    reservePopulated(out, cand.size());
    for (const Candidate& c : cand) out.push_back(c.tri);
    return out;
  }
  std::sort(cand.begin(), cand.end());
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t a = 0; a < cand.size();) {
    size_t b = a + 1;
    while (b < cand.size() && cand[b].key == cand[a].key) ++b;
    if (b - a > 2)
      return invalidData(what + ": the face (" + std::to_string(cand[a].key[0]) + ", " +
                         std::to_string(cand[a].key[1]) + ", " + std::to_string(cand[a].key[2]) +
                         ") belongs to three tetrahedra or more");
    if (b - a == 1) out.push_back(cand[a].tri);
    a = b;
  }
  return out;
}

StatusOr<EncodedLevel> encodeStructuredPiece(const TetMesh& mesh, const StructuredBlock& block,
                                             const GridEncodeOptions& options, GridEncodeReport* report) {
  const std::string what = "structured piece";
  if (block.first_point != 0)
    return unsupported(what + ": the block starts at point " + std::to_string(block.first_point) +
                       ", not at the level's first point");
  {
    const Status st = mesh.checkConsistency(what);
    if (!st.isOk()) return unsupported(st.message());
  }
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  if (np >= kNoIndex || nt >= kNoIndex) return unsupported(what + ": more than 2^32-2 points or tetrahedra");
  for (size_t t = 0; t < nt; ++t) {
    const Tet& v = mesh.tets[t];
    if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3])
      return unsupported(what + ": tetrahedron " + std::to_string(t) + " repeats a vertex");
  }
  auto matched = matchGridLayout(mesh, block.dims, block.aliases);
  if (!matched.isOk()) return unsupported(what + ": " + matched.status().message());
  GridLayout layout = std::move(*matched);
  // Cell values coded once per cell where every cell's tetrahedra agree (VTK's cell data).
  if (!mesh.cell_fields.empty()) {
    bool per_cell = true;
    uint64_t t = 0;
    size_t x = 0;
    for (uint64_t cell = 0; cell < layout.cells() && per_cell; ++cell) {
      uint64_t count = layout.split;
      if (x < layout.exceptions.size() && layout.exceptions[x].cell == cell) count = layout.exceptions[x++].tets.size();
      for (const Field& f : mesh.cell_fields) {
        const size_t item = f.components * f.valueSize();
        for (uint64_t u = t + 1; u < t + count && per_cell; ++u)
          per_cell = std::memcmp(&f.bytes[u * item], &f.bytes[t * item], item) == 0;
      }
      t += count;
    }
    layout.cell_values_per_cell = per_cell;
  }
  // The boundary from the grid, which the decoder computes so. A block of rule cells alone (no alias,
  // no exception) is a conforming tetrahedralization of its box: no face is in three tetrahedra and
  // its boundary is the box's, which gridBoundary gives for every rule (the tests compare it with the
  // face adjacency's). Aliases and exceptions can make either false, so there it must be what the
  // generic face matching finds (it is, for a mesh with no face in three tetrahedra); the faces'
  // classes, 2 bytes a tetrahedron, are gone before the piece is coded, and a large grid of rule
  // cells does without them.
  const bool rule_cells_only = layout.aliases.empty() && layout.exceptions.empty();
  std::vector<Triangle> generic;
  if (!rule_cells_only) {
    const FaceClasses faces = classifyFaces(mesh);
    if (faces.non_manifold_faces > 0)
      return unsupported(what + ": " + std::to_string(faces.non_manifold_faces) +
                         " faces are shared by three or more tetrahedra (non-manifold)");
    generic = boundaryTriangles(mesh, faces);
  }
  GTN_ASSIGN_OR_RETURN(auto boundary, gridBoundary(layout, what));
  if (!rule_cells_only) {
    auto canonical = [](std::vector<Triangle>& v) {
      for (Triangle& t : v) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      std::sort(v.begin(), v.end());
    };
    std::vector<Triangle> mine(boundary.begin(), boundary.end());
    canonical(generic);
    canonical(mine);
    if (generic != mine)
      return unsupported(what + ": the block's boundary (" + std::to_string(mine.size()) +
                         " triangles) is not the mesh's (" + std::to_string(generic.size()) + ")");
    generic = {};
  }
  auto piece = encodeGridPiece(layout, mesh, options, report);
  if (!piece.isOk()) return unsupported(piece.status().message());

  EncodedLevel out;
  out.header = levelHeaderOf(mesh);
  out.header.boundary_triangles = boundary.size();
  out.connectivity = std::move(*piece);
  out.point_fields.resize(mesh.point_fields.size());
  out.cell_fields.resize(mesh.cell_fields.size());
  // The mesh's points are the layout's vertices in order and its tetrahedra gridTets (matchGridLayout):
  // tet_order stays empty, the identity.
  out.vertex_order.resize(np);
  for (size_t v = 0; v < np; ++v) out.vertex_order[v] = static_cast<uint32_t>(v);
  return out;
}

Status decodeStructuredPiece(const LevelHeader& header, std::span<const uint8_t> bytes, MeshSink& sink,
                             const std::string& what, const DecodeFields* fields) {
  GridSchema schema;
  schema.coord_type = header.coord_type;
  schema.point_fields = header.point_fields;
  schema.cell_fields = header.cell_fields;
  GridFieldSelection selection;
  // A sink that takes the level whole gets the piece's tetrahedra as gridTets makes them; otherwise
  // they are made cell by cell below.
  const bool whole = sink.takesWholeLevel();
  selection.tets = whole;
  std::vector<char> point_out(header.point_fields.size(), 0), cell_out(header.cell_fields.size(), 0);
  if (fields) {
    selection.point = fields->point;
    selection.cell = fields->cell;
    for (size_t f = 0; f < point_out.size(); ++f)
      point_out[f] = !fields->point.empty() && (f >= fields->point.size() || !fields->point[f]);
    for (size_t f = 0; f < cell_out.size(); ++f)
      cell_out[f] = !fields->cell.empty() && (f >= fields->cell.size() || !fields->cell[f]);
  }
  // The boundary triangles come from the layout alone: made beside the streams' decoding.
  std::vector<std::array<uint32_t, 3>> boundary;
  selection.beside = [&](const GridLayout& layout) -> Status {
    GTN_ASSIGN_OR_RETURN(boundary, gridBoundary(layout, what + ": structured piece"));
    return Status::ok();
  };
  GTN_ASSIGN_OR_RETURN(DecodedGridPiece piece, decodeGridPiece(bytes, schema, what, &selection));
  if (fields && fields->streams_done) fields->streams_done(point_out, cell_out);
  const GridLayout& l = piece.layout;
  TetMesh& m = piece.mesh;
  const uint64_t V = m.numPoints(), T = l.tets();
  if (V != header.points || T != header.tets)
    return invalidData(what + ": the structured piece has " + std::to_string(V) + " vertices and " + std::to_string(T) +
                       " tetrahedra, the header says " + std::to_string(header.points) + " and " +
                       std::to_string(header.tets));
  if (boundary.size() != header.boundary_triangles)
    return invalidData(what + ": the structured piece has " + std::to_string(boundary.size()) +
                       " boundary triangles, the header says " + std::to_string(header.boundary_triangles));
  if (whole) {
    TetMesh level;
    level.coords = std::move(piece.mesh.coords);
    level.tets = std::move(piece.mesh.tets);
    level.point_fields = std::move(piece.mesh.point_fields);
    level.cell_fields = std::move(piece.mesh.cell_fields);
    // Distinct nodes and corners never repeat a vertex; aliases can.
    if (!l.aliases.empty())
      for (size_t t = 0; t < level.tets.size(); ++t) {
        const Tet& v = level.tets[t];
        if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3])
          return invalidData(what + ": structured piece: tetrahedron " + std::to_string(t) + " repeats a vertex");
      }
    return sink.wholeLevel(header, std::move(level), std::move(boundary));
  }
  const CellTets gen(l);
  const uint64_t ci = l.dims[0] - 1, cj = l.dims[1] - 1, ck = l.dims[2] - 1;
  const size_t nx = l.exceptions.size();
  Tet tets[32];
  // When each vertex retires. Without aliases: a node retires in its last cell, the last of the (up
  // to) eight around it; when that is a rule cell, after its last rule tetrahedron there (no table
  // needed), else (an exception) after the last tetrahedron that uses it, found among its cells, as
  // do the extra points: those few go to `special`, (tetrahedron, vertex) in order, or to `unused`.
  // With aliases: every vertex's last tetrahedron in `last` (kNoIndex: none), from a pass over all
  // tetrahedra that also refuses a tetrahedron that repeats a vertex (distinct nodes and corners
  // never do).
  const bool structural = l.aliases.empty();
  std::vector<uint32_t> last(structural ? 0 : V, kNoIndex);
  std::vector<std::pair<uint32_t, uint32_t>> special;
  std::vector<uint32_t> unused;
  // Corners whose node has no later cell along an axis: offset 0 along it, or the last cell.
  constexpr uint8_t kLowI = 0x99, kLowJ = 0x33, kLowK = 0x0F;  // corners with dx, dy, dz = 0
  auto lastCellCorners = [&](uint64_t i, uint64_t j, uint64_t k) {
    return static_cast<uint8_t>((k + 1 == ck ? 0xFF : kLowK) & (j + 1 == cj ? 0xFF : kLowJ) &
                                (i + 1 == ci ? 0xFF : kLowI));
  };
  const uint64_t ni = l.dims[0], nj = l.dims[1];
  uint64_t off[8];
  for (int q = 0; q < 8; ++q) off[q] = gen.cornerOffset(q);
  if (structural && nx > 0) {
    std::vector<uint32_t> ex_first(nx);  // each exception's first tetrahedron
    {
      uint64_t shift = 0;  // tetrahedra the exceptions so far have less than rule cells (mod 2^64)
      for (size_t x = 0; x < nx; ++x) {
        ex_first[x] = static_cast<uint32_t>(l.exceptions[x].cell * uint64_t{l.split} - shift);
        shift += l.split - l.exceptions[x].tets.size();
      }
    }
    auto exceptionBefore = [&](uint64_t cell) {  // exceptions at cells below `cell`
      return static_cast<size_t>(std::lower_bound(l.exceptions.begin(), l.exceptions.end(), cell,
                                                  [](const GridException& e, uint64_t c) { return e.cell < c; }) -
                                 l.exceptions.begin());
    };
    // The last tetrahedron of cell (a, b, c) that uses vertex v (corner q of a rule cell), or kNoIndex.
    auto lastUse = [&](uint64_t a, uint64_t b, uint64_t c, int q, uint32_t v) -> uint32_t {
      const uint64_t cell = a + ci * (b + cj * c);
      const size_t x = exceptionBefore(cell);
      if (x < nx && l.exceptions[x].cell == cell) {
        const uint32_t n = gen.tets(a, b, c, x, tets);
        for (uint32_t r = n; r-- > 0;)
          if (tets[r][0] == v || tets[r][1] == v || tets[r][2] == v || tets[r][3] == v) return ex_first[x] + r;
        return kNoIndex;
      }
      const uint64_t first =
          x == 0 ? cell * l.split
                 : ex_first[x - 1] + l.exceptions[x - 1].tets.size() + (cell - l.exceptions[x - 1].cell - 1) * l.split;
      for (uint32_t r = l.split; r-- > 0;)
        if (gen.lastInRule(static_cast<int>((a + b + c + l.parity) & 1), r) & (1u << q))
          return static_cast<uint32_t>(first + r);
      return kNoIndex;
    };
    for (size_t x = 0; x < nx; ++x) {
      const GridException& e = l.exceptions[x];
      const uint64_t i = e.cell % ci, j = (e.cell / ci) % cj, k = e.cell / (ci * cj);
      for (unsigned bits = lastCellCorners(i, j, k); bits; bits &= bits - 1) {
        const int q = std::countr_zero(bits);
        const uint64_t node[3] = {i + kDx[q], j + kDy[q], k + kDz[q]};
        const uint32_t v = static_cast<uint32_t>(node[0] + ni * (node[1] + nj * node[2]));
        // Its cells, last first: (node - 1 or node) along each axis, inside the box.
        uint32_t found = kNoIndex;
        for (int cc = 1; cc >= 0 && found == kNoIndex; --cc)
          for (int bb = 1; bb >= 0 && found == kNoIndex; --bb)
            for (int aa = 1; aa >= 0 && found == kNoIndex; --aa) {
              if (node[0] + aa < 1 || node[1] + bb < 1 || node[2] + cc < 1) continue;
              const uint64_t a = node[0] + aa - 1, b = node[1] + bb - 1, c = node[2] + cc - 1;
              if (a >= ci || b >= cj || c >= ck) continue;
              const int corner = (1 - cc) * 4 + ((1 - bb) ? ((1 - aa) ? 2 : 3) : ((1 - aa) ? 1 : 0));
              found = lastUse(a, b, c, corner, v);
            }
        if (found == kNoIndex) unused.push_back(v);
        else special.emplace_back(found, v);
      }
      // Its extra points, used by its tetrahedra alone.
      if (e.extras) {
        const uint32_t n = gen.tets(i, j, k, x, tets);
        for (uint32_t v = gen.firstExtra(x); v < gen.firstExtra(x) + e.extras; ++v) {
          uint32_t found = kNoIndex;
          for (uint32_t r = n; r-- > 0 && found == kNoIndex;)
            if (tets[r][0] == v || tets[r][1] == v || tets[r][2] == v || tets[r][3] == v) found = ex_first[x] + r;
          if (found == kNoIndex) unused.push_back(v);
          else special.emplace_back(found, v);
        }
      }
    }
    std::sort(special.begin(), special.end());
  }
  if (!structural) {
    uint32_t t = 0;
    size_t x = 0;
    uint64_t cell = 0;
    for (uint64_t k = 0; k < ck; ++k)
      for (uint64_t j = 0; j < cj; ++j)
        for (uint64_t i = 0; i < ci; ++i, ++cell) {
          const bool exception = x < nx && l.exceptions[x].cell == cell;
          const uint32_t n = gen.tets(i, j, k, exception ? x : nx, tets);
          x += exception;
          for (uint32_t q = 0; q < n; ++q, ++t) {
            const Tet& v = tets[q];
            if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3])
              return invalidData(what + ": structured piece: tetrahedron " + std::to_string(t) + " repeats a vertex");
            last[v[0]] = last[v[1]] = last[v[2]] = last[v[3]] = t;
          }
        }
    for (uint64_t v = 0; v < V; ++v)
      if (last[v] == kNoIndex) unused.push_back(static_cast<uint32_t>(v));
  }

  GTN_RETURN_IF_ERROR(sink.beginLevel(header));
  {
    ItemGather values(m.point_fields);
    const bool none = m.point_fields.empty();
    for (uint64_t v = 0; v < V; ++v)
      GTN_RETURN_IF_ERROR(sink.vertex(static_cast<uint32_t>(v), &m.coords[3 * v], none ? nullptr : values.item(v)));
  }
  for (const auto& tri : boundary) GTN_RETURN_IF_ERROR(sink.boundaryTriangle(tri.data()));
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  for (uint32_t v : unused) GTN_RETURN_IF_ERROR(sink.retireVertex(v));
  ItemGather values(m.cell_fields);
  const bool none = m.cell_fields.empty();
  uint32_t t = 0;
  if (structural) {
    uint8_t retire[2][6];
    for (int odd = 0; odd < 2; ++odd)
      for (uint32_t r = 0; r < l.split; ++r) retire[odd][r] = gen.lastInRule(odd, r);
    size_t x = 0, at = 0;
    uint64_t cell = 0;
    for (uint64_t k = 0; k < ck; ++k)
      for (uint64_t j = 0; j < cj; ++j)
        for (uint64_t i = 0; i < ci; ++i, ++cell) {
          const bool exception = x < nx && l.exceptions[x].cell == cell;
          const uint64_t base = i + ni * (j + nj * k);
          const int odd = static_cast<int>((i + j + k + l.parity) & 1);
          const uint8_t allowed = exception ? 0 : lastCellCorners(i, j, k);
          const uint32_t n = gen.tets(i, j, k, exception ? x : nx, tets);
          x += exception;
          for (uint32_t q = 0; q < n; ++q, ++t) {
            GTN_RETURN_IF_ERROR(sink.tet(tets[q].data(), none ? nullptr : values.item(t)));
            for (unsigned bits = retire[odd][q] & allowed; bits; bits &= bits - 1)
              GTN_RETURN_IF_ERROR(sink.retireVertex(static_cast<uint32_t>(base + off[std::countr_zero(bits)])));
            for (; at < special.size() && special[at].first == t; ++at)
              GTN_RETURN_IF_ERROR(sink.retireVertex(special[at].second));
          }
        }
  } else {
    size_t x = 0;
    uint64_t cell = 0;
    for (uint64_t k = 0; k < ck; ++k)
      for (uint64_t j = 0; j < cj; ++j)
        for (uint64_t i = 0; i < ci; ++i, ++cell) {
          const bool exception = x < nx && l.exceptions[x].cell == cell;
          const uint32_t n = gen.tets(i, j, k, exception ? x : nx, tets);
          x += exception;
          for (uint32_t q = 0; q < n; ++q, ++t) {
            const Tet& tet = tets[q];
            GTN_RETURN_IF_ERROR(sink.tet(tet.data(), none ? nullptr : values.item(t)));
            for (uint32_t v : tet)
              if (last[v] == t) GTN_RETURN_IF_ERROR(sink.retireVertex(v));
          }
        }
  }
  return sink.endLevel();
}

}  // namespace gtn
