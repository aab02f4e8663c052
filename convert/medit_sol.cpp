// Medit solution files (.sol ASCII, .solb binary), the per-vertex and per-element values that Medit,
// MMG, FreeFem and libMeshb write beside a .mesh/.meshb: SolAtVertices becomes point fields,
// SolAtTetrahedra cell fields (of a mesh of tetrahedra only: the tetrahedra then keep the order of the
// file's Tetrahedra section). Other SolAt* sections (of faces, edges, or of elements that are split)
// are skipped with a warning.
//
// A solution section: a line count, a type count, the types (1 scalar, 2 vector of `dimension`
// components, 3 symmetric matrix of d(d+1)/2, 4 full matrix of d^2), then per line the values of
// every type in order. Reals are 32-bit in version 1, 64-bit from version 2. In binary (libMeshb's
// layout, read by GmfBinary as for .meshb): the line count is an int32 (int64 in version 4), the type
// count and the types are int32 in every version.
#include <cstring>

#include "convert/ascii_rows.h"
#include "convert/gmf_binary.h"
#include "convert/medit_cells.h"
#include "convert/text_reader.h"
#include "format/file_io.h"

namespace gtn {

namespace {

constexpr uint32_t kDimension = 3, kSolAtVertices = 62, kSolAtTetrahedra = 66;
// Keyword codes of the other solution sections (skipped): SolAtPyramids, SolAtEdges .. SolAtHexahedra,
// DSolAtVertices.
bool otherSolutionKeyword(uint32_t code) { return code == 26 || (code >= 63 && code <= 69 && code != 66); }

constexpr int64_t kMaxTypes = 1000;  // libMeshb's GmfMaxTyp

// Components of a solution type in 3D, 0 for an unknown type.
uint32_t typeComponents(int64_t type) {
  switch (type) {
    case 1: return 1;
    case 2: return 3;
    case 3: return 6;
    case 4: return 9;
    default: return 0;
  }
}

// The fields a solution section fills, named after the file ("u" for u.sol; "u_1", "u_2" ... when
// the section has several types) unless the mesh already has the name.
class SolutionTarget {
 public:
  SolutionTarget(const std::string& path, ImportResult* result) : result_(result) {
    const size_t slash = path.find_last_of('/');
    stem_ = path.substr(slash == std::string::npos ? 0 : slash + 1);
    const size_t dot = stem_.find_last_of('.');
    if (dot != std::string::npos && dot > 0) stem_.resize(dot);
  }
  // Fields for `types` on `items` entries (cells when `cells`), in the value type of `version`.
  std::vector<Field> make(const std::vector<int64_t>& types, size_t items, int version, bool cells) const {
    std::vector<Field> out;
    const std::vector<Field>& existing = cells ? result_->mesh.cell_fields : result_->mesh.point_fields;
    for (size_t k = 0; k < types.size(); ++k) {
      std::string name = types.size() == 1 ? stem_ : stem_ + "_" + std::to_string(k + 1);
      for (const Field& f : existing)
        if (f.name == name) name += "_sol";
      out.emplace_back(name, typeComponents(types[k]), version == 1 ? ScalarType::kFloat32 : ScalarType::kFloat64,
                       items);
    }
    return out;
  }

 private:
  ImportResult* result_;
  std::string stem_;
};

// What a section must match: the mesh's vertices, or its tetrahedra (when it has only those).
struct SectionTarget {
  size_t items;
  bool cells;
};

class SolutionReader {
 public:
  SolutionReader(const std::string& path, bool tets_only, ImportResult* result)
      : path_(path), tets_only_(tets_only), result_(result), target_(path, result) {}

  Status readAscii(const std::string& text);
  Status readBinary(const std::string& bytes);
  bool sawSolution() const { return saw_solution_; }

