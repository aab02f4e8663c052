// Medit .mesh (ASCII) importer: keyword sections, each a count followed by that many entries of a
// fixed number of values. Vertices and the volume elements (Tetrahedra, Hexahedra, Prisms, Pyramids)
// are read (1-based, a reference number after each); hexahedra, prisms and pyramids are split into
// tetrahedra as the VTK importers split theirs (medit_cells.h gives the corner numbering). Every other
// known section is skipped: by its count of values, or, for the links to a geometry whose layout
// changed between libMeshb versions, one line per entry (as libMeshb writes them); a warning per
// keyword counts its entries (boundary triangles and their references, edges, corners ...). The
// single values (Iterations, Time, AngleOfCornerBound, BoundingBox) become metadata
// ("medit.Time"). A section of another program is skipped, with a warning, up to the next keyword:
// entries are numbers, keywords words. A file whose first keyword is unknown is not a Medit file.
#include <algorithm>
#include <cctype>
#include <cmath>

#include "convert/ascii_rows.h"
#include "convert/import.h"
#include "convert/medit_cells.h"
#include "format/file_io.h"

namespace gtn {

namespace {
constexpr int64_t kMaxItems = 0xFFFFFFFDll;

// Sections skipped: values per entry, with -1 standing for the dimension.
enum class Skip {
  kValues,  // a count, then count x values values
  kLines,   // a count, then count lines (libMeshb changed these entries' layout between versions)
  kSingle,  // no count: `values` values (Iterations, Time, ...)
};
struct SkippedSection {
  const char* keyword;
  int values;
  bool volume = false;  // higher-order volume elements: skipping them loses volume, so a warning says so
  Skip skip = Skip::kValues;
};
constexpr SkippedSection kSkipped[] = {
    {"Edges", 3},
    {"Triangles", 4},
    {"Quadrilaterals", 5},
    {"EdgesP2", 4},
    {"TrianglesP2", 7},
    {"QuadrilateralsQ2", 10},
    {"Corners", 1},
    {"Ridges", 1},
    {"RequiredVertices", 1},
    {"RequiredEdges", 1},
    {"RequiredTriangles", 1},
    {"RequiredQuadrilaterals", 1},
    {"RequiredTetrahedra", 1},
    {"RequiredHexahedra", 1},
    {"Normals", -1},
    {"Tangents", -1},
    {"NormalAtVertices", 2},
    {"NormalAtTriangleVertices", 3},
    {"NormalAtQuadrilateralVertices", 3},
    {"TangentAtEdgeVertices", 3},
    {"TangentAtVertices", 2},
    {"Crack", 2},
    // Links of the mesh to a geometry (libMeshb's GmfVertexOnGeometricVertex and its kin); the
    // singular and plural spellings of the two libMeshb generations.
    {"VertexOnGeometricVertex", 0, false, Skip::kLines},
    {"VertexOnGeometricEdge", 0, false, Skip::kLines},
    {"VertexOnGeometricTriangle", 0, false, Skip::kLines},
    {"VertexOnGeometricQuadrilateral", 0, false, Skip::kLines},
    {"EdgeOnGeometricEdge", 0, false, Skip::kLines},
    {"TriangleOnGeometricTriangle", 0, false, Skip::kLines},
    {"TriangleOnGeometricQuadrilateral", 0, false, Skip::kLines},
    {"QuadrilateralOnGeometricTriangle", 0, false, Skip::kLines},
    {"QuadrilateralOnGeometricQuadrilateral", 0, false, Skip::kLines},
    {"VerticesOnGeometricVertices", 0, false, Skip::kLines},
    {"VerticesOnGeometricEdges", 0, false, Skip::kLines},
    {"VerticesOnGeometricTriangles", 0, false, Skip::kLines},
    {"VerticesOnGeometricQuadrilaterals", 0, false, Skip::kLines},
    {"EdgesOnGeometricEdges", 0, false, Skip::kLines},
    {"SubDomainFromGeom", 0, false, Skip::kLines},
    {"SubDomainFromMesh", 0, false, Skip::kLines},
    {"Iterations", 1, false, Skip::kSingle},
    {"Time", 1, false, Skip::kSingle},
    {"AngleOfCornerBound", 1, false, Skip::kSingle},
    {"BoundingBox", 6, false, Skip::kSingle},
};

// What a skipped section held, for its warning.
std::string skippedWhat(const SkippedSection& s) {
  const std::string k = s.keyword;
  if (k.rfind("Edges", 0) == 0 || k.rfind("Triangles", 0) == 0 || k.rfind("Quadrilaterals", 0) == 0)
    return "elements of lower dimension, with their references: only volume elements become tetrahedra";
  if (k == "Corners" || k == "Ridges" || k.rfind("Required", 0) == 0) return "marks on vertices and elements, not read";
  if (k.find("Normal") != std::string::npos || k.find("Tangent") != std::string::npos)
    return "normals and tangents, not read";
  if (s.skip == Skip::kLines) return "links to a geometry, not read";
  return "not read";
}

// The number of values on the first entry's line of a section whose count was just read (`rest`:
// the text after the count), where the count ends its line; -1 where an entry follows it on its
// line. gmsh writes second-order quadrilaterals and hexahedra under the linear keywords
// (Quadrilaterals with 9 nodes, Hexahedra with 27), one element per line: that line tells them apart.
int64_t firstEntryWidth(std::string_view rest) {
  size_t i = 0;
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; };
  while (i < rest.size() && blank(rest[i])) ++i;
  if (i < rest.size() && rest[i] != '\n' && rest[i] != '#') return -1;
  // The next line that holds a value.
  for (;;) {
    while (i < rest.size() && rest[i] != '\n') ++i;
    if (i >= rest.size()) return 0;
    ++i;
    while (i < rest.size() && blank(rest[i])) ++i;
    if (i < rest.size() && rest[i] != '\n' && rest[i] != '#') break;
  }
  int64_t values = 0;
  while (i < rest.size() && rest[i] != '\n' && rest[i] != '#') {
    ++values;
    while (i < rest.size() && !blank(rest[i]) && rest[i] != '\n') ++i;
    while (i < rest.size() && blank(rest[i])) ++i;
  }
  return values;
}

// The values per entry that a skipped section of lower-dimensional elements may hold besides its own
// (the nodes and reference of its second-order forms, as gmsh writes them under the linear keyword).
std::vector<int64_t> secondOrderValues(std::string_view keyword) {
  if (keyword == "Edges") return {4};
  if (keyword == "Triangles") return {7};
  if (keyword == "Quadrilaterals") return {9, 10};
  return {};
}

// The entries of one keyword's skipped sections: how many, and where the first began.
struct SkippedEntries {
  const SkippedSection* section;
  int64_t entries = 0;
  size_t line = 0;
  int sections = 0;
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

// Whether a token is a word (a section keyword), not a number: entries hold only numbers (nan and
// inf among them).
bool isKeyword(std::string_view tok) {
  double x;
  return std::isalpha(static_cast<unsigned char>(tok[0])) && !parseDouble(tok, &x);
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

// The reader of one .mesh file: a loop over its keywords, one method per kind of section.
class MeditReader {
 public:
  MeditReader(const std::string& path, const std::string& text) : path_(path), reader_(path, text) {}
  StatusOr<ImportResult> read(const ImportOptions& options);

 private:
  // The next keyword: one already read (that ended a skipped section), else the next token.
  bool nextKeyword(std::string_view* tok);
  Status readSection(std::string_view tok);
  Status readVersion();
  Status readDimension();
  Status skipQuotedString(std::string_view keyword);
  Status readVertices();
  Status readVertexRef(size_t i, size_t n, Field* ref, std::vector<double>* real_refs);
  Status readVolumeSection(const MeditVolumeKeyword& kw);
  Status skipUnknownSection(std::string_view keyword);
  Status skipSection(const SkippedSection& section);
  void noteSkipped(const SkippedSection& section, int64_t count, size_t line);
  Status finish(const ImportOptions& options);

  const std::string& path_;
  TextReader reader_;
  ImportResult result_;
  int64_t dimension_ = 0;
  MeditCells cells_;
  bool have_vertices_ = false, seen_keyword_ = false;
  // Higher-order volume sections skipped, for the error when nothing else is left.
  std::string skipped_volume_;
  std::vector<SkippedEntries> skipped_;  // the other skipped sections, per keyword in file order
  std::string_view pending_;             // a keyword already read (it ended a skipped section)
};

StatusOr<ImportResult> MeditReader::read(const ImportOptions& options) {
  std::string_view tok;
  while (nextKeyword(&tok)) {
    if (sameKeyword(tok, "End")) break;
    GTN_RETURN_IF_ERROR(readSection(tok));
    seen_keyword_ = true;
  }
  GTN_RETURN_IF_ERROR(finish(options));
  return std::move(result_);
}

bool MeditReader::nextKeyword(std::string_view* tok) {
  if (pending_.empty()) return reader_.next(tok);
  *tok = pending_;
  pending_ = {};
  return true;
}

Status MeditReader::readSection(std::string_view tok) {
  if (sameKeyword(tok, "MeshVersionFormatted")) return readVersion();
  if (sameKeyword(tok, "Dimension")) return readDimension();
  if (sameKeyword(tok, "Geometry") || sameKeyword(tok, "Identifier")) return skipQuotedString(tok);
  if (sameKeyword(tok, "Vertices")) return readVertices();
  if (const MeditVolumeKeyword* kw = volumeKeyword(tok)) return readVolumeSection(*kw);
  for (const SkippedSection& s : kSkipped) {
    if (sameKeyword(tok, s.keyword)) return skipSection(s);
  }
  return skipUnknownSection(tok);
}

Status MeditReader::readVersion() {
  GTN_ASSIGN_OR_RETURN(const int64_t version, reader_.readInt("mesh version"));
  if (version < 1 || version > 4) return reader_.error("unknown MeshVersionFormatted " + std::to_string(version));
  return Status::ok();
}

Status MeditReader::readDimension() {
  GTN_ASSIGN_OR_RETURN(dimension_, reader_.readInt("dimension"));
  if (dimension_ != 3) {
    return reader_.error("dimension " + std::to_string(dimension_) +
                         ": only 3-dimensional (tetrahedral) Medit meshes are supported");
  }
  return Status::ok();
}

// A quoted string (a file name, a title), possibly with spaces.
Status MeditReader::skipQuotedString(std::string_view keyword) {
  std::string_view value;
  if (!reader_.next(&value)) return reader_.errorAtEnd("a quoted string");
  const size_t line = reader_.line();
  bool open = value.front() == '"' && (value.size() < 2 || value.back() != '"');
  while (open) {
    if (!reader_.next(&value) || reader_.line() != line)
      return invalidData(reader_.path() + ":" + std::to_string(line) + ": " + std::string(keyword) +
                         ": the quoted string is not closed on its line");
    open = value.back() != '"';
  }
  return Status::ok();
}

Status MeditReader::readVertices() {
  if (dimension_ != 3) return reader_.error("Vertices before a 'Dimension 3' line");
  if (have_vertices_) return reader_.error("a second Vertices section");
  GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader_, 4, "vertices"));
  const size_t n = static_cast<size_t>(count);
  TetMesh& mesh = result_.mesh;
  mesh.coords.resize(3 * n);
  // References are integers, but TetGen -g writes a point attribute there, a real number: then they
  // are all kept as float64 (`real_refs` holds them once the first one is not an integer).
  Field ref("ref", 1, ScalarType::kInt32, n);
  std::vector<double> real_refs;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      GTN_ASSIGN_OR_RETURN(mesh.coords[3 * i + c], reader_.readDouble("a vertex coordinate"));
      if (!std::isfinite(mesh.coords[3 * i + c]))
        return reader_.error("vertex " + std::to_string(i + 1) + " has a non-finite " + "xyz"[c] + " coordinate");
    }
    GTN_RETURN_IF_ERROR(readVertexRef(i, n, &ref, &real_refs));
  }
  if (!real_refs.empty()) {
    ref = Field("ref", 1, ScalarType::kFloat64, n);
    for (size_t i = 0; i < n; ++i) ref.set<double>(i, 0, real_refs[i]);
  }
  mesh.point_fields.push_back(std::move(ref));
  have_vertices_ = true;
  return Status::ok();
}

