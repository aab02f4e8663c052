// <gatun/mesh.h>: Mesh, Field and ScalarType, the data every part of the API exchanges.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace gatun {

/*-************************************
 *  Meshes
 **************************************/

/*! ScalarType : the type of coordinates and field values, kept as the source had it. */
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

/*! scalarSize() : bytes per value of `type` (1 to 8). */
size_t scalarSize(ScalarType type);
/*! scalarTypeName() : "int8" ... "uint64", "float32", "float64". The string is static. */
const char* scalarTypeName(ScalarType type);

/*! ScalarTypeOf<T>::value : the ScalarType of the C++ arithmetic type T (int8_t ... double). */
template <class T>
struct ScalarTypeOf;
template <>
struct ScalarTypeOf<int8_t> {
  static constexpr ScalarType value = ScalarType::kInt8;
};
template <>
struct ScalarTypeOf<uint8_t> {
  static constexpr ScalarType value = ScalarType::kUInt8;
};
template <>
struct ScalarTypeOf<int16_t> {
  static constexpr ScalarType value = ScalarType::kInt16;
};
template <>
struct ScalarTypeOf<uint16_t> {
  static constexpr ScalarType value = ScalarType::kUInt16;
};
template <>
struct ScalarTypeOf<int32_t> {
  static constexpr ScalarType value = ScalarType::kInt32;
};
template <>
struct ScalarTypeOf<uint32_t> {
  static constexpr ScalarType value = ScalarType::kUInt32;
};
template <>
struct ScalarTypeOf<int64_t> {
  static constexpr ScalarType value = ScalarType::kInt64;
};
template <>
struct ScalarTypeOf<uint64_t> {
  static constexpr ScalarType value = ScalarType::kUInt64;
};
template <>
struct ScalarTypeOf<float> {
  static constexpr ScalarType value = ScalarType::kFloat32;
};
template <>
struct ScalarTypeOf<double> {
  static constexpr ScalarType value = ScalarType::kFloat64;
};

/*! Field : a named array of `components` values per item (per point, or per tetrahedron), stored as
 *  raw little-endian bytes in `type`, so that every value survives bit for bit (NaN payloads too).
 *  `bytes` holds items * components * scalarSize(type) bytes, item by item. */
struct Field {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat32;
  std::vector<uint8_t> bytes;

  /*! itemCount() : the number of items the bytes hold (0 when components is 0). */
  size_t itemCount() const;
  /*! value() : component `component` of item `item`, converted to double. Both must be in range. */
  double value(size_t item, uint32_t component = 0) const;

  /*! of() : a field of `components` values per item from `values` (item by item, so
   *  values.size() / components items), in the type of T (int8_t ... double). */
  template <class T>
  static Field of(std::string name, uint32_t components, const std::vector<T>& values) {
    Field f;
    f.name = std::move(name);
    f.components = components;
    f.type = ScalarTypeOf<T>::value;
    f.bytes.resize(values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(f.bytes.data(), values.data(), f.bytes.size());
    return f;
  }
};

/*! Tet : the four point indices of a tetrahedron. Gatun stores positively oriented tetrahedra:
 *  (p1 - p0) . ((p2 - p0) x (p3 - p0)) > 0. */
using Tet = std::array<uint32_t, 4>;

/*! Mesh : a tetrahedral mesh with point and cell fields and free-form metadata.
 *  `points` holds x, y, z per point as double; with coord_type kFloat32 every coordinate is exactly
 *  a float32 value and is stored as float32. Each point field has pointCount() items, each cell
 *  field tetCount(). */
struct Mesh {
  ScalarType coord_type = ScalarType::kFloat64; /* kFloat32 or kFloat64 */
  std::vector<double> points;
  std::vector<Tet> tets;
  std::vector<Field> point_fields;
  std::vector<Field> cell_fields;
  std::vector<std::pair<std::string, std::string>> metadata;

  size_t pointCount() const { return points.size() / 3; }
  size_t tetCount() const { return tets.size(); }
  /*! pointField(), cellField() : the field named `name`, or nullptr. The pointer is valid until the
   *  mesh's field list changes. */
  const Field* pointField(const std::string& name) const;
  const Field* cellField(const std::string& name) const;
};

}  // namespace gatun