 private:
  // The entries of `section` (a keyword) must number what the mesh has; nullopt-like `ok` false for a
  // section that is skipped (its warning given).
  StatusOr<bool> accept(const char* section, bool cells, int64_t count, size_t* items) {
    saw_solution_ = true;
    if (cells && !tets_only_) {
      result_->report.warnings.push_back(path_ + ": " + section +
                                         " skipped: the mesh's other elements were split into tetrahedra, which "
                                         "element values do not follow");
      return false;
    }
    *items = cells ? result_->mesh.numTets() : result_->mesh.numPoints();
    if (count != static_cast<int64_t>(*items))
      return Status(invalidData(path_ + ": " + section + " has " + std::to_string(count) +
                                " entries but the mesh has " + std::to_string(*items) +
                                (cells ? " tetrahedra" : " vertices")));
    return true;
  }
  // Keeps the fields of one section (`types`, in order). A symmetric matrix (type 3) is stored by
  // Medit as its lower triangle by rows, m11 m21 m22 m31 m32 m33; its components are put in VTK's
  // order for 6-component tensors, XX YY ZZ XY YZ XZ, which every exported file and viewer
  // assumes, and a warning says so.
  void store(std::vector<Field>* fields, const std::vector<int64_t>& types, bool cells, const std::string& where) {
    saw_solution_ = true;
    constexpr uint32_t kToVtk[6] = {0, 3, 1, 5, 4, 2};  // Medit component c goes to VTK component kToVtk[c]
    for (size_t k = 0; k < fields->size(); ++k) {
      Field& f = (*fields)[k];
      if (types[k] != 3) continue;
      const size_t vs = f.valueSize(), item = 6 * vs;
      std::vector<uint8_t> row(item);
      for (size_t i = 0; i < f.itemCount(); ++i) {
        uint8_t* p = f.bytes.data() + i * item;
        for (uint32_t c = 0; c < 6; ++c) std::memcpy(row.data() + kToVtk[c] * vs, p + c * vs, vs);
        std::memcpy(p, row.data(), item);
      }
      result_->report.warnings.push_back(path_ + ": " + where + ": the symmetric matrix '" + f.name +
                                         "' is stored in VTK's component order (XX YY ZZ XY YZ XZ), not Medit's "
                                         "(m11 m21 m22 m31 m32 m33)");
    }
    auto& dest = cells ? result_->mesh.cell_fields : result_->mesh.point_fields;
    for (Field& f : *fields) dest.push_back(std::move(f));
  }