// Vertex i's reference (of n): into `ref` while all are 32-bit integers, else into `real_refs`
// (with those before it, and a warning the first time).
Status MeditReader::readVertexRef(size_t i, size_t n, Field* ref, std::vector<double>* real_refs) {
  std::string_view r_tok;
  if (!reader_.next(&r_tok)) return reader_.errorAtEnd("a reference number");
  int64_t r = 0;
  double x = 0;
  if (real_refs->empty() && parseInt(r_tok, &r) && r >= INT32_MIN && r <= INT32_MAX) {
    ref->set<int32_t>(i, 0, static_cast<int32_t>(r));
    return Status::ok();
  }
  if (!parseDouble(r_tok, &x))
    return reader_.error("expected vertex " + std::to_string(i + 1) + "'s reference (a number), found " +
                         quotedToken(r_tok));
  if (real_refs->empty()) {
    real_refs->reserve(n);
    for (size_t j = 0; j < i; ++j) real_refs->push_back(ref->get(j, 0));
    result_.report.warnings.push_back("vertex " + std::to_string(i + 1) + " (line " + std::to_string(reader_.line()) +
                                      ") has the reference " + std::string(r_tok) +
                                      ", not a 32-bit integer (TetGen -g writes a point attribute there): the "
                                      "vertex references are kept as float64");
  }
  real_refs->push_back(x);
  return Status::ok();
}

