#include "codec/pieces_check.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstring>

#include "codec/level_check.h"
#include "mesh/index.h"

namespace gtn {

namespace {
bool sameLayout(const std::vector<Field>& a, const std::vector<Field>& b) {
  if (a.size() != b.size()) return false;
  for (size_t f = 0; f < a.size(); ++f)
    if (a[f].name != b[f].name || a[f].type != b[f].type || a[f].components != b[f].components) return false;
  return true;
}
// Whether item `i` of `a`'s fields equals item `j` of `b`'s, byte for byte.
bool sameItem(const std::vector<Field>& a, size_t i, const std::vector<Field>& b, size_t j) {
  for (size_t f = 0; f < a.size(); ++f) {
    const size_t n = a[f].components * a[f].valueSize();
    if (std::memcmp(&a[f].bytes[i * n], &b[f].bytes[j * n], n) != 0) return false;
  }
  return true;
}
// The first i < n for which `difference(i)` names one (a reason, else nullptr), or n; the items are
// looked at in parallel.
template <class Difference>
size_t firstWith(size_t n, const Difference& difference) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, size_t{1} << 14), n,
      [&](const tbb::blocked_range<size_t>& r, size_t first) {
        if (first < r.begin()) return first;  // a smaller one is known already
        for (size_t i = r.begin(); i < r.end(); ++i)
          if (difference(i)) return i;
        return first;
      },
      [](size_t a, size_t b) { return std::min(a, b); });
}
}  // namespace

PiecedLevelView piecedViewOf(const PiecedLevel& level) {
  PiecedLevelView v;
  v.header = &level.header;
  v.pieces = level.pieces;
  v.classes = level.classes;
  for (const auto& s : level.seam_streams) v.seam_streams.emplace_back(s);
  v.payloads.resize(level.encoded.size());
  for (size_t p = 0; p < level.encoded.size(); ++p) {
    v.payloads[p].header = level.encoded[p].header;
    v.payloads[p].streams = payloadOf(level.encoded[p]);
  }
  return v;
}

