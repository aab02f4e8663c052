// Medit binary (.meshb, libMeshb's GMF binary) importer.
//
// The keyword records are read by GmfBinary (gmf_binary.h). Keywords read: GmfDimension 3,
// GmfVertices 4, GmfTetrahedra 8, GmfPrisms 9, GmfHexahedra 10, GmfPyramids 49, up to GmfEnd 54.
// For Dimension, an int32 (the dimension is 32-bit in every version); for the element and vertex
// keywords an int count (int64 in version 4) and that many entries: a vertex is `dimension` reals and
// an int reference, an element its corner numbers (1-based) and an int reference. The keywords read
// are those of the ASCII reader; any other is skipped by its next-keyword position, which must move
// forward and stay inside the file, with a warning per keyword that counts its entries (boundary
// triangles, edges, corners ...); the single values (Iterations, Time, AngleOfCornerBound,
// BoundingBox) become metadata ("medit.Time"). Every count is checked against the bytes left before
// anything is allocated.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <vector>

#include "convert/gmf_binary.h"
#include "convert/import.h"
#include "convert/medit_cells.h"
#include "format/file_io.h"

namespace gtn {

namespace {

constexpr uint32_t kDimension = 3, kVertices = 4, kTetrahedra = 8, kPrisms = 9, kHexahedra = 10, kPyramids = 49,
                   kTetrahedraP2 = 30, kHexahedraQ2 = 33, kPrismsP2 = 86, kPyramidsP2 = 87;

// Volume elements the reader skips (higher-order and polyhedral ones): skipping them loses volume,
// so a warning names them.
struct SkippedVolume {
  uint32_t code;
  const char* name;
};
constexpr SkippedVolume kSkippedVolumes[] = {
    {46, "Polyhedra"},   {96, "TetrahedraP3"}, {97, "TetrahedraP4"}, {98, "HexahedraQ3"}, {99, "HexahedraQ4"},
    {100, "PyramidsP3"}, {101, "PyramidsP4"},  {102, "PrismsP3"},    {103, "PrismsP4"},
};

// libMeshb's keyword names by code (GmfKwdCod; "" for the codes it reserves).
constexpr const char* kKeywordNames[] = {
    "",
    "MeshVersionFormatted",
    "",
    "Dimension",
    "Vertices",
    "Edges",
    "Triangles",
    "Quadrilaterals",
    "Tetrahedra",
    "Prisms",
    "Hexahedra",
    "IterationsAll",
    "TimesAll",
    "Corners",
    "Ridges",
    "RequiredVertices",
    "RequiredEdges",
    "RequiredTriangles",
    "RequiredQuadrilaterals",
    "TangentAtEdgeVertices",
    "NormalAtVertices",
    "NormalAtTriangleVertices",
    "NormalAtQuadrilateralVertices",
    "AngleOfCornerBound",
    "TrianglesP2",
    "EdgesP2",
    "SolAtPyramids",
    "QuadrilateralsQ2",
    "ISolAtPyramids",
    "SubDomainFromGeom",
    "TetrahedraP2",
    "Fault_NearTri",
    "Fault_Inter",
    "HexahedraQ2",
    "ExtraVerticesAtEdges",
    "ExtraVerticesAtTriangles",
    "ExtraVerticesAtQuadrilaterals",
    "ExtraVerticesAtTetrahedra",
    "ExtraVerticesAtPrisms",
    "ExtraVerticesAtHexahedra",
    "VerticesOnGeometricVertices",
    "VerticesOnGeometricEdges",
    "VerticesOnGeometricTriangles",
    "VerticesOnGeometricQuadrilaterals",
    "EdgesOnGeometricEdges",
    "Fault_FreeEdge",
    "Polyhedra",
    "Polygons",
    "Fault_Overlap",
    "Pyramids",
    "BoundingBox",
    "Body",
    "PrivateTable",
    "Fault_BadShape",
    "End",
    "TrianglesOnGeometricTriangles",
    "TrianglesOnGeometricQuadrilaterals",
    "QuadrilateralsOnGeometricTriangles",
    "QuadrilateralsOnGeometricQuadrilaterals",
    "Tangents",
    "Normals",
    "TangentAtVertices",
    "SolAtVertices",
    "SolAtEdges",
    "SolAtTriangles",
    "SolAtQuadrilaterals",
    "SolAtTetrahedra",
    "SolAtPrisms",
    "SolAtHexahedra",
    "DSolAtVertices",
    "ISolAtVertices",
    "ISolAtEdges",
    "ISolAtTriangles",
    "ISolAtQuadrilaterals",
    "ISolAtTetrahedra",
    "ISolAtPrisms",
    "ISolAtHexahedra",
    "Iterations",
    "Time",
    "Fault_SmallTri",
    "CoarseHexahedra",
    "Comments",
    "PeriodicVertices",
    "PeriodicEdges",
    "PeriodicTriangles",
    "PeriodicQuadrilaterals",
    "PrismsP2",
    "PyramidsP2",
    "QuadrilateralsQ3",
    "QuadrilateralsQ4",
    "TrianglesP3",
    "TrianglesP4",
    "EdgesP3",
    "EdgesP4",
    "IRefGroups",
    "DRefGroups",
    "TetrahedraP3",
    "TetrahedraP4",
    "HexahedraQ3",
    "HexahedraQ4",
    "PyramidsP3",
    "PyramidsP4",
    "PrismsP3",
    "PrismsP4",
};
constexpr uint32_t kAngleOfCornerBound = 23, kBoundingBox = 50, kIterations = 77, kTime = 78;

// What a skipped keyword held, for its warning.
std::string skippedWhat(const std::string& k) {
  if (k.rfind("Edges", 0) == 0 || k.rfind("Triangles", 0) == 0 || k.rfind("Quadrilaterals", 0) == 0 || k == "Polygons")
    return "elements of lower dimension, with their references: only volume elements become tetrahedra";
  if (k == "Corners" || k == "Ridges" || k.rfind("Required", 0) == 0) return "marks on vertices and elements, not read";
  if (k.find("Sol") != std::string::npos) return "solution values inside the mesh file, not read";
  return "not read";
}

// The volume keyword for a GMF keyword code, or null.
const MeditVolumeKeyword* volumeKeyword(uint32_t code) {
  switch (code) {
    case kTetrahedra: return &kMeditVolumeKeywords[0];
    case kHexahedra: return &kMeditVolumeKeywords[1];
    case kPrisms: return &kMeditVolumeKeywords[2];
    case kPyramids: return &kMeditVolumeKeywords[3];
    case kTetrahedraP2: return &kMeditVolumeKeywords[4];
    case kHexahedraQ2: return &kMeditVolumeKeywords[5];
    case kPrismsP2: return &kMeditVolumeKeywords[6];
    case kPyramidsP2: return &kMeditVolumeKeywords[7];
    default: return nullptr;
  }
}

class MeshbReader {
 public:
  MeshbReader(const std::string& path, const std::string& bytes) : path_(path), in_(path, bytes) {}

