// What Gatun's TetGen files record beyond TetGen's numbers, shared by the TetGen importer and
// exporter. TetGen's .node/.ele/.face carry only numeric columns (node attributes, one boundary
// marker, element attributes, face markers); the exporter adds comment lines at the top of the .node
// and the .ele, which TetGen skips, saying what the columns are:
//
//   # gtn-coordinates: float32                     coordinate precision (float32 or float64)
//   # gtn-point-fields: NAME:COMPONENTS:TYPE ...   .node attribute columns, field by field, in order;
//                                                  a trailing ":marker" marks the field held in the
//                                                  boundary-marker column instead
//   # gtn-cell-fields: NAME:COMPONENTS:TYPE ...    .ele attribute columns; ":face" marks the 4-component
//                                                  int32 field held in the .face markers instead
//   # gtn-metadata: KEY VALUE                      one line per metadata entry (in the .node)
//
// NAME, KEY and VALUE are percent-escaped: every byte outside [A-Za-z0-9_.+-] is written %XX, so
// that names hold no space, colon or '#'. Values are written as the shortest text that reads back
// bit-exactly in their type (std::to_chars: float32 values as float32), NaN as nan(0xBITS) with its
// full bit pattern (a form strtod, and so TetGen, also reads).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn::tetgen {

constexpr std::string_view kCoordinatesKey = "gtn-coordinates:";
constexpr std::string_view kPointFieldsKey = "gtn-point-fields:";
constexpr std::string_view kCellFieldsKey = "gtn-cell-fields:";
constexpr std::string_view kMetadataKey = "gtn-metadata:";
constexpr std::string_view kMarkerTag = "marker";
constexpr std::string_view kFaceTag = "face";

// Names TetGen files give to the fields they hold when no gtn- comment names them.
constexpr const char* kBoundaryMarkerName = "boundary_marker";  // .node marker column, int32
constexpr const char* kFaceMarkerName = "face_marker";          // .face markers per local face, int32 x 4
constexpr const char* kRegionName = "region";                   // first .ele attribute, float64

// "x" from "x.node", "x.ele", "x.face" or "x".
std::string basePath(const std::string& path);

// A triangle's vertex indices in increasing order: the key that identifies a face.
std::array<uint32_t, 3> sortedTriangle(uint32_t a, uint32_t b, uint32_t c);

// One field as the gtn-*-fields comments describe it.
struct ColumnField {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat64;
  bool tagged = false;  // held outside the attribute columns (":marker" / ":face")
};

std::string escapeText(std::string_view text);
// False on a malformed %XX sequence.
bool unescapeText(std::string_view text, std::string* out);

// "NAME:COMPONENTS:TYPE[:tag] ..." for the fields; `tag` is appended to tagged ones.
std::string formatFieldList(const std::vector<ColumnField>& fields, std::string_view tag);
// Inverse of formatFieldList; `why` says what is wrong on failure.
bool parseFieldList(std::string_view text, std::string_view tag, std::vector<ColumnField>* fields, std::string* why);

// A gtn- comment line found at the top of a file: `key` includes the colon, `value` is trimmed.
struct Comment {
  size_t line = 0;
  std::string_view key;
  std::string_view value;
};
// The gtn- comments among the comment and blank lines that open `text` (the first other line ends
// the search, so a large file is not scanned).
std::vector<Comment> leadingComments(std::string_view text);

// Appends the shortest text that reads back as exactly the value of type `type` stored at `value`.
void appendValue(std::string* out, ScalarType type, const uint8_t* value);
// Parses `token` as a value of `type` into `value` (scalarSize(type) bytes); false when the token is
// not a number of that type (integers out of the type's range included).
bool parseValue(std::string_view token, ScalarType type, uint8_t* value);

}  // namespace gtn::tetgen
