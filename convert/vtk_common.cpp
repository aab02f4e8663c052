#include "convert/vtk_common.h"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>

#include "convert/text_reader.h"
#include "mesh/fresh_memory.h"

namespace gtn {

const char* vtkCellTypeName(int type) {
  switch (type) {
    case 0: return "VTK_EMPTY_CELL";
    case 1: return "VTK_VERTEX";
    case 2: return "VTK_POLY_VERTEX";
    case 3: return "VTK_LINE";
    case 4: return "VTK_POLY_LINE";
    case 5: return "VTK_TRIANGLE";
    case 6: return "VTK_TRIANGLE_STRIP";
    case 7: return "VTK_POLYGON";
    case 8: return "VTK_PIXEL";
    case 9: return "VTK_QUAD";
    case 10: return "VTK_TETRA";
    case 11: return "VTK_VOXEL";
    case 12: return "VTK_HEXAHEDRON";
    case 13: return "VTK_WEDGE";
    case 14: return "VTK_PYRAMID";
    case 15: return "VTK_PENTAGONAL_PRISM";
    case 16: return "VTK_HEXAGONAL_PRISM";
    case 21: return "VTK_QUADRATIC_EDGE";
    case 22: return "VTK_QUADRATIC_TRIANGLE";
    case 23: return "VTK_QUADRATIC_QUAD";
    case 24: return "VTK_QUADRATIC_TETRA";
    case 25: return "VTK_QUADRATIC_HEXAHEDRON";
    case 26: return "VTK_QUADRATIC_WEDGE";
    case 27: return "VTK_QUADRATIC_PYRAMID";
    case 28: return "VTK_BIQUADRATIC_QUAD";
    case 29: return "VTK_TRIQUADRATIC_HEXAHEDRON";
    case 30: return "VTK_QUADRATIC_LINEAR_QUAD";
    case 31: return "VTK_QUADRATIC_LINEAR_WEDGE";
    case 32: return "VTK_BIQUADRATIC_QUADRATIC_WEDGE";
    case 33: return "VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON";
    case 34: return "VTK_BIQUADRATIC_TRIANGLE";
    case 35: return "VTK_CUBIC_LINE";
    case 36: return "VTK_QUADRATIC_POLYGON";
    case 37: return "VTK_TRIQUADRATIC_PYRAMID";
    case 41: return "VTK_CONVEX_POINT_SET";
    case 42: return "VTK_POLYHEDRON";
    case 51: return "VTK_PARAMETRIC_CURVE";
    case 60: return "VTK_HIGHER_ORDER_CURVE";
    case 61: return "VTK_HIGHER_ORDER_TRIANGLE";
    case 62: return "VTK_HIGHER_ORDER_QUADRILATERAL";
    case 64: return "VTK_HIGHER_ORDER_TETRAHEDRON";
    case 65: return "VTK_HIGHER_ORDER_WEDGE";
    case 67: return "VTK_HIGHER_ORDER_HEXAHEDRON";
    case 68: return "VTK_LAGRANGE_CURVE";
    case 69: return "VTK_LAGRANGE_TRIANGLE";
    case 70: return "VTK_LAGRANGE_QUADRILATERAL";
    case 71: return "VTK_LAGRANGE_TETRAHEDRON";
    case 72: return "VTK_LAGRANGE_HEXAHEDRON";
    case 73: return "VTK_LAGRANGE_WEDGE";
    case 74: return "VTK_LAGRANGE_PYRAMID";
    case 75: return "VTK_BEZIER_CURVE";
    case 76: return "VTK_BEZIER_TRIANGLE";
    case 77: return "VTK_BEZIER_QUADRILATERAL";
    case 78: return "VTK_BEZIER_TETRAHEDRON";
    case 79: return "VTK_BEZIER_HEXAHEDRON";
    case 80: return "VTK_BEZIER_WEDGE";
    case 81: return "VTK_BEZIER_PYRAMID";
    default: return "unknown";
  }
}

namespace {
struct NamedType {
  const char* name;
  ScalarType type;
};
constexpr NamedType kXmlTypes[] = {
    {"Int8", ScalarType::kInt8},
    {"UInt8", ScalarType::kUInt8},
    {"Int16", ScalarType::kInt16},
    {"UInt16", ScalarType::kUInt16},
    {"Int32", ScalarType::kInt32},
    {"UInt32", ScalarType::kUInt32},
    {"Int64", ScalarType::kInt64},
    {"UInt64", ScalarType::kUInt64},
    {"Float32", ScalarType::kFloat32},
    {"Float64", ScalarType::kFloat64},
    // Names written by VTK before the sized names existed.
    {"Char", ScalarType::kInt8},
    {"UnsignedChar", ScalarType::kUInt8},
    {"Short", ScalarType::kInt16},
    {"UnsignedShort", ScalarType::kUInt16},
    {"Int", ScalarType::kInt32},
    {"UnsignedInt", ScalarType::kUInt32},
    {"Float", ScalarType::kFloat32},
    {"Double", ScalarType::kFloat64},
};
constexpr NamedType kLegacyTypes[] = {
    {"char", ScalarType::kInt8},
    {"unsigned_char", ScalarType::kUInt8},
    {"signed_char", ScalarType::kInt8},
    {"short", ScalarType::kInt16},
    {"unsigned_short", ScalarType::kUInt16},
    {"int", ScalarType::kInt32},
    {"unsigned_int", ScalarType::kUInt32},
    {"long", ScalarType::kInt64},
    {"unsigned_long", ScalarType::kUInt64},
    {"vtktypeint64", ScalarType::kInt64},
    {"vtktypeuint64", ScalarType::kUInt64},
    // The sized names of version 5.1 files, which meshio writes for every integer type.
    {"vtktypeint8", ScalarType::kInt8},
    {"vtktypeuint8", ScalarType::kUInt8},
    {"vtktypeint16", ScalarType::kInt16},
    {"vtktypeuint16", ScalarType::kUInt16},
    {"vtktypeint32", ScalarType::kInt32},
    {"vtktypeuint32", ScalarType::kUInt32},
    {"float", ScalarType::kFloat32},
    {"double", ScalarType::kFloat64},
    {"vtkidtype", ScalarType::kInt32},  // VTK writes vtkIdType arrays as 32-bit ints in legacy files
};

constexpr char kBase64Chars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64Value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

void putLittle(std::vector<uint8_t>* out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}
}  // namespace

bool vtkXmlTypeFromName(const std::string& name, ScalarType* out) {
  for (const NamedType& t : kXmlTypes) {
    if (name == t.name) {
      *out = t.type;
      return true;
    }
  }
  return false;
}

const char* vtkXmlTypeName(ScalarType type) { return kXmlTypes[static_cast<int>(type)].name; }

bool vtkLegacyTypeFromName(const std::string& name, ScalarType* out) {
  std::string lower = name;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const NamedType& t : kLegacyTypes) {
    if (lower == t.name) {
      *out = t.type;
      return true;
    }
  }
  return false;
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size() && i < 5; ++i) out += (i ? ", '" : "'") + names[i] + "'";
  if (names.size() > 5) out += ", ...";
  return out;
}