Status MeditReader::readVolumeSection(const MeditVolumeKeyword& linear_kw) {
  TetMesh& mesh = result_.mesh;
  const std::string where = "line " + std::to_string(reader_.line());
  GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader_, linear_kw.nodes + 1, linear_kw.name));
  // A linear keyword whose first element has the nodes of its second-order form (gmsh's writer):
  // the section is read as that form.
  const MeditVolumeKeyword* chosen = &linear_kw;
  if (const MeditVolumeKeyword* second = secondOrderForm(linear_kw); second && count > 0) {
    const MeditVolumeKeyword& higher = *second;
    if (firstEntryWidth(reader_.rest()) == higher.nodes + 1) {
      chosen = &higher;
      result_.report.warnings.push_back(
          "the " + std::string(linear_kw.name) + " section (" + where + ") holds " + std::to_string(higher.nodes) +
          " nodes per element (second-order elements, as gmsh writes them): read as " + higher.name);
    }
  }
  const MeditVolumeKeyword& kw = *chosen;
  cells_.addSection(kw, where);
  const size_t n = static_cast<size_t>(count);
  const int64_t np = have_vertices_ ? static_cast<int64_t>(mesh.numPoints()) : kMaxItems;
  cells_.reserve(kw, n, &mesh);
  for (size_t e = 0; e < n; ++e) {
    uint32_t corners[kMeditMaxNodes];
    for (int k = 0; k < kw.nodes; ++k) {
      GTN_ASSIGN_OR_RETURN(const int64_t v, reader_.readInt("a vertex number"));
      if (v < 1 || v > np) {
        return reader_.error(std::string(kw.singular) + " " + std::to_string(e + 1) + " refers to vertex " +
                             std::to_string(v) + "; vertices are numbered 1 to " + std::to_string(np));
      }
      if (!have_vertices_)
        cells_.noteLateVertex(v, std::string(kw.singular) + " " + std::to_string(e + 1), reader_.line());
      corners[k] = static_cast<uint32_t>(v - 1);
    }
    GTN_ASSIGN_OR_RETURN(const int32_t r, readRef(reader_));
    cells_.add(kw, corners, r, &mesh);
  }
  return Status::ok();
}

