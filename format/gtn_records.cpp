#include "format/gtn_records.h"

#include <algorithm>
#include <bit>
#include <cstdint>

#include "format/gtn_bytes.h"

namespace gtn {

namespace {

Status readScalarType(ByteReader& r, ScalarType* t, const char* name) {
  const uint64_t at = r.offset();
  uint8_t v;
  GTN_RETURN_IF_ERROR(r.u8(&v, name));
  if (v >= kNumScalarTypes) return r.errorAt(at, std::string(name) + " " + std::to_string(v) + " is not a scalar type");
  *t = static_cast<ScalarType>(v);
  return Status::ok();
}

Status readBox(ByteReader& r, double mn[3], double mx[3]) {
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&mn[i], "bounding box minimum"));
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&mx[i], "bounding box maximum"));
  return Status::ok();
}
}  // namespace

void writeFields(ByteWriter& w, const std::vector<FieldDesc>& fields) {
  w.varint(fields.size());
  for (const FieldDesc& f : fields) {
    w.string(f.name);
    w.varint(f.components);
    w.u8(static_cast<uint8_t>(f.type));
  }
}

Status readFields(ByteReader& r, std::vector<FieldDesc>* fields, const char* what) {
  uint64_t n;
  // Each description takes at least 3 bytes: bound the count by the payload before reserving.
  GTN_RETURN_IF_ERROR(r.varintAtMost(&n, std::min<uint64_t>(kGtnMaxFields, r.remaining() / 3), what));
  fields->resize(n);
  for (FieldDesc& f : *fields) {
    GTN_RETURN_IF_ERROR(r.string(&f.name, "field name"));
    uint64_t c;
    const uint64_t at = r.offset();
    GTN_RETURN_IF_ERROR(r.varintAtMost(&c, kGtnMaxComponents, "field components"));
    if (c == 0) return r.errorAt(at, "field '" + f.name + "' has 0 components");
    f.components = static_cast<uint32_t>(c);
    GTN_RETURN_IF_ERROR(readScalarType(r, &f.type, "field type"));
  }
  return Status::ok();
}

std::vector<uint8_t> encodeFileHeader(const GtnFileHeader& h) {
  ByteWriter w;
  w.u8(h.writer_flags);
  w.varint(h.level_count);
  w.varint(h.points);
  w.varint(h.tets);
  w.varint(h.draft);
  w.varint(h.piece_tets);
  w.u8(static_cast<uint8_t>(h.coord_type));
  writeFields(w, h.point_fields);
  writeFields(w, h.cell_fields);
  for (double v : h.bbox_min) w.f64(v);
  for (double v : h.bbox_max) w.f64(v);
  w.string(h.tool_version);
  w.string(h.command_line);
  w.varint(h.metadata.size());
  for (const auto& [k, v] : h.metadata) {
    w.string(k);
    w.string(v);
  }
  return std::move(w.bytes());
}

Status decodeFileHeader(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnFileHeader* h) {
  ByteReader r(payload, offset, what + ": GHDR");
  GTN_RETURN_IF_ERROR(r.u8(&h->writer_flags, "writer flags"));  // unused bits: ignored
  uint64_t at = r.offset();
  GTN_RETURN_IF_ERROR(r.varintAtMost(&h->level_count, kGtnMaxLevels, "level count"));
  if (h->level_count == 0) return r.errorAt(at, "level count is 0; a file holds at least level 0");
  GTN_RETURN_IF_ERROR(r.varint(&h->points, "point count"));
  GTN_RETURN_IF_ERROR(r.varint(&h->tets, "tetrahedron count"));
  at = r.offset();
  GTN_RETURN_IF_ERROR(r.varint(&h->draft, "draft revision"));
  if (h->draft != kGtnDraftRevision)
    return Status(StatusCode::kUnsupported,
                  what + ": GHDR: byte offset " + std::to_string(at) + ": the file follows draft revision " +
                      std::to_string(h->draft) + " of format 2.0; this gtn reads draft revision " +
                      std::to_string(kGtnDraftRevision) + " only: convert the source mesh again");
  GTN_RETURN_IF_ERROR(r.varint(&h->piece_tets, "piece tetrahedron bound"));
  at = r.offset();
  GTN_RETURN_IF_ERROR(readScalarType(r, &h->coord_type, "coordinate type"));
  if (!isFloatType(h->coord_type)) return r.errorAt(at, "coordinate type must be float32 (8) or float64 (9)");
  GTN_RETURN_IF_ERROR(readFields(r, &h->point_fields, "point field count"));
  GTN_RETURN_IF_ERROR(readFields(r, &h->cell_fields, "cell field count"));
  GTN_RETURN_IF_ERROR(readBox(r, h->bbox_min, h->bbox_max));
  GTN_RETURN_IF_ERROR(r.string(&h->tool_version, "tool version"));
  GTN_RETURN_IF_ERROR(r.string(&h->command_line, "command line"));
  uint64_t n;
  GTN_RETURN_IF_ERROR(r.varintAtMost(&n, r.remaining() / 2, "metadata count"));
  h->metadata.resize(n);
  for (auto& [k, v] : h->metadata) {
    GTN_RETURN_IF_ERROR(r.string(&k, "metadata key"));
    GTN_RETURN_IF_ERROR(r.string(&v, "metadata value"));
  }
  return r.expectEnd("the GHDR payload");
}