std::string piecedLosslessMismatch(const TetMesh& source, const PiecedLevel& level, const RuleGridTets* tets) {
  if (tets && !(level.isGrid() && level.tet_order.empty()))
    return "a grid's tetrahedra given for a level that is not one structured piece";
  if (level.encoded.size() != level.pieces.size() || level.pieces.empty())
    return "the level has " + std::to_string(level.pieces.size()) + " pieces and " +
           std::to_string(level.encoded.size()) + " encodings";
  if (level.pieces.size() == 1 && level.pieces[0].kind == 0) return losslessMismatch(source, level.encoded[0]);
  const size_t np = source.numPoints(), nt = tets ? tets->size() : source.numTets();
  if (level.vertex_order.size() != np || (level.tet_order.size() != nt && !(level.isGrid() && level.tet_order.empty())))
    return "the encoder's renumbering does not cover the source";
  const PiecedLevelView view = piecedViewOf(level);
  if (level.isGrid() && level.tet_order.empty()) {
    // Compared with the source as it decodes: no decoded copy is held (its tetrahedra alone take 16
    // bytes each, and a large grid's check beside its merge tree's encoding was a convert's peak).
    return structuredLosslessMismatch(source, pieceHeader(level.header, level.pieces[0]),
                                      view.payloads[0].streams.connectivity, level.vertex_order, tets);
  }
  auto decoded = decodePieces(view, {}, "the encoded level");
  if (!decoded.isOk()) return "it does not decode: " + decoded.status().message();
  const TetMesh& got = decoded->mesh;
  if (got.numPoints() != np || got.numTets() != nt)
    return std::to_string(got.numPoints()) + " points and " + std::to_string(got.numTets()) +
           " tetrahedra decoded, the source has " + std::to_string(np) + " and " + std::to_string(nt);
  if (got.coord_type != source.coord_type) return "the coordinate type changed";
  if (!sameLayout(got.point_fields, source.point_fields) || !sameLayout(got.cell_fields, source.cell_fields))
    return "field names, types or components changed";
  // The renumberings first (cheap, one pass each), then the comparisons, in parallel: a grid's level
  // has millions of points and tetrahedra. The first difference by source item is reported.
  std::vector<char> seen(np, 0);
  for (size_t v = 0; v < np; ++v) {
    const uint32_t d = level.vertex_order[v];
    if (d >= np || seen[d]) return "the encoder's vertex order is not a permutation";
    seen[d] = 1;
  }
  if (!level.tet_order.empty()) {
    std::vector<char> placed(nt, 0);
    for (size_t t = 0; t < nt; ++t) {
      const uint64_t d = level.tet_order[t];
      if (d >= nt || placed[d]) return "the encoder's tetrahedron order is not a permutation";
      placed[d] = 1;
    }
  }
  auto pointDifference = [&](size_t v) -> const char* {
    const uint32_t d = level.vertex_order[v];
    if (std::memcmp(got.point(d), source.point(v), 3 * sizeof(double)) != 0) return " moved";
    if (!sameItem(source.point_fields, v, got.point_fields, d)) return " has other field values";
    return nullptr;
  };
  if (const size_t v = firstWith(np, pointDifference); v < np)
    return "source point " + std::to_string(v) + " (decoded " + std::to_string(level.vertex_order[v]) + ")" +
           pointDifference(v);
  auto tetDifference = [&](size_t t) -> const char* {
    const uint64_t d = level.tetPosition(t);
    int perm[4], inversions = 0;
    for (int i = 0; i < 4; ++i) {
      perm[i] = -1;
      const uint32_t want = level.vertex_order[source.tets[t][i]];
      for (int j = 0; j < 4; ++j)
        if (got.tets[d][j] == want) perm[i] = j;
      if (perm[i] < 0) return " has other vertices";
      for (int j = 0; j < i; ++j) inversions += perm[j] > perm[i];
    }
    if (inversions % 2) return " is reversed";
    if (!sameItem(source.cell_fields, t, got.cell_fields, d)) return " has other field values";
    return nullptr;
  };
  if (const size_t t = firstWith(nt, tetDifference); t < nt)
    return "source tetrahedron " + std::to_string(t) + " (decoded " + std::to_string(level.tetPosition(t)) + ")" +
           tetDifference(t);
  return "";
}

