// Medit binary (.meshb, libMeshb's GMF binary) importer.
//
// Layout (libMeshb 7 documentation and reference reader, LoicMarechal/libMeshb):
//   int32  code      1, written in the writer's byte order: read as 0x01000000 the file is byte-swapped
//   int32  version   1: 32-bit reals, integers and positions; 2: 64-bit reals; 3: 64-bit reals and
//                    positions; 4: 64-bit reals, positions and integers
//   then keyword records, each:
//   int32  keyword   its code (GmfDimension 3, GmfVertices 4, GmfTetrahedra 8, GmfPrisms 9,
//                    GmfHexahedra 10, GmfPyramids 49, GmfEnd 54, ...)
//   pos    next      the absolute byte offset of the next keyword record, 0 after the last one
//   then, for Dimension, an int32 (the dimension is 32-bit in every version); for the element and
//   vertex keywords an int count (int64 in version 4) and that many entries: a vertex is `dimension`
//   reals and an int reference, an element its corner numbers (1-based) and an int reference.
// The keywords read are those of the ASCII reader; any other is skipped by its next-keyword
// position, which must move forward and stay inside the file. Every count is checked against the
// bytes left before anything is allocated.
#include <cstring>

#include "convert/import.h"
#include "convert/medit_cells.h"
#include "format/file_io.h"

namespace gtn {

namespace {

constexpr uint32_t kDimension = 3, kVertices = 4, kTetrahedra = 8, kPrisms = 9, kHexahedra = 10,
                   kPyramids = 49, kEnd = 54;

// Volume elements the reader skips (higher-order and polyhedral ones): skipping them loses volume,
// so a warning names them.
struct SkippedVolume {
  uint32_t code;
  const char* name;
};
constexpr SkippedVolume kSkippedVolumes[] = {
    {30, "TetrahedraP2"}, {33, "HexahedraQ2"},  {46, "Polyhedra"},    {86, "PrismsP2"},    {87, "PyramidsP2"},
    {96, "TetrahedraP3"}, {97, "TetrahedraP4"}, {98, "HexahedraQ3"},  {99, "HexahedraQ4"}, {100, "PyramidsP3"},
    {101, "PyramidsP4"},  {102, "PrismsP3"},    {103, "PrismsP4"},
};

// The volume keyword for a GMF keyword code, or null.
const MeditVolumeKeyword* volumeKeyword(uint32_t code) {
  switch (code) {
    case kTetrahedra: return &kMeditVolumeKeywords[0];
    case kHexahedra: return &kMeditVolumeKeywords[1];
    case kPrisms: return &kMeditVolumeKeywords[2];
    case kPyramids: return &kMeditVolumeKeywords[3];
    default: return nullptr;
  }
}

class MeshbReader {
 public:
  MeshbReader(const std::string& path, const std::string& bytes) : path_(path), bytes_(bytes) {}

  StatusOr<ImportResult> read(const ImportOptions& options);

 private:
  Status fail(uint64_t at, const std::string& reason) const {
    return invalidData(path_ + ": byte offset " + std::to_string(at) + ": " + reason);
  }
  // Fails unless `n` bytes from pos_ lie inside the file (and, when `limit` is set, before it).
  Status need(uint64_t n, const std::string& what, uint64_t limit) const {
    const uint64_t end = limit ? limit : bytes_.size();
    if (pos_ > end || n > end - pos_) {
      return fail(pos_, what + " needs " + std::to_string(n) + " bytes but " +
                            (limit ? "the next keyword starts at byte offset " + std::to_string(limit)
                                   : "the file ends at byte offset " + std::to_string(bytes_.size())));
    }
    return Status::ok();
  }
  uint64_t word(size_t size) {
    uint8_t b[8];
    std::memcpy(b, bytes_.data() + pos_, size);
    pos_ += size;
    uint64_t v = 0;
    for (size_t i = 0; i < size; ++i) v |= static_cast<uint64_t>(b[swap_ ? size - 1 - i : i]) << (8 * i);
    return v;
  }
  int64_t integer() {
    const uint64_t v = word(int_size_);
    return int_size_ == 4 ? static_cast<int64_t>(static_cast<int32_t>(v)) : static_cast<int64_t>(v);
  }
  double real() {
    const uint64_t v = word(real_size_);
    if (real_size_ == 4) {
      const uint32_t u = static_cast<uint32_t>(v);
      float f;
      std::memcpy(&f, &u, 4);
      return f;
    }
    double d;
    std::memcpy(&d, &v, 8);
    return d;
  }
  // The entry count after a keyword record's header, checked against the bytes before `limit`.
  StatusOr<uint64_t> count(const char* keyword, uint64_t entry_size, uint64_t limit);
  Status readVertices(uint64_t limit);
  Status readElements(const MeditVolumeKeyword& kw, uint64_t limit);