LevelRecordContext levelRecordContext(const GtnFileHeader& h) {
  LevelRecordContext c;
  for (int i = 0; i < 3; ++i) {
    c.prev_min[i] = h.bbox_min[i];
    c.prev_max[i] = h.bbox_max[i];
  }
  c.streams = 3 + h.point_fields.size() + h.cell_fields.size();
  return c;
}

LevelRecordContext nextLevelRecordContext(const LevelRecordContext& c, const GtnLevelRecord& r) {
  LevelRecordContext n = c;
  for (int i = 0; i < 3; ++i) {
    n.prev_min[i] = r.bbox_min[i];
    n.prev_max[i] = r.bbox_max[i];
  }
  return n;
}

namespace {
// The six bounds of a box in LHDR order: min x, y, z, max x, y, z.
double& bound(double mn[3], double mx[3], int k) { return k < 3 ? mn[k] : mx[k - 3]; }
double bound(const double mn[3], const double mx[3], int k) { return k < 3 ? mn[k] : mx[k - 3]; }
bool sameBits(double a, double b) { return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b); }
}  // namespace

std::vector<uint8_t> encodeLevelRecord(const GtnLevelRecord& l, const LevelRecordContext& c) {
  ByteWriter w;
  w.varint(l.level);
  w.varint(l.merges);
  w.f64(l.ratio);
  w.varint(l.points);
  w.varint(l.tets);
  w.varint(l.boundary_triangles);
  // The box: a bit per bound equal to the previous box's, then the others.
  uint8_t same = 0;
  for (int k = 0; k < 6; ++k)
    if (sameBits(bound(l.bbox_min, l.bbox_max, k), bound(c.prev_min, c.prev_max, k))) same |= uint8_t(1u << k);
  w.u8(same);
  for (int k = 0; k < 6; ++k)
    if (!(same & (1u << k))) w.f64(bound(l.bbox_min, l.bbox_max, k));
  w.varint(l.pieces.size());
  for (size_t i = 0; i < l.pieces.size(); ++i) {
    const PieceInfo& p = l.pieces[i];
    w.u8(p.kind);
    if (l.pieces.size() == 1) {  // the level's counts and box are the piece's
      w.varint(p.own_boundary_points);
    } else {
      w.varint(p.points);
      w.varint(p.own_points);
      w.varint(p.own_boundary_points);
      w.varint(p.tets);
      w.varint(p.boundary_triangles);
      for (double v : p.bbox_min) w.f64(v);
      for (double v : p.bbox_max) w.f64(v);
    }
    if (p.kind == kPieceUnstructured)
      for (uint64_t size : l.streams.at(i)) w.varint(size);
  }
  w.u8(l.base);
  return std::move(w.bytes());
}

