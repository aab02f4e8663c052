// A level as pieces (codec/pieces.h).
#include "codec/pieces.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "codec/edge_points.h"
#include "codec/packed_values.h"
#include "codec/prediction.h"
#include "codec/range_coder.h"
#include "codec/structured_piece.h"
#include "codec/value_coder.h"
#include "mesh/faces.h"
#include "mesh/index.h"

namespace gtn {

namespace {

// ---- the piece tree ------------------------------------------------------------------------------

// Recursive bisection of `order[b, e)` (tetrahedron indices) at the median of the centroids along
// the axis of their largest extent (ties: x, y, z; equal centroids by tetrahedron index); the left
// part takes the floor(n / 2) smallest. Appends each leaf range to `leaves` (in any order).
void bisect(const std::vector<double>& centroid, std::vector<uint32_t>& order, size_t b, size_t e, uint64_t bound,
            std::vector<std::pair<size_t, size_t>>& leaves, std::mutex& leaves_mutex) {
  if (e - b <= bound) {
    std::lock_guard<std::mutex> lock(leaves_mutex);
    leaves.emplace_back(b, e);
    return;
  }
  double lo[3], hi[3];
  for (int i = 0; i < 3; ++i) lo[i] = hi[i] = centroid[3 * size_t{order[b]} + i];
  for (size_t k = b; k < e; ++k)
    for (int i = 0; i < 3; ++i) {
      const double c = centroid[3 * size_t{order[k]} + i];
      lo[i] = std::min(lo[i], c);
      hi[i] = std::max(hi[i], c);
    }
  int axis = 0;
  for (int i = 1; i < 3; ++i)
    if (hi[i] - lo[i] > hi[axis] - lo[axis]) axis = i;
  const size_t mid = b + (e - b) / 2;
  std::nth_element(order.begin() + b, order.begin() + mid, order.begin() + e, [&](uint32_t x, uint32_t y) {
    const double cx = centroid[3 * size_t{x} + axis], cy = centroid[3 * size_t{y} + axis];
    return cx != cy ? cx < cy : x < y;
  });
  auto left = [&] { bisect(centroid, order, b, mid, bound, leaves, leaves_mutex); };
  auto right = [&] { bisect(centroid, order, mid, e, bound, leaves, leaves_mutex); };
  if (e - b > (uint64_t{1} << 16)) {
    tbb::parallel_invoke(left, right);
  } else {
    left();
    right();
  }
}

// piece[t] for every tetrahedron, pieces numbered in tree order (left first).
std::vector<uint32_t> partition(const TetMesh& mesh, uint64_t piece_tets, uint32_t* n_pieces) {
  const size_t nt = mesh.numTets();
  std::vector<double> centroid(3 * nt);
  tbb::parallel_for(size_t{0}, nt, [&](size_t t) {
    for (int i = 0; i < 3; ++i) {
      double c = 0;
      for (uint32_t v : mesh.tets[t]) c += mesh.coords[3 * size_t{v} + i];
      centroid[3 * t + i] = c / 4;
    }
  });
  std::vector<uint32_t> order(nt);
  for (size_t t = 0; t < nt; ++t) order[t] = static_cast<uint32_t>(t);
  std::vector<std::pair<size_t, size_t>> leaves;
  std::mutex leaves_mutex;
  bisect(centroid, order, 0, nt, piece_tets, leaves, leaves_mutex);
  std::sort(leaves.begin(), leaves.end());
  std::vector<uint32_t> piece(nt);
  for (size_t p = 0; p < leaves.size(); ++p)
    for (size_t k = leaves[p].first; k < leaves[p].second; ++k) piece[order[k]] = static_cast<uint32_t>(p);
  *n_pieces = static_cast<uint32_t>(leaves.size());
  return piece;
}

// ---- seam class streams ----------------------------------------------------------------------------

// The components of a vertex as a seam stream stores them: x, y, z in the coordinate type, then every
// point field's components.
struct ComponentLayout {
  std::vector<ScalarType> types;
  std::vector<size_t> offsets;  // in an item
  size_t item_bytes = 0;
  // packValues' value size: 1, so that its byte planes are those of every byte of the item whatever
  // the components' sizes (the same planes as per-component planes when the sizes are equal).
  size_t value_size = 1;

