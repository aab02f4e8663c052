// TetMesh: a tetrahedral mesh with points in source precision, named per-vertex and per-cell fields
// and free-form metadata. The in-memory mesh is one sink of the mesh stream among others.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "mesh/status.h"

namespace gtn {

enum class ScalarType : uint8_t {
  kInt8 = 0,
  kUInt8 = 1,
  kInt16 = 2,
  kUInt16 = 3,
  kInt32 = 4,
  kUInt32 = 5,
  kInt64 = 6,
  kUInt64 = 7,
  kFloat32 = 8,
  kFloat64 = 9,
};
constexpr int kNumScalarTypes = 10;

size_t scalarSize(ScalarType type);
// "int8" ... "uint64", "float32", "float64".
const char* scalarTypeName(ScalarType type);
bool scalarTypeFromName(const std::string& name, ScalarType* out);
inline bool isFloatType(ScalarType t) { return t == ScalarType::kFloat32 || t == ScalarType::kFloat64; }
// The value of `type` stored at `p` (unaligned), as a double.
double scalarAsDouble(ScalarType type, const uint8_t* p);

// A named array with `components` values per item, stored as raw little-endian bytes in the source
// type so that every value survives bit for bit (NaN payloads included).
struct Field {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat32;
  std::vector<uint8_t> bytes;

  Field() = default;
  Field(std::string n, uint32_t comps, ScalarType t, size_t items)
      : name(std::move(n)), components(comps), type(t), bytes(items * comps * scalarSize(t)) {}

  size_t valueSize() const { return scalarSize(type); }
  size_t itemCount() const { return components == 0 ? 0 : bytes.size() / (components * valueSize()); }
  // Value of component c of item i converted to double (for statistics and interpolation only).
  double get(size_t i, uint32_t c) const;
  template <class T>
  T* data() {
    return reinterpret_cast<T*>(bytes.data());
  }
  template <class T>
  const T* data() const {
    return reinterpret_cast<const T*>(bytes.data());
  }
  template <class T>
  void set(size_t i, uint32_t c, T v) {
    std::memcpy(bytes.data() + (i * components + c) * sizeof(T), &v, sizeof(T));
  }
  // Copies item `from` of `src` (same type and components) to item `to` of this field.
  void copyItem(const Field& src, size_t from, size_t to);
};

using Tet = std::array<uint32_t, 4>;

// A structured block a mesh is (PLOT3D, VTK's structured datasets): its dims[0] x dims[1] x dims[2]
// nodes, i fastest, are the mesh's points from `first_point` on in node order, but for the nodes in
// `aliases` (welded: they are an earlier node's point and have none of their own); the points after
// the nodes are the Steiner points of its cells, and its tetrahedra come cell by cell. The structured
// encoder (codec/structured_piece.h) codes such a mesh by the block's dimensions, split rule and
// exceptions instead of its connectivity.
struct StructuredBlock {
  uint64_t first_point = 0;
  uint32_t dims[3] = {0, 0, 0};
  std::vector<std::pair<uint32_t, uint32_t>> aliases;  // (node, earlier node it is), node increasing
};

struct TetMesh {
  // Precision of the source coordinates. Coordinates are held as double; when coord_type is
  // kFloat32 every coordinate is exactly a float32 value and is written back as float32.
  ScalarType coord_type = ScalarType::kFloat64;
  std::vector<double> coords;  // x, y, z per point
  std::vector<Tet> tets;       // positively oriented after import normalisation
  std::vector<Field> point_fields;
  std::vector<Field> cell_fields;  // one item per tetrahedron (region attributes, references)
  std::vector<std::pair<std::string, std::string>> metadata;
  // The structured block the mesh is, where an importer read it as one (importMesh keeps it only
  // when the mesh is exactly that block, as codec/grid_coder.h's matchGridLayout finds it); empty
  // otherwise. Not stored in .gtn files. A hint only: the structured encoder checks the mesh against
  // it and refuses a mesh that is not the block (after a change to its points or tetrahedra).
  std::vector<StructuredBlock> blocks;

  size_t numPoints() const { return coords.size() / 3; }
  size_t numTets() const { return tets.size(); }
  const double* point(size_t i) const { return coords.data() + 3 * i; }

  const Field* findPointField(const std::string& name) const;
  void setMetadata(const std::string& key, const std::string& value);
  const std::string* findMetadata(const std::string& key) const;

  // Structural consistency: indices in range, field sizes match, coordinates finite and exactly
  // representable in coord_type. `what` names the mesh in the message.
  Status checkConsistency(const std::string& what) const;
};

// What an importer did to the data on the way in, for the user to see.
struct ImportReport {
  size_t flipped = 0;         // cells reoriented to positive volume
  size_t zero_volume = 0;     // cells with zero volume (kept, reported)
  size_t dropped_cells = 0;   // cells removed (e.g. touching an IBLANK hole)
  size_t welded_points = 0;   // points merged by --weld
  size_t collapsed_tets = 0;  // tetrahedra dropped because welding collapsed them
  size_t steiner_points = 0;  // points added to split cells conformingly
  std::vector<std::string> warnings;
};

struct ImportResult {
  TetMesh mesh;
  ImportReport report;
};

}  // namespace gtn