Status decodeLevelRecord(std::span<const uint8_t> payload, uint64_t offset, const std::string& what,
                         const LevelRecordContext& c, GtnLevelRecord* l) {
  ByteReader r(payload, offset, what + ": LHDR");
  GTN_RETURN_IF_ERROR(r.varint(&l->level, "level index"));
  GTN_RETURN_IF_ERROR(r.varint(&l->merges, "merge count"));
  const uint64_t at = r.offset();
  GTN_RETURN_IF_ERROR(r.f64(&l->ratio, "ratio"));
  if (!(l->ratio >= 0.0 && l->ratio <= 1.0)) return r.errorAt(at, "ratio is not in [0, 1]");
  GTN_RETURN_IF_ERROR(r.varint(&l->points, "point count"));
  GTN_RETURN_IF_ERROR(r.varint(&l->tets, "tetrahedron count"));
  GTN_RETURN_IF_ERROR(r.varint(&l->boundary_triangles, "boundary triangle count"));
  const uint64_t at_same = r.offset();
  uint8_t same;
  GTN_RETURN_IF_ERROR(r.u8(&same, "bounding box bits"));
  if (same & 0xC0) return r.errorAt(at_same, "bounding box bits 6 and 7 are set; they must be 0");
  for (int k = 0; k < 6; ++k) {
    if (same & (1u << k)) bound(l->bbox_min, l->bbox_max, k) = bound(c.prev_min, c.prev_max, k);
    else GTN_RETURN_IF_ERROR(r.f64(&bound(l->bbox_min, l->bbox_max, k), "bounding box bound"));
  }
  uint64_t n;
  uint64_t at_n = r.offset();
  // An entry of one of several pieces takes at least 54 bytes: bound the count by the payload first.
  GTN_RETURN_IF_ERROR(
      r.varintAtMost(&n, std::max<uint64_t>(1, std::min<uint64_t>(kGtnMaxPieces, r.remaining() / 54)), "piece count"));
  if (n == 0) return r.errorAt(at_n, "piece count is 0; a level has at least one piece");
  l->pieces.resize(n);
  l->streams.assign(n, {});
  uint64_t tets = 0;
  for (size_t i = 0; i < n; ++i) {
    PieceInfo& p = l->pieces[i];
    const std::string piece = "piece " + std::to_string(i);
    uint64_t at_p = r.offset();
    GTN_RETURN_IF_ERROR(r.u8(&p.kind, "piece kind"));
    if (p.kind != kPieceUnstructured && p.kind != kPieceStructured)
      return r.errorAt(at_p, piece + " has kind " + std::to_string(p.kind) +
                                 ", which this reader does not know (0: unstructured, 1: structured)");
    if (p.kind == kPieceStructured && n != 1)
      return r.errorAt(at_p, piece + " is structured in a level of " + std::to_string(n) +
                                 " pieces; a structured piece is a level's only piece");
    at_p = r.offset();
    if (n == 1) {  // one piece: the level's counts and box, and its own boundary points
      if (l->points > kGtnMaxPiecePoints)
        return r.errorAt(at_p, "the level's one piece has " + std::to_string(l->points) + " points, more than " +
                                   std::to_string(kGtnMaxPiecePoints));
      p.points = p.own_points = l->points;
      p.tets = l->tets;
      p.boundary_triangles = l->boundary_triangles;
      for (int k = 0; k < 3; ++k) {
        p.bbox_min[k] = l->bbox_min[k];
        p.bbox_max[k] = l->bbox_max[k];
      }
      GTN_RETURN_IF_ERROR(r.varintAtMost(&p.own_boundary_points, p.own_points, "piece own boundary point count"));
      tets = p.tets;
    } else {
      GTN_RETURN_IF_ERROR(r.varintAtMost(&p.points, kGtnMaxPiecePoints, "piece point count"));
      GTN_RETURN_IF_ERROR(r.varintAtMost(&p.own_points, p.points, "piece own point count"));
      GTN_RETURN_IF_ERROR(r.varintAtMost(&p.own_boundary_points, p.own_points, "piece own boundary point count"));
      GTN_RETURN_IF_ERROR(r.varintAtMost(&p.tets, l->tets - tets, "piece tetrahedron count (beyond the level's)"));
      tets += p.tets;
      GTN_RETURN_IF_ERROR(r.varint(&p.boundary_triangles, "piece boundary triangle count"));
      GTN_RETURN_IF_ERROR(readBox(r, p.bbox_min, p.bbox_max));
    }
    if (p.kind != kPieceUnstructured) continue;
    // Its streams' sizes, one varint (at least a byte) each: checked against the payload before
    // anything is reserved; their sum must fit in a chunk.
    const uint64_t at_s = r.offset();
    if (r.remaining() < c.streams)
      return r.errorAt(at_s,
                       piece + ": its " + std::to_string(c.streams) + " stream sizes need more bytes than remain");
    std::vector<uint64_t>& sizes = l->streams[i];
    sizes.resize(c.streams);
    uint64_t sum = 0;
    for (uint64_t& size : sizes) {
      GTN_RETURN_IF_ERROR(r.varint(&size, "stream size"));
      if (size > (uint64_t{1} << 62) - sum) return r.errorAt(at_s, piece + ": its stream sizes sum beyond 2^62 bytes");
      sum += size;
    }
  }
  if (tets != l->tets)
    return r.errorAt(
        at_n, "the pieces' tetrahedra sum to " + std::to_string(tets) + ", the level has " + std::to_string(l->tets));
  const uint64_t at_base = r.offset();
  GTN_RETURN_IF_ERROR(r.u8(&l->base, "base"));
  if (l->base > 1) return r.errorAt(at_base, "base is " + std::to_string(l->base) + " (0: none, 1: the next level)");
  if (l->base == 1 && (n != 1 || l->pieces[0].kind != kPieceUnstructured))
    return r.errorAt(at_base, "a level that names the next level's vertices (base 1) must be one unstructured piece");
  return r.expectEnd("the LHDR payload");
}