  explicit ComponentLayout(const LevelHeader& h) {
    auto add = [&](ScalarType t) {
      types.push_back(t);
      offsets.push_back(item_bytes);
      item_bytes += scalarSize(t);
    };
    for (int i = 0; i < 3; ++i) add(h.coord_type);
    for (const FieldDesc& d : h.point_fields)
      for (uint32_t c = 0; c < d.components; ++c) add(d.type);
  }
};

// A class's stream, in the smaller of two forms: range coded (first byte 0), each component's key
// (value_coder.h) coded by the level codec's value coder against the previous vertex's; or packed
// (codec/packed_values.h), the items holding each key's difference from the previous vertex's modulo
// the type's width.
void seamKeys(const TetMesh& mesh, const LevelHeader& h, const ComponentLayout& layout, uint32_t v, uint64_t* keys) {
  size_t c = 0;
  for (int i = 0; i < 3; ++i) {
    uint8_t raw[8];
    level::storeCoordinate(h.coord_type, mesh.coords[3 * size_t{v} + i], raw);
    keys[c] = keyFromRaw(layout.types[c], raw);
    ++c;
  }
  for (const Field& f : mesh.point_fields) {
    const size_t vs = f.valueSize();
    for (uint32_t j = 0; j < f.components; ++j, ++c)
      keys[c] = keyFromRaw(f.type, &f.bytes[(size_t{v} * f.components + j) * vs]);
  }
}

std::vector<uint8_t> encodeSeamStream(const TetMesh& mesh, const LevelHeader& h, const ComponentLayout& layout,
                                      const std::vector<uint32_t>& vertices) {
  const size_t n = vertices.size(), ib = layout.item_bytes, nc = layout.types.size();
  std::vector<uint8_t> items(n * ib);
  std::vector<uint64_t> prev(nc, 0), keys(nc);
  std::vector<uint8_t> coded;
  {
    EntropyCoder<true> coder(&coded);
    std::vector<ValueCoder> vc;
    for (ScalarType t : layout.types) vc.emplace_back(t, 1);
    for (size_t k = 0; k < n; ++k) {
      seamKeys(mesh, h, layout, vertices[k], keys.data());
      for (size_t c = 0; c < nc; ++c) {
        const ScalarType t = layout.types[c];
        const uint64_t pred = k == 0 ? keyFromPrediction(t, 0.0) : prev[c];
        vc[c].code(coder, 0, pred, keys[c]);
        const uint64_t delta = (keys[c] - prev[c]) & level::keyMask(scalarBits(t));
        uint8_t* out = &items[k * ib + layout.offsets[c]];
        for (size_t b = 0; b < scalarSize(t); ++b) out[b] = static_cast<uint8_t>(delta >> (8 * b));
        prev[c] = keys[c];
      }
    }
    coder.finish();
  }
  std::vector<uint8_t> packed = packValues(items.data(), n, ib, layout.value_size, coded.size());
  return !packed.empty() && packed.size() < coded.size() ? packed : coded;
}

// Decodes a class stream of `n` vertices into coordinates (3 per vertex) and point values (the
// header's point fields' items concatenated).
Status decodeSeamStream(std::span<const uint8_t> stream, uint64_t n, const LevelHeader& h,
                        const ComponentLayout& layout, const std::string& what, double* coords, uint8_t* values) {
  const size_t nc = layout.types.size();
  std::vector<uint64_t> prev(nc, 0);
  size_t value_bytes = 0;
  for (const FieldDesc& d : h.point_fields) value_bytes += d.itemBytes();
  auto store = [&](uint64_t k, size_t c, uint64_t key, size_t* out) -> Status {
    const ScalarType t = layout.types[c];
    uint8_t raw[8];
    rawFromKey(t, key, raw);
    if (c < 3) {
      const double x = doubleFromRaw(t, raw);
      if (!std::isfinite(x)) return invalidData(what + ": a seam vertex has a non-finite coordinate");
      coords[3 * k + c] = x;
    } else {
      std::memcpy(values + k * value_bytes + *out, raw, scalarSize(t));
      *out += scalarSize(t);
    }
    return Status::ok();
  };
  if (!isPackedStream(stream)) {
    EntropyCoder<false> coder(stream);
    std::vector<ValueCoder> vc;
    for (ScalarType t : layout.types) vc.emplace_back(t, 1);
    for (uint64_t k = 0; k < n; ++k) {
      size_t out = 0;
      for (size_t c = 0; c < nc; ++c) {
        const uint64_t pred = k == 0 ? keyFromPrediction(layout.types[c], 0.0) : prev[c];
        const uint64_t key = vc[c].code(coder, 0, pred, 0);
        if (!coder.ok()) return invalidData(what + ": the stream is corrupt or truncated");
        prev[c] = key;
        GTN_RETURN_IF_ERROR(store(k, c, key, &out));
      }
    }
    if (!coder.finishedCleanly()) return invalidData(what + ": the stream is corrupt, truncated or has trailing bytes");
    return Status::ok();
  }
  PackedReader reader;
  GTN_RETURN_IF_ERROR(reader.open(stream, n, layout.item_bytes, layout.value_size, what));
  for (uint64_t k = 0; k < n; ++k) {
    const uint8_t* item = reader.next();
    if (!item) return invalidData(what + ": " + reader.error());
    size_t out = 0;
    for (size_t c = 0; c < nc; ++c) {
      const ScalarType t = layout.types[c];
      uint64_t delta = 0;
      for (size_t b = 0; b < scalarSize(t); ++b) delta |= uint64_t{item[layout.offsets[c] + b]} << (8 * b);
      const uint64_t key = (prev[c] + delta) & level::keyMask(scalarBits(t));
      prev[c] = key;
      GTN_RETURN_IF_ERROR(store(k, c, key, &out));
    }
  }
  const Status st = reader.finish();
  return st.isOk() ? st : invalidData(what + ": " + st.message());
}

PieceInfo infoOf(const EncodedLevel& e, uint32_t seam_count) {
  PieceInfo info;
  info.points = e.header.points;
  info.own_points = e.header.points - seam_count;
  info.tets = e.header.tets;
  info.boundary_triangles = e.header.boundary_triangles;
  for (int i = 0; i < 3; ++i) {
    info.bbox_min[i] = e.header.bbox_min[i];
    info.bbox_max[i] = e.header.bbox_max[i];
  }
  return info;
}

}  // namespace

std::vector<std::vector<uint32_t>> pieceSeamLists(std::span<const SeamClass> classes, size_t pieces) {
  std::vector<std::vector<uint32_t>> lists(pieces);
  uint64_t first = 0;
  for (const SeamClass& c : classes) {
    for (uint32_t p : c.pieces)
      if (p < pieces)
        for (uint64_t k = 0; k < c.points; ++k) lists[p].push_back(static_cast<uint32_t>(first + k));
    first += c.points;
  }
  return lists;
}

LevelHeader pieceHeader(const LevelHeader& level, const PieceInfo& piece) {
  LevelHeader h = level;
  h.points = piece.points;
  h.tets = piece.tets;
  h.boundary_triangles = piece.boundary_triangles;
  for (int i = 0; i < 3; ++i) {
    h.bbox_min[i] = piece.bbox_min[i];
    h.bbox_max[i] = piece.bbox_max[i];
  }
  return h;
}

std::vector<uint32_t> piecesInBox(std::span<const PieceInfo> pieces, const double lo[3], const double hi[3]) {
  std::vector<uint32_t> out;
  for (size_t p = 0; p < pieces.size(); ++p) {
    bool meets = true;
    for (int i = 0; i < 3; ++i) meets = meets && pieces[p].bbox_min[i] <= hi[i] && pieces[p].bbox_max[i] >= lo[i];
    if (meets) out.push_back(static_cast<uint32_t>(p));
  }
  return out;
}

namespace {

// The mesh of one piece of `src`: its vertices (those of the tetrahedra `tl` and the unused points
// `unused`, in source order, listed in `verts`) with their coordinates and point values, and the
// tetrahedra `tl` in that order with their cell values.
TetMesh pieceMeshOf(const TetMesh& src, const std::vector<uint32_t>& tl, const std::vector<uint32_t>& unused,
                    std::vector<uint32_t>& verts) {
  for (uint32_t t : tl)
    for (uint32_t v : src.tets[t]) verts.push_back(v);
  verts.insert(verts.end(), unused.begin(), unused.end());
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::unordered_map<uint32_t, uint32_t> local;
  local.reserve(verts.size());
  for (size_t k = 0; k < verts.size(); ++k) local.emplace(verts[k], static_cast<uint32_t>(k));
  TetMesh piece;
  piece.coord_type = src.coord_type;
  piece.metadata = src.metadata;
  piece.coords.resize(3 * verts.size());
  for (size_t k = 0; k < verts.size(); ++k)
    for (int i = 0; i < 3; ++i) piece.coords[3 * k + i] = src.coords[3 * size_t{verts[k]} + i];
  for (const Field& f : src.point_fields) {
    Field g(f.name, f.components, f.type, verts.size());
    const size_t ib = f.components * f.valueSize();
    for (size_t k = 0; k < verts.size(); ++k) std::memcpy(&g.bytes[k * ib], &f.bytes[size_t{verts[k]} * ib], ib);
    piece.point_fields.push_back(std::move(g));
  }
  piece.tets.resize(tl.size());
  for (size_t k = 0; k < tl.size(); ++k)
    for (int j = 0; j < 4; ++j) piece.tets[k][j] = local.at(src.tets[tl[k]][j]);
  for (const Field& f : src.cell_fields) {
    Field g(f.name, f.components, f.type, tl.size());
    const size_t ib = f.components * f.valueSize();
    for (size_t k = 0; k < tl.size(); ++k) std::memcpy(&g.bytes[k * ib], &f.bytes[size_t{tl[k]} * ib], ib);
    piece.cell_fields.push_back(std::move(g));
  }
  return piece;
}

}  // namespace

namespace {

// Codes one piece's mesh with its seam options and fills its table entry (its own boundary points: the
// own vertices its boundary coding introduces).
Status encodePieceMesh(const TetMesh& piece, const EncodeOptions& opt, PieceInfo& info, EncodedLevel& encoded) {
  GTN_ASSIGN_OR_RETURN(EncodedLevel e, encodeLevel(piece, opt));
  info = infoOf(e, opt.seam_count);
  uint64_t own_boundary = 0;
  for (size_t k = 0; k < piece.numPoints(); ++k)
    if ((opt.seam.empty() || opt.seam[k] == kNoIndex) && e.vertex_order[k] < e.boundary_points) ++own_boundary;
  info.own_boundary_points = own_boundary;
  encoded = std::move(e);
  return Status::ok();
}

}  // namespace

PiecedLevel onePieceLevel(EncodedLevel e, uint8_t kind) {
  PiecedLevel l;
  l.header = e.header;
  l.pieces = {infoOf(e, 0)};
  l.pieces[0].kind = kind;
  // A structured piece gives every vertex before the boundary triangles.
  l.pieces[0].own_boundary_points = kind == kPieceStructured ? e.header.points : e.boundary_points;
  // A structured piece's checks and decoding read the level's renumbering, not the piece's: moved, not
  // copied (its tetrahedron order is the identity, left empty).
  if (kind == kPieceStructured) {
    l.vertex_order = std::move(e.vertex_order);
    l.tet_order = std::move(e.tet_order);
  } else {
    l.vertex_order = e.vertex_order;
    l.tet_order = e.tet_order;
  }
  l.encoded.push_back(std::move(e));
  return l;
}

SeamValues ChainSeams::view(std::vector<uint32_t>* seam_of_id) const {
  SeamValues s;
  s.count = count;
  s.coords = coords.data();
  s.values = values.data();
  s.seam_of_id = seam_of_id;
  return s;
}

ChainSeams chainSeamsOf(const TetMesh& next, const std::vector<uint32_t>& next_order) {
  ChainSeams out;
  const size_t n = next.numPoints();
  out.count = static_cast<uint32_t>(n);
  out.coords.resize(3 * n);
  size_t item = 0;
  for (const Field& f : next.point_fields) item += f.components * f.valueSize();
  out.values.resize(item * n);
  for (size_t v = 0; v < n && v < next_order.size(); ++v) {
    const size_t id = next_order[v];
    if (id >= n) continue;
    std::memcpy(&out.coords[3 * id], next.point(v), 3 * sizeof(double));
    size_t at = 0;
    for (const Field& f : next.point_fields) {
      const size_t b = f.components * f.valueSize();
      std::memcpy(&out.values[item * id + at], f.bytes.data() + b * v, b);
      at += b;
    }
  }
  return out;
}

StatusOr<PiecedLevel> encodeChainedLevel(const TetMesh& mesh, const std::vector<uint32_t>& next_index,
                                         const std::vector<uint32_t>& next_order) {
  if (next_index.size() != mesh.numPoints())
    return usageError("encodeChainedLevel: the map to the next level does not match the mesh");
  EncodeOptions options;
  options.structured = false;
  options.seam.assign(mesh.numPoints(), kNoIndex);
  std::vector<char> named(next_order.size(), 0);
  for (size_t v = 0; v < next_index.size(); ++v) {
    if (next_index[v] == kNoIndex) continue;
    if (next_index[v] >= next_order.size() || next_order[next_index[v]] >= next_order.size() ||
        named[next_order[next_index[v]]])
      return usageError("encodeChainedLevel: the map to the next level is not one to one");
    options.seam[v] = next_order[next_index[v]];
    named[options.seam[v]] = 1;
  }
  options.seam_count = static_cast<uint32_t>(next_order.size());
  GTN_ASSIGN_OR_RETURN(EncodedLevel e, encodeLevel(mesh, options));
  PiecedLevel level = onePieceLevel(std::move(e));
  level.base = 1;
  return level;
}

namespace {

// The unused points (unused(v)) of a mesh cut into n_pieces pieces, per piece, increasing: each goes
// with a piece that uses the edge it lies on (the level codec codes it with that edge), else with the
// last piece. first_piece[v]: the first piece that uses v (kNoIndex: none).
template <class Unused>
std::vector<std::vector<uint32_t>> placeUnusedPoints(const TetMesh& mesh, const std::vector<uint32_t>& first_piece,
                                                     uint32_t n_pieces, Unused&& unused_point) {
  std::vector<std::vector<uint32_t>> out(n_pieces);
  const size_t np = mesh.numPoints();
  std::vector<char> unused(np, 0);
  bool any = false;
  for (size_t v = 0; v < np; ++v)
    if (unused_point(v)) unused[v] = any = true;
  if (!any) return out;
  for (const EdgePoint& e : findEdgePoints(mesh)) {
    if (!unused[e.point] || first_piece[e.a] == kNoIndex) continue;
    out[first_piece[e.a]].push_back(e.point);
    unused[e.point] = 0;
  }
  for (size_t v = 0; v < np; ++v)
    if (unused[v]) out[n_pieces - 1].push_back(static_cast<uint32_t>(v));
  for (auto& list : out) std::sort(list.begin(), list.end());
  return out;
}

size_t streamBytes(const EncodedLevel& x) {
  size_t n = x.boundary.size() + x.connectivity.size() + x.geometry.size();
  for (const auto& f : x.point_fields) n += f.size();
  for (const auto& f : x.cell_fields) n += f.size();
  return n;
}

StatusOr<PiecedLevel> encodeCut(const TetMesh& mesh, const EncodeOptions& options, uint64_t piece_tets);

}  // namespace

StatusOr<PiecedLevel> encodePieces(const TetMesh& mesh, const EncodeOptions& options, uint64_t piece_tets) {
  if (piece_tets < kMinPieceTets) return usageError("encodePieces: pieces must hold at least 4096 tetrahedra");
  if (!options.seam.empty()) return usageError("encodePieces: the seams are the pieces' own");
  // A level that is one structured block is one structured piece: up to the bound where that is smaller
  // than the level codec's piece; at the default bound also beyond it (one piece decodes at memory
  // speed, where pieces of the level codec would decode in parallel at a small fraction of it); at
  // another bound not beyond it (the pieces that bound asks for, for region reads and parallel readers).
  StatusOr<EncodedLevel> grid = invalidData("not a structured block");
  if (mesh.blocks.size() == 1 && options.structured &&
      (mesh.numTets() <= piece_tets || piece_tets == kDefaultPieceTets))
    grid = encodeStructuredPiece(mesh, mesh.blocks[0]);
  if (mesh.numTets() <= piece_tets) {
    StatusOr<EncodedLevel> e = encodeLevel(mesh, options);
    if (!e.isOk()) return e.status();
    if (grid.isOk() && streamBytes(*grid) < streamBytes(*e))
      return onePieceLevel(std::move(grid).value(), kPieceStructured);
    return onePieceLevel(std::move(e).value());
  }
  // Larger than the bound: the level codec's pieces are not tried (on grids they take more bytes, and
  // they decode many times slower).
  if (grid.isOk()) return onePieceLevel(std::move(grid).value(), kPieceStructured);
  return encodeCut(mesh, options, piece_tets);
}

namespace {

// encodePieces for a level of more than piece_tets tetrahedra: cut, and each piece coded.
StatusOr<PiecedLevel> encodeCut(const TetMesh& mesh, const EncodeOptions& options, uint64_t piece_tets) {
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  PiecedLevel out;
  GTN_RETURN_IF_ERROR(mesh.checkConsistency("encodePieces"));
  uint32_t n_pieces = 0;
  const std::vector<uint32_t> piece_of = partition(mesh, piece_tets, &n_pieces);
  std::vector<std::vector<uint32_t>> piece_tets_list(n_pieces);
  for (size_t t = 0; t < nt; ++t) piece_tets_list[piece_of[t]].push_back(static_cast<uint32_t>(t));

  // Seam vertices: used by tetrahedra of two pieces or more; each vertex's first piece.
  std::vector<uint32_t> first_piece(np, kNoIndex);
  std::vector<char> is_seam(np, 0);
  for (uint32_t p = 0; p < n_pieces; ++p)
    for (uint32_t t : piece_tets_list[p])
      for (uint32_t v : mesh.tets[t]) {
        if (first_piece[v] == kNoIndex) {
          first_piece[v] = p;
        } else if (first_piece[v] != p) {
          is_seam[v] = 1;
        }
      }
  std::vector<std::pair<uint32_t, uint32_t>> uses;  // (seam vertex, piece)
  for (uint32_t p = 0; p < n_pieces; ++p)
    for (uint32_t t : piece_tets_list[p])
      for (uint32_t v : mesh.tets[t])
        if (is_seam[v]) uses.emplace_back(v, p);
  std::sort(uses.begin(), uses.end());
  uses.erase(std::unique(uses.begin(), uses.end()), uses.end());
  std::map<std::vector<uint32_t>, std::vector<uint32_t>> class_vertices;  // piece list -> its vertices
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    std::vector<uint32_t> key;
    while (j < uses.size() && uses[j].first == uses[i].first) key.push_back(uses[j++].second);
    class_vertices[key].push_back(uses[i].first);  // increasing vertex order
    i = j;
  }
  uses.clear();
  uses.shrink_to_fit();
  std::vector<uint32_t> seam_id(np, kNoIndex);  // global id of a seam vertex
  std::vector<const std::vector<uint32_t>*> class_list;
  uint32_t n_seam = 0;
  for (const auto& [key, verts] : class_vertices) {
    out.classes.push_back({key, verts.size()});
    class_list.push_back(&verts);
    for (uint32_t v : verts) seam_id[v] = n_seam++;
  }