  const std::string& path_;
  bool tets_only_;
  ImportResult* result_;
  SolutionTarget target_;
  bool saw_solution_ = false;
};

Status SolutionReader::readAscii(const std::string& text) {
  TextReader reader(path_, text);
  int version = 0;
  int64_t dimension = 0;
  std::string_view tok;
  while (reader.next(&tok)) {
    if (sameKeyword(tok, "End")) break;
    if (sameKeyword(tok, "MeshVersionFormatted")) {
      GTN_ASSIGN_OR_RETURN(const int64_t v, reader.readInt("solution version"));
      if (v < 1 || v > 4) return reader.error("unknown MeshVersionFormatted " + std::to_string(v));
      version = static_cast<int>(v);
      continue;
    }
    if (version == 0)
      return Status(StatusCode::kNotOurFile,
                    reader.error("not a Medit solution file: it starts with " + quotedToken(tok)).message());
    if (sameKeyword(tok, "Dimension")) {
      GTN_ASSIGN_OR_RETURN(dimension, reader.readInt("dimension"));
      if (dimension != 3)
        return reader.error("dimension " + std::to_string(dimension) + ": only 3D solutions are read");
      continue;
    }
    const bool vertices = sameKeyword(tok, "SolAtVertices"), tets = sameKeyword(tok, "SolAtTetrahedra");
    const bool other = !vertices && !tets && tok.size() > 5 && sameKeyword(tok.substr(0, 5), "SolAt");
    if (sameKeyword(tok, "Time") || sameKeyword(tok, "Iterations")) {
      if (!reader.next(&tok)) return reader.errorAtEnd("a value");
      continue;
    }
    if (!vertices && !tets && !other)
      return reader.error("unknown section " + quotedToken(tok) + " in a solution file");
    if (dimension != 3) return reader.error(std::string(tok) + " before a 'Dimension 3' line");
    const std::string section(tok);
    const size_t line = reader.line();
    GTN_ASSIGN_OR_RETURN(const int64_t count, reader.readInt((section + " count").c_str()));
    GTN_ASSIGN_OR_RETURN(const int64_t ntypes, reader.readInt((section + " type count").c_str()));
    if (ntypes < 1 || ntypes > kMaxTypes) return reader.error(section + ": type count " + std::to_string(ntypes));
    std::vector<int64_t> types(static_cast<size_t>(ntypes));
    int64_t size = 0;
    for (int64_t& t : types) {
      GTN_ASSIGN_OR_RETURN(t, reader.readInt((section + " type").c_str()));
      if (typeComponents(t) == 0)
        return reader.error(section + ": solution type " + std::to_string(t) +
                            " (known: 1 scalar, 2 vector, 3 symmetric matrix, 4 matrix)");
      size += typeComponents(t);
    }
    GTN_RETURN_IF_ERROR(checkCountFits(reader, count, size, section + " values"));
    size_t items = 0;
    bool keep = false;
    if (!other) {
      GTN_ASSIGN_OR_RETURN(keep, accept(section.c_str(), tets, count, &items));
    } else {
      saw_solution_ = true;
      result_->report.warnings.push_back(path_ + ":" + std::to_string(line) + ": " + section +
                                         " skipped (only SolAtVertices and SolAtTetrahedra are read)");
    }
    if (!keep) {
      for (int64_t i = 0; i < count * size; ++i)
        if (!reader.next(&tok)) return reader.errorAtEnd((section + " values").c_str());
      continue;
    }
    std::vector<Field> fields = target_.make(types, items, version, tets);
    for (size_t i = 0; i < items; ++i)
      for (Field& f : fields)
        for (uint32_t c = 0; c < f.components; ++c) {
          GTN_ASSIGN_OR_RETURN(const double v, reader.readDouble((section + " value").c_str()));
          if (f.type == ScalarType::kFloat32) f.set<float>(i, c, static_cast<float>(v));
          else f.set<double>(i, c, v);
        }
    store(&fields, types, tets, "line " + std::to_string(line));
  }
  if (version == 0) return Status(StatusCode::kNotOurFile, path_ + ": empty, not a Medit solution file");
  return Status::ok();
}

Status SolutionReader::readBinary(const std::string& bytes) {
  GmfBinary in(path_, bytes);
  GTN_RETURN_IF_ERROR(in.open(".solb"));
  const size_t real_size = in.realSize();
  int64_t dimension = 0;
  uint32_t keyword = 0;
  uint64_t at = 0, end = 0;
  while (true) {
    GTN_ASSIGN_OR_RETURN(const bool more, in.nextKeyword(&keyword, &at, &end));
    if (!more) break;
    if (keyword == kDimension) {
      GTN_RETURN_IF_ERROR(in.readDimension3(at, end, "only 3D solutions are read"));
      dimension = 3;
      continue;
    }
    if (keyword != kSolAtVertices && keyword != kSolAtTetrahedra && !otherSolutionKeyword(keyword)) continue;
    const bool tets = keyword == kSolAtTetrahedra;
    const std::string section = keyword == kSolAtVertices ? "SolAtVertices"
                                : tets                    ? "SolAtTetrahedra"
                                                          : "solution keyword " + std::to_string(keyword);
    if (dimension != 3) return in.fail(at, section + " before a Dimension 3 keyword");
    // The line count is an int of the version's size; the type count and the types are int32.
    GTN_RETURN_IF_ERROR(in.need(in.intSize() + 4, section + " header", end));
    const int64_t count = in.integer();
    const int64_t ntypes = static_cast<int32_t>(in.word(4));
    if (count < 0) return in.fail(at, section + " count " + std::to_string(count) + " is negative");
    if (ntypes < 1 || ntypes > kMaxTypes) return in.fail(at, section + ": type count " + std::to_string(ntypes));
    GTN_RETURN_IF_ERROR(in.need(4 * static_cast<uint64_t>(ntypes), section + " types", end));
    std::vector<int64_t> types(static_cast<size_t>(ntypes));
    uint64_t size = 0;
    for (int64_t& t : types) {
      t = static_cast<int32_t>(in.word(4));
      if (typeComponents(t) == 0)
        return in.fail(at, section + ": solution type " + std::to_string(t) +
                               " (known: 1 scalar, 2 vector, 3 symmetric matrix, 4 matrix)");
      size += typeComponents(t);
    }
    const uint64_t left = end - in.position();
    if (static_cast<uint64_t>(count) > left / (size * real_size))
      return in.fail(at, section + ": " + std::to_string(count) + " entries of " + std::to_string(size * real_size) +
                             " bytes do not fit in the " + std::to_string(left) + " bytes before byte offset " +
                             std::to_string(end));
    if (otherSolutionKeyword(keyword)) {
      saw_solution_ = true;
      result_->report.warnings.push_back(path_ + ": byte offset " + std::to_string(at) + ": " + section +
                                         " skipped (only SolAtVertices and SolAtTetrahedra are read)");
      continue;
    }
    size_t items = 0;
    GTN_ASSIGN_OR_RETURN(const bool keep, accept(section.c_str(), tets, count, &items));
    if (!keep) continue;
    std::vector<Field> fields = target_.make(types, items, in.version(), tets);
    for (size_t i = 0; i < items; ++i)
      for (Field& f : fields)
        for (uint32_t c = 0; c < f.components; ++c) {
          // The field has the file's real width: the bits are copied as they are.
          const uint64_t v = in.realBits();
          std::memcpy(f.bytes.data() + (i * f.components + c) * real_size, &v, real_size);
        }
    store(&fields, types, tets, "byte offset " + std::to_string(at));
  }
  return Status::ok();
}

}  // namespace

Status readMeditSolutions(const std::vector<std::string>& paths, bool tets_only, ImportResult* result) {
  for (const std::string& path : paths) {
    GTN_ASSIGN_OR_RETURN(const std::string bytes, readWholeFile(path));
    SolutionReader reader(path, tets_only, result);
    const bool binary = bytes.size() >= 4 && (std::memcmp(bytes.data(), "\x01\0\0\0", 4) == 0 ||
                                              std::memcmp(bytes.data(), "\0\0\0\x01", 4) == 0);
    GTN_RETURN_IF_ERROR(binary ? reader.readBinary(bytes) : reader.readAscii(bytes));
    if (!reader.sawSolution())
      result->report.warnings.push_back(path +
                                        ": no solution section (SolAtVertices, SolAtTetrahedra, ...): no field read");
  }
  return Status::ok();
}

}  // namespace gtn
