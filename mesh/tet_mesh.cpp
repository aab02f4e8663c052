#include "mesh/tet_mesh.h"

#include <cmath>

namespace gtn {

namespace {
constexpr const char* kTypeNames[kNumScalarTypes] = {"int8",   "uint8", "int16",  "uint16",  "int32",
                                                     "uint32", "int64", "uint64", "float32", "float64"};
constexpr size_t kTypeSizes[kNumScalarTypes] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

template <class T>
double load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}
}  // namespace

size_t scalarSize(ScalarType type) { return kTypeSizes[static_cast<int>(type)]; }
const char* scalarTypeName(ScalarType type) { return kTypeNames[static_cast<int>(type)]; }

bool scalarTypeFromName(const std::string& name, ScalarType* out) {
  for (int i = 0; i < kNumScalarTypes; ++i) {
    if (name == kTypeNames[i]) {
      *out = static_cast<ScalarType>(i);
      return true;
    }
  }
  return false;
}

double scalarAsDouble(ScalarType type, const uint8_t* p) {
  switch (type) {
    case ScalarType::kInt8: return load<int8_t>(p);
    case ScalarType::kUInt8: return load<uint8_t>(p);
    case ScalarType::kInt16: return load<int16_t>(p);
    case ScalarType::kUInt16: return load<uint16_t>(p);
    case ScalarType::kInt32: return load<int32_t>(p);
    case ScalarType::kUInt32: return load<uint32_t>(p);
    case ScalarType::kInt64: return load<int64_t>(p);
    case ScalarType::kUInt64: return load<uint64_t>(p);
    case ScalarType::kFloat32: return load<float>(p);
    case ScalarType::kFloat64: return load<double>(p);
  }
  return 0.0;
}

double Field::get(size_t i, uint32_t c) const {
  return scalarAsDouble(type, bytes.data() + (i * components + c) * valueSize());
}

void Field::copyItem(const Field& src, size_t from, size_t to) {
  const size_t item = components * valueSize();
  std::memcpy(bytes.data() + to * item, src.bytes.data() + from * item, item);
}

const Field* TetMesh::findPointField(const std::string& name) const {
  for (const Field& f : point_fields)
    if (f.name == name) return &f;
  return nullptr;
}

void TetMesh::setMetadata(const std::string& key, const std::string& value) {
  for (auto& kv : metadata) {
    if (kv.first == key) {
      kv.second = value;
      return;
    }
  }
  metadata.emplace_back(key, value);
}

const std::string* TetMesh::findMetadata(const std::string& key) const {
  for (const auto& kv : metadata)
    if (kv.first == key) return &kv.second;
  return nullptr;
}

Status TetMesh::checkConsistency(const std::string& what) const {
  if (coords.size() % 3 != 0) return invalidData(what + ": coordinate array length is not a multiple of 3");
  if (coord_type != ScalarType::kFloat32 && coord_type != ScalarType::kFloat64)
    return invalidData(what + ": coordinates must be float32 or float64");
  const size_t n = numPoints();
  for (size_t i = 0; i < coords.size(); ++i) {
    if (!std::isfinite(coords[i]))
      return invalidData(what + ": point " + std::to_string(i / 3) + " has a non-finite coordinate");
    if (coord_type == ScalarType::kFloat32 && static_cast<double>(static_cast<float>(coords[i])) != coords[i])
      return invalidData(what + ": point " + std::to_string(i / 3) + " is not a float32 value");
  }
  for (size_t t = 0; t < tets.size(); ++t) {
    for (uint32_t v : tets[t]) {
      if (v >= n)
        return invalidData(what + ": tetrahedron " + std::to_string(t) + " refers to point " + std::to_string(v) +
                           " but there are " + std::to_string(n) + " points");
    }
  }
  for (const Field& f : point_fields) {
    if (f.components == 0 || f.bytes.size() != n * f.components * f.valueSize())
      return invalidData(what + ": point field '" + f.name + "' does not have one item per point");
  }
  for (const Field& f : cell_fields) {
    if (f.components == 0 || f.bytes.size() != tets.size() * f.components * f.valueSize())
      return invalidData(what + ": cell field '" + f.name + "' does not have one item per tetrahedron");
  }
  return Status::ok();
}

}  // namespace gtn