  const std::vector<std::vector<uint32_t>> piece_unused =
      placeUnusedPoints(mesh, first_piece, n_pieces, [&](size_t v) { return first_piece[v] == kNoIndex; });

  const std::vector<std::vector<uint32_t>> seam_lists = pieceSeamLists(out.classes, n_pieces);
  out.encoded.resize(n_pieces);
  out.pieces.resize(n_pieces);
  std::vector<std::vector<uint32_t>> local_to_source(n_pieces);
  std::vector<std::vector<uint32_t>> local_seam(n_pieces);  // per local vertex: seam index or kNoIndex
  std::vector<Status> failures(n_pieces, Status::ok());
  // Per piece, its boundary faces whose vertices are all seam vertices (sorted source indices): a cut
  // face appears in two pieces.
  std::vector<std::vector<std::array<uint32_t, 3>>> seam_faces(n_pieces);
  tbb::parallel_for(uint32_t{0}, n_pieces, [&](uint32_t p) {
    // The piece's mesh: its vertices in source order, its tetrahedra in source order.
    std::vector<uint32_t>& verts = local_to_source[p];
    const TetMesh piece = pieceMeshOf(mesh, piece_tets_list[p], piece_unused[p], verts);
    {
      const FaceAdjacency adj = computeFaceAdjacency(piece);
      for (size_t t = 0; t < piece.tets.size(); ++t)
        for (int k = 0; k < 4; ++k) {
          if (adj.neighbor[4 * t + k] != kNoNeighbor) continue;
          std::array<uint32_t, 3> f;
          bool seam = true;
          for (int j = 0; j < 3; ++j) {
            f[j] = verts[piece.tets[t][kTetFace[k][j]]];
            seam = seam && seam_id[f[j]] != kNoIndex;
          }
          if (!seam) continue;
          std::sort(f.begin(), f.end());
          seam_faces[p].push_back(f);
        }
    }
    EncodeOptions opt = options;
    std::unordered_map<uint32_t, uint32_t> seam_index;  // global seam id -> index in the piece's list
    for (size_t k = 0; k < seam_lists[p].size(); ++k) seam_index.emplace(seam_lists[p][k], static_cast<uint32_t>(k));
    opt.seam.assign(verts.size(), kNoIndex);
    for (size_t k = 0; k < verts.size(); ++k)
      if (seam_id[verts[k]] != kNoIndex) opt.seam[k] = seam_index.at(seam_id[verts[k]]);
    opt.seam_count = static_cast<uint32_t>(seam_lists[p].size());
    local_seam[p] = opt.seam;
    failures[p] = encodePieceMesh(piece, opt, out.pieces[p], out.encoded[p]);
  });
  for (const Status& st : failures)
    if (!st.isOk()) return st;