  StatusOr<ImportResult> read(const ImportOptions& options);

 private:
  // The entry count after a keyword record's header, checked against the bytes before `end`.
  StatusOr<uint64_t> count(const char* keyword, uint64_t entry_size, uint64_t end);
  Status readVertices(uint64_t end);
  Status readElements(const MeditVolumeKeyword& kw, uint64_t end);

  const std::string& path_;
  GmfBinary in_;
  int64_t dimension_ = 0;
  bool have_vertices_ = false;
  std::string skipped_volume_;
  // The other skipped keywords in file order: name, entries (-1: not counted), first byte offset, records.
  struct Skipped {
    std::string name;
    int64_t entries;
    uint64_t at;
    int records;
  };
  std::vector<Skipped> skipped_;
  Status skip(uint32_t keyword, uint64_t at, uint64_t end);
  ImportResult result_;
  MeditCells cells_;
};

StatusOr<uint64_t> MeshbReader::count(const char* keyword, uint64_t entry_size, uint64_t end) {
  const uint64_t at = in_.position();
  GTN_RETURN_IF_ERROR(in_.need(in_.intSize(), std::string(keyword) + " count", end));
  const int64_t n = in_.integer();
  if (n < 0) return in_.fail(at, std::string(keyword) + " count " + std::to_string(n) + " is negative");
  const uint64_t left = end - in_.position();
  if (static_cast<uint64_t>(n) > left / entry_size) {
    return in_.fail(at, std::string(keyword) + " count " + std::to_string(n) + " needs " +
                            (static_cast<uint64_t>(n) > UINT64_MAX / entry_size
                                 ? std::string("more bytes than a file can hold")
                                 : std::to_string(static_cast<uint64_t>(n) * entry_size) + " bytes") +
                            " but " + std::to_string(left) + " are left before byte offset " + std::to_string(end));
  }
  if (static_cast<uint64_t>(n) >= UINT32_MAX) return unsupported(path_ + ": more than 2^32-2 " + keyword);
  return static_cast<uint64_t>(n);
}

Status MeshbReader::readVertices(uint64_t end) {
  const uint64_t at = in_.position();
  if (dimension_ != 3) return in_.fail(at, "Vertices before a Dimension keyword");
  if (have_vertices_) return in_.fail(at, "a second Vertices keyword");
  have_vertices_ = true;
  GTN_ASSIGN_OR_RETURN(const uint64_t n, count("Vertices", 3 * in_.realSize() + in_.intSize(), end));
  TetMesh& mesh = result_.mesh;
  mesh.coords.resize(3 * n);
  mesh.coord_type = in_.realSize() == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  Field ref("ref", 1, ScalarType::kInt32, n);
  for (uint64_t i = 0; i < n; ++i) {
    const uint64_t xyz_at = in_.position();
    for (int c = 0; c < 3; ++c) mesh.coords[3 * i + c] = in_.real();
    if (!std::isfinite(mesh.coords[3 * i]) || !std::isfinite(mesh.coords[3 * i + 1]) ||
        !std::isfinite(mesh.coords[3 * i + 2]))
      return in_.fail(xyz_at, "vertex " + std::to_string(i + 1) + " has a non-finite coordinate");
    const uint64_t ref_at = in_.position();
    const int64_t r = in_.integer();
    if (r < INT32_MIN || r > INT32_MAX)
      return in_.fail(ref_at, "vertex " + std::to_string(i + 1) + " has reference " + std::to_string(r) +
                                  ", outside the 32-bit range");
    ref.set<int32_t>(i, 0, static_cast<int32_t>(r));
  }
  mesh.point_fields.push_back(std::move(ref));
  return Status::ok();
}

Status MeshbReader::readElements(const MeditVolumeKeyword& kw, uint64_t end) {
  const uint64_t at = in_.position();
  cells_.addSection(kw, "byte offset " + std::to_string(at));
  GTN_ASSIGN_OR_RETURN(const uint64_t n, count(kw.name, (kw.nodes + 1) * in_.intSize(), end));
  TetMesh& mesh = result_.mesh;
  // Before the Vertices keyword (any order is allowed) only the range of an index is checked here.
  const int64_t np = have_vertices_ ? static_cast<int64_t>(mesh.numPoints()) : int64_t{UINT32_MAX} - 1;
  cells_.reserve(kw, n, &mesh);
  for (uint64_t e = 0; e < n; ++e) {
    uint32_t corners[kMeditMaxNodes];
    for (int k = 0; k < kw.nodes; ++k) {
      const uint64_t v_at = in_.position();
      const int64_t v = in_.integer();
      if (v < 1 || v > np)
        return in_.fail(v_at, std::string(kw.singular) + " " + std::to_string(e + 1) + " refers to vertex " +
                                  std::to_string(v) + "; vertices are numbered 1 to " + std::to_string(np));
      if (!have_vertices_) cells_.noteLateVertex(v, std::string(kw.singular) + " " + std::to_string(e + 1), v_at);
      corners[k] = static_cast<uint32_t>(v - 1);
    }
    const uint64_t ref_at = in_.position();
    const int64_t r = in_.integer();
    if (r < INT32_MIN || r > INT32_MAX)
      return in_.fail(ref_at, std::string(kw.singular) + " " + std::to_string(e + 1) + " has reference " +
                                  std::to_string(r) + ", outside the 32-bit range");
    cells_.add(kw, corners, static_cast<int32_t>(r), &mesh);
  }
  return Status::ok();
}

// A keyword the reader does not use: a single value becomes metadata; the others are counted for a
// warning (the entry count that starts their data, where they have one).
Status MeshbReader::skip(uint32_t keyword, uint64_t at, uint64_t end) {
  const bool named = keyword < std::size(kKeywordNames) && kKeywordNames[keyword][0] != '\0';
  const std::string name = named ? kKeywordNames[keyword] : "keyword " + std::to_string(keyword);
  if (keyword == kAngleOfCornerBound || keyword == kBoundingBox || keyword == kIterations || keyword == kTime) {
    const int n = keyword == kBoundingBox ? 6 : 1;
    const uint64_t size = keyword == kIterations ? in_.intSize() : in_.realSize();
    GTN_RETURN_IF_ERROR(in_.need(n * size, name, end));
    std::string text;
    for (int i = 0; i < n; ++i) {
      char value[32];
      if (keyword == kIterations) std::snprintf(value, sizeof value, "%lld", static_cast<long long>(in_.integer()));
      else std::snprintf(value, sizeof value, "%.17g", in_.real());
      if (i) text += ' ';
      text += value;
    }
    result_.mesh.setMetadata("medit." + name, text);
    return Status::ok();
  }
  int64_t entries = -1;
  if (named && end - in_.position() >= in_.intSize()) entries = in_.integer();
  if (entries < 0) entries = -1;
  auto it = std::find_if(skipped_.begin(), skipped_.end(), [&](const Skipped& s) { return s.name == name; });
  if (it == skipped_.end()) it = skipped_.insert(skipped_.end(), Skipped{name, 0, at, 0});
  if (entries < 0) it->entries = -1;
  else if (it->entries >= 0) it->entries += entries;
  ++it->records;
  return Status::ok();
}

StatusOr<ImportResult> MeshbReader::read(const ImportOptions& options) {
  GTN_RETURN_IF_ERROR(in_.open(".meshb"));
  uint32_t keyword = 0;
  uint64_t at = 0, end = 0;
  while (true) {
    GTN_ASSIGN_OR_RETURN(const bool more, in_.nextKeyword(&keyword, &at, &end));
    if (!more) break;
    if (keyword == kDimension) {
      GTN_RETURN_IF_ERROR(in_.readDimension3(at, end, "only 3-dimensional (tetrahedral) Medit meshes are supported"));
      dimension_ = 3;
    } else if (keyword == kVertices) {
      GTN_RETURN_IF_ERROR(readVertices(end));
    } else if (const MeditVolumeKeyword* kw = volumeKeyword(keyword)) {
      GTN_RETURN_IF_ERROR(readElements(*kw, end));
    } else {
      bool volume = false;
      for (const SkippedVolume& v : kSkippedVolumes) {
        if (v.code != keyword) continue;
        volume = true;
        skipped_volume_ +=
            (skipped_volume_.empty() ? "" : ", ") + std::string(v.name) + " (byte offset " + std::to_string(at) + ")";
        result_.report.warnings.push_back("skipped " + std::string(v.name) + " at byte offset " + std::to_string(at) +
                                          ": higher-order and polyhedral elements are not read, so their volume is "
                                          "missing");
      }
      if (!volume) GTN_RETURN_IF_ERROR(skip(keyword, at, end));
    }
  }
  if (!have_vertices_) return invalidData(path_ + ": no Vertices keyword");
  if (cells_.empty()) return invalidData(path_ + ": " + noVolumeElements(skipped_volume_));
  if (cells_.late_vertex > static_cast<int64_t>(result_.mesh.numPoints()))
    return in_.fail(cells_.late_place, cells_.late_element + " refers to vertex " + std::to_string(cells_.late_vertex) +
                                           "; vertices are numbered 1 to " + std::to_string(result_.mesh.numPoints()));
  cells_.warnAboutSections(&result_);
  for (const Skipped& s : skipped_) {
    const std::string where = "byte offset " + std::to_string(s.at) +
                              (s.records > 1 ? " and " + std::to_string(s.records - 1) + " more records" : "");
    result_.report.warnings.push_back(
        "skipped " + (s.entries >= 0 ? std::to_string(s.entries) + " " + s.name : s.name) + " (" + where + "): " +
        (s.name.rfind("keyword ", 0) == 0 ? std::string("a keyword unknown to this reader, not read")
                                          : skippedWhat(s.name)));
  }
  GTN_RETURN_IF_ERROR(finishMeditImport(path_, "meshb", &cells_, options, &result_));
  return std::move(result_);
}

}  // namespace

StatusOr<ImportResult> importMeshb(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const std::string bytes, readWholeFile(path));
  MeshbReader reader(path, bytes);
  return reader.read(options);
}

}  // namespace gtn
