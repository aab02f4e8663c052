// What the legacy VTK and VTK XML readers and the .vtu writer share: type names of both dialects,
// cell type names, byte swapping, zlib block framing (vtkZLibDataCompressor) and base64.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// VTK cell type numbers this project reads (others are rejected by name).
constexpr uint8_t kVtkTetra = 10;
constexpr uint8_t kVtkVoxel = 11;
constexpr uint8_t kVtkHexahedron = 12;
constexpr uint8_t kVtkWedge = 13;
constexpr uint8_t kVtkPyramid = 14;
constexpr uint8_t kVtkPentagonalPrism = 15;
constexpr uint8_t kVtkHexagonalPrism = 16;
constexpr uint8_t kVtkPolyhedron = 42;
constexpr uint8_t kVtkQuadraticTetra = 24;
constexpr uint8_t kVtkQuadraticHexahedron = 25;
constexpr uint8_t kVtkQuadraticWedge = 26;
constexpr uint8_t kVtkQuadraticPyramid = 27;
constexpr uint8_t kVtkTriquadraticHexahedron = 29;
constexpr uint8_t kVtkLagrangeWedge = 73;
constexpr uint8_t kVtkBezierWedge = 80;

// vtkGhostType, VTK's marks of ghost and blanked points and cells (vtkDataSetAttributes): a
// duplicate is a copy of what another piece owns, a hidden one is not part of the dataset (blanking).
constexpr char kVtkGhostArray[] = "vtkGhostType";
constexpr uint8_t kVtkDuplicatePoint = 1, kVtkHiddenPoint = 2;
constexpr uint8_t kVtkDuplicateCell = 1, kVtkHiddenCell = 32;
// The marks of `fields`' ghost array when it is VTK's (UInt8, one component, `items` values), or null.
const uint8_t* vtkGhostMarks(const std::vector<Field>& fields, size_t items);

// Array names for a warning, quoted: "'TIME', 'CYCLE'", the first five and "..." after them.
std::string joinNames(const std::vector<std::string>& names);

// "VTK_TETRA", "VTK_QUADRATIC_HEXAHEDRON", ... or "unknown" for numbers VTK does not define.
const char* vtkCellTypeName(int type);

// XML DataArray type attribute ("Float32", "UInt8", old names "Int", "Float", ...) to a ScalarType.
bool vtkXmlTypeFromName(const std::string& name, ScalarType* out);
// The XML name VTK writes for a ScalarType ("Int8" ... "Float64").
const char* vtkXmlTypeName(ScalarType type);
// Legacy data type keyword ("float", "unsigned_short", "vtktypeint64", ...) to a ScalarType. "long"
// and "unsigned_long" are 64-bit, as VTK reads them on LP64 systems.
bool vtkLegacyTypeFromName(const std::string& name, ScalarType* out);
// The legacy keyword VTK's writer uses for a ScalarType ("char", ..., "vtktypeint64", "double").
const char* vtkLegacyTypeName(ScalarType type);

// Reverses the byte order of each `value_size`-byte value in place.
void swapByteOrder(uint8_t* data, size_t bytes, size_t value_size);

// Standard base64 (RFC 4648, '=' padding). Decoding ignores nothing: `text` must hold only base64
// characters; returns false on a bad character, misplaced padding or a length not a multiple of 4.
std::string base64Encode(const uint8_t* data, size_t size);
bool base64Decode(std::string_view text, std::vector<uint8_t>* out);
// Exact decoded size of a well-formed base64 text (padding accounted for).
size_t base64DecodedSize(std::string_view text);

// vtkZLibDataCompressor framing: header [nblocks, blocksize, lastblocksize, csize_0 ...] in
// `header_bytes`-wide little-endian integers, then the compressed blocks. Returns header and blocks
// separately so that the base64 writer can encode them the way VTK does (apart).
void zlibCompressBlocks(const uint8_t* data, size_t size, size_t block_size, int header_bytes,
                        std::vector<uint8_t>* header, std::vector<uint8_t>* blocks);

// Parses one text token as a value of `type` and stores it, little-endian, at `out`; false when the
// token is not a number of that type (integers must be in range, without a fraction).
bool parseScalarToken(std::string_view token, ScalarType type, uint8_t* out);

// Converts `count` little-endian values of `type` to int64 (false at a value that is not an integer
// representable in int64: a float, or an unsigned value above INT64_MAX; *bad gets its index) or to
// double.
bool scalarsToInt64(ScalarType type, const uint8_t* data, size_t count, std::vector<int64_t>* out, size_t* bad);
void scalarsToDouble(ScalarType type, const uint8_t* data, size_t count, std::vector<double>* out);

// Expands a per-cell field to one item per tetrahedron: tet t takes the value of cell tet_cell[t].
Field expandCellField(const Field& per_cell, const std::vector<uint32_t>& tet_cell);

}  // namespace gtn