// A keyword of no known section: the first keyword of a file that is not a Medit file, else a
// section of another program (ParMmg's ParallelTriangleCommunicators, whose entries follow in a
// second section without a count; libMeshb's ISolAtTetrahedra ...). Every entry of every section is
// numbers, so an unknown one ends at the next word.
Status MeditReader::skipUnknownSection(std::string_view keyword) {
  if (!seen_keyword_)
    return Status(StatusCode::kNotOurFile,
                  reader_.error("not a Medit .mesh file: it starts with " + quotedToken(keyword)).message());
  if (!isKeyword(keyword))
    return reader_.error("expected a section keyword, found " + quotedToken(keyword) +
                         " (the section before holds more values than its count says)");
  const std::string name(keyword);
  const size_t line = reader_.line();
  uint64_t numbers = 0;
  std::string_view t;
  while (reader_.next(&t)) {
    if (isKeyword(t)) {
      pending_ = t;
      break;
    }
    ++numbers;
  }
  result_.report.warnings.push_back("skipped the unknown section '" + name + "' (line " + std::to_string(line) + ", " +
                                    std::to_string(numbers) + " numbers up to the next keyword)");
  return Status::ok();
}

// A known section that is not read: its single values become metadata; a counted section is skipped
// by its values or by its lines, and noted for its warning.
Status MeditReader::skipSection(const SkippedSection& section) {
  if (dimension_ != 3) return reader_.error(std::string(section.keyword) + " before a 'Dimension 3' line");
  int64_t values = section.values < 0 ? dimension_ : section.values;
  const size_t line = reader_.line();
  const std::string entries = std::string(section.keyword) + " entries";
  std::string_view tok;
  if (section.skip == Skip::kSingle) {
    std::string text;
    for (int64_t i = 0; i < values; ++i) {
      if (!reader_.next(&tok)) return reader_.errorAtEnd(entries.c_str());
      if (i) text += ' ';
      text += tok;
    }
    result_.mesh.setMetadata(std::string("medit.") + section.keyword, text);
    return Status::ok();
  }
  GTN_ASSIGN_OR_RETURN(const int64_t count, readCount(reader_, std::max<int64_t>(values, 1), section.keyword));
  if (section.skip == Skip::kValues && count > 0) {
    const int64_t width = firstEntryWidth(reader_.rest());
    for (const int64_t v : secondOrderValues(section.keyword))
      if (width == v && count <= kMaxItems / v) values = v;
  }
  if (section.skip == Skip::kLines) {
    reader_.skipLine();  // the rest of the count's line
    for (int64_t i = 0; i < count; ++i) {
      if (!reader_.next(&tok)) return reader_.errorAtEnd(entries.c_str());
      reader_.skipLine();
    }
  }
  for (int64_t i = 0; section.skip == Skip::kValues && i < count * values; ++i) {
    if (!reader_.next(&tok)) return reader_.errorAtEnd(entries.c_str());
    if (isKeyword(tok))
      return reader_.error(std::string(section.keyword) + " (line " + std::to_string(line) + ") announces " +
                           std::to_string(count) + " entries of " + std::to_string(values) + " values; found " +
                           quotedToken(tok) + " after " + std::to_string(i) + " values");
  }
  noteSkipped(section, count, line);
  return Status::ok();
}