  const std::string& path_;
  const std::string& bytes_;
  uint64_t pos_ = 0;
  bool swap_ = false;
  size_t int_size_ = 4, real_size_ = 4, pos_size_ = 4;
  int64_t dimension_ = 0;
  bool have_vertices_ = false;
  std::string skipped_volume_;
  ImportResult result_;
  MeditCells cells_;
};

StatusOr<uint64_t> MeshbReader::count(const char* keyword, uint64_t entry_size, uint64_t limit) {
  const uint64_t at = pos_;
  GTN_RETURN_IF_ERROR(need(int_size_ == 8 ? 8 : 4, std::string(keyword) + " count", limit));
  const int64_t n = int_size_ == 8 ? static_cast<int64_t>(word(8)) : static_cast<int32_t>(word(4));
  if (n < 0) return fail(at, std::string(keyword) + " count " + std::to_string(n) + " is negative");
  const uint64_t end = limit ? limit : bytes_.size();
  if (static_cast<uint64_t>(n) > (end - pos_) / entry_size) {
    return fail(at, std::string(keyword) + " count " + std::to_string(n) + " needs " +
                        (static_cast<uint64_t>(n) > UINT64_MAX / entry_size
                             ? std::string("more bytes than a file can hold")
                             : std::to_string(static_cast<uint64_t>(n) * entry_size) + " bytes") +
                        " but " + std::to_string(end - pos_) + " are left before byte offset " + std::to_string(end));
  }
  if (static_cast<uint64_t>(n) >= UINT32_MAX) return unsupported(path_ + ": more than 2^32-2 " + keyword);
  return static_cast<uint64_t>(n);
}

Status MeshbReader::readVertices(uint64_t limit) {
  const uint64_t at = pos_;
  if (dimension_ != 3) return fail(at, "Vertices before a Dimension keyword");
  if (have_vertices_) return fail(at, "a second Vertices keyword");
  have_vertices_ = true;
  GTN_ASSIGN_OR_RETURN(const uint64_t n, count("Vertices", 3 * real_size_ + int_size_, limit));
  TetMesh& mesh = result_.mesh;
  mesh.coords.resize(3 * n);
  mesh.coord_type = real_size_ == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  Field ref("ref", 1, ScalarType::kInt32, n);
  for (uint64_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) mesh.coords[3 * i + c] = real();
    const uint64_t ref_at = pos_;
    const int64_t r = integer();
    if (r < INT32_MIN || r > INT32_MAX)
      return fail(ref_at, "vertex " + std::to_string(i + 1) + " has reference " + std::to_string(r) +
                              ", outside the 32-bit range");
    ref.set<int32_t>(i, 0, static_cast<int32_t>(r));
  }
  mesh.point_fields.push_back(std::move(ref));
  return Status::ok();
}

Status MeshbReader::readElements(const MeditVolumeKeyword& kw, uint64_t limit) {
  const uint64_t at = pos_;
  if (!have_vertices_) return fail(at, std::string(kw.name) + " before Vertices is not supported");
  if (!cells_.firstSection(kw)) return fail(at, std::string("a second ") + kw.name + " keyword");
  GTN_ASSIGN_OR_RETURN(const uint64_t n, count(kw.name, (kw.corners + 1) * int_size_, limit));
  TetMesh& mesh = result_.mesh;
  const int64_t np = static_cast<int64_t>(mesh.numPoints());
  cells_.reserve(kw, n, &mesh);
  for (uint64_t e = 0; e < n; ++e) {
    uint32_t corners[8];
    for (int k = 0; k < kw.corners; ++k) {
      const uint64_t v_at = pos_;
      const int64_t v = integer();
      if (v < 1 || v > np)
        return fail(v_at, std::string(kw.singular) + " " + std::to_string(e + 1) + " refers to vertex " +
                              std::to_string(v) + "; vertices are numbered 1 to " + std::to_string(np));
      corners[k] = static_cast<uint32_t>(v - 1);
    }
    const uint64_t ref_at = pos_;
    const int64_t r = integer();
    if (r < INT32_MIN || r > INT32_MAX)
      return fail(ref_at, std::string(kw.singular) + " " + std::to_string(e + 1) + " has reference " +
                              std::to_string(r) + ", outside the 32-bit range");
    cells_.add(kw, corners, static_cast<int32_t>(r), &mesh);
  }
  return Status::ok();
}

StatusOr<ImportResult> MeshbReader::read(const ImportOptions& options) {
  if (bytes_.size() < 8)
    return Status(StatusCode::kNotOurFile, path_ + ": " + std::to_string(bytes_.size()) +
                                               " bytes: too short for a .meshb header (code and version)");
  const uint64_t code = word(4);
  if (code == 0x01000000u) {
    swap_ = true;
  } else if (code != 1) {
    return Status(StatusCode::kNotOurFile, path_ + ": byte offset 0: not a .meshb file: its first word is " +
                                               std::to_string(code) + ", not 1 in either byte order");
  }
  const uint64_t version = word(4);
  if (version < 1 || version > 4)
    return unsupported(path_ + ": byte offset 4: .meshb version " + std::to_string(version) +
                       " is not supported (known: 1 to 4)");
  real_size_ = version == 1 ? 4 : 8;
  pos_size_ = version >= 3 ? 8 : 4;
  int_size_ = version == 4 ? 8 : 4;

  while (pos_ < bytes_.size()) {
    const uint64_t at = pos_;
    GTN_RETURN_IF_ERROR(need(4 + pos_size_, "a keyword header (code and next-keyword position)", 0));
    const uint32_t keyword = static_cast<uint32_t>(word(4));
    const uint64_t next = word(pos_size_);
    if (keyword == kEnd) break;
    if (next != 0 && (next <= at || next > bytes_.size()))
      return fail(at, "keyword " + std::to_string(keyword) + " says the next keyword is at byte offset " +
                          std::to_string(next) + ", outside (" + std::to_string(at) + ", " +
                          std::to_string(bytes_.size()) + "]");
    if (keyword == kDimension) {
      GTN_RETURN_IF_ERROR(need(4, "Dimension", next));
      const int64_t d = static_cast<int32_t>(word(4));
      if (d != 3)
        return fail(at, "dimension " + std::to_string(d) + ": only 3-dimensional (tetrahedral) Medit meshes are supported");
      dimension_ = d;
    } else if (keyword == kVertices) {
      GTN_RETURN_IF_ERROR(readVertices(next));
    } else if (const MeditVolumeKeyword* kw = volumeKeyword(keyword)) {
      GTN_RETURN_IF_ERROR(readElements(*kw, next));
    } else {
      for (const SkippedVolume& v : kSkippedVolumes) {
        if (v.code != keyword) continue;
        skipped_volume_ += (skipped_volume_.empty() ? "" : ", ") + std::string(v.name) + " (byte offset " +
                           std::to_string(at) + ")";
        result_.report.warnings.push_back("skipped " + std::string(v.name) + " at byte offset " + std::to_string(at) +
                                          ": higher-order and polyhedral elements are not read, so their volume is "
                                          "missing");
      }
    }
    if (next == 0) break;  // the last keyword
    pos_ = next;
  }
  if (!have_vertices_) return invalidData(path_ + ": no Vertices keyword");
  if (cells_.empty()) return invalidData(path_ + ": " + noVolumeElements(skipped_volume_));
  const bool tets_only = cells_.other_refs.empty();
  GTN_RETURN_IF_ERROR(finishMeditImport(path_, "meshb", &cells_, options, &result_));
  GTN_RETURN_IF_ERROR(readMeditSolutions(options.medit_solutions, tets_only, &result_));
  return std::move(result_);
}

}  // namespace

StatusOr<ImportResult> importMeshb(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const std::string bytes, readWholeFile(path));
  MeshbReader reader(path, bytes);
  return reader.read(options);
}

}  // namespace gtn
