#include "codec/structured_piece.h"

#include <algorithm>
#include <cstring>

#include "mesh/faces.h"
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

// The rule's tetrahedra of a cell as corner symbols (the layout's handedness applied), and which of
// their faces lie on which cell face: faces[variant][f] lists (tetrahedron, local face).
struct RuleFaces {
  std::vector<std::array<uint8_t, 2>> faces[2][6];
  explicit RuleFaces(const GridLayout& l) {
    for (int odd = 0; odd < 2; ++odd) {
      const auto rule = gridRuleTets(l.split, odd != 0);
      for (size_t r = 0; r < rule.size(); ++r) {
        std::array<uint8_t, 4> s = rule[r];
        if (l.left_handed) std::swap(s[2], s[3]);
        for (int k = 0; k < 4; ++k) {
          const int f = cellFaceOf(s[kTetFace[k][0]], s[kTetFace[k][1]], s[kTetFace[k][2]]);
          if (f >= 0) faces[odd][f].push_back({static_cast<uint8_t>(r), static_cast<uint8_t>(k)});
        }
      }
    }
  }
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

StatusOr<std::vector<std::array<uint32_t, 3>>> gridBoundary(const GridLayout& l, std::span<const Tet> tets,
                                                            const std::string& what) {
  const uint64_t ci = l.dims[0] - 1, cj = l.dims[1] - 1, ck = l.dims[2] - 1, cells = l.cells();
  if (tets.size() != l.tets()) return invalidData(what + ": the tetrahedra are not the structured layout's");
  const RuleFaces rule(l);
  const uint32_t split = l.split;
  // Each exception's first tetrahedron; a rule cell's is found from the nearest exception before it.
  const size_t nx = l.exceptions.size();
  std::vector<uint64_t> ex_first(nx);
  {
    uint64_t shift = 0;  // tetrahedra the exceptions so far have less than rule cells (mod 2^64)
    for (size_t x = 0; x < nx; ++x) {
      ex_first[x] = l.exceptions[x].cell * uint64_t{split} - shift;
      shift += split - l.exceptions[x].tets.size();
    }
  }
  auto exceptionAt = [&](uint64_t cell) -> size_t {  // its index, or nx
    auto it = std::lower_bound(l.exceptions.begin(), l.exceptions.end(), cell,
                               [](const GridException& e, uint64_t c) { return e.cell < c; });
    return it != l.exceptions.end() && it->cell == cell ? static_cast<size_t>(it - l.exceptions.begin()) : nx;
  };
  auto firstTet = [&](uint64_t cell) -> uint64_t {  // of a rule cell
    auto it = std::lower_bound(l.exceptions.begin(), l.exceptions.end(), cell,
                               [](const GridException& e, uint64_t c) { return e.cell < c; });
    if (it == l.exceptions.begin()) return cell * split;
    const size_t x = static_cast<size_t>(it - l.exceptions.begin()) - 1;
    return ex_first[x] + l.exceptions[x].tets.size() + (cell - l.exceptions[x].cell - 1) * split;
  };
  auto oddOf = [&](uint64_t i, uint64_t j, uint64_t k) { return static_cast<int>((i + j + k + l.parity) & 1); };
  std::vector<Candidate> cand;
  // A rule cell's triangles on its face f.
  auto ruleFace = [&](uint64_t i, uint64_t j, uint64_t k, int f) {
    const uint64_t cell = i + ci * (j + cj * k);
    const uint64_t t0 = firstTet(cell);
    for (const auto& [r, face] : rule.faces[oddOf(i, j, k)][f]) addCandidate(tets[t0 + r], face, cand);
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
    for (uint64_t t = ex_first[x]; t < ex_first[x] + e.tets.size(); ++t)
      for (int k = 0; k < 4; ++k) addCandidate(tets[t], k, cand);
    const uint64_t i = e.cell % ci, j = (e.cell / ci) % cj, k = e.cell / (ci * cj);
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
  // The faces met once.
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
  (void)cells;
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
  // The boundary from the grid, which the decoder computes so: it must be what the generic face
  // adjacency finds (it is, for a mesh with no face in three tetrahedra).
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  if (adj.non_manifold_faces > 0)
    return unsupported(what + ": " + std::to_string(adj.non_manifold_faces) +
                       " faces are shared by three or more tetrahedra (non-manifold)");
  GTN_ASSIGN_OR_RETURN(auto boundary, gridBoundary(layout, mesh.tets, what));
  {
    std::vector<Triangle> generic = boundaryTriangles(mesh, adj);
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
  }
  auto piece = encodeGridPiece(layout, mesh, options, report);
  if (!piece.isOk()) return unsupported(piece.status().message());

  EncodedLevel out;
  LevelHeader& h = out.header;
  h.points = np;
  h.tets = nt;
  h.boundary_triangles = boundary.size();
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
  out.connectivity = std::move(*piece);
  out.point_fields.resize(mesh.point_fields.size());
  out.cell_fields.resize(mesh.cell_fields.size());
  // The mesh's points are the layout's vertices in order and its tetrahedra gridTets (matchGridLayout).
  out.vertex_order.resize(np);
  for (size_t v = 0; v < np; ++v) out.vertex_order[v] = static_cast<uint32_t>(v);
  out.tet_order.resize(nt);
  for (size_t t = 0; t < nt; ++t) out.tet_order[t] = t;
  return out;
}

Status decodeStructuredPiece(const LevelHeader& header, std::span<const uint8_t> bytes, MeshSink& sink,
                             const std::string& what, const DecodeFields* fields) {
  GridSchema schema;
  schema.coord_type = header.coord_type;
  schema.point_fields = header.point_fields;
  schema.cell_fields = header.cell_fields;
  GridFieldSelection selection;
  std::vector<char> point_out(header.point_fields.size(), 0), cell_out(header.cell_fields.size(), 0);
  if (fields) {
    selection.point = fields->point;
    selection.cell = fields->cell;
    for (size_t f = 0; f < point_out.size(); ++f)
      point_out[f] = !fields->point.empty() && (f >= fields->point.size() || !fields->point[f]);
    for (size_t f = 0; f < cell_out.size(); ++f)
      cell_out[f] = !fields->cell.empty() && (f >= fields->cell.size() || !fields->cell[f]);
  }
  GTN_ASSIGN_OR_RETURN(DecodedGridPiece piece, decodeGridPiece(bytes, schema, what, &selection));
  if (fields && fields->streams_done) fields->streams_done(point_out, cell_out);
  const GridLayout& l = piece.layout;
  const TetMesh& m = piece.mesh;
  const uint64_t V = m.numPoints(), T = m.tets.size();
  if (V != header.points || T != header.tets)
    return invalidData(what + ": the structured piece has " + std::to_string(V) + " vertices and " +
                       std::to_string(T) + " tetrahedra, the header says " + std::to_string(header.points) + " and " +
                       std::to_string(header.tets));
  // Rule tetrahedra of distinct nodes repeat none; aliases and explicit cells may.
  if (!l.aliases.empty() || !l.exceptions.empty()) {
    for (uint64_t t = 0; t < T; ++t) {
      const Tet& v = m.tets[t];
      if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3])
        return invalidData(what + ": structured piece: tetrahedron " + std::to_string(t) + " repeats a vertex");
    }
  }
  GTN_ASSIGN_OR_RETURN(const auto boundary, gridBoundary(l, m.tets, what + ": structured piece"));
  if (boundary.size() != header.boundary_triangles)
    return invalidData(what + ": the structured piece has " + std::to_string(boundary.size()) +
                       " boundary triangles, the header says " + std::to_string(header.boundary_triangles));
  // Each vertex's last tetrahedron (kNoIndex: none).
  std::vector<uint32_t> last(V, kNoIndex);
  for (uint64_t t = 0; t < T; ++t)
    for (uint32_t v : m.tets[t]) last[v] = static_cast<uint32_t>(t);

  GTN_RETURN_IF_ERROR(sink.beginLevel(header));
  {
    ItemGather values(m.point_fields);
    const bool none = m.point_fields.empty();
    for (uint64_t v = 0; v < V; ++v)
      GTN_RETURN_IF_ERROR(sink.vertex(static_cast<uint32_t>(v), &m.coords[3 * v], none ? nullptr : values.item(v)));
  }
  for (const auto& tri : boundary) GTN_RETURN_IF_ERROR(sink.boundaryTriangle(tri.data()));
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  for (uint64_t v = 0; v < V; ++v)
    if (last[v] == kNoIndex) GTN_RETURN_IF_ERROR(sink.retireVertex(static_cast<uint32_t>(v)));
  {
    ItemGather values(m.cell_fields);
    const bool none = m.cell_fields.empty();
    for (uint64_t t = 0; t < T; ++t) {
      const Tet& tet = m.tets[t];
      GTN_RETURN_IF_ERROR(sink.tet(tet.data(), none ? nullptr : values.item(t)));
      for (uint32_t v : tet)
        if (last[v] == t) GTN_RETURN_IF_ERROR(sink.retireVertex(v));
    }
  }
  return sink.endLevel();
}

}  // namespace gtn
