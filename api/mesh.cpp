// The API's value types (include/gatun/result.h, include/gatun/mesh.h) and their conversions to the
// layers' (api/internal.h).
#include <cstring>
#include <utility>

#include "gatun/mesh.h"
#include "gatun/result.h"
#include "internal.h"

namespace gatun {

// The API's codes are the library's, in the same order.
static_assert(static_cast<int>(ErrorCode::kIo) == static_cast<int>(gtn::StatusCode::kIo));
static_assert(static_cast<int>(ErrorCode::kUsage) == static_cast<int>(gtn::StatusCode::kUsage));
static_assert(static_cast<int>(ErrorCode::kInvalidData) == static_cast<int>(gtn::StatusCode::kInvalidData));
static_assert(static_cast<int>(ScalarType::kFloat64) == static_cast<int>(gtn::ScalarType::kFloat64));
static_assert(static_cast<int>(ScalarType::kInt8) == static_cast<int>(gtn::ScalarType::kInt8));

const char* version() { return GTN_VERSION_STRING; }

int Error::exitCode() const { return gtn::exitCodeFor(static_cast<gtn::StatusCode>(code_)); }

size_t scalarSize(ScalarType type) { return gtn::scalarSize(static_cast<gtn::ScalarType>(type)); }

const char* scalarTypeName(ScalarType type) { return gtn::scalarTypeName(static_cast<gtn::ScalarType>(type)); }

size_t Field::itemCount() const {
  const size_t item = static_cast<size_t>(components) * scalarSize(type);
  return item == 0 ? 0 : bytes.size() / item;
}

double Field::value(size_t item, uint32_t component) const {
  return gtn::scalarAsDouble(static_cast<gtn::ScalarType>(type),
                             bytes.data() + (item * components + component) * scalarSize(type));
}

namespace {
const Field* findField(const std::vector<Field>& fields, const std::string& name) {
  for (const Field& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}
}  // namespace

const Field* Mesh::pointField(const std::string& name) const { return findField(point_fields, name); }
const Field* Mesh::cellField(const std::string& name) const { return findField(cell_fields, name); }

}  // namespace gatun

namespace gtn::api {

gatun::Error toError(const Status& status) {
  if (status.isOk()) return gatun::Error();
  return gatun::Error(static_cast<gatun::ErrorCode>(status.code()), status.message());
}

namespace {
std::vector<Field> toFields(const std::vector<gatun::Field>& fields) {
  std::vector<Field> out;
  out.reserve(fields.size());
  for (const gatun::Field& f : fields) {
    Field g;
    g.name = f.name;
    g.components = f.components;
    g.type = static_cast<ScalarType>(f.type);
    g.bytes = f.bytes;
    out.push_back(std::move(g));
  }
  return out;
}

std::vector<gatun::Field> fromFields(std::vector<Field>&& fields) {
  std::vector<gatun::Field> out;
  out.reserve(fields.size());
  for (Field& g : fields) {
    gatun::Field f;
    f.name = std::move(g.name);
    f.components = g.components;
    f.type = static_cast<gatun::ScalarType>(g.type);
    f.bytes = std::move(g.bytes);
    out.push_back(std::move(f));
  }
  return out;
}
}  // namespace

TetMesh toTetMesh(const gatun::Mesh& mesh) {
  TetMesh t;
  t.coord_type = static_cast<ScalarType>(mesh.coord_type);
  t.coords = mesh.points;
  t.tets = mesh.tets;
  t.point_fields = toFields(mesh.point_fields);
  t.cell_fields = toFields(mesh.cell_fields);
  t.metadata = mesh.metadata;
  return t;
}

gatun::Mesh fromTetMesh(TetMesh&& t) {
  gatun::Mesh mesh;
  mesh.coord_type = static_cast<gatun::ScalarType>(t.coord_type);
  mesh.points = std::move(t.coords);
  mesh.tets = std::move(t.tets);
  mesh.point_fields = fromFields(std::move(t.point_fields));
  mesh.cell_fields = fromFields(std::move(t.cell_fields));
  mesh.metadata = std::move(t.metadata);
  return mesh;
}

ImportOptions toImportOptions(const gatun::ImportOptions& options) {
  ImportOptions o;
  o.split = options.split;
  o.weld = options.weld;
  o.exodus_time_step = options.exodus_time_step;
  return o;
}

void appendImportWarnings(const std::string& input, const ImportReport& r, std::vector<std::string>* warnings) {
  if (!warnings) return;
  auto add = [&](const std::string& what) { warnings->push_back(input + ": " + what); };
  if (r.flipped) add("flipped " + std::to_string(r.flipped) + " tetrahedra to positive orientation");
  if (r.zero_volume) add(std::to_string(r.zero_volume) + " tetrahedra have zero volume (kept)");
  if (r.dropped_cells) add("dropped " + std::to_string(r.dropped_cells) + " cells");
  if (r.welded_points)
    add("welded " + std::to_string(r.welded_points) + " points, dropped " + std::to_string(r.collapsed_tets) +
        " collapsed tetrahedra");
  if (r.steiner_points)
    add("added " + std::to_string(r.steiner_points) + " Steiner points to split cells conformingly");
  for (const std::string& w : r.warnings) {
    // A warning that already names the input or one of its files, as is (as `gtn convert` prints it).
    const bool named = w.rfind(input, 0) == 0 && w.size() > input.size() &&
                       (w.compare(input.size(), 2, ": ") == 0 ||
                        (w[input.size()] == '.' && w.find(": ", input.size()) < w.find(' ', input.size())));
    warnings->push_back(named ? w : input + ": " + w);
  }
}

}  // namespace gtn::api
