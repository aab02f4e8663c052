// Writing one .gtn from a mesh held in parts (format/gtn_parts.h). The exchange, step by step (every
// message up starts with the sender's status, every message down with part 0's verdict, so that a
// failure anywhere ends every part at the same step):
//   up 1: layout (coordinate type, fields, metadata), piece count, exposed points (keys, pieces, values)
//   down 1: the orphans (keys held but unused by the exposed copies)      up 2: which a part uses
//   down 2: the classes, every part's first piece and exposed points' status
//   up 3: the coded pieces and seam faces
//   down 3: the piece table and seam streams                               up 4: each part's check
//   down 4: whether part 0 wrote the file
#include "format/gtn_parts.h"

#include <cstring>

#include "codec/pieces_check.h"
#include "format/file_io.h"
#include "format/gtn_bytes.h"
#include "format/gtn_records.h"

namespace gtn {

namespace {

// ---- messages ------------------------------------------------------------------------------------

void putStatus(ByteWriter& w, const Status& st) {
  w.u8(static_cast<uint8_t>(st.code()));
  w.string(st.isOk() ? std::string() : st.message());
}

Status getStatus(ByteReader& r, Status* st) {
  uint8_t code = 0;
  std::string message;
  GTN_RETURN_IF_ERROR(r.u8(&code, "status"));
  GTN_RETURN_IF_ERROR(r.string(&message, "message"));
  if (code > static_cast<uint8_t>(StatusCode::kIo)) return r.error("unknown status code");
  *st = code == 0 ? Status::ok() : Status(static_cast<StatusCode>(code), message);
  return Status::ok();
}

void putBytes(ByteWriter& w, const std::vector<uint8_t>& b) {
  w.varint(b.size());
  w.raw(b);
}

Status getBytes(ByteReader& r, std::vector<uint8_t>* b) {
  uint64_t n = 0;
  GTN_RETURN_IF_ERROR(r.varintAtMost(&n, r.remaining(), "byte count"));
  std::span<const uint8_t> s;
  GTN_RETURN_IF_ERROR(r.bytes(&s, n, "bytes"));
  b->assign(s.begin(), s.end());
  return Status::ok();
}

Status getU32(ByteReader& r, uint32_t* v, const char* name) {
  uint64_t x = 0;
  GTN_RETURN_IF_ERROR(r.varintAtMost(&x, UINT32_MAX, name));
  *v = static_cast<uint32_t>(x);
  return Status::ok();
}

// A count of items of at least `min_bytes` each, bounded by what is left to read.
Status getCount(ByteReader& r, uint64_t* n, size_t min_bytes, const char* name) {
  return r.varintAtMost(n, r.remaining() / std::max<size_t>(min_bytes, 1), name);
}

// What a level header says of the mesh's layout (no counts, no box).
void putLayout(ByteWriter& w, const LevelHeader& h) {
  w.u8(static_cast<uint8_t>(h.coord_type));
  writeFields(w, h.point_fields);
  writeFields(w, h.cell_fields);
  w.varint(h.metadata.size());
  for (const auto& [k, v] : h.metadata) {
    w.string(k);
    w.string(v);
  }
}

Status getLayout(ByteReader& r, LevelHeader* h) {
  uint8_t type = 0;
  GTN_RETURN_IF_ERROR(r.u8(&type, "coordinate type"));
  h->coord_type = static_cast<ScalarType>(type);
  GTN_RETURN_IF_ERROR(readFields(r, &h->point_fields, "point field count"));
  GTN_RETURN_IF_ERROR(readFields(r, &h->cell_fields, "cell field count"));
  uint64_t n = 0;
  GTN_RETURN_IF_ERROR(getCount(r, &n, 2, "metadata count"));
  h->metadata.resize(n);
  for (auto& [k, v] : h->metadata) {
    GTN_RETURN_IF_ERROR(r.string(&k, "metadata key"));
    GTN_RETURN_IF_ERROR(r.string(&v, "metadata value"));
  }
  return Status::ok();
}

bool sameLayout(const LevelHeader& a, const LevelHeader& b) {
  auto same = [](const std::vector<FieldDesc>& x, const std::vector<FieldDesc>& y) {
    if (x.size() != y.size()) return false;
    for (size_t i = 0; i < x.size(); ++i)
      if (x[i].name != y[i].name || x[i].components != y[i].components || x[i].type != y[i].type) return false;
    return true;
  };
  return a.coord_type == b.coord_type && same(a.point_fields, b.point_fields) && same(a.cell_fields, b.cell_fields);
}

void putPieceInfo(ByteWriter& w, const PieceInfo& p) {
  w.u8(p.kind);
  w.varint(p.points);
  w.varint(p.own_points);
  w.varint(p.own_boundary_points);
  w.varint(p.tets);
  w.varint(p.boundary_triangles);
  for (int i = 0; i < 3; ++i) w.f64(p.bbox_min[i]);
  for (int i = 0; i < 3; ++i) w.f64(p.bbox_max[i]);
}

Status getPieceInfo(ByteReader& r, PieceInfo* p) {
  GTN_RETURN_IF_ERROR(r.u8(&p->kind, "piece kind"));
  GTN_RETURN_IF_ERROR(r.varint(&p->points, "piece points"));
  GTN_RETURN_IF_ERROR(r.varint(&p->own_points, "own points"));
  GTN_RETURN_IF_ERROR(r.varint(&p->own_boundary_points, "own boundary points"));
  GTN_RETURN_IF_ERROR(r.varint(&p->tets, "piece tetrahedra"));
  GTN_RETURN_IF_ERROR(r.varint(&p->boundary_triangles, "boundary triangles"));
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&p->bbox_min[i], "box"));
  for (int i = 0; i < 3; ++i) GTN_RETURN_IF_ERROR(r.f64(&p->bbox_max[i], "box"));
  return Status::ok();
}