  // The level's header, and the global orders (codec/pieces.h).
  {
    LevelHeader& h = out.header;
    h = out.encoded[0].header;
    h.points = np;
    h.tets = nt;
    h.boundary_triangles = 0;
    for (const PieceInfo& info : out.pieces) {
      for (int i = 0; i < 3; ++i) {
        h.bbox_min[i] = std::min(h.bbox_min[i], info.bbox_min[i]);
        h.bbox_max[i] = std::max(h.bbox_max[i], info.bbox_max[i]);
      }
    }
  }
  out.vertex_order.assign(np, kNoIndex);
  out.tet_order.assign(nt, 0);
  uint64_t bnd_base = n_seam, int_base = n_seam, tet_base = 0;
  for (const PieceInfo& info : out.pieces) int_base += info.own_boundary_points;
  for (uint32_t p = 0; p < n_pieces; ++p) {
    const EncodedLevel& e = out.encoded[p];
    const std::vector<uint32_t>& verts = local_to_source[p];
    std::vector<uint32_t> by_id(verts.size());
    for (size_t k = 0; k < verts.size(); ++k) by_id[e.vertex_order[k]] = static_cast<uint32_t>(k);
    for (size_t id = 0; id < by_id.size(); ++id) {
      const uint32_t k = by_id[id], v = verts[k];
      if (local_seam[p][k] != kNoIndex) {
        out.vertex_order[v] = seam_id[v];
      } else if (id < e.boundary_points) {
        out.vertex_order[v] = static_cast<uint32_t>(bnd_base++);
      } else {
        out.vertex_order[v] = static_cast<uint32_t>(int_base++);
      }
    }
    const std::vector<uint32_t>& tl = piece_tets_list[p];
    for (size_t k = 0; k < tl.size(); ++k) out.tet_order[tl[k]] = tet_base + e.tet_order[k];
    tet_base += tl.size();
  }
  // Boundary triangles of the level: those of the pieces, less the cut faces (two per face).
  {
    std::vector<std::array<uint32_t, 3>> cut;
    for (auto& list : seam_faces) cut.insert(cut.end(), list.begin(), list.end());
    std::sort(cut.begin(), cut.end());
    uint64_t pairs = 0;
    for (size_t i = 0; i + 1 < cut.size(); ++i)
      if (cut[i] == cut[i + 1]) ++pairs;
    uint64_t sum = 0;
    for (const PieceInfo& info : out.pieces) sum += info.boundary_triangles;
    out.header.boundary_triangles = sum - 2 * pairs;
  }
  // The class streams, in parallel.
  const ComponentLayout layout(out.header);
  out.seam_streams.resize(out.classes.size());
  tbb::parallel_for(size_t{0}, out.classes.size(), [&](size_t c) {
    out.seam_streams[c] = encodeSeamStream(mesh, out.header, layout, *class_list[c]);
  });
  return out;
}

}  // namespace