std::string partLosslessMismatch(const TetMesh& part, const EncodedPart& encoded, uint32_t first_piece,
                                 const PiecedLevelView& view) {
  const size_t n_mine = encoded.pieces.size();
  if (n_mine == 0) return "";
  const size_t n_pieces = view.pieces.size();
  if (first_piece + n_mine > n_pieces || encoded.encoded.size() != n_mine || encoded.piece_vertices.size() != n_mine ||
      encoded.piece_tets.size() != n_mine || encoded.seam_id.size() != part.numPoints())
    return "the part's pieces do not match the level's piece table";
  std::vector<uint32_t> chosen(n_mine);
  for (size_t p = 0; p < n_mine; ++p) chosen[p] = static_cast<uint32_t>(first_piece + p);
  auto decoded = decodePieces(view, chosen, "the encoded part");
  if (!decoded.isOk()) return "it does not decode: " + decoded.status().message();
  const TetMesh& got = decoded->mesh;
  if (got.coord_type != part.coord_type) return "the coordinate type changed";
  if (!sameLayout(got.point_fields, part.point_fields) || !sameLayout(got.cell_fields, part.cell_fields))
    return "field names, types or components changed";
  // The level's global ids (codec/pieces.h) of the part's vertices and tetrahedra.
  uint64_t n_seam = 0, own_bnd_all = 0;
  for (const SeamClass& c : view.classes) n_seam += c.points;
  for (const PieceInfo& info : view.pieces) own_bnd_all += info.own_boundary_points;
  uint64_t bnd = n_seam, in = n_seam + own_bnd_all, tet_base = 0;
  for (uint32_t g = 0; g < first_piece; ++g) {
    bnd += view.pieces[g].own_boundary_points;
    in += view.pieces[g].own_points - view.pieces[g].own_boundary_points;
    tet_base += view.pieces[g].tets;
  }
  // Decoded mesh index of each global vertex id, and of each global tetrahedron position from the
  // part's first (its pieces' tetrahedra are one run).
  const uint64_t first_tet = tet_base, n_level_points = view.header->points;
  std::vector<uint32_t> vertex_at(n_level_points, kNoIndex), tet_at(got.numTets(), kNoIndex);
  for (size_t d = 0; d < got.numPoints(); ++d) {
    const uint64_t g = decoded->global_vertex.empty() ? d : decoded->global_vertex[d];
    if (g >= n_level_points) return "a decoded vertex id beyond the level's points";
    vertex_at[g] = static_cast<uint32_t>(d);
  }
  for (size_t d = 0; d < got.numTets(); ++d) {
    const uint64_t g = decoded->global_tet.empty() ? d : decoded->global_tet[d];
    if (g < first_tet || g - first_tet >= tet_at.size()) return "a decoded tetrahedron beyond the part's";
    tet_at[g - first_tet] = static_cast<uint32_t>(d);
  }
  std::vector<uint64_t> global(part.numPoints(), UINT64_MAX);
  for (size_t p = 0; p < n_mine; ++p) {
    const EncodedLevel& e = encoded.encoded[p];
    const std::vector<uint32_t>& verts = encoded.piece_vertices[p];
    if (e.vertex_order.size() != verts.size()) return "piece " + std::to_string(first_piece + p) + ": vertex order";
    std::vector<uint32_t> by_id(verts.size());
    for (size_t k = 0; k < verts.size(); ++k) {
      if (e.vertex_order[k] >= verts.size()) return "piece " + std::to_string(first_piece + p) + ": vertex order";
      by_id[e.vertex_order[k]] = static_cast<uint32_t>(k);
    }
    for (size_t id = 0; id < by_id.size(); ++id) {
      const uint32_t v = verts[by_id[id]];
      if (encoded.seam_id[v] != kNoIndex) {
        global[v] = encoded.seam_id[v];
      } else {
        global[v] = id < e.boundary_points ? bnd++ : in++;
      }
    }
    const std::vector<uint32_t>& tl = encoded.piece_tets[p];
    if (e.tet_order.size() != tl.size()) return "piece " + std::to_string(first_piece + p) + ": tetrahedron order";
    for (size_t k = 0; k < tl.size(); ++k) {
      const uint32_t t = tl[k];
      auto which = [t] { return "part tetrahedron " + std::to_string(t); };  // made only for a difference
      const uint64_t pos = tet_base + e.tet_order[k] - first_tet;
      if (pos >= tet_at.size() || tet_at[pos] == kNoIndex) return which() + " was not decoded";
      const uint32_t d_tet = tet_at[pos];
      int perm[4], inversions = 0;
      for (int i = 0; i < 4; ++i) {
        perm[i] = -1;
        for (int j = 0; j < 4; ++j) {
          const uint32_t d = got.tets[d_tet][j];
          const uint64_t gid = decoded->global_vertex.empty() ? d : decoded->global_vertex[d];
          if (gid == global[part.tets[t][i]]) perm[i] = j;
        }
        if (perm[i] < 0) return which() + " has other vertices";
        for (int j = 0; j < i; ++j) inversions += perm[j] > perm[i];
      }
      if (inversions % 2) return which() + " is reversed";
      if (!sameItem(part.cell_fields, t, got.cell_fields, d_tet)) return which() + " has other field values";
    }
    tet_base += view.pieces[first_piece + p].tets;
  }
  for (size_t v = 0; v < part.numPoints(); ++v) {
    if (global[v] == UINT64_MAX) continue;  // another part's
    auto which = [v] { return "part point " + std::to_string(v); };
    const uint32_t d = global[v] < vertex_at.size() ? vertex_at[global[v]] : kNoIndex;
    if (d == kNoIndex) return which() + " was not decoded";
    if (std::memcmp(got.point(d), part.point(v), 3 * sizeof(double)) != 0) return which() + " moved";
    if (!sameItem(part.point_fields, v, got.point_fields, d)) return which() + " has other field values";
  }
  return "";
}

}  // namespace gtn
