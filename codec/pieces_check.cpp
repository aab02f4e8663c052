#include "codec/pieces_check.h"

#include <cstring>

#include "codec/level_check.h"

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

std::string piecedLosslessMismatch(const TetMesh& source, const PiecedLevel& level) {
  if (level.encoded.size() != level.pieces.size() || level.pieces.empty())
    return "the level has " + std::to_string(level.pieces.size()) + " pieces and " +
           std::to_string(level.encoded.size()) + " encodings";
  if (level.pieces.size() == 1 && level.pieces[0].kind == 0) return losslessMismatch(source, level.encoded[0]);
  const size_t np = source.numPoints(), nt = source.numTets();
  if (level.vertex_order.size() != np || level.tet_order.size() != nt)
    return "the encoder's renumbering does not cover the source";
  const PiecedLevelView view = piecedViewOf(level);
  auto decoded = decodePieces(view, {}, "the encoded level");
  if (!decoded.isOk()) return "it does not decode: " + decoded.status().message();
  const TetMesh& got = decoded->mesh;
  if (got.numPoints() != np || got.numTets() != nt)
    return std::to_string(got.numPoints()) + " points and " + std::to_string(got.numTets()) +
           " tetrahedra decoded, the source has " + std::to_string(np) + " and " + std::to_string(nt);
  if (got.coord_type != source.coord_type) return "the coordinate type changed";
  if (!sameLayout(got.point_fields, source.point_fields) || !sameLayout(got.cell_fields, source.cell_fields))
    return "field names, types or components changed";
  std::vector<char> seen(np, 0);
  for (size_t v = 0; v < np; ++v) {
    const uint32_t d = level.vertex_order[v];
    if (d >= np || seen[d]) return "the encoder's vertex order is not a permutation";
    seen[d] = 1;
    const std::string which = "source point " + std::to_string(v) + " (decoded " + std::to_string(d) + ")";
    if (std::memcmp(got.point(d), source.point(v), 3 * sizeof(double)) != 0) return which + " moved";
    if (!sameItem(source.point_fields, v, got.point_fields, d)) return which + " has other field values";
  }
  std::vector<char> placed(nt, 0);
  for (size_t t = 0; t < nt; ++t) {
    const uint64_t d = level.tet_order[t];
    if (d >= nt || placed[d]) return "the encoder's tetrahedron order is not a permutation";
    placed[d] = 1;
    const std::string which = "source tetrahedron " + std::to_string(t) + " (decoded " + std::to_string(d) + ")";
    int perm[4], inversions = 0;
    for (int i = 0; i < 4; ++i) {
      perm[i] = -1;
      const uint32_t want = level.vertex_order[source.tets[t][i]];
      for (int j = 0; j < 4; ++j)
        if (got.tets[d][j] == want) perm[i] = j;
      if (perm[i] < 0) return which + " has other vertices";
      for (int j = 0; j < i; ++j) inversions += perm[j] > perm[i];
    }
    if (inversions % 2) return which + " is reversed";
    if (!sameItem(source.cell_fields, t, got.cell_fields, d)) return which + " has other field values";
  }
  return "";
}

}  // namespace gtn
