#include "mesh/mesh_stream.h"

#include <cstring>

#include "mesh/fresh_memory.h"

namespace gtn {

namespace {

// Appends one item of a field (n bytes, usually one 4- or 8-byte value): copies of a constant size
// compile to a single move, where vector::insert calls memmove for every item.
inline void appendBytes(std::vector<uint8_t>& bytes, const uint8_t* p, size_t n) {
  const size_t at = bytes.size();
  bytes.resize(at + n);
  uint8_t* out = bytes.data() + at;
  switch (n) {
    case 4: std::memcpy(out, p, 4); break;
    case 8: std::memcpy(out, p, 8); break;
    default: std::memcpy(out, p, n);
  }
}

}  // namespace

Status MeshSink::wholeLevel(const LevelHeader&, TetMesh&&, std::vector<std::array<uint32_t, 3>>&&) {
  return usageError("mesh stream: this sink takes a level's events, not the whole level");
}

Status TetMeshBuilder::wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                                  std::vector<std::array<uint32_t, 3>>&& boundary) {
  header_ = header;
  mesh_ = std::move(mesh);
  mesh_.coord_type = header.coord_type;
  mesh_.metadata = header.metadata;
  mesh_.blocks.clear();
  boundary_ = std::move(boundary);
  return Status::ok();
}

Status TetMeshBuilder::beginLevel(const LevelHeader& header) {
  header_ = header;
  mesh_ = TetMesh();
  boundary_.clear();
  mesh_.coord_type = header.coord_type;
  mesh_.metadata = header.metadata;
  // Reserve only what the header promises within a sane bound; the stream itself is authoritative.
  const uint64_t kReserveCap = uint64_t{1} << 26;
  mesh_.coords.reserve(3 * std::min<uint64_t>(header.points, kReserveCap));
  mesh_.tets.reserve(std::min<uint64_t>(header.tets, kReserveCap));
  for (const FieldDesc& d : header.point_fields) {
    mesh_.point_fields.emplace_back(d.name, d.components, d.type, 0);
    mesh_.point_fields.back().bytes.reserve(d.itemBytes() * std::min<uint64_t>(header.points, kReserveCap));
  }
  for (const FieldDesc& d : header.cell_fields) {
    mesh_.cell_fields.emplace_back(d.name, d.components, d.type, 0);
    mesh_.cell_fields.back().bytes.reserve(d.itemBytes() * std::min<uint64_t>(header.tets, kReserveCap));
  }
  coords_ready_ = {};
  tets_ready_ = {};
  point_ready_.assign(mesh_.point_fields.size(), {});
  cell_ready_.assign(mesh_.cell_fields.size(), {});
  return Status::ok();
}

Status TetMeshBuilder::vertex(uint32_t id, const double xyz[3], const uint8_t* values) {
  if (id != mesh_.numPoints()) return invalidData("mesh stream: vertex ids must be consecutive");
  coords_ready_.before(mesh_.coords, 3);
  mesh_.coords.insert(mesh_.coords.end(), xyz, xyz + 3);
  for (size_t k = 0; k < mesh_.point_fields.size(); ++k) {
    Field& f = mesh_.point_fields[k];
    const size_t n = f.components * f.valueSize();
    point_ready_[k].before(f.bytes, n);
    appendBytes(f.bytes, values, n);
    values += n;
  }
  return Status::ok();
}

Status TetMeshBuilder::boundaryTriangle(const uint32_t v[3]) {
  boundary_.push_back({v[0], v[1], v[2]});
  return Status::ok();
}

Status TetMeshBuilder::tet(const uint32_t v[4], const uint8_t* cell_values) {
  tets_ready_.before(mesh_.tets, 1);
  mesh_.tets.push_back({v[0], v[1], v[2], v[3]});
  for (size_t k = 0; k < mesh_.cell_fields.size(); ++k) {
    Field& f = mesh_.cell_fields[k];
    const size_t n = f.components * f.valueSize();
    cell_ready_[k].before(f.bytes, n);
    appendBytes(f.bytes, cell_values, n);
    cell_values += n;
  }
  return Status::ok();
}

namespace {
// Item i of `fields`, concatenated in their order, into `out` (resized to the item's bytes).
void packItem(const std::vector<Field>& fields, size_t i, std::vector<uint8_t>& out) {
  out.clear();
  for (const Field& f : fields) {
    const size_t n = f.components * f.valueSize();
    out.insert(out.end(), f.bytes.begin() + i * n, f.bytes.begin() + (i + 1) * n);
  }
}
}  // namespace

Status replayLevel(const LevelHeader& header, const TetMesh& mesh, const std::vector<std::array<uint32_t, 3>>& boundary,
                   MeshSink& sink) {
  GTN_RETURN_IF_ERROR(sink.beginLevel(header));
  std::vector<uint8_t> item;
  const uint32_t n = static_cast<uint32_t>(mesh.numPoints());
  for (uint32_t v = 0; v < n; ++v) {
    packItem(mesh.point_fields, v, item);
    GTN_RETURN_IF_ERROR(sink.vertex(v, mesh.point(v), item.empty() ? nullptr : item.data()));
  }
  for (const std::array<uint32_t, 3>& t : boundary) GTN_RETURN_IF_ERROR(sink.boundaryTriangle(t.data()));
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    packItem(mesh.cell_fields, i, item);
    GTN_RETURN_IF_ERROR(sink.tet(mesh.tets[i].data(), item.empty() ? nullptr : item.data()));
  }
  for (uint32_t v = 0; v < n; ++v) GTN_RETURN_IF_ERROR(sink.retireVertex(v));
  return sink.endLevel();
}

}  // namespace gtn