std::vector<uint8_t> encodeSeamTable(const std::vector<SeamClass>& classes,
                                     const std::vector<std::vector<uint8_t>>& streams) {
  ByteWriter w;
  w.varint(classes.size());
  for (size_t c = 0; c < classes.size(); ++c) {
    const SeamClass& k = classes[c];
    w.varint(k.pieces.size());
    for (size_t i = 0; i < k.pieces.size(); ++i)
      w.varint(i == 0 ? uint64_t{k.pieces[0]} : uint64_t{k.pieces[i]} - k.pieces[i - 1] - 1);
    w.varint(k.points);
    w.varint(c < streams.size() ? streams[c].size() : 0);
  }
  for (const auto& s : streams) w.raw(s);
  return std::move(w.bytes());
}

Status decodeSeamTable(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, uint64_t level,
                       uint64_t points, std::span<const PieceInfo> pieces, GtnSeamTable* t) {
  ByteReader r(payload, offset, what + ": SEAM of level " + std::to_string(level));
  const uint64_t np = pieces.size();
  uint64_t n;
  // A class takes at least 5 bytes.
  GTN_RETURN_IF_ERROR(r.varintAtMost(&n, r.remaining() / 5, "seam class count"));
  t->classes.assign(n, {});
  t->streams.assign(n, {});
  std::vector<uint64_t> seam_of(np, 0);  // seam points each piece uses
  uint64_t seam_points = 0, stream_bytes = 0;
  for (size_t c = 0; c < n; ++c) {
    SeamClass& k = t->classes[c];
    const std::string cls = "seam class " + std::to_string(c);
    uint64_t at = r.offset();
    uint64_t m;
    GTN_RETURN_IF_ERROR(r.varintAtMost(&m, std::min<uint64_t>(np, r.remaining()), "seam class piece count"));
    if (m < 2) return r.errorAt(at, cls + " names " + std::to_string(m) + " piece(s); a class names at least 2");
    k.pieces.resize(m);
    uint64_t next = 0;  // the smallest index the next piece may have
    for (size_t i = 0; i < m; ++i) {
      at = r.offset();
      uint64_t d;
      GTN_RETURN_IF_ERROR(r.varint(&d, "seam class piece"));
      if (i > 0 && d > UINT64_MAX - next) {  // next + d wraps: a piece at or before the one named before
        const uint64_t named = next + d;
        return r.errorAt(at,
                         cls + " names piece " + std::to_string(named) +
                             (named == k.pieces[i - 1] ? " twice" : " after piece " + std::to_string(k.pieces[i - 1])) +
                             ": a class names each piece once, in increasing order");
      }
      if (d >= np || next > np - 1 - d)
        return r.errorAt(at, cls + " names a piece beyond the level's " + std::to_string(np) + " pieces");
      k.pieces[i] = static_cast<uint32_t>(next + d);
      next = k.pieces[i] + uint64_t{1};
    }
    at = r.offset();
    GTN_RETURN_IF_ERROR(r.varintAtMost(&k.points, points - seam_points, "seam class point count (beyond the level's)"));
    if (k.points == 0) return r.errorAt(at, cls + " has no point");
    seam_points += k.points;
    if (c > 0 && !(t->classes[c - 1].pieces < k.pieces))
      return r.errorAt(at, cls +
                               " is not after the class before it (classes are in increasing order of their "
                               "piece lists, each list once)");
    for (uint32_t p : k.pieces) seam_of[p] += k.points;
    GTN_RETURN_IF_ERROR(r.varintAtMost(&t->streams[c].second, r.remaining() - stream_bytes, "seam class stream size"));
    stream_bytes += t->streams[c].second;
  }
  const uint64_t table_end = r.offset() - offset;
  if (stream_bytes != r.remaining())
    return r.error("the seam class streams take " + std::to_string(stream_bytes) + " bytes, the chunk holds " +
                   std::to_string(r.remaining()) + " after the table");
  uint64_t pos = table_end;
  for (auto& s : t->streams) {
    s.first = pos;
    pos += s.second;
  }
  uint64_t own = 0;
  for (size_t p = 0; p < np; ++p) {
    const PieceInfo& piece = pieces[p];
    own += piece.own_points;
    if (piece.points - piece.own_points != seam_of[p])
      return r.errorAt(offset,
                       "piece " + std::to_string(p) + " uses " + std::to_string(piece.points - piece.own_points) +
                           " seam points by the level header, " + std::to_string(seam_of[p]) + " by the seam table");
  }
  if (own + seam_points != points)
    return r.errorAt(offset, "the pieces' own points (" + std::to_string(own) + ") and the seam points (" +
                                 std::to_string(seam_points) + ") do not sum to the level's " + std::to_string(points));
  return Status::ok();
}