const uint8_t* vtkGhostMarks(const std::vector<Field>& fields, size_t items) {
  for (const Field& f : fields)
    if (f.name == kVtkGhostArray && f.type == ScalarType::kUInt8 && f.components == 1 && f.itemCount() == items)
      return f.bytes.data();
  return nullptr;
}

const char* vtkLegacyTypeName(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8: return "char";
    case ScalarType::kUInt8: return "unsigned_char";
    case ScalarType::kInt16: return "short";
    case ScalarType::kUInt16: return "unsigned_short";
    case ScalarType::kInt32: return "int";
    case ScalarType::kUInt32: return "unsigned_int";
    case ScalarType::kInt64: return "vtktypeint64";
    case ScalarType::kUInt64: return "vtktypeuint64";
    case ScalarType::kFloat32: return "float";
    case ScalarType::kFloat64: return "double";
  }
  return "double";
}

void swapByteOrder(uint8_t* data, size_t bytes, size_t value_size) {
  if (value_size <= 1) return;
  for (size_t i = 0; i + value_size <= bytes; i += value_size) std::reverse(data + i, data + i + value_size);
}

std::string base64Encode(const uint8_t* data, size_t size) {
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= size; i += 3) {
    const uint32_t v = (uint32_t{data[i]} << 16) | (uint32_t{data[i + 1]} << 8) | data[i + 2];
    out += kBase64Chars[v >> 18];
    out += kBase64Chars[(v >> 12) & 63];
    out += kBase64Chars[(v >> 6) & 63];
    out += kBase64Chars[v & 63];
  }
  if (i < size) {
    const uint32_t v = (uint32_t{data[i]} << 16) | (i + 1 < size ? uint32_t{data[i + 1]} << 8 : 0);
    out += kBase64Chars[v >> 18];
    out += kBase64Chars[(v >> 12) & 63];
    out += i + 1 < size ? kBase64Chars[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

size_t base64DecodedSize(std::string_view text) {
  if (text.size() % 4 != 0) return 0;
  size_t n = text.size() / 4 * 3;
  if (!text.empty() && text.back() == '=') --n;
  if (text.size() >= 2 && text[text.size() - 2] == '=') --n;
  return n;
}

bool base64Decode(std::string_view text, std::vector<uint8_t>* out) {
  out->clear();
  if (text.size() % 4 != 0) return false;
  reservePopulated(*out, text.size() / 4 * 3);
  for (size_t i = 0; i < text.size(); i += 4) {
    const bool last = i + 4 == text.size();
    int v[4];
    int pad = 0;
    for (int k = 0; k < 4; ++k) {
      const char c = text[i + k];
      if (c == '=' && last && k >= 2) {
        v[k] = 0;
        ++pad;
      } else {
        if (pad) return false;  // a character after padding
        v[k] = base64Value(c);
        if (v[k] < 0) return false;
      }
    }
    const uint32_t w = (uint32_t(v[0]) << 18) | (uint32_t(v[1]) << 12) | (uint32_t(v[2]) << 6) | uint32_t(v[3]);
    out->push_back(static_cast<uint8_t>(w >> 16));
    if (pad < 2) out->push_back(static_cast<uint8_t>(w >> 8));
    if (pad < 1) out->push_back(static_cast<uint8_t>(w));
  }
  return true;
}

void zlibCompressBlocks(const uint8_t* data, size_t size, size_t block_size, int header_bytes,
                        std::vector<uint8_t>* header, std::vector<uint8_t>* blocks) {
  const size_t num_blocks = (size + block_size - 1) / block_size;
  const size_t last = size % block_size;  // 0: the last block is full (VTK's convention)
  header->clear();
  blocks->clear();
  putLittle(header, num_blocks, header_bytes);
  putLittle(header, block_size, header_bytes);
  putLittle(header, last, header_bytes);
  std::vector<uint8_t> buffer(compressBound(static_cast<uLong>(block_size)));
  for (size_t b = 0; b < num_blocks; ++b) {
    const size_t begin = b * block_size;
    const size_t n = std::min(block_size, size - begin);
    uLongf out_size = static_cast<uLongf>(buffer.size());
    // compress2 cannot fail here: the buffer is compressBound-sized and the level valid.
    compress2(buffer.data(), &out_size, data + begin, static_cast<uLong>(n), Z_DEFAULT_COMPRESSION);
    putLittle(header, out_size, header_bytes);
    blocks->insert(blocks->end(), buffer.data(), buffer.data() + out_size);
  }
}

bool parseScalarToken(std::string_view token, ScalarType type, uint8_t* out) {
  auto store = [out](auto v) {
    std::memcpy(out, &v, sizeof(v));
    return true;
  };
  auto integer = [&](int64_t lo, int64_t hi, auto tag) {
    int64_t v;
    if (!parseInt(token, &v) || v < lo || v > hi) return false;
    return store(static_cast<decltype(tag)>(v));
  };
  switch (type) {
    case ScalarType::kInt8: return integer(INT8_MIN, INT8_MAX, int8_t{});
    case ScalarType::kUInt8: return integer(0, UINT8_MAX, uint8_t{});
    case ScalarType::kInt16: return integer(INT16_MIN, INT16_MAX, int16_t{});
    case ScalarType::kUInt16: return integer(0, UINT16_MAX, uint16_t{});
    case ScalarType::kInt32: return integer(INT32_MIN, INT32_MAX, int32_t{});
    case ScalarType::kUInt32: return integer(0, UINT32_MAX, uint32_t{});
    case ScalarType::kInt64: return integer(INT64_MIN, INT64_MAX, int64_t{});
    case ScalarType::kUInt64: {
      std::string_view t = token;
      if (!t.empty() && t.front() == '+') t.remove_prefix(1);
      uint64_t v;
      auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
      if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) return false;
      return store(v);
    }
    case ScalarType::kFloat32: {
      float v;
      return parseFloat(token, &v) && store(v);
    }
    case ScalarType::kFloat64: {
      double v;
      return parseDouble(token, &v) && store(v);
    }
  }
  return false;
}

namespace {
template <class T>
T loadAs(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
}  // namespace

bool scalarsToInt64(ScalarType type, const uint8_t* data, size_t count, std::vector<int64_t>* out, size_t* bad) {
  resizePopulated(*out, count);
  const size_t s = scalarSize(type);
  for (size_t i = 0; i < count; ++i) {
    const uint8_t* p = data + i * s;
    int64_t v;
    switch (type) {
      case ScalarType::kInt8: v = loadAs<int8_t>(p); break;
      case ScalarType::kUInt8: v = loadAs<uint8_t>(p); break;
      case ScalarType::kInt16: v = loadAs<int16_t>(p); break;
      case ScalarType::kUInt16: v = loadAs<uint16_t>(p); break;
      case ScalarType::kInt32: v = loadAs<int32_t>(p); break;
      case ScalarType::kUInt32: v = loadAs<uint32_t>(p); break;
      case ScalarType::kInt64: v = loadAs<int64_t>(p); break;
      case ScalarType::kUInt64: {
        const uint64_t u = loadAs<uint64_t>(p);
        if (u > static_cast<uint64_t>(INT64_MAX)) {
          *bad = i;
          return false;
        }
        v = static_cast<int64_t>(u);
        break;
      }
      default: *bad = i; return false;
    }
    (*out)[i] = v;
  }
  return true;
}

void scalarsToDouble(ScalarType type, const uint8_t* data, size_t count, std::vector<double>* out) {
  Field view;
  view.type = type;
  view.components = 1;
  view.bytes.assign(data, data + count * scalarSize(type));
  out->resize(count);
  for (size_t i = 0; i < count; ++i) (*out)[i] = view.get(i, 0);
}

Field expandCellField(const Field& per_cell, const std::vector<uint32_t>& tet_cell) {
  Field out(per_cell.name, per_cell.components, per_cell.type, tet_cell.size());
  for (size_t t = 0; t < tet_cell.size(); ++t) out.copyItem(per_cell, tet_cell[t], t);
  return out;
}

}  // namespace gtn
