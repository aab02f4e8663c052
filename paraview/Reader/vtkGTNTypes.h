// Between the library's fields (raw bytes in their stored type) and VTK's data arrays, shared by
// vtkGTNReader and vtkGTNWriter. Internal to the module.
#pragma once

#include <cstring>
#include <optional>
#include <vector>

#include "vtkDataArray.h"
#include "vtkSmartPointer.h"
#include "vtkType.h"

#include "mesh/tet_mesh.h"

namespace vtkgtn {

inline int vtkTypeOf(gtn::ScalarType t) {
  switch (t) {
    case gtn::ScalarType::kInt8: return VTK_SIGNED_CHAR;
    case gtn::ScalarType::kUInt8: return VTK_UNSIGNED_CHAR;
    case gtn::ScalarType::kInt16: return VTK_SHORT;
    case gtn::ScalarType::kUInt16: return VTK_UNSIGNED_SHORT;
    case gtn::ScalarType::kInt32: return VTK_INT;
    case gtn::ScalarType::kUInt32: return VTK_UNSIGNED_INT;
    case gtn::ScalarType::kInt64: return VTK_LONG_LONG;
    case gtn::ScalarType::kUInt64: return VTK_UNSIGNED_LONG_LONG;
    case gtn::ScalarType::kFloat32: return VTK_FLOAT;
    case gtn::ScalarType::kFloat64: return VTK_DOUBLE;
  }
  return VTK_VOID;
}

// The field's type for a VTK array type; nullopt for types a .gtn field cannot hold.
inline std::optional<gtn::ScalarType> scalarTypeOf(int vtk_type) {
  switch (vtk_type) {
    case VTK_SIGNED_CHAR: return gtn::ScalarType::kInt8;
    case VTK_CHAR:
      return sizeof(char) == 1 && static_cast<char>(-1) < 0 ? gtn::ScalarType::kInt8 : gtn::ScalarType::kUInt8;
    case VTK_UNSIGNED_CHAR: return gtn::ScalarType::kUInt8;
    case VTK_SHORT: return gtn::ScalarType::kInt16;
    case VTK_UNSIGNED_SHORT: return gtn::ScalarType::kUInt16;
    case VTK_INT: return gtn::ScalarType::kInt32;
    case VTK_UNSIGNED_INT: return gtn::ScalarType::kUInt32;
    case VTK_LONG: return sizeof(long) == 8 ? gtn::ScalarType::kInt64 : gtn::ScalarType::kInt32;
    case VTK_UNSIGNED_LONG: return sizeof(long) == 8 ? gtn::ScalarType::kUInt64 : gtn::ScalarType::kUInt32;
    case VTK_LONG_LONG:
    case VTK_ID_TYPE: return sizeof(vtkIdType) == 8 ? gtn::ScalarType::kInt64 : gtn::ScalarType::kInt32;
    case VTK_UNSIGNED_LONG_LONG: return gtn::ScalarType::kUInt64;
    case VTK_FLOAT: return gtn::ScalarType::kFloat32;
    case VTK_DOUBLE: return gtn::ScalarType::kFloat64;
    default: return std::nullopt;
  }
}

// A VTK array of `field`'s type holding the items `items` of `field`, in that order (nullptr: all).
inline vtkSmartPointer<vtkDataArray> toVtkArray(const gtn::Field& field, const std::vector<uint32_t>* items) {
  vtkSmartPointer<vtkDataArray> a;
  a.TakeReference(vtkDataArray::CreateDataArray(vtkTypeOf(field.type)));
  a->SetName(field.name.c_str());
  a->SetNumberOfComponents(static_cast<int>(field.components));
  a->SetNumberOfTuples(static_cast<vtkIdType>(items ? items->size() : field.itemCount()));
  const size_t item_bytes = field.components * field.valueSize();
  auto* out = static_cast<uint8_t*>(a->GetVoidPointer(0));
  if (!items) {
    if (!field.bytes.empty()) std::memcpy(out, field.bytes.data(), field.bytes.size());
    return a;
  }
  for (size_t i = 0; i < items->size(); ++i)
    std::memcpy(out + i * item_bytes, field.bytes.data() + static_cast<size_t>((*items)[i]) * item_bytes, item_bytes);
  return a;
}

}  // namespace vtkgtn