std::vector<uint8_t> encodeDirectory(const GtnDirectory& d) {
  ByteWriter w;
  w.varint(d.size());
  for (const auto& level : d) {
    w.varint(level.size());
    for (const GtnDirectoryEntry& e : level) {
      w.raw(e.tag.c.data(), 4);
      w.varint(e.offset);
      w.varint(e.size);
    }
  }
  return std::move(w.bytes());
}

Status decodeDirectory(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, uint64_t level_count,
                       GtnDirectory* d) {
  ByteReader r(payload, offset, what + ": DIRC");
  uint64_t n;
  const uint64_t at = r.offset();
  GTN_RETURN_IF_ERROR(r.varint(&n, "directory level count"));
  if (n != level_count)
    return r.errorAt(
        at, "directory lists " + std::to_string(n) + " levels, the header declares " + std::to_string(level_count));
  d->assign(n, {});
  for (auto& level : *d) {
    uint64_t m;
    // An entry takes at least 6 bytes.
    GTN_RETURN_IF_ERROR(r.varintAtMost(&m, r.remaining() / 6, "directory chunk count"));
    level.resize(m);
    for (GtnDirectoryEntry& e : level) {
      std::span<const uint8_t> tag;
      GTN_RETURN_IF_ERROR(r.bytes(&tag, 4, "directory chunk type"));
      std::copy(tag.begin(), tag.end(), e.tag.c.begin());
      GTN_RETURN_IF_ERROR(r.varint(&e.offset, "directory chunk offset"));
      GTN_RETURN_IF_ERROR(r.varint(&e.size, "directory chunk size"));
    }
  }
  return r.expectEnd("the DIRC payload");
}

std::vector<uint8_t> encodeTrailer(const GtnTrailer& t) {
  ByteWriter w;
  w.u64(t.directory_offset);
  w.u64(t.directory_size);
  return std::move(w.bytes());
}

Status decodeTrailer(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnTrailer* t) {
  ByteReader r(payload, offset, what + ": GEND");
  if (payload.size() != kGtnEndPayloadSize)
    return r.error("the end chunk's payload is " + std::to_string(payload.size()) + " bytes, not 16");
  GTN_RETURN_IF_ERROR(r.u64(&t->directory_offset, "directory offset"));
  GTN_RETURN_IF_ERROR(r.u64(&t->directory_size, "directory size"));
  if ((t->directory_offset == 0) != (t->directory_size == 0))
    return r.errorAt(offset, "directory offset and size must both be 0 or both be non-zero");
  return Status::ok();
}

}  // namespace gtn