// The bytes of a point as the parts compare and part 0 stores it: x, y, z as doubles, then every
// point field's item.
void putPointItem(ByteWriter& w, const TetMesh& m, uint32_t v) {
  for (int i = 0; i < 3; ++i) w.f64(m.coords[3 * size_t{v} + i]);
  for (const Field& f : m.point_fields) {
    const size_t ib = f.components * f.valueSize();
    w.raw(&f.bytes[size_t{v} * ib], ib);
  }
}

size_t pointItemBytes(const LevelHeader& h) {
  size_t n = 24;
  for (const FieldDesc& d : h.point_fields) n += d.itemBytes();
  return n;
}

// ---- the exchange --------------------------------------------------------------------------------

class Exchange {
 public:
  Exchange(PartExchange& ex, std::string path) : ex_(ex), path_(std::move(path)) {}
  bool root() const { return ex_.part() == 0; }

  // Every part sends `payload` after its status; on part 0, `all` gets the payloads (status read off),
  // and the first failure (by part) is returned. Elsewhere returns ok.
  Status up(const Status& local, ByteWriter* payload, std::vector<std::vector<uint8_t>>* all) {
    ByteWriter w;
    putStatus(w, local);
    std::vector<uint8_t> mine = std::move(w.bytes());
    if (payload) {
      mine.insert(mine.end(), payload->bytes().begin(), payload->bytes().end());
      payload->bytes() = {};
    }
    std::vector<std::vector<uint8_t>> got;
    GTN_RETURN_IF_ERROR(ex_.gather(mine, &got));
    if (!root()) return Status::ok();
    if (got.size() != static_cast<size_t>(ex_.parts())) return ioError(path_ + ": the gather lost parts");
    all->clear();
    Status first = Status::ok();
    for (size_t q = 0; q < got.size(); ++q) {
      ByteReader r(got[q], 0, path_ + ": message of part " + std::to_string(q));
      Status st;
      GTN_RETURN_IF_ERROR(getStatus(r, &st));
      if (!st.isOk() && first.isOk()) first = st;
      all->emplace_back(got[q].begin() + static_cast<std::ptrdiff_t>(r.offset()), got[q].end());
    }
    return first;
  }

  // Part 0 sends `verdict` and `payload`; every part gets the verdict back and (when ok) the payload.
  Status down(const Status& verdict, ByteWriter* payload, std::vector<uint8_t>* out) {
    std::vector<uint8_t> bytes;
    if (root()) {
      ByteWriter w;
      putStatus(w, verdict);
      bytes = std::move(w.bytes());
      if (verdict.isOk() && payload) bytes.insert(bytes.end(), payload->bytes().begin(), payload->bytes().end());
    }
    GTN_RETURN_IF_ERROR(ex_.broadcast(&bytes));
    ByteReader r(bytes, 0, path_ + ": message of part 0");
    Status st;
    GTN_RETURN_IF_ERROR(getStatus(r, &st));
    if (!st.isOk()) return st;
    if (out) out->assign(bytes.begin() + static_cast<std::ptrdiff_t>(r.offset()), bytes.end());
    return Status::ok();
  }

