#include "format/gtn_records.h"

#include <algorithm>

#include "format/gtn_bytes.h"

namespace gtn {

namespace {
void writeFields(ByteWriter& w, const std::vector<FieldDesc>& fields) {
  w.varint(fields.size());
  for (const FieldDesc& f : fields) {
    w.string(f.name);
    w.varint(f.components);
    w.u8(static_cast<uint8_t>(f.type));
  }
}

Status readScalarType(ByteReader& r, ScalarType* t, const char* name) {
  const uint64_t at = r.offset();
  uint8_t v;
  GTN_RETURN_IF_ERROR(r.u8(&v, name));
  if (v >= kNumScalarTypes) return r.errorAt(at, std::string(name) + " " + std::to_string(v) + " is not a scalar type");
  *t = static_cast<ScalarType>(v);
  return Status::ok();
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

Status readBox(ByteReader& r, double mn[3], double mx[3]) {
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&mn[i], "bounding box minimum"));
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&mx[i], "bounding box maximum"));
  return Status::ok();
}
}  // namespace

std::vector<uint8_t> encodeFileHeader(const GtnFileHeader& h) {
  ByteWriter w;
  w.u8(h.writer_flags);
  w.varint(h.level_count);
  w.varint(h.points);
  w.varint(h.tets);
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

std::vector<uint8_t> encodeLevelRecord(const GtnLevelRecord& l) {
  ByteWriter w;
  w.varint(l.level);
  w.varint(l.merges);
  w.f64(l.ratio);
  w.varint(l.points);
  w.varint(l.tets);
  w.varint(l.boundary_triangles);
  for (double v : l.bbox_min) w.f64(v);
  for (double v : l.bbox_max) w.f64(v);
  return std::move(w.bytes());
}

Status decodeLevelRecord(std::span<const uint8_t> payload, uint64_t offset, const std::string& what,
                         GtnLevelRecord* l) {
  ByteReader r(payload, offset, what + ": LHDR");
  GTN_RETURN_IF_ERROR(r.varint(&l->level, "level index"));
  GTN_RETURN_IF_ERROR(r.varint(&l->merges, "merge count"));
  const uint64_t at = r.offset();
  GTN_RETURN_IF_ERROR(r.f64(&l->ratio, "ratio"));
  if (!(l->ratio >= 0.0 && l->ratio <= 1.0)) return r.errorAt(at, "ratio is not in [0, 1]");
  GTN_RETURN_IF_ERROR(r.varint(&l->points, "point count"));
  GTN_RETURN_IF_ERROR(r.varint(&l->tets, "tetrahedron count"));
  GTN_RETURN_IF_ERROR(r.varint(&l->boundary_triangles, "boundary triangle count"));
  GTN_RETURN_IF_ERROR(readBox(r, l->bbox_min, l->bbox_max));
  return r.expectEnd("the LHDR payload");
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