// A skipped section of `count` entries at `line`: counted per keyword for one warning at the end, or,
// higher-order volume elements, warned of now (their volume is missing).
void MeditReader::noteSkipped(const SkippedSection& section, int64_t count, size_t line) {
  if (count <= 0) return;
  if (!section.volume) {
    auto it =
        std::find_if(skipped_.begin(), skipped_.end(), [&](const SkippedEntries& e) { return e.section == &section; });
    if (it == skipped_.end()) it = skipped_.insert(skipped_.end(), SkippedEntries{&section, 0, line, 0});
    it->entries += count;
    ++it->sections;
    return;
  }
  const std::string what =
      std::to_string(count) + " " + section.keyword + " elements (line " + std::to_string(line) + ")";
  skipped_volume_ += (skipped_volume_.empty() ? "" : ", ") + what;
  result_.report.warnings.push_back("skipped " + what +
                                    ": higher-order elements are not read, so their volume is missing");
}

// After the last section: vertices and volume elements present and consistent, the warnings of the
// skipped sections, and the cells split into tetrahedra.
Status MeditReader::finish(const ImportOptions& options) {
  const TetMesh& mesh = result_.mesh;
  if (!have_vertices_) return reader_.error("no Vertices section");
  if (cells_.empty()) return reader_.error(noVolumeElements(skipped_volume_));
  if (cells_.late_vertex > static_cast<int64_t>(mesh.numPoints()))
    return invalidData(path_ + ":" + std::to_string(cells_.late_place) + ": " + cells_.late_element +
                       " refers to vertex " + std::to_string(cells_.late_vertex) + "; vertices are numbered 1 to " +
                       std::to_string(mesh.numPoints()));
  cells_.warnAboutSections(&result_);
  for (const SkippedEntries& e : skipped_) {
    const std::string more = e.sections > 1 ? " and " + std::to_string(e.sections - 1) + " more sections" : "";
    result_.report.warnings.push_back("skipped " + std::to_string(e.entries) + " " + e.section->keyword + " (line " +
                                      std::to_string(e.line) + more + "): " + skippedWhat(*e.section));
  }
  return finishMeditImport(path_, "medit", &cells_, options, &result_);
}
}  // namespace

StatusOr<ImportResult> importMedit(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const std::string text, readWholeFile(path));
  MeditReader reader(path, text);
  return reader.read(options);
}

}  // namespace gtn