StatusOr<DecodedPieces> decodePieces(const PiecedLevelView& view, const std::vector<uint32_t>& chosen_in,
                                     const std::string& what, const DecodeFields* fields) {
  const LevelHeader& h = *view.header;
  const size_t n_pieces = view.pieces.size();
  std::vector<uint32_t> chosen = chosen_in;
  if (chosen.empty())
    for (uint32_t p = 0; p < n_pieces; ++p) chosen.push_back(p);
  for (size_t k = 0; k < chosen.size(); ++k)
    if (chosen[k] >= n_pieces || (k > 0 && chosen[k] <= chosen[k - 1]))
      return usageError(what + ": the pieces asked for are not increasing piece indices of the level");
  if (view.payloads.size() != n_pieces || view.seam_streams.size() != view.classes.size())
    return usageError(what + ": the streams do not match the level's pieces and classes");
  const bool all = chosen.size() == n_pieces;
  std::vector<char> is_chosen(n_pieces, 0);
  for (uint32_t p : chosen) is_chosen[p] = 1;

  // Seam vertices: the classes that hold a chosen piece, decoded in parallel.
  const size_t n_classes = view.classes.size();
  std::vector<uint64_t> class_first(n_classes + 1, 0);   // global seam id of each class's first vertex
  std::vector<uint64_t> class_out(n_classes, kNoIndex);  // its first output id, kNoIndex: not decoded
  uint64_t n_seam_out = 0;
  for (size_t c = 0; c < n_classes; ++c) {
    class_first[c + 1] = class_first[c] + view.classes[c].points;
    bool needed = false;
    for (uint32_t p : view.classes[c].pieces) needed = needed || (p < n_pieces && is_chosen[p]);
    if (needed) {
      class_out[c] = n_seam_out;
      n_seam_out += view.classes[c].points;
    }
  }
  const uint64_t n_seam_all = class_first[n_classes];
  uint64_t own_bnd = 0, own_int = 0, tets = 0;
  for (uint32_t p : chosen) {
    const PieceInfo& info = view.pieces[p];
    if (info.own_boundary_points > info.own_points || info.own_points > info.points)
      return invalidData(what + ": piece " + std::to_string(p) + "'s vertex counts are inconsistent");
    own_bnd += info.own_boundary_points;
    own_int += info.own_points - info.own_boundary_points;
    tets += info.tets;
  }
  const uint64_t n_out = n_seam_out + own_bnd + own_int;
  if (n_out >= kNoIndex || tets >= kNoIndex) return invalidData(what + ": too many points or tetrahedra");
  if (all && (n_out != h.points || tets != h.tets))
    return invalidData(what + ": the pieces' counts do not add up to the level's");

  DecodedPieces out;
  TetMesh& mesh = out.mesh;
  mesh.coord_type = h.coord_type;
  mesh.metadata = h.metadata;
  mesh.coords.resize(3 * n_out);
  size_t value_bytes = 0;
  std::vector<size_t> field_offset;
  for (const FieldDesc& d : h.point_fields) {
    field_offset.push_back(value_bytes);
    value_bytes += d.itemBytes();
    mesh.point_fields.emplace_back(d.name, d.components, d.type, n_out);
  }
  for (const FieldDesc& d : h.cell_fields) mesh.cell_fields.emplace_back(d.name, d.components, d.type, tets);
  mesh.tets.resize(tets);

  const ComponentLayout layout(h);
  std::vector<std::vector<double>> seam_coords(n_classes);
  std::vector<std::vector<uint8_t>> seam_values(n_classes);
  std::vector<Status> class_status(n_classes, Status::ok());
  tbb::parallel_for(size_t{0}, n_classes, [&](size_t c) {
    if (class_out[c] == kNoIndex) return;
    const uint64_t n = view.classes[c].points;
    seam_coords[c].resize(3 * n);
    seam_values[c].resize(n * value_bytes);
    class_status[c] = decodeSeamStream(view.seam_streams[c], n, h, layout, what + ", seam class " + std::to_string(c),
                                       seam_coords[c].data(), seam_values[c].data());
    if (!class_status[c].isOk()) return;
    const uint64_t first = class_out[c];
    std::memcpy(&mesh.coords[3 * first], seam_coords[c].data(), 3 * n * sizeof(double));
    for (size_t f = 0; f < h.point_fields.size(); ++f) {
      const size_t ib = h.point_fields[f].itemBytes();
      for (uint64_t k = 0; k < n; ++k)
        std::memcpy(&mesh.point_fields[f].bytes[(first + k) * ib], &seam_values[c][k * value_bytes + field_offset[f]],
                    ib);
    }
  });
  for (const Status& st : class_status)
    if (!st.isOk()) return st;

  // Each chosen piece's seam list, as classes and offsets.
  struct SeamRef {
    uint32_t cls;
    uint64_t k;
  };
  std::vector<std::vector<SeamRef>> seam_refs(n_pieces);
  for (size_t c = 0; c < n_classes; ++c)
    for (uint32_t p : view.classes[c].pieces)
      if (p < n_pieces && is_chosen[p])
        for (uint64_t k = 0; k < view.classes[c].points; ++k) seam_refs[p].push_back({static_cast<uint32_t>(c), k});

  // Output bases of each chosen piece.
  std::vector<uint64_t> bnd_base(n_pieces), int_base(n_pieces), tet_base(n_pieces);
  {
    uint64_t b = n_seam_out, i = n_seam_out + own_bnd, t = 0;
    for (uint32_t p : chosen) {
      bnd_base[p] = b;
      int_base[p] = i;
      tet_base[p] = t;
      b += view.pieces[p].own_boundary_points;
      i += view.pieces[p].own_points - view.pieces[p].own_boundary_points;
      t += view.pieces[p].tets;
    }
  }

  // A sink that writes one piece's vertices and tetrahedra into the stitched mesh.
  class StitchSink : public MeshSink {
   public:
    StitchSink(const LevelHeader& h, TetMesh& mesh, const std::vector<size_t>& field_offset,
               const std::vector<SeamRef>& refs, const std::vector<uint64_t>& class_out, uint64_t bnd_base,
               uint64_t n_bnd, uint64_t int_base, uint64_t n_int, uint64_t tet_base, uint64_t n_tets)
        : h_(h),
          mesh_(mesh),
          field_offset_(field_offset),
          refs_(refs),
          class_out_(class_out),
          bnd_next_(bnd_base),
          bnd_end_(bnd_base + n_bnd),
          int_next_(int_base),
          int_end_(int_base + n_int),
          tet_next_(tet_base),
          tet_end_(tet_base + n_tets) {}
    std::vector<uint32_t> seam_of_id;
    std::vector<std::array<uint32_t, 3>> boundary;
    Status beginLevel(const LevelHeader&) override { return Status::ok(); }
    Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
      if (id != map_.size() || seam_of_id.size() <= map_.size()) return invalidData("vertex ids out of order");
      const uint32_t s = seam_of_id[id];
      uint64_t out;
      if (s != kNoIndex) {
        out = class_out_[refs_[s].cls] + refs_[s].k;
      } else if (!boundary_done_) {
        if (bnd_next_ >= bnd_end_) return invalidData("more own vertices on the boundary than the piece table says");
        out = bnd_next_++;
      } else {
        if (int_next_ >= int_end_) return invalidData("more own vertices than the piece table says");
        out = int_next_++;
      }
      map_.push_back(static_cast<uint32_t>(out));
      if (s != kNoIndex) return Status::ok();  // the class's values are already in place
      for (int i = 0; i < 3; ++i) mesh_.coords[3 * out + i] = xyz[i];
      for (size_t f = 0; f < h_.point_fields.size(); ++f) {
        const size_t ib = h_.point_fields[f].itemBytes();
        std::memcpy(&mesh_.point_fields[f].bytes[out * ib], values + field_offset_[f], ib);
      }
      return Status::ok();
    }
    Status boundaryTriangle(const uint32_t v[3]) override {
      boundary.push_back({map_[v[0]], map_[v[1]], map_[v[2]]});
      return Status::ok();
    }
    Status endBoundary() override {
      boundary_done_ = true;
      if (bnd_next_ != bnd_end_) return invalidData("fewer own vertices on the boundary than the piece table says");
      return Status::ok();
    }
    Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
      if (tet_next_ >= tet_end_) return invalidData("more tetrahedra than the piece table says");
      const uint64_t t = tet_next_++;
      for (int j = 0; j < 4; ++j) mesh_.tets[t][j] = map_[v[j]];
      size_t off = 0;
      for (size_t f = 0; f < h_.cell_fields.size(); ++f) {
        const size_t ib = h_.cell_fields[f].itemBytes();
        std::memcpy(&mesh_.cell_fields[f].bytes[t * ib], cell_values + off, ib);
        off += ib;
      }
      return Status::ok();
    }
    Status retireVertex(uint32_t) override { return Status::ok(); }
    Status endLevel() override {
      if (int_next_ != int_end_ || tet_next_ != tet_end_)
        return invalidData("fewer vertices or tetrahedra than the piece table says");
      return Status::ok();
    }

   private:
    const LevelHeader& h_;
    TetMesh& mesh_;
    const std::vector<size_t>& field_offset_;
    const std::vector<SeamRef>& refs_;
    const std::vector<uint64_t>& class_out_;
    std::vector<uint32_t> map_;
    bool boundary_done_ = false;
    uint64_t bnd_next_, bnd_end_, int_next_, int_end_, tet_next_, tet_end_;
  };

  std::vector<std::vector<std::array<uint32_t, 3>>> boundaries(n_pieces);
  std::vector<Status> piece_status(n_pieces, Status::ok());
  tbb::parallel_for(size_t{0}, chosen.size(), [&](size_t i) {
    const uint32_t p = chosen[i];
    const PieceInfo& info = view.pieces[p];
    const std::string piece_what = n_pieces > 1 ? what + ", piece " + std::to_string(p) : what;
    if (info.points - info.own_points != seam_refs[p].size()) {
      piece_status[p] = invalidData(piece_what + ": its seam vertices differ from its seam classes'");
      return;
    }
    const LevelHeader ph = pieceHeader(h, info);
    StitchSink sink(h, mesh, field_offset, seam_refs[p], class_out, bnd_base[p], info.own_boundary_points, int_base[p],
                    info.own_points - info.own_boundary_points, tet_base[p], info.tets);
    // The piece's seam values, gathered in its seam-list order.
    const size_t ns = seam_refs[p].size();
    std::vector<double> coords(3 * ns);
    std::vector<uint8_t> values(ns * value_bytes);
    for (size_t k = 0; k < ns; ++k) {
      const SeamRef& r = seam_refs[p][k];
      std::memcpy(&coords[3 * k], &seam_coords[r.cls][3 * r.k], 3 * sizeof(double));
      if (value_bytes > 0) std::memcpy(&values[k * value_bytes], &seam_values[r.cls][r.k * value_bytes], value_bytes);
    }
    Status st = Status::ok();
    if (info.kind == kPieceStructured) {
      // A structured piece: a level of one piece, no seam vertex.
      if (n_pieces != 1) {
        piece_status[p] = invalidData(piece_what + ": a structured piece in a level of several pieces");
        return;
      }
      sink.seam_of_id.assign(info.points, kNoIndex);
      st = decodeStructuredPiece(ph, view.payloads[p].streams.connectivity, sink, piece_what, fields);
    } else if (info.kind != kPieceUnstructured) {
      st = invalidData(piece_what + ": unknown piece kind " + std::to_string(info.kind));
    } else {
      SeamValues seams;
      seams.count = static_cast<uint32_t>(ns);
      seams.coords = coords.data();
      seams.values = values.data();
      seams.seam_of_id = &sink.seam_of_id;
      st = decodeLevel(ph, view.payloads[p].streams, sink, nullptr, piece_what, fields, &seams);
    }
    if (!st.isOk()) {
      piece_status[p] = st.code() == StatusCode::kInvalidData && st.message().rfind(piece_what, 0) != 0
                            ? invalidData(piece_what + ": " + st.message())
                            : st;
      return;
    }
    boundaries[p] = std::move(sink.boundary);
  });
  for (uint32_t p : chosen)
    if (!piece_status[p].isOk()) return piece_status[p];

  // The boundary: every piece's triangles but the cut faces between two decoded pieces (a triangle of
  // seam vertices that another decoded piece has too, reversed).
  {
    auto key = [](const std::array<uint32_t, 3>& t) {
      std::array<uint32_t, 3> s = t;
      std::sort(s.begin(), s.end());
      return s;
    };
    std::map<std::array<uint32_t, 3>, uint32_t> seen;
    for (uint32_t p : chosen)
      for (const auto& t : boundaries[p])
        if (t[0] < n_seam_out && t[1] < n_seam_out && t[2] < n_seam_out) ++seen[key(t)];
    for (uint32_t p : chosen)
      for (const auto& t : boundaries[p]) {
        if (t[0] < n_seam_out && t[1] < n_seam_out && t[2] < n_seam_out && seen[key(t)] > 1) continue;
        out.boundary.push_back(t);
      }
  }
  if (all && out.boundary.size() != h.boundary_triangles)
    return invalidData(what + ": the pieces' boundaries do not give the level's boundary triangles");

  if (!all) {
    out.global_vertex.resize(n_out);
    for (size_t c = 0; c < n_classes; ++c)
      if (class_out[c] != kNoIndex)
        for (uint64_t k = 0; k < view.classes[c].points; ++k)
          out.global_vertex[class_out[c] + k] = static_cast<uint32_t>(class_first[c] + k);
    uint64_t gb = n_seam_all, gi = n_seam_all;
    for (const PieceInfo& info : view.pieces) gi += info.own_boundary_points;
    out.global_tet.resize(tets);
    uint64_t gt = 0;
    for (uint32_t p = 0; p < n_pieces; ++p) {
      const PieceInfo& info = view.pieces[p];
      if (is_chosen[p]) {
        for (uint64_t k = 0; k < info.own_boundary_points; ++k)
          out.global_vertex[bnd_base[p] + k] = static_cast<uint32_t>(gb + k);
        for (uint64_t k = 0; k < info.own_points - info.own_boundary_points; ++k)
          out.global_vertex[int_base[p] + k] = static_cast<uint32_t>(gi + k);
        for (uint64_t k = 0; k < info.tets; ++k) out.global_tet[tet_base[p] + k] = gt + k;
      }
      gb += info.own_boundary_points;
      gi += info.own_points - info.own_boundary_points;
      gt += info.tets;
    }
  }
  return out;
}