 private:
  PartExchange& ex_;
  std::string path_;
};

// Part 0's reading of one part's first message.
struct ExposedMessage {
  LevelHeader layout;
  PartExposed exposed;
  std::vector<uint8_t> items;  // per exposed point, pointItemBytes(layout)
};

Status readExposed(std::span<const uint8_t> bytes, const std::string& what, ExposedMessage* m) {
  ByteReader r(bytes, 0, what);
  GTN_RETURN_IF_ERROR(getLayout(r, &m->layout));
  GTN_RETURN_IF_ERROR(getU32(r, &m->exposed.pieces, "pieces"));
  uint64_t n = 0;
  GTN_RETURN_IF_ERROR(getCount(r, &n, 24, "exposed points"));
  const size_t ib = pointItemBytes(m->layout);
  m->exposed.keys.resize(n);
  m->exposed.uses_first.assign(1, 0);
  m->items.resize(n * ib);
  for (uint64_t i = 0; i < n; ++i) {
    for (uint64_t& k : m->exposed.keys[i]) GTN_RETURN_IF_ERROR(r.u64(&k, "key"));
    uint64_t uses = 0;
    GTN_RETURN_IF_ERROR(getCount(r, &uses, 1, "uses"));
    for (uint64_t k = 0; k < uses; ++k) {
      uint32_t p = 0;
      GTN_RETURN_IF_ERROR(getU32(r, &p, "piece"));
      m->exposed.uses.push_back(p);
    }
    m->exposed.uses_first.push_back(static_cast<uint32_t>(m->exposed.uses.size()));
    std::span<const uint8_t> item;
    GTN_RETURN_IF_ERROR(r.bytes(&item, ib, "point values"));
    std::memcpy(&m->items[i * ib], item.data(), ib);
  }
  return r.expectEnd("the exposed points");
}

void putClasses(ByteWriter& w, const std::vector<SeamClass>& classes) {
  w.varint(classes.size());
  for (const SeamClass& c : classes) {
    w.varint(c.pieces.size());
    for (uint32_t p : c.pieces) w.varint(p);
    w.varint(c.points);
  }
}

Status getClasses(ByteReader& r, std::vector<SeamClass>* classes) {
  uint64_t n = 0;
  GTN_RETURN_IF_ERROR(getCount(r, &n, 3, "classes"));
  classes->resize(n);
  for (SeamClass& c : *classes) {
    uint64_t k = 0;
    GTN_RETURN_IF_ERROR(getCount(r, &k, 1, "class pieces"));
    c.pieces.resize(k);
    for (uint32_t& p : c.pieces) GTN_RETURN_IF_ERROR(getU32(r, &p, "class piece"));
    GTN_RETURN_IF_ERROR(r.varint(&c.points, "class points"));
  }
  return Status::ok();
}

}  // namespace

