// Medit .mesh (ASCII) importer: keyword sections, each a count followed by that many entries of a
// fixed number of values. Vertices and the volume elements (Tetrahedra, Hexahedra, Prisms, Pyramids)
// are read (1-based, a reference number after each); hexahedra, prisms and pyramids are split into
// tetrahedra as the VTK importers split theirs (medit_cells.h gives the corner numbering). Every other
// known section is skipped by its count, and an unknown keyword is an error (its entries could not be
// skipped safely).
#include <cctype>
#include <cmath>
#include <cstring>

#include "convert/ascii_rows.h"
#include "convert/import.h"
#include "convert/medit_cells.h"
#include "format/file_io.h"

namespace gtn {

namespace {
constexpr int64_t kMaxItems = 0xFFFFFFFDll;

bool sameKeyword(std::string_view a, const char* b) {
  if (a.size() != std::strlen(b)) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}

// Sections skipped by count: values per entry, with -1 standing for the dimension.
struct SkippedSection {
  const char* keyword;
  int values;
  bool volume = false;  // higher-order volume elements: skipping them loses volume, so a warning says so
};
constexpr SkippedSection kSkipped[] = {
    {"Edges", 3},           {"Triangles", 4},          {"Quadrilaterals", 5},
    {"EdgesP2", 4},         {"TrianglesP2", 7},        {"QuadrilateralsQ2", 10},
    {"TetrahedraP2", 11, true}, {"HexahedraQ2", 28, true},
    {"Corners", 1},         {"Ridges", 1},             {"RequiredVertices", 1},
    {"RequiredEdges", 1},   {"RequiredTriangles", 1},  {"RequiredQuadrilaterals", 1},
    {"RequiredTetrahedra", 1}, {"RequiredHexahedra", 1}, {"Normals", -1},
    {"Tangents", -1},       {"NormalAtVertices", 2},   {"NormalAtTriangleVertices", 3},
    {"NormalAtQuadrilateralVertices", 3}, {"TangentAtEdgeVertices", 3}, {"TangentAtVertices", 2},
    {"Crack", 2},
};

StatusOr<int64_t> readCount(TextReader& reader, int64_t values_per_entry, const std::string& what) {
  GTN_ASSIGN_OR_RETURN(const int64_t count, reader.readInt((what + " count").c_str()));
  if (count > kMaxItems) return reader.error(what + " count " + std::to_string(count) + " is too large");
  GTN_RETURN_IF_ERROR(checkCountFits(reader, count, values_per_entry, what));
  return count;
}

StatusOr<int32_t> readRef(TextReader& reader) {
  std::string_view tok;
  if (!reader.next(&tok)) return reader.errorAtEnd("a reference number");
  GTN_ASSIGN_OR_RETURN(const int64_t v, parseIntToken(reader, tok, INT32_MIN, INT32_MAX, "reference number"));
  return static_cast<int32_t>(v);
}

// The volume keyword `tok` names (Hexaedra is an old spelling of Hexahedra, Pentahedra an old name
// of Prisms), or null.
const MeditVolumeKeyword* volumeKeyword(std::string_view tok) {
  if (sameKeyword(tok, "Hexaedra")) return &kMeditVolumeKeywords[1];
  if (sameKeyword(tok, "Pentahedra")) return &kMeditVolumeKeywords[2];
  for (const MeditVolumeKeyword& k : kMeditVolumeKeywords) {
    if (sameKeyword(tok, k.name)) return &k;
  }
  return nullptr;
}
}  // namespace

StatusOr<ImportResult> importMedit(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const std::string text, readWholeFile(path));
  TextReader reader(path, text);
  ImportResult result;
  TetMesh& mesh = result.mesh;
  int64_t dimension = 0;
  MeditCells cells;
  bool have_vertices = false, seen_keyword = false;
  std::string skipped_volume;  // higher-order volume sections skipped, for the error when nothing else is left
  std::string_view tok;
  while (true) {
    if (!reader.next(&tok)) break;
    if (sameKeyword(tok, "End")) break;
    if (sameKeyword(tok, "MeshVersionFormatted")) {
      GTN_ASSIGN_OR_RETURN(const int64_t version, reader.readInt("mesh version"));
      if (version < 1 || version > 4) return reader.error("unknown MeshVersionFormatted " + std::to_string(version));
    } else if (sameKeyword(tok, "Dimension")) {
      GTN_ASSIGN_OR_RETURN(dimension, reader.readInt("dimension"));
      if (dimension != 3) {
        return reader.error("dimension " + std::to_string(dimension) +
                            ": only 3-dimensional (tetrahedral) Medit meshes are supported");
      }
    } else if (sameKeyword(tok, "Geometry") || sameKeyword(tok, "Identifier")) {
      // A quoted string (a file name, a title), possibly with spaces.
      std::string_view value;
      if (!reader.next(&value)) return reader.errorAtEnd("a quoted string");
      const size_t line = reader.line();
      bool open = value.front() == '"' && (value.size() < 2 || value.back() != '"');
      while (open) {
        if (!reader.next(&value) || reader.line() != line)
          return invalidData(reader.path() + ":" + std::to_string(line) + ": " + std::string(tok) +
                             ": the quoted string is not closed on its line");
        open = value.back() != '"';
      }
    } else if (sameKeyword(tok, "Vertices")) {
      if (dimension != 3) return reader.error("Vertices before a 'Dimension 3' line");
      if (have_vertices) return reader.error("a second Vertices section");
      GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader, 4, "vertices"));
      const size_t n = static_cast<size_t>(count);
      mesh.coords.resize(3 * n);
      Field ref("ref", 1, ScalarType::kInt32, n);
      for (size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
          GTN_ASSIGN_OR_RETURN(mesh.coords[3 * i + c], reader.readDouble("a vertex coordinate"));
          if (!std::isfinite(mesh.coords[3 * i + c]))
            return reader.error("vertex " + std::to_string(i + 1) + " has a non-finite " + "xyz"[c] + " coordinate");
        }
        GTN_ASSIGN_OR_RETURN(const int32_t r, readRef(reader));
        ref.set<int32_t>(i, 0, r);
      }
      mesh.point_fields.push_back(std::move(ref));
      have_vertices = true;
    } else if (const MeditVolumeKeyword* kw = volumeKeyword(tok)) {
      if (!have_vertices) return reader.error(std::string(kw->name) + " before Vertices is not supported");
      if (!cells.firstSection(*kw)) return reader.error(std::string("a second ") + kw->name + " section");
      GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader, kw->corners + 1, kw->name));
      const size_t n = static_cast<size_t>(count);
      const int64_t np = static_cast<int64_t>(mesh.numPoints());
      cells.reserve(*kw, n, &mesh);
      for (size_t e = 0; e < n; ++e) {
        uint32_t corners[8];
        for (int k = 0; k < kw->corners; ++k) {
          GTN_ASSIGN_OR_RETURN(const int64_t v, reader.readInt("a vertex number"));
          if (v < 1 || v > np) {
            return reader.error(std::string(kw->singular) + " " + std::to_string(e + 1) + " refers to vertex " +
                                std::to_string(v) + "; vertices are numbered 1 to " + std::to_string(np));
          }
          corners[k] = static_cast<uint32_t>(v - 1);
        }
        GTN_ASSIGN_OR_RETURN(const int32_t r, readRef(reader));
        cells.add(*kw, corners, r, &mesh);
      }
    } else {
      const SkippedSection* section = nullptr;
      for (const SkippedSection& s : kSkipped) {
        if (sameKeyword(tok, s.keyword)) section = &s;
      }
      if (!section) {
        if (!seen_keyword)
          return Status(StatusCode::kNotOurFile, reader.error("not a Medit .mesh file: it starts with " +
                                                              quotedToken(tok)).message());
        return reader.error("unknown Medit section " + quotedToken(tok) + " (its entries cannot be skipped safely)");
      }
      if (dimension != 3) return reader.error(std::string(section->keyword) + " before a 'Dimension 3' line");
      const int64_t values = section->values < 0 ? dimension : section->values;
      const size_t line = reader.line();
      GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader, values, section->keyword));
      for (int64_t i = 0; i < count * values; ++i) {
        if (!reader.next(&tok)) return reader.errorAtEnd((std::string(section->keyword) + " entries").c_str());
      }
      if (section->volume && count > 0) {
        const std::string what = std::to_string(count) + " " + section->keyword + " elements (line " +
                                 std::to_string(line) + ")";
        skipped_volume += (skipped_volume.empty() ? "" : ", ") + what;
        result.report.warnings.push_back("skipped " + what +
                                         ": higher-order elements are not read, so their volume is missing");
      }
    }
    seen_keyword = true;
  }
  if (!have_vertices) return reader.error("no Vertices section");
  if (cells.empty()) return reader.error(noVolumeElements(skipped_volume));
  const bool tets_only = cells.other_refs.empty();
  GTN_RETURN_IF_ERROR(finishMeditImport(path, "medit", &cells, options, &result));
  GTN_RETURN_IF_ERROR(readMeditSolutions(options.medit_solutions, tets_only, &result));
  return result;
}

}  // namespace gtn