// ---- a level held in parts ----------------------------------------------------------------------------

StatusOr<PartPlan> planPart(const TetMesh& part, uint64_t piece_tets) {
  if (piece_tets < kMinPieceTets) return usageError("planPart: pieces must hold at least 4096 tetrahedra");
  GTN_RETURN_IF_ERROR(part.checkConsistency("the part"));
  const size_t np = part.numPoints(), nt = part.numTets();
  PartPlan plan;
  if (nt > 0) plan.piece_of = partition(part, piece_tets, &plan.pieces);
  // Per vertex, the pieces that use it: (vertex, piece) pairs, sorted.
  std::vector<std::pair<uint32_t, uint32_t>> uses;
  uses.reserve(4 * nt);
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t v : part.tets[t]) uses.emplace_back(v, plan.piece_of[t]);
  std::sort(uses.begin(), uses.end());
  uses.erase(std::unique(uses.begin(), uses.end()), uses.end());
  std::vector<char> exposed(np, 1);  // unused vertices are exposed
  std::vector<uint32_t> first(np + 1, 0);
  for (const auto& u : uses) ++first[u.first + 1];
  for (size_t v = 0; v < np; ++v) {
    first[v + 1] += first[v];
    if (first[v + 1] - first[v] == 1) exposed[v] = 0;  // one piece: exposed only on the boundary
  }
  if (nt > 0) {
    const FaceAdjacency adj = computeFaceAdjacency(part);
    for (size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 4; ++k)
        if (adj.neighbor[4 * t + k] == kNoNeighbor)
          for (int j = 0; j < 3; ++j) exposed[part.tets[t][kTetFace[k][j]]] = 1;
  }
  plan.uses_first.push_back(0);
  for (size_t v = 0; v < np; ++v) {
    if (!exposed[v]) continue;
    plan.exposed.push_back(static_cast<uint32_t>(v));
    for (uint32_t k = first[v]; k < first[v + 1]; ++k) plan.uses.push_back(uses[k].second);
    plan.uses_first.push_back(static_cast<uint32_t>(plan.uses.size()));
  }
  return plan;
}

