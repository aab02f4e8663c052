// Legacy VTK (.vtk) import: DATASET UNSTRUCTURED_GRID in ASCII or BINARY (big-endian), the classic
// CELLS layout and the OFFSETS/CONNECTIVITY layout of version 5.1; the 3D structured datasets
// STRUCTURED_GRID (a curvilinear grid, as PLOT3D's), RECTILINEAR_GRID and STRUCTURED_POINTS, whose
// hexahedral cells are split like PLOT3D's (5 with alternating parity or 6); point and cell attributes
// (SCALARS, COLOR_SCALARS, VECTORS, NORMALS, TEXTURE_COORDINATES, TENSORS, TENSORS6, GLOBAL_IDS,
// PEDIGREE_IDS, FIELD) kept in their source types. String arrays (ASCII or BINARY) are skipped.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>

#include "convert/ascii_rows.h"
#include "convert/cell_split.h"
#include "convert/import.h"
#include "convert/text_reader.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"

namespace gtn {

namespace {

std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

// Legacy names encode characters such as spaces as %XX.
std::string decodeName(std::string_view s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += static_cast<char>(std::stoi(std::string(s.substr(i + 1, 2)), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

class LegacyReader {
 public:
  LegacyReader(const std::string& path, std::string_view text) : path_(path), text_(text), tr_(path, text, '\0') {}

  StatusOr<ImportResult> read(const ImportOptions& options);

 private:
  Status header();
  // Reads `count` values of `type` (ASCII tokens, or big-endian binary starting on the next line).
  Status readValues(ScalarType type, uint64_t count, const std::string& what, std::vector<uint8_t>* out);
  StatusOr<std::string> token(const char* what);
  StatusOr<uint64_t> count(const char* what);
  StatusOr<ScalarType> dataType(const std::string& what);
  Status readIndexArray(uint64_t count, const std::string& what, std::vector<int64_t>* out, ScalarType type);
  Status readPoints();
  Status readCells();
  Status readCellTypes();
  Status readAttribute(const std::string& keyword);
  // The structured datasets: DIMENSIONS, ORIGIN, SPACING (or ASPECT_RATIO), X/Y/Z_COORDINATES.
  Status readDimensions();
  Status readTriple(const std::string& keyword, double out[3]);
  Status readAxis(int axis);
  bool structured() const { return dataset_ != Dataset::kNone && dataset_ != Dataset::kUnstructured; }
  uint64_t structuredPoints() const { return dims_[0] * dims_[1] * dims_[2]; }
  uint64_t structuredCells() const { return (dims_[0] - 1) * (dims_[1] - 1) * (dims_[2] - 1); }
  // Checks a structured dataset, makes the points of rectilinear grids and structured points (from
  // the axes, or the origin and spacing) and hands it to finishStructuredImport.
  Status finishStructured(const ImportOptions& options);
  Status readFieldData(std::vector<Field>* into);
  static bool isStringType(std::string_view name);
  // When the data type ahead names strings (STRING, UTF8_STRING): reads past the `kind` array `name`
  // of comps x tuples strings, warns when `warn` (text is not mesh data) and returns true; else reads
  // nothing and returns false.
  StatusOr<bool> skipStringArray(const std::string& kind, const std::string& name, uint64_t comps, uint64_t tuples,
                                 bool warn);
  // Reads past the strings of a string array whose type keyword was just read.
  Status skipStrings(uint64_t comps, uint64_t tuples, const std::string& what);
  void skipMetadata();

  const std::string& path_;
  std::string_view text_;
  TextReader tr_;
  bool binary_ = false;
  bool bits_ahead_ = false;  // dataType read "bit": the next readValues reads a bit array
  enum class Dataset { kNone, kUnstructured, kStructuredGrid, kRectilinear, kStructuredPoints };
  Dataset dataset_ = Dataset::kNone;
  uint64_t dims_[3] = {0, 0, 0};
  bool have_dims_ = false;
  double origin_[3] = {0, 0, 0}, spacing_[3] = {1, 1, 1};
  std::vector<double> axis_[3];
  bool have_axis_[3] = {false, false, false}, axis_f32_[3] = {false, false, false};
  ImportResult result_;
  VtkCells cells_;
  bool have_points_ = false, have_cells_ = false, have_types_ = false;
  // The attribute section being read: 0 none, 1 POINT_DATA, 2 CELL_DATA.
  int section_ = 0;
  uint64_t section_items_ = 0;
  std::vector<Field> cell_fields_;
  // What is read past, for the warnings: METADATA blocks (annotations of arrays) and lookup tables.
  size_t metadata_blocks_ = 0, metadata_line_ = 0;
  uint64_t last_components_ = 1;  // of the array read last: the lines of a METADATA block's COMPONENT_NAMES
  std::vector<std::string> lookup_tables_;
  void warnAboutSkipped();
};

StatusOr<std::string> LegacyReader::token(const char* what) {
  std::string_view t;
  if (!tr_.next(&t)) return tr_.errorAtEnd(what);
  return std::string(t);
}

StatusOr<uint64_t> LegacyReader::count(const char* what) {
  GTN_ASSIGN_OR_RETURN(int64_t v, tr_.readInt(what));
  if (v < 0) return tr_.error(std::string(what) + " is negative");
  return static_cast<uint64_t>(v);
}

StatusOr<ScalarType> LegacyReader::dataType(const std::string& what) {
  GTN_ASSIGN_OR_RETURN(std::string name, token("a data type"));
  ScalarType t;
  if (upper(name) == "BIT") {
    // vtkBitArray: kept as uint8 values 0 and 1 (readValues unpacks the next array).
    bits_ahead_ = true;
    return ScalarType::kUInt8;
  }
  if (!vtkLegacyTypeFromName(name, &t))
    return Status(StatusCode::kUnsupported, path_ + ":" + std::to_string(tr_.line()) + ": " + what + ": data type " +
                                                quotedToken(name) + " is not supported");
  return t;
}

Status LegacyReader::header() {
  const size_t e1 = text_.find('\n');
  if (text_.rfind("# vtk DataFile Version", 0) != 0 || e1 == std::string_view::npos)
    return Status(StatusCode::kNotOurFile, path_ + ":1: not a legacy VTK file (no '# vtk DataFile Version' line)");
  const size_t e2 = text_.find('\n', e1 + 1);  // the title line
  if (e2 == std::string_view::npos) return invalidData(path_ + ":2: file ends in the title line");
  tr_.seek(e2 + 1);
  GTN_ASSIGN_OR_RETURN(std::string mode, token("ASCII or BINARY"));
  const std::string m = upper(mode);
  if (m != "ASCII" && m != "BINARY") return tr_.error("expected ASCII or BINARY, found " + quotedToken(mode));
  binary_ = m == "BINARY";
  return Status::ok();
}

Status LegacyReader::readValues(ScalarType type, uint64_t n, const std::string& what, std::vector<uint8_t>* out) {
  if (bits_ahead_) {
    bits_ahead_ = false;
    if (binary_) {
      // Packed 8 to a byte, the first value in the most significant bit.
      tr_.skipLine();
      const size_t at = tr_.offset();
      const size_t left = at <= text_.size() ? text_.size() - at : 0;
      const uint64_t bytes = n / 8 + (n % 8 != 0);
      if (bytes > left)
        return invalidData(path_ + ": byte offset " + std::to_string(at) + ": file ends inside the binary data of " +
                           what + " (" + std::to_string(n) + " bits need " + std::to_string(bytes) + " bytes, " +
                           std::to_string(left) + " left)");
      out->resize(n);
      for (uint64_t i = 0; i < n; ++i) (*out)[i] = (static_cast<uint8_t>(text_[at + i / 8]) >> (7 - i % 8)) & 1;
      tr_.seek(at + bytes);
      return Status::ok();
    }
    GTN_RETURN_IF_ERROR(readValues(ScalarType::kUInt8, n, what, out));
    for (uint8_t& b : *out) b = b != 0;
    return Status::ok();
  }
  const size_t size = scalarSize(type);
  if (binary_) {
    tr_.skipLine();
    const size_t at = tr_.offset();
    const size_t left = at <= text_.size() ? text_.size() - at : 0;
    if (n > left / size)
      return invalidData(path_ + ": byte offset " + std::to_string(at) + ": file ends inside the binary data of " +
                         what + " (" + std::to_string(n) + " values of " + std::to_string(size) + " bytes need " +
                         std::to_string(n * size) + " bytes, " + std::to_string(left) + " left)");
    out->assign(text_.data() + at, text_.data() + at + n * size);
    swapByteOrder(out->data(), out->size(), size);  // legacy binary is big-endian
    tr_.seek(at + n * size);
    return Status::ok();
  }
  // Every ASCII value takes at least two characters (digit and separator): bounds the allocation.
  if (n > tr_.rest().size() / 2 + 1)
    return tr_.error("file ends before the " + std::to_string(n) + " values of " + what);
  out->resize(n * size);
  std::string_view t;
  for (uint64_t i = 0; i < n; ++i) {
    if (!tr_.next(&t)) return tr_.errorAtEnd(("value " + std::to_string(i) + " of " + what).c_str());
    if (!parseScalarToken(t, type, out->data() + i * size))
      return tr_.error("value " + std::to_string(i) + " of " + what + " is not a " + scalarTypeName(type) + ": " +
                       quotedToken(t));
  }
  return Status::ok();
}

Status LegacyReader::readIndexArray(uint64_t n, const std::string& what, std::vector<int64_t>* out, ScalarType type) {
  last_components_ = 1;
  std::vector<uint8_t> raw;
  GTN_RETURN_IF_ERROR(readValues(type, n, what, &raw));
  size_t bad = 0;
  if (!scalarsToInt64(type, raw.data(), n, out, &bad))
    return tr_.error(what + ": value " + std::to_string(bad) + " is not an index");
  return Status::ok();
}

Status LegacyReader::readPoints() {
  GTN_ASSIGN_OR_RETURN(uint64_t n, count("point count"));
  GTN_ASSIGN_OR_RETURN(ScalarType type, dataType("POINTS"));
  std::vector<uint8_t> raw;
  if (n > UINT64_MAX / 3) return tr_.error("point count too large");
  last_components_ = 3;
  GTN_RETURN_IF_ERROR(readValues(type, 3 * n, "POINTS", &raw));
  scalarsToDouble(type, raw.data(), 3 * n, &result_.mesh.coords);
  result_.mesh.coord_type = type == ScalarType::kFloat32 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  have_points_ = true;
  return Status::ok();
}

Status LegacyReader::readCells() {
  GTN_ASSIGN_OR_RETURN(uint64_t a, count("cell count"));
  GTN_ASSIGN_OR_RETURN(uint64_t b, count("cell list size"));
  const size_t cells_line = tr_.line();
  TextReader peek = tr_;
  std::string_view t;
  if (peek.next(&t) && upper(t) == "OFFSETS") {
    // Version 5.1: CELLS <offsets> <connectivity>, then the two arrays with their own types.
    tr_.next(&t);
    GTN_ASSIGN_OR_RETURN(ScalarType ot, dataType("OFFSETS"));
    GTN_RETURN_IF_ERROR(readIndexArray(a, "OFFSETS", &cells_.offsets, ot));
    GTN_ASSIGN_OR_RETURN(std::string kw, token("CONNECTIVITY"));
    if (upper(kw) != "CONNECTIVITY") return tr_.error("expected CONNECTIVITY after OFFSETS, found " + quotedToken(kw));
    GTN_ASSIGN_OR_RETURN(ScalarType ct, dataType("CONNECTIVITY"));
    GTN_RETURN_IF_ERROR(readIndexArray(b, "CONNECTIVITY", &cells_.connectivity, ct));
    if (cells_.offsets.empty()) cells_.offsets.push_back(0);
    for (size_t i = 1; i < cells_.offsets.size(); ++i)
      if (cells_.offsets[i] < cells_.offsets[i - 1]) return tr_.error("OFFSETS decrease at entry " + std::to_string(i));
  } else {
    // Classic layout: per cell its point count, then the points (int32 in binary files).
    std::vector<int64_t> list;
    GTN_RETURN_IF_ERROR(readIndexArray(b, "CELLS", &list, ScalarType::kInt32));
    // Every cell takes at least its count from the list: checked before anything is reserved.
    if (a > list.size())
      return invalidData(path_ + ":" + std::to_string(cells_line) + ": CELLS: " + std::to_string(a) +
                         " cells cannot fit in a list of " + std::to_string(list.size()) + " numbers");
    cells_.offsets.assign(1, 0);
    cells_.connectivity.clear();
    cells_.offsets.reserve(a + 1);
    cells_.connectivity.reserve(b);
    size_t pos = 0;
    for (uint64_t c = 0; c < a; ++c) {
      if (pos >= list.size())
        return tr_.error("CELLS: the list of " + std::to_string(b) + " numbers ends at cell " + std::to_string(c) +
                         " of " + std::to_string(a));
      const int64_t k = list[pos++];
      if (k < 0 || static_cast<uint64_t>(k) > list.size() - pos)
        return tr_.error("CELLS: cell " + std::to_string(c) + " has " + std::to_string(k) +
                         " points, more than the list holds");
      cells_.connectivity.insert(cells_.connectivity.end(), list.begin() + pos, list.begin() + pos + k);
      pos += k;
      cells_.offsets.push_back(static_cast<int64_t>(cells_.connectivity.size()));
    }
    if (pos != list.size())
      return tr_.error("CELLS: " + std::to_string(list.size() - pos) + " numbers left over after " + std::to_string(a) +
                       " cells");
  }
  have_cells_ = true;
  return Status::ok();
}

Status LegacyReader::readCellTypes() {
  GTN_ASSIGN_OR_RETURN(uint64_t n, count("cell type count"));
  std::vector<int64_t> types;
  GTN_RETURN_IF_ERROR(readIndexArray(n, "CELL_TYPES", &types, ScalarType::kInt32));
  cells_.types.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (types[i] < 0 || types[i] > 255)
      return tr_.error("CELL_TYPES: cell " + std::to_string(i) + " has type " + std::to_string(types[i]) +
                       ", not a VTK cell type");
    cells_.types[i] = static_cast<int32_t>(types[i]);
  }
  have_types_ = true;
  return Status::ok();
}

void LegacyReader::skipMetadata() {
  // METADATA blocks (version 5.1) end at the first empty line, but for the lines after COMPONENT_NAMES:
  // one per component of the array before the block, empty for a component without a name.
  if (metadata_blocks_++ == 0) metadata_line_ = tr_.line();
  tr_.skipLine();
  uint64_t name_lines = 0;
  while (tr_.offset() < text_.size()) {
    const size_t at = tr_.offset();
    size_t end = text_.find('\n', at);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view line = text_.substr(at, end - at);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.remove_prefix(1);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.remove_suffix(1);
    tr_.skipLine();
    if (name_lines > 0) {
      --name_lines;
      continue;
    }
    if (line.empty()) break;
    if (upper(line) == "COMPONENT_NAMES") name_lines = last_components_;
  }
}

void LegacyReader::warnAboutSkipped() {
  if (metadata_blocks_ > 0)
    result_.report.warnings.push_back("skipped " + std::to_string(metadata_blocks_) + " METADATA block" +
                                      (metadata_blocks_ > 1 ? "s" : "") + " (line " + std::to_string(metadata_line_) +
                                      (metadata_blocks_ > 1 ? " and on" : "") +
                                      "): component names and information keys of arrays, not read");
  if (!lookup_tables_.empty())
    result_.report.warnings.push_back("skipped " + std::to_string(lookup_tables_.size()) + " LOOKUP_TABLE definition" +
                                      (lookup_tables_.size() > 1 ? "s" : "") + " (" + joinNames(lookup_tables_) +
                                      "): colour tables are not read");
}

Status LegacyReader::readFieldData(std::vector<Field>* into) {
  std::vector<std::string> dataset_arrays;  // into == nullptr: the names of what is read past
  const size_t field_line = tr_.line();     // of the FIELD keyword
  GTN_ASSIGN_OR_RETURN(std::string field_name, token("field name"));
  GTN_ASSIGN_OR_RETURN(uint64_t arrays, count("array count"));
  for (uint64_t a = 0; a < arrays; ++a) {
    GTN_ASSIGN_OR_RETURN(std::string name, token("array name"));
    if (upper(name) == "METADATA") {  // belongs to the previous array
      skipMetadata();
      --a;
      continue;
    }
    if (name == "NULL_ARRAY") continue;  // vtkDataWriter's line for an array that is null: nothing follows
    GTN_ASSIGN_OR_RETURN(uint64_t comps, count("component count"));
    GTN_ASSIGN_OR_RETURN(uint64_t tuples, count("tuple count"));
    last_components_ = comps;
    GTN_ASSIGN_OR_RETURN(const bool strings, skipStringArray("FIELD array", name, comps, tuples, into != nullptr));
    if (strings) {
      if (!into) dataset_arrays.push_back(decodeName(name));
      continue;
    }
    GTN_ASSIGN_OR_RETURN(ScalarType type, dataType("FIELD array " + name));
    if (comps == 0 || comps > 4096) return tr_.error("FIELD array " + name + ": bad component count");
    if (tuples > UINT64_MAX / comps) return tr_.error("FIELD array " + name + ": too many values");
    Field f(decodeName(name), static_cast<uint32_t>(comps), type, 0);
    GTN_RETURN_IF_ERROR(readValues(type, comps * tuples, "FIELD array " + name, &f.bytes));
    if (into) {
      if (tuples != section_items_)
        return tr_.error("FIELD array " + name + " has " + std::to_string(tuples) + " tuples, expected " +
                         std::to_string(section_items_));
      into->push_back(std::move(f));
    } else {
      dataset_arrays.push_back(f.name);
    }
  }
  // The dataset's own arrays (TIME, CYCLE, ...) describe no point or cell: a warning names them.
  if (!into && !dataset_arrays.empty())
    result_.report.warnings.push_back("line " + std::to_string(field_line) + ": the dataset's FIELD arrays (" +
                                      joinNames(dataset_arrays) + ") are not kept: they belong to no point or cell");
  return Status::ok();
}

bool LegacyReader::isStringType(std::string_view name) {
  const std::string u = upper(name);
  return u == "STRING" || u == "UTF8_STRING";
}

StatusOr<bool> LegacyReader::skipStringArray(const std::string& kind, const std::string& name, uint64_t comps,
                                             uint64_t tuples, bool warn) {
  TextReader peek = tr_;
  std::string_view type_name;
  if (!peek.next(&type_name) || !isStringType(type_name)) return false;
  tr_.next(&type_name);
  GTN_RETURN_IF_ERROR(skipStrings(comps, tuples, kind + " " + name));
  if (warn)
    result_.report.warnings.push_back("line " + std::to_string(tr_.line()) + ": skipped " + kind + " " +
                                      decodeName(name) + " (" + std::string(type_name) + "): text is not mesh data");
  return true;
}

Status LegacyReader::skipStrings(uint64_t comps, uint64_t tuples, const std::string& what) {
  if (comps != 0 && tuples > UINT64_MAX / comps) return tr_.error(what + ": too many values");
  const uint64_t n = comps * tuples;
  tr_.skipLine();  // the rest of the array's header line
  if (binary_) {
    // vtkDataWriter writes each string as a big-endian length header and its bytes: the first byte's
    // two high bits give the header's size (3: one byte, 2: two, 1: four, 0: eight bytes) and the
    // rest of the header, without those two bits (all 64 bits for the eight-byte one), the length.
    uint64_t at = tr_.offset();
    const uint64_t size = text_.size();
    if (n > size - std::min(at, size))
      return invalidData(path_ + ": byte offset " + std::to_string(at) + ": " + what + ": " + std::to_string(n) +
                         " strings cannot fit in the " + std::to_string(size - std::min(at, size)) + " bytes left");
    for (uint64_t i = 0; i < n; ++i) {
      if (at >= size)
        return invalidData(path_ + ": byte offset " + std::to_string(at) + ": file ends after " + std::to_string(i) +
                           " of the " + std::to_string(n) + " strings of " + what);
      const unsigned kind = static_cast<unsigned char>(text_[at]) >> 6;
      const uint64_t header = kind == 3 ? 1 : kind == 2 ? 2 : kind == 1 ? 4 : 8;
      if (header > size - at)
        return invalidData(path_ + ": byte offset " + std::to_string(at) + ": file ends inside the length of string " +
                           std::to_string(i + 1) + " of " + what);
      uint64_t length = 0;
      for (uint64_t b = 0; b < header; ++b) length = length << 8 | static_cast<unsigned char>(text_[at + b]);
      if (header < 8) length &= (uint64_t{1} << (8 * header - 2)) - 1;
      if (length > size - at - header)
        return invalidData(path_ + ": byte offset " + std::to_string(at) + ": string " + std::to_string(i + 1) +
                           " of " + what + " is " + std::to_string(length) + " bytes long, past the end of the file");
      at += header + length;
    }
    tr_.seek(at);
    return Status::ok();
  }
  // VTK writes one string per line, %-encoded (so an empty string is an empty line).
  for (uint64_t i = 0; i < n; ++i) {
    if (tr_.offset() >= text_.size())
      return tr_.error("file ends after " + std::to_string(i) + " of the " + std::to_string(n) + " strings of " + what);
    tr_.skipLine();
  }
  return Status::ok();
}

Status LegacyReader::readAttribute(const std::string& kw) {
  std::vector<Field>* into = section_ == 1 ? &result_.mesh.point_fields : &cell_fields_;
  if (kw == "FIELD") return readFieldData(into);
  GTN_ASSIGN_OR_RETURN(std::string name, token("attribute name"));
  uint64_t comps = 0;
  ScalarType type = ScalarType::kFloat32;
  if (kw == "SCALARS") {
    GTN_ASSIGN_OR_RETURN(type, dataType("SCALARS " + name));
    comps = 1;
    std::string_view t;
    if (tr_.nextOnLine(&t)) {
      int64_t c;
      if (!parseInt(t, &c) || c < 1 || c > 4) return tr_.error("SCALARS " + name + ": bad component count");
      comps = static_cast<uint64_t>(c);
    }
    TextReader peek = tr_;
    if (peek.next(&t) && upper(t) == "LOOKUP_TABLE") {
      tr_.next(&t);
      GTN_ASSIGN_OR_RETURN(std::string table, token("lookup table name"));
    }
  } else if (kw == "COLOR_SCALARS") {
    GTN_ASSIGN_OR_RETURN(comps, count("component count"));
    if (comps < 1 || comps > 4) return tr_.error("COLOR_SCALARS " + name + ": bad component count");
    type = binary_ ? ScalarType::kUInt8 : ScalarType::kFloat32;
  } else if (kw == "LOOKUP_TABLE") {
    // A table definition (colours for SCALARS): not mesh data, read past it.
    GTN_ASSIGN_OR_RETURN(uint64_t entries, count("lookup table size"));
    if (entries > UINT64_MAX / 4) return tr_.error("lookup table too large");
    std::vector<uint8_t> skipped;
    lookup_tables_.push_back(name);
    return readValues(binary_ ? ScalarType::kUInt8 : ScalarType::kFloat32, 4 * entries, "LOOKUP_TABLE " + name,
                      &skipped);
  } else if (kw == "GLOBAL_IDS" || kw == "PEDIGREE_IDS") {
    // One id per item; pedigree ids may be strings, which are not mesh data.
    if (kw == "PEDIGREE_IDS") {
      last_components_ = 1;
      GTN_ASSIGN_OR_RETURN(const bool strings, skipStringArray(kw, name, 1, section_items_, true));
      if (strings) return Status::ok();
    }
    GTN_ASSIGN_OR_RETURN(type, dataType(kw + " " + name));
    comps = 1;
  } else if (kw == "VECTORS" || kw == "NORMALS") {
    GTN_ASSIGN_OR_RETURN(type, dataType(kw + " " + name));
    comps = 3;
  } else if (kw == "TENSORS" || kw == "TENSORS6") {
    GTN_ASSIGN_OR_RETURN(type, dataType(kw + " " + name));
    comps = kw == "TENSORS" ? 9 : 6;
  } else if (kw == "TEXTURE_COORDINATES") {
    GTN_ASSIGN_OR_RETURN(comps, count("dimension"));
    if (comps < 1 || comps > 3) return tr_.error("TEXTURE_COORDINATES " + name + ": bad dimension");
    GTN_ASSIGN_OR_RETURN(type, dataType(kw + " " + name));
  } else {
    return tr_.error("unknown keyword " + quotedToken(kw));
  }
  Field f(decodeName(name), static_cast<uint32_t>(comps), type, 0);
  if (section_items_ > UINT64_MAX / comps) return tr_.error(kw + " " + name + ": too many values");
  last_components_ = comps;
  GTN_RETURN_IF_ERROR(readValues(type, comps * section_items_, kw + " " + name, &f.bytes));
  if (kw == "COLOR_SCALARS" && !binary_) {
    // ASCII colours are written as floats in [0, 1]; VTK's reader makes them the bytes the binary
    // form holds (255 v + 0.5, truncated), and so does this one.
    Field bytes(f.name, f.components, ScalarType::kUInt8, section_items_);
    const float* v = f.data<float>();
    for (size_t i = 0; i < bytes.bytes.size(); ++i)
      bytes.bytes[i] = static_cast<uint8_t>(std::clamp(255.0 * static_cast<double>(v[i]) + 0.5, 0.0, 255.0));
    f = std::move(bytes);
  }
  into->push_back(std::move(f));
  return Status::ok();
}

Status LegacyReader::readDimensions() {
  for (int a = 0; a < 3; ++a) {
    GTN_ASSIGN_OR_RETURN(dims_[a], count("a DIMENSIONS value"));
  }
  for (int a = 0; a < 3; ++a)
    if (dims_[a] < 2)
      return Status(StatusCode::kUnsupported,
                    tr_.error("DIMENSIONS " + std::to_string(dims_[0]) + " " + std::to_string(dims_[1]) + " " +
                              std::to_string(dims_[2]) +
                              ": a structured dataset with fewer than 2 points along an axis has no volume cells; "
                              "only 3D grids can be split into tetrahedra")
                        .message());
  // Point indices are 32-bit. And the points of RECTILINEAR_GRID and STRUCTURED_POINTS are not in
  // the file: a few bytes could declare billions of them, so their number is bounded by the file's
  // size (any point data takes at least a byte per point).
  const uint64_t limit = dataset_ == Dataset::kStructuredGrid
                             ? UINT32_MAX
                             : std::min<uint64_t>(UINT32_MAX, 64 * text_.size() + (1u << 20));
  if (dims_[0] > limit || dims_[1] > limit / dims_[0] || dims_[2] > limit / (dims_[0] * dims_[1]))
    return tr_.error("DIMENSIONS " + std::to_string(dims_[0]) + " " + std::to_string(dims_[1]) + " " +
                     std::to_string(dims_[2]) + " declare more points than " +
                     (limit == UINT32_MAX ? std::string("32-bit indices can number")
                                          : "a file of " + std::to_string(text_.size()) + " bytes describes"));
  have_dims_ = true;
  return Status::ok();
}

Status LegacyReader::readTriple(const std::string& keyword, double out[3]) {
  for (int a = 0; a < 3; ++a) {
    GTN_ASSIGN_OR_RETURN(out[a], tr_.readDouble((keyword + " value").c_str()));
    if (!std::isfinite(out[a])) return tr_.error(keyword + ": value " + std::to_string(a) + " is not finite");
  }
  return Status::ok();
}

Status LegacyReader::readAxis(int axis) {
  const std::string what = std::string(1, static_cast<char>('X' + axis)) + "_COORDINATES";
  GTN_ASSIGN_OR_RETURN(uint64_t n, count("coordinate count"));
  GTN_ASSIGN_OR_RETURN(ScalarType type, dataType(what));
  last_components_ = 1;
  if (have_dims_ && n != dims_[axis])
    return tr_.error(what + " " + std::to_string(n) + " does not match DIMENSIONS (" + std::to_string(dims_[axis]) +
                     " along this axis)");
  std::vector<uint8_t> raw;
  GTN_RETURN_IF_ERROR(readValues(type, n, what, &raw));
  scalarsToDouble(type, raw.data(), n, &axis_[axis]);
  for (double v : axis_[axis])
    if (!std::isfinite(v)) return tr_.error(what + ": a coordinate is not finite");
  have_axis_[axis] = true;
  axis_f32_[axis] = type == ScalarType::kFloat32;
  return Status::ok();
}

Status LegacyReader::finishStructured(const ImportOptions& options) {
  const char* name = dataset_ == Dataset::kStructuredGrid ? "STRUCTURED_GRID"
                     : dataset_ == Dataset::kRectilinear  ? "RECTILINEAR_GRID"
                                                          : "STRUCTURED_POINTS";
  if (!have_dims_) return invalidData(path_ + ": DATASET " + name + " without DIMENSIONS");
  const uint64_t nx = dims_[0], ny = dims_[1], nz = dims_[2], np = structuredPoints();
  TetMesh& mesh = result_.mesh;
  if (dataset_ == Dataset::kStructuredGrid) {
    if (!have_points_) return invalidData(path_ + ": no POINTS section");
    if (mesh.numPoints() != np)
      return invalidData(path_ + ": POINTS " + std::to_string(mesh.numPoints()) + " does not match DIMENSIONS (" +
                         std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz) + " = " +
                         std::to_string(np) + " points)");
  } else if (dataset_ == Dataset::kRectilinear) {
    for (int a = 0; a < 3; ++a) {
      const std::string what = std::string(1, static_cast<char>('X' + a)) + "_COORDINATES";
      if (!have_axis_[a]) return invalidData(path_ + ": RECTILINEAR_GRID without " + what);
      // (An axis read before DIMENSIONS was not checked against it.)
      if (axis_[a].size() != dims_[a])
        return invalidData(path_ + ": " + what + " has " + std::to_string(axis_[a].size()) + " values but DIMENSIONS " +
                           std::to_string(dims_[a]) + " along this axis");
    }
    rectilinearPoints(axis_, &mesh.coords);
    mesh.coord_type = axis_f32_[0] && axis_f32_[1] && axis_f32_[2] ? ScalarType::kFloat32 : ScalarType::kFloat64;
  } else {
    // VTK's image data: point (i, j, k) at origin + (i, j, k) * spacing.
    const int64_t first[3] = {0, 0, 0};
    imagePoints(dims_, first, origin_, spacing_, nullptr, &mesh.coords);
    mesh.coord_type = ScalarType::kFloat64;
  }
  return finishStructuredImport(path_, dims_, cell_fields_, options, &result_);
}

StatusOr<ImportResult> LegacyReader::read(const ImportOptions& options) {
  GTN_RETURN_IF_ERROR(header());
  bool have_dataset = false;
  std::string_view t;
  while (tr_.next(&t)) {
    const std::string kw = upper(t);
    if (kw == "DATASET") {
      GTN_ASSIGN_OR_RETURN(std::string type, token("dataset type"));
      const std::string u = upper(type);
      if (u == "UNSTRUCTURED_GRID") {
        dataset_ = Dataset::kUnstructured;
      } else if (u == "STRUCTURED_GRID") {
        dataset_ = Dataset::kStructuredGrid;
      } else if (u == "RECTILINEAR_GRID") {
        dataset_ = Dataset::kRectilinear;
      } else if (u == "STRUCTURED_POINTS") {
        dataset_ = Dataset::kStructuredPoints;
      } else {
        return Status(StatusCode::kUnsupported,
                      path_ + ":" + std::to_string(tr_.line()) + ": DATASET " + type +
                          " is not supported (it holds no volume cells: only UNSTRUCTURED_GRID, STRUCTURED_GRID, "
                          "RECTILINEAR_GRID and STRUCTURED_POINTS do)");
      }
      have_dataset = true;
    } else if (kw == "DIMENSIONS" && structured() && section_ == 0) {
      GTN_RETURN_IF_ERROR(readDimensions());
    } else if (kw == "ORIGIN" && dataset_ == Dataset::kStructuredPoints && section_ == 0) {
      GTN_RETURN_IF_ERROR(readTriple(kw, origin_));
    } else if ((kw == "SPACING" || kw == "ASPECT_RATIO") && dataset_ == Dataset::kStructuredPoints && section_ == 0) {
      GTN_RETURN_IF_ERROR(readTriple(kw, spacing_));
    } else if ((kw == "X_COORDINATES" || kw == "Y_COORDINATES" || kw == "Z_COORDINATES") &&
               dataset_ == Dataset::kRectilinear && section_ == 0) {
      GTN_RETURN_IF_ERROR(readAxis(kw[0] - 'X'));
    } else if (kw == "POINTS" && (dataset_ == Dataset::kUnstructured || dataset_ == Dataset::kStructuredGrid)) {
      GTN_RETURN_IF_ERROR(readPoints());
    } else if (kw == "CELLS") {
      GTN_RETURN_IF_ERROR(readCells());
    } else if (kw == "CELL_TYPES") {
      GTN_RETURN_IF_ERROR(readCellTypes());
    } else if (kw == "POINT_DATA" || kw == "CELL_DATA") {
      GTN_ASSIGN_OR_RETURN(section_items_, count("item count"));
      section_ = kw == "POINT_DATA" ? 1 : 2;
      uint64_t expected = section_ == 1 ? result_.mesh.numPoints() : cells_.types.size();
      if (structured()) {
        if (!have_dims_) return tr_.error(kw + " before DIMENSIONS");
        expected = section_ == 1 ? structuredPoints() : structuredCells();
      }
      if (section_items_ != expected)
        return tr_.error(kw + " " + std::to_string(section_items_) + " does not match the " + std::to_string(expected) +
                         (section_ == 1 ? " points" : " cells"));
    } else if (kw == "METADATA") {
      skipMetadata();
    } else if (kw == "FIELD" && section_ == 0) {
      GTN_RETURN_IF_ERROR(readFieldData(nullptr));  // dataset-level field data (TIME, ...): not mesh data
    } else if (section_ != 0) {
      GTN_RETURN_IF_ERROR(readAttribute(kw));
    } else {
      return tr_.error("unexpected keyword " + quotedToken(t));
    }
  }
  if (!have_dataset) return invalidData(path_ + ": no DATASET line");
  warnAboutSkipped();
  if (structured()) {
    GTN_RETURN_IF_ERROR(finishStructured(options));
    return std::move(result_);
  }
  if (!have_points_) return invalidData(path_ + ": no POINTS section");
  // VTK's writer leaves both out for a grid without cells (read as such, like a .vtu of 0 cells).
  if (have_cells_ != have_types_)
    return invalidData(path_ +
                       (have_cells_ ? ": CELLS without a CELL_TYPES section" : ": CELL_TYPES without a CELLS section"));
  if (cells_.types.size() + 1 != cells_.offsets.size())
    return invalidData(path_ + ": CELL_TYPES lists " + std::to_string(cells_.types.size()) + " cells but CELLS " +
                       std::to_string(cells_.offsets.size() - 1));
  GTN_RETURN_IF_ERROR(finishVtkImport(path_, cells_, cell_fields_, options, &result_));
  return std::move(result_);
}

}  // namespace

StatusOr<ImportResult> importVtkLegacy(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(std::string text, readWholeFile(path));
  LegacyReader reader(path, text);
  return reader.read(options);
}

}  // namespace gtn