Status writeGtnFromParts(const std::string& path, const TetMesh& part, const std::vector<PointKey>& keys,
                         bool coordinate_keys, PartExchange& exchange, const GtnWriteOptions& options,
                         PartsWriteReport* report, const Status& local_failure) {
  Exchange ex(exchange, path);
  const int me = exchange.part(), n_parts = exchange.parts();
  const std::string who = path + ": part " + std::to_string(me);
  auto local = [&](const Status& st) { return st.isOk() ? st : Status(st.code(), who + ": " + st.message()); };

  // Up 1: the part's plan and exposed points.
  Status st = local_failure;
  if (st.isOk() && keys.size() != part.numPoints()) st = usageError("one key per point is needed");
  PartPlan plan;
  if (st.isOk()) {
    auto p = planPart(part, options.piece_tets);
    if (p.isOk()) plan = std::move(p).value();
    else st = p.status();
  }
  const LevelHeader my_layout = levelHeaderOf(part);
  {
    ByteWriter w;
    putLayout(w, my_layout);
    w.varint(plan.pieces);
    const bool any = st.isOk() && plan.pieces > 0;  // a part without tetrahedra adds nothing
    w.varint(any ? plan.exposed.size() : 0);
    if (any)
      for (size_t i = 0; i < plan.exposed.size(); ++i) {
        const uint32_t v = plan.exposed[i];
        for (uint64_t k : keys[v]) w.u64(k);
        w.varint(plan.uses_first[i + 1] - plan.uses_first[i]);
        for (uint32_t k = plan.uses_first[i]; k < plan.uses_first[i + 1]; ++k) w.varint(plan.uses[k]);
        putPointItem(w, part, v);
      }
    if (st.isOk() && plan.pieces == 0) plan = PartPlan{};  // nothing exposed
    if (st.isOk() && plan.pieces == 0) plan.piece_of.assign(part.numTets(), 0);
    std::vector<std::vector<uint8_t>> all;
    st = ex.up(local(st), &w, &all);
    // Part 0: the seam plan.
    SeamPlan seams;
    std::vector<ExposedMessage> msgs;
    LevelHeader layout;
    TetMesh seam_mesh;
    ByteWriter down;
    if (ex.root() && st.isOk()) {
      msgs.resize(all.size());
      int with_pieces = -1;
      for (size_t q = 0; q < all.size() && st.isOk(); ++q) {
        st = readExposed(all[q], path + ": message of part " + std::to_string(q), &msgs[q]);
        if (st.isOk() && msgs[q].exposed.pieces > 0) {
          if (with_pieces < 0) {
            with_pieces = static_cast<int>(q);
            layout = msgs[q].layout;
          } else if (!sameLayout(layout, msgs[q].layout)) {
            st = invalidData(path + ": part " + std::to_string(q) +
                             " has another coordinate type or other fields than part " + std::to_string(with_pieces) +
                             " (every part must carry the same arrays)");
          }
        }
      }
      if (st.isOk() && with_pieces < 0) st = usageError(path + ": no part holds a tetrahedron");
      std::vector<PartExposed> exposed;
      for (ExposedMessage& m : msgs) exposed.push_back(std::move(m.exposed));
      if (st.isOk()) {
        auto p = planSeams(exposed, coordinate_keys);
        if (p.isOk()) seams = std::move(p).value();
        else st = Status(p.status().code(), path + ": " + p.status().message());
      }
      // Every copy of a seam vertex agrees with the one stored.
      const size_t ib = pointItemBytes(layout);
      for (size_t q = 0; q < seams.status.size() && st.isOk(); ++q)
        for (size_t i = 0; i < seams.status[q].size(); ++i) {
          const uint32_t s = seams.status[q][i];
          if (s == kPartOwnVertex || s == kPartDropVertex) continue;
          const auto [sq, si] = seams.seam_source[s];
          if (std::memcmp(&msgs[q].items[i * ib], &msgs[sq].items[si * ib], ib) != 0) {
            const PointKey& k = exposed[q].keys[i];
            st = invalidData(path + ": parts " + std::to_string(sq) + " and " + std::to_string(q) +
                             " hold different coordinates or point values for the shared point with key (" +
                             std::to_string(k[0]) + ", " + std::to_string(k[1]) + ", " + std::to_string(k[2]) + ")");
            break;
          }
        }
      if (st.isOk()) {
        down.varint(seams.orphans.size());
        for (const PointKey& k : seams.orphans)
          for (uint64_t x : k) down.u64(x);
      }
      if (st.isOk()) {
        // The seam vertices' values, for the class streams.
        seam_mesh.coord_type = layout.coord_type;
        const size_t n = seams.seam_source.size();
        seam_mesh.coords.resize(3 * n);
        for (const FieldDesc& d : layout.point_fields)
          seam_mesh.point_fields.emplace_back(d.name, d.components, d.type, n);
        for (size_t s = 0; s < n; ++s) {
          const auto [sq, si] = seams.seam_source[s];
          const uint8_t* item = &msgs[sq].items[si * ib];
          std::memcpy(&seam_mesh.coords[3 * s], item, 24);
          size_t off = 24;
          for (Field& f : seam_mesh.point_fields) {
            const size_t fb = f.components * f.valueSize();
            std::memcpy(&f.bytes[s * fb], item + off, fb);
            off += fb;
          }
        }
      }
      msgs.clear();
    }
    // Down 1 / up 2: the orphans.
    std::vector<uint8_t> got;
    GTN_RETURN_IF_ERROR(ex.down(st, &down, &got));
    std::vector<PointKey> orphans;
    {
      ByteReader r(got, 0, path + ": orphans");
      uint64_t n = 0;
      st = getCount(r, &n, 24, "orphans");
      orphans.resize(st.isOk() ? n : 0);
      for (PointKey& k : orphans)
        for (uint64_t& x : k)
          if (st.isOk()) st = r.u64(&x, "key");
    }
    ByteWriter used;
    const std::vector<char> flags = usedKeys(part, keys, orphans);
    for (char f : flags) used.u8(static_cast<uint8_t>(f));
    std::vector<std::vector<uint8_t>> answers;
    st = ex.up(local(st), &used, &answers);
    ByteWriter plan_msg;
    if (ex.root() && st.isOk()) {
      std::vector<char> any(seams.orphans.size(), 0);
      for (const auto& a : answers)
        for (size_t k = 0; k < a.size() && k < any.size(); ++k) any[k] = any[k] || a[k];
      settleOrphans(seams, any);
      putClasses(plan_msg, seams.classes);
      for (uint32_t f : seams.first_piece) plan_msg.varint(f);
      for (const auto& s : seams.status) {
        plan_msg.varint(s.size());
        for (uint32_t x : s) plan_msg.varint(x);
      }
    }
    // Down 2: the plan; each part codes its pieces.
    GTN_RETURN_IF_ERROR(ex.down(st, &plan_msg, &got));
    std::vector<SeamClass> classes;
    std::vector<uint32_t> first_piece(n_parts + 1, 0), status;
    {
      ByteReader r(got, 0, path + ": seam plan");
      st = getClasses(r, &classes);
      for (uint32_t& f : first_piece)
        if (st.isOk()) st = getU32(r, &f, "first piece");
      for (int q = 0; q < n_parts && st.isOk(); ++q) {
        uint64_t n = 0;
        st = getCount(r, &n, 1, "status");
        std::vector<uint32_t> s(st.isOk() ? n : 0);
        for (uint32_t& x : s)
          if (st.isOk()) st = getU32(r, &x, "status");
        if (q == me) status = std::move(s);
      }
    }
    if (st.isOk() && status.size() != plan.exposed.size()) st = usageError("the seam plan does not match the part");
    EncodedPart encoded;
    if (st.isOk()) {
      auto e = encodePart(part, plan, classes, first_piece[me], status);
      if (e.isOk()) encoded = std::move(e).value();
      else st = e.status();
    }
    // Up 3: the coded pieces.
    ByteWriter pieces_msg;
    if (st.isOk()) {
      pieces_msg.varint(encoded.pieces.size());
      for (size_t p = 0; p < encoded.pieces.size(); ++p) {
        putPieceInfo(pieces_msg, encoded.pieces[p]);
        const EncodedLevel& e = encoded.encoded[p];
        putBytes(pieces_msg, e.boundary);
        putBytes(pieces_msg, e.connectivity);
        putBytes(pieces_msg, e.geometry);
        for (const auto& s : e.point_fields) putBytes(pieces_msg, s);
        for (const auto& s : e.cell_fields) putBytes(pieces_msg, s);
        pieces_msg.varint(e.boundary_points);
      }
      pieces_msg.varint(encoded.seam_faces.size());
      for (const auto& f : encoded.seam_faces)
        for (uint32_t x : f) pieces_msg.varint(x);
    }
    st = ex.up(local(st), &pieces_msg, &all);
    PiecedLevel level;
    ByteWriter table;
    if (ex.root() && st.isOk()) {
      std::vector<EncodedPart> parts(all.size());
      for (size_t q = 0; q < all.size() && st.isOk(); ++q) {
        ByteReader r(all[q], 0, path + ": pieces of part " + std::to_string(q));
        uint64_t n = 0;
        st = getCount(r, &n, 20, "pieces");
        EncodedPart& ep = parts[q];
        ep.pieces.resize(st.isOk() ? n : 0);
        ep.encoded.resize(ep.pieces.size());
        for (size_t p = 0; p < n && st.isOk(); ++p) {
          st = getPieceInfo(r, &ep.pieces[p]);
          EncodedLevel& e = ep.encoded[p];
          e.header = pieceHeader(layout, ep.pieces[p]);
          if (st.isOk()) st = getBytes(r, &e.boundary);
          if (st.isOk()) st = getBytes(r, &e.connectivity);
          if (st.isOk()) st = getBytes(r, &e.geometry);
          e.point_fields.resize(layout.point_fields.size());
          e.cell_fields.resize(layout.cell_fields.size());
          for (auto& s : e.point_fields)
            if (st.isOk()) st = getBytes(r, &s);
          for (auto& s : e.cell_fields)
            if (st.isOk()) st = getBytes(r, &s);
          if (st.isOk()) st = r.varint(&e.boundary_points, "boundary points");
        }
        uint64_t faces = 0;
        if (st.isOk()) st = getCount(r, &faces, 3, "seam faces");
        ep.seam_faces.resize(st.isOk() ? faces : 0);
        for (auto& f : ep.seam_faces)
          for (uint32_t& x : f)
            if (st.isOk()) st = getU32(r, &x, "seam face");
        if (st.isOk()) st = r.expectEnd("the pieces");
      }
      all.clear();
      if (st.isOk()) {
        auto l = assembleParts(std::move(parts), seams, seam_mesh);
        if (l.isOk()) level = std::move(l).value();
        else st = Status(l.status().code(), path + ": " + l.status().message());
      }
      if (st.isOk()) {
        table.varint(level.header.points);
        table.varint(level.header.tets);
        table.varint(level.header.boundary_triangles);
        table.varint(level.pieces.size());
        for (const PieceInfo& p : level.pieces) putPieceInfo(table, p);
        table.varint(level.seam_streams.size());
        for (const auto& s : level.seam_streams) putBytes(table, s);
      }
    }
    // Down 3: the piece table and seam streams; each part checks its pieces.
    GTN_RETURN_IF_ERROR(ex.down(st, &table, &got));
    LevelHeader header = pieceHeader(my_layout, PieceInfo{});
    std::vector<PieceInfo> infos;
    std::vector<std::vector<uint8_t>> seam_streams;
    {
      ByteReader r(got, 0, path + ": piece table");
      st = r.varint(&header.points, "points");
      if (st.isOk()) st = r.varint(&header.tets, "tetrahedra");
      if (st.isOk()) st = r.varint(&header.boundary_triangles, "boundary triangles");
      uint64_t n = 0;
      if (st.isOk()) st = getCount(r, &n, 20, "pieces");
      infos.resize(st.isOk() ? n : 0);
      for (PieceInfo& p : infos)
        if (st.isOk()) st = getPieceInfo(r, &p);
      if (st.isOk()) st = getCount(r, &n, 1, "seam streams");
      seam_streams.resize(st.isOk() ? n : 0);
      for (auto& s : seam_streams)
        if (st.isOk()) st = getBytes(r, &s);
    }
    if (report && st.isOk()) {
      report->pieces_per_part.clear();
      for (int q = 0; q < n_parts; ++q) report->pieces_per_part.push_back(first_piece[q + 1] - first_piece[q]);
      report->points = header.points;
      report->tets = header.tets;
      report->seam_points = 0;
      for (const SeamClass& c : classes) report->seam_points += c.points;
      report->exposed_points = 0;
      for (size_t q = 0; ex.root() && q < seams.status.size(); ++q) report->exposed_points += seams.status[q].size();
    }
    if (st.isOk() && options.verify && !encoded.pieces.empty()) {
      PiecedLevelView view;
      view.header = &header;
      view.pieces = infos;
      view.classes = classes;
      for (const auto& s : seam_streams) view.seam_streams.emplace_back(s);
      view.payloads.resize(infos.size());
      for (size_t p = 0; p < encoded.encoded.size() && first_piece[me] + p < infos.size(); ++p) {
        view.payloads[first_piece[me] + p].header = pieceHeader(header, infos[first_piece[me] + p]);
        view.payloads[first_piece[me] + p].streams = payloadOf(encoded.encoded[p]);
      }
      const std::string why = view.seam_streams.size() == classes.size() || infos.size() == 1
                                  ? partLosslessMismatch(part, encoded, first_piece[me], view)
                                  : "the seam streams do not match the classes";
      if (!why.empty())
        st = invalidData("level 0 would not decode back to the part (" + why +
                         "), so the file was not written; this is a bug in gtn's encoder, please report it");
    }
    // Up 4: the checks; part 0 writes the file.
    st = ex.up(local(st), nullptr, &all);
    if (ex.root() && st.isOk()) {
      GtnWriteOptions wo = options;
      std::string parts_note = std::to_string(n_parts);
      parts_note.append(" parts:");
      for (int q = 0; q < n_parts; ++q)
        parts_note.append(" ").append(std::to_string(first_piece[q + 1] - first_piece[q]));
      wo.command_line.append(" (").append(parts_note).append(" pieces)");
      level.header.level = 0;
      level.header.merges = 0;
      st = writeFileAtomically(path, [&](std::FILE* f) -> Status {
        GtnStreamWriter w(fileOutput(f), wo);
        GTN_RETURN_IF_ERROR(namedByOutput(path, w.begin(level.header, 1)));
        GTN_RETURN_IF_ERROR(namedByOutput(path, w.addLevel(level, 0.0, std::nullopt)));
        return namedByOutput(path, w.finish());
      });
    }
    // Down 4: the outcome.
    return ex.down(st, nullptr, nullptr);
  }
}

}  // namespace gtn