StatusOr<SeamPlan> planSeams(const std::vector<PartExposed>& parts, bool coordinate_keys) {
  SeamPlan plan;
  plan.first_piece.push_back(0);
  for (const PartExposed& p : parts) {
    if (p.uses_first.size() != p.keys.size() + 1 || p.uses_first.back() != p.uses.size())
      return usageError("planSeams: a part's exposed vertices and their pieces do not match");
    plan.first_piece.push_back(plan.first_piece.back() + p.pieces);
  }
  // Every copy of every key: (key, part, exposed index), sorted by key then part.
  struct Copy {
    PointKey key;
    uint32_t part, index;
    bool operator<(const Copy& o) const { return std::tie(key, part, index) < std::tie(o.key, o.part, o.index); }
  };
  std::vector<Copy> copies;
  for (uint32_t q = 0; q < parts.size(); ++q) {
    plan.status.emplace_back(parts[q].keys.size(), kPartOwnVertex);
    for (uint32_t i = 0; i < parts[q].keys.size(); ++i) copies.push_back({parts[q].keys[i], q, i});
  }
  std::sort(copies.begin(), copies.end());
  // Per key: the level's pieces that use it; seam keys grouped by class (classes in piece-list order,
  // each class's keys in key order, as the copies are sorted).
  std::map<std::vector<uint32_t>, std::vector<std::pair<size_t, size_t>>> class_keys;  // -> copy ranges
  for (size_t i = 0; i < copies.size();) {
    size_t j = i;
    std::vector<uint32_t> pieces;
    while (j < copies.size() && copies[j].key == copies[i].key) {
      const Copy& c = copies[j];
      if (j > i && c.part == copies[j - 1].part) {
        std::string key;
        if (coordinate_keys) {
          double x[3];
          std::memcpy(x, c.key.data(), sizeof x);
          key = "coordinates (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", " + std::to_string(x[2]) +
                "): without point global ids, points are matched across parts by their coordinates, which "
                "coincident points make ambiguous";
        } else {
          key = "global id " + std::to_string(c.key[0]);
        }
        return invalidData("part " + std::to_string(c.part) + " holds two points with the same " + key);
      }
      const PartExposed& p = parts[c.part];
      for (uint32_t k = p.uses_first[c.index]; k < p.uses_first[c.index + 1]; ++k) {
        if (p.uses[k] >= p.pieces) return usageError("planSeams: a part names a piece it does not have");
        pieces.push_back(plan.first_piece[c.part] + p.uses[k]);
      }
      ++j;
    }
    std::sort(pieces.begin(), pieces.end());
    if (pieces.size() >= 2) {
      class_keys[pieces].emplace_back(i, j);
    } else if (pieces.size() == 1) {
      // One piece's own: the part that uses it keeps it, the others drop their copies.
      for (size_t k = i; k < j; ++k) {
        const uint32_t q = copies[k].part;
        const bool user = pieces[0] >= plan.first_piece[q] && pieces[0] < plan.first_piece[q + 1];
        plan.status[q][copies[k].index] = user ? kPartOwnVertex : kPartDropVertex;
      }
    } else {
      // An orphan: the first holder with pieces keeps it for now.
      plan.orphans.push_back(copies[i].key);
      plan.orphan_holders.emplace_back();
      bool kept = false;
      for (size_t k = i; k < j; ++k) {
        const uint32_t q = copies[k].part;
        plan.orphan_holders.back().emplace_back(q, copies[k].index);
        const bool keep = !kept && parts[q].pieces > 0;
        kept = kept || keep;
        plan.status[q][copies[k].index] = keep ? kPartOwnVertex : kPartDropVertex;
      }
    }
    i = j;
  }
  uint32_t seam = 0;
  for (const auto& [pieces, ranges] : class_keys) {
    plan.classes.push_back({pieces, ranges.size()});
    for (const auto& [i, j] : ranges) {
      for (size_t k = i; k < j; ++k) plan.status[copies[k].part][copies[k].index] = seam;
      plan.seam_source.emplace_back(copies[i].part, copies[i].index);
      ++seam;
    }
  }
  return plan;
}

void settleOrphans(SeamPlan& plan, const std::vector<char>& used) {
  for (size_t k = 0; k < plan.orphans.size() && k < used.size(); ++k)
    if (used[k])
      for (const auto& [q, i] : plan.orphan_holders[k]) plan.status[q][i] = kPartDropVertex;
}

std::vector<char> usedKeys(const TetMesh& part, std::span<const PointKey> part_keys, std::span<const PointKey> keys) {
  std::vector<char> out(keys.size(), 0);
  if (keys.empty()) return out;
  std::map<PointKey, size_t> wanted;
  for (size_t k = 0; k < keys.size(); ++k) wanted.emplace(keys[k], k);
  std::vector<char> seen(part.numPoints(), 0);
  for (const Tet& t : part.tets)
    for (uint32_t v : t) {
      if (seen[v] || v >= part_keys.size()) continue;
      seen[v] = 1;
      const auto it = wanted.find(part_keys[v]);
      if (it != wanted.end()) out[it->second] = 1;
    }
  return out;
}

StatusOr<EncodedPart> encodePart(const TetMesh& part, const PartPlan& plan, std::span<const SeamClass> classes,
                                 uint32_t first_piece, std::span<const uint32_t> status, const EncodeOptions& options) {
  if (!options.seam.empty()) return usageError("encodePart: the seams are the parts' own");
  if (status.size() != plan.exposed.size() || plan.piece_of.size() != part.numTets())
    return usageError("encodePart: the plan or the status does not match the part");
  const size_t np = part.numPoints(), nt = part.numTets();
  const uint32_t n_pieces = plan.pieces;
  EncodedPart out;
  out.seam_id.assign(np, kNoIndex);
  std::vector<char> dropped(np, 0);
  uint64_t n_seam = 0;
  for (const SeamClass& c : classes) n_seam += c.points;
  for (size_t i = 0; i < plan.exposed.size(); ++i) {
    const uint32_t s = status[i];
    if (s == kPartDropVertex) {
      dropped[plan.exposed[i]] = 1;
    } else if (s != kPartOwnVertex) {
      if (s >= n_seam) return usageError("encodePart: a seam id beyond the classes");
      out.seam_id[plan.exposed[i]] = s;
    }
  }
  if (n_pieces == 0) return out;
  out.piece_tets.resize(n_pieces);
  for (size_t t = 0; t < nt; ++t) out.piece_tets[plan.piece_of[t]].push_back(static_cast<uint32_t>(t));
  std::vector<uint32_t> first_use(np, kNoIndex);
  for (uint32_t p = 0; p < n_pieces; ++p)
    for (uint32_t t : out.piece_tets[p])
      for (uint32_t v : part.tets[t])
        if (first_use[v] == kNoIndex) first_use[v] = p;
  // A dropped vertex is another part's: no tetrahedron here may use it.
  for (size_t v = 0; v < np; ++v)
    if (dropped[v] && first_use[v] != kNoIndex)
      return usageError("encodePart: vertex " + std::to_string(v) + " is used here but another part's");
  // Unused own points (encodePieces' rule).
  const std::vector<std::vector<uint32_t>> piece_unused =
      placeUnusedPoints(part, first_use, n_pieces, [&](size_t v) { return first_use[v] == kNoIndex && !dropped[v]; });
  // Each piece's seam list: the classes that hold it, in class order, each class's ids in order.
  std::vector<std::unordered_map<uint32_t, uint32_t>> seam_index(n_pieces);  // global seam id -> index
  {
    uint64_t first = 0;
    for (const SeamClass& c : classes) {
      for (uint32_t g : c.pieces)
        if (g >= first_piece && g - first_piece < n_pieces) {
          auto& index = seam_index[g - first_piece];
          for (uint64_t k = 0; k < c.points; ++k)
            index.emplace(static_cast<uint32_t>(first + k), static_cast<uint32_t>(index.size()));
        }
      first += c.points;
    }
  }
  out.piece_vertices.resize(n_pieces);
  out.pieces.resize(n_pieces);
  out.encoded.resize(n_pieces);
  std::vector<std::vector<std::array<uint32_t, 3>>> seam_faces(n_pieces);
  std::vector<Status> failures(n_pieces, Status::ok());
  tbb::parallel_for(uint32_t{0}, n_pieces, [&](uint32_t p) {
    std::vector<uint32_t>& verts = out.piece_vertices[p];
    const TetMesh piece = pieceMeshOf(part, out.piece_tets[p], piece_unused[p], verts);
    {
      const FaceAdjacency adj = computeFaceAdjacency(piece);
      for (size_t t = 0; t < piece.tets.size(); ++t)
        for (int k = 0; k < 4; ++k) {
          if (adj.neighbor[4 * t + k] != kNoNeighbor) continue;
          std::array<uint32_t, 3> f;
          bool seam = true;
          for (int j = 0; j < 3; ++j) {
            f[j] = out.seam_id[verts[piece.tets[t][kTetFace[k][j]]]];
            seam = seam && f[j] != kNoIndex;
          }
          if (!seam) continue;
          std::sort(f.begin(), f.end());
          seam_faces[p].push_back(f);
        }
    }
    EncodeOptions opt = options;
    opt.seam.assign(verts.size(), kNoIndex);
    for (size_t k = 0; k < verts.size(); ++k) {
      const uint32_t s = out.seam_id[verts[k]];
      if (s == kNoIndex) continue;
      const auto it = seam_index[p].find(s);
      if (it == seam_index[p].end()) {
        failures[p] = usageError("encodePart: piece " + std::to_string(first_piece + p) + " uses seam vertex " +
                                 std::to_string(s) + ", whose class does not hold it");
        return;
      }
      opt.seam[k] = it->second;
    }
    opt.seam_count = static_cast<uint32_t>(seam_index[p].size());
    failures[p] = encodePieceMesh(piece, opt, out.pieces[p], out.encoded[p]);
  });
  for (const Status& st : failures)
    if (!st.isOk()) return st;
  for (auto& list : seam_faces) out.seam_faces.insert(out.seam_faces.end(), list.begin(), list.end());
  return out;
}

StatusOr<PiecedLevel> assembleParts(std::vector<EncodedPart>&& parts, const SeamPlan& plan, const TetMesh& seams) {
  PiecedLevel out;
  uint64_t n_seam = 0;
  for (const SeamClass& c : plan.classes) n_seam += c.points;
  if (seams.numPoints() != n_seam) return usageError("assembleParts: the seam mesh does not hold every seam vertex");
  if (parts.size() + 1 != plan.first_piece.size()) return usageError("assembleParts: parts and plan do not match");
  std::vector<std::array<uint32_t, 3>> cut;
  for (size_t q = 0; q < parts.size(); ++q) {
    EncodedPart& part = parts[q];
    if (part.pieces.size() != part.encoded.size() ||
        part.pieces.size() != plan.first_piece[q + 1] - plan.first_piece[q])
      return usageError("assembleParts: part " + std::to_string(q) + " has other pieces than the plan");
    for (size_t p = 0; p < part.pieces.size(); ++p) {
      out.pieces.push_back(part.pieces[p]);
      out.encoded.push_back(std::move(part.encoded[p]));
    }
    cut.insert(cut.end(), part.seam_faces.begin(), part.seam_faces.end());
  }
  if (out.pieces.empty()) return usageError("the parts hold no tetrahedra");
  LevelHeader& h = out.header;
  h = out.encoded[0].header;
  h.points = n_seam;
  h.tets = 0;
  h.boundary_triangles = 0;
  for (size_t p = 0; p < out.pieces.size(); ++p) {
    const LevelHeader& e = out.encoded[p].header;
    if (e.coord_type != h.coord_type || e.point_fields.size() != h.point_fields.size() ||
        e.cell_fields.size() != h.cell_fields.size())
      return invalidData("piece " + std::to_string(p) + " has another coordinate type or other fields than piece 0");
    for (int f = 0; f < 2; ++f) {
      const auto& a = f ? e.cell_fields : e.point_fields;
      const auto& b = f ? h.cell_fields : h.point_fields;
      for (size_t i = 0; i < a.size(); ++i)
        if (a[i].name != b[i].name || a[i].type != b[i].type || a[i].components != b[i].components)
          return invalidData("piece " + std::to_string(p) + "'s field '" + a[i].name + "' differs from piece 0's");
    }
    const PieceInfo& info = out.pieces[p];
    h.points += info.own_points;
    h.tets += info.tets;
    h.boundary_triangles += info.boundary_triangles;
    for (int i = 0; i < 3; ++i) {
      h.bbox_min[i] = std::min(h.bbox_min[i], info.bbox_min[i]);
      h.bbox_max[i] = std::max(h.bbox_max[i], info.bbox_max[i]);
    }
  }
  if (h.points >= kNoIndex || out.pieces.size() > kNoIndex / 2)
    return invalidData("the parts hold too many points or pieces for one level");
  std::sort(cut.begin(), cut.end());
  for (size_t i = 0; i + 1 < cut.size(); ++i)
    if (cut[i] == cut[i + 1]) h.boundary_triangles -= 2;
  if (out.pieces.size() == 1) {
    if (!plan.classes.empty()) return invalidData("a level of one piece with seam classes");
    out.header.boundary_triangles = out.pieces[0].boundary_triangles;
    return out;
  }
  out.classes = plan.classes;
  // The seam mesh must carry the level's point fields.
  if (seams.coord_type != h.coord_type || seams.point_fields.size() != h.point_fields.size())
    return usageError("assembleParts: the seam mesh's coordinate type or point fields differ from the level's");
  const ComponentLayout layout(h);
  out.seam_streams.resize(out.classes.size());
  std::vector<uint64_t> class_first(out.classes.size() + 1, 0);
  for (size_t c = 0; c < out.classes.size(); ++c) class_first[c + 1] = class_first[c] + out.classes[c].points;
  tbb::parallel_for(size_t{0}, out.classes.size(), [&](size_t c) {
    std::vector<uint32_t> vertices(out.classes[c].points);
    for (size_t k = 0; k < vertices.size(); ++k) vertices[k] = static_cast<uint32_t>(class_first[c] + k);
    out.seam_streams[c] = encodeSeamStream(seams, out.header, layout, vertices);
  });
  return out;
}

Status emitDecoded(const LevelHeader& header, const DecodedPieces& decoded, MeshSink& sink) {
  const TetMesh& mesh = decoded.mesh;
  const size_t np = mesh.numPoints(), nt = mesh.numTets();
  LevelHeader h = header;
  h.points = np;
  h.tets = nt;
  h.boundary_triangles = decoded.boundary.size();
  GTN_RETURN_IF_ERROR(sink.beginLevel(h));
  size_t value_bytes = 0;
  for (const Field& f : mesh.point_fields) value_bytes += f.components * f.valueSize();
  std::vector<uint8_t> values(value_bytes);
  size_t next = 0;
  auto emitUpTo = [&](size_t end) -> Status {
    for (; next < end; ++next) {
      size_t off = 0;
      for (const Field& f : mesh.point_fields) {
        const size_t ib = f.components * f.valueSize();
        std::memcpy(&values[off], &f.bytes[next * ib], ib);
        off += ib;
      }
      GTN_RETURN_IF_ERROR(
          sink.vertex(static_cast<uint32_t>(next), mesh.point(next), value_bytes ? values.data() : nullptr));
    }
    return Status::ok();
  };
  size_t boundary_end = 0;
  for (const auto& t : decoded.boundary)
    for (uint32_t v : t) boundary_end = std::max<size_t>(boundary_end, size_t{v} + 1);
  GTN_RETURN_IF_ERROR(emitUpTo(boundary_end));
  for (const auto& t : decoded.boundary) GTN_RETURN_IF_ERROR(sink.boundaryTriangle(t.data()));
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  // Each vertex's last tetrahedron, to retire it there.
  std::vector<uint32_t> last(np, kNoIndex);
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t v : mesh.tets[t]) last[v] = static_cast<uint32_t>(t);
  size_t cell_bytes = 0;
  for (const Field& f : mesh.cell_fields) cell_bytes += f.components * f.valueSize();
  std::vector<uint8_t> cells(cell_bytes);
  // Vertices no tetrahedron uses are retired as soon as they are emitted.
  auto retireUnused = [&](size_t from, size_t to) -> Status {
    for (size_t v = from; v < to; ++v)
      if (last[v] == kNoIndex) GTN_RETURN_IF_ERROR(sink.retireVertex(static_cast<uint32_t>(v)));
    return Status::ok();
  };
  GTN_RETURN_IF_ERROR(retireUnused(0, boundary_end));
  for (size_t t = 0; t < nt; ++t) {
    const Tet& v = mesh.tets[t];
    const size_t need = size_t{std::max(std::max(v[0], v[1]), std::max(v[2], v[3]))} + 1;
    if (need > next) {
      const size_t from = next;
      GTN_RETURN_IF_ERROR(emitUpTo(need));
      GTN_RETURN_IF_ERROR(retireUnused(from, need));
    }
    size_t off = 0;
    for (const Field& f : mesh.cell_fields) {
      const size_t ib = f.components * f.valueSize();
      std::memcpy(&cells[off], &f.bytes[t * ib], ib);
      off += ib;
    }
    GTN_RETURN_IF_ERROR(sink.tet(v.data(), cell_bytes ? cells.data() : nullptr));
    for (int j = 0; j < 4; ++j) {
      bool repeated = false;
      for (int i = 0; i < j; ++i) repeated = repeated || v[i] == v[j];
      if (!repeated && last[v[j]] == t) GTN_RETURN_IF_ERROR(sink.retireVertex(v[j]));
    }
  }
  const size_t from = next;
  GTN_RETURN_IF_ERROR(emitUpTo(np));
  GTN_RETURN_IF_ERROR(retireUnused(from, np));
  return sink.endLevel();
}

}  // namespace gtn
