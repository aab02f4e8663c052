// gmsh .msh importer, written from the format's documentation: MSH 2.x (2.0 to 2.2) and 4.1, ASCII
// and binary (either byte order, told by the integer 1 after the $MeshFormat line).
//
// Every node becomes a point, in the order of $Nodes or MSH 2's $ParametricNodes (tags may be sparse:
// they are mapped; parametric coordinates are not kept). Volume elements (tetrahedra, hexahedra,
// prisms, pyramids, of any order) become VTK cells of their corners and are split as the VTK
// importers split theirs (cell_split.h); the other nodes of higher-order elements stay as
// unreferenced points. Elements of lower dimension (points, lines, triangles, quadrangles) are
// skipped with a warning counting them by type, and so are their $ElementData values.
// Cell fields, as meshio names them: "gmsh:physical" (the element's physical group: its first tag in
// MSH 2, its entity's first physical tag in MSH 4.1; 0 for none) and "gmsh:geometrical" (its
// elementary entity; in a partitioned MSH 4.1 file the physical tags and the parent of the partitioned
// entity in $PartitionedEntities, so that a mesh gives the same fields partitioned or not). MSH 2
// lists an element once per physical group it belongs to: the repetitions (same type and nodes) are
// read once, in the first group, with a warning. $NodeData and $ElementData become point and cell
// fields (float64, their number of components) named by their first string tag; of several time
// steps of one name, the last (the largest time step index) is read, the sections of that step
// (partitions) together, and a warning says so. $ElementNodeData and other sections are skipped with
// a warning naming them. Names of volume physical groups go into the metadata as
// gmsh.physical_name.<tag>.
//
// Counts are never trusted: each is checked against the bytes left in the file before anything is
// allocated for it. Errors name the file and the line (text) or byte offset (binary data).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "convert/cell_split.h"
#include "convert/import.h"
#include "convert/text_reader.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"
#include "mesh/index.h"

namespace gtn {

namespace {

constexpr int64_t kMaxItems = 0xFFFFFFFDll;

// gmsh element types: number of nodes, dimension and, for volume elements, the linear VTK cell of
// their corners (which come first in every order).
struct GmshType {
  int type;
  int nodes;
  int dim;
  uint8_t vtk;  // 0: not a volume element
  const char* name;
};

constexpr GmshType kGmshTypes[] = {
    {1, 2, 1, 0, "line"},
    {2, 3, 2, 0, "triangle"},
    {3, 4, 2, 0, "quadrangle"},
    {4, 4, 3, kVtkTetra, "tetrahedron"},
    {5, 8, 3, kVtkHexahedron, "hexahedron"},
    {6, 6, 3, kVtkWedge, "prism"},
    {7, 5, 3, kVtkPyramid, "pyramid"},
    {8, 3, 1, 0, "line3"},
    {9, 6, 2, 0, "triangle6"},
    {10, 9, 2, 0, "quadrangle9"},
    {11, 10, 3, kVtkTetra, "tetrahedron10"},
    {12, 27, 3, kVtkHexahedron, "hexahedron27"},
    {13, 18, 3, kVtkWedge, "prism18"},
    {14, 14, 3, kVtkPyramid, "pyramid14"},
    {15, 1, 0, 0, "point"},
    {16, 8, 2, 0, "quadrangle8"},
    {17, 20, 3, kVtkHexahedron, "hexahedron20"},
    {18, 15, 3, kVtkWedge, "prism15"},
    {19, 13, 3, kVtkPyramid, "pyramid13"},
    {20, 9, 2, 0, "triangle9"},
    {21, 10, 2, 0, "triangle10"},
    {22, 12, 2, 0, "triangle12"},
    {23, 15, 2, 0, "triangle15"},
    {24, 15, 2, 0, "triangle15i"},
    {25, 21, 2, 0, "triangle21"},
    {26, 4, 1, 0, "line4"},
    {27, 5, 1, 0, "line5"},
    {28, 6, 1, 0, "line6"},
    {29, 20, 3, kVtkTetra, "tetrahedron20"},
    {30, 35, 3, kVtkTetra, "tetrahedron35"},
    {31, 56, 3, kVtkTetra, "tetrahedron56"},
    {36, 16, 2, 0, "quadrangle16"},
    {37, 25, 2, 0, "quadrangle25"},
    {38, 36, 2, 0, "quadrangle36"},
    {42, 28, 2, 0, "triangle28"},
    {43, 36, 2, 0, "triangle36"},
    {44, 45, 2, 0, "triangle45"},
    {45, 55, 2, 0, "triangle55"},
    {46, 66, 2, 0, "triangle66"},
    {47, 49, 2, 0, "quadrangle49"},
    {48, 64, 2, 0, "quadrangle64"},
    {49, 81, 2, 0, "quadrangle81"},
    {50, 100, 2, 0, "quadrangle100"},
    {51, 121, 2, 0, "quadrangle121"},
    {62, 7, 1, 0, "line7"},
    {63, 8, 1, 0, "line8"},
    {64, 9, 1, 0, "line9"},
    {65, 10, 1, 0, "line10"},
    {66, 11, 1, 0, "line11"},
    {71, 84, 3, kVtkTetra, "tetrahedron84"},
    {72, 120, 3, kVtkTetra, "tetrahedron120"},
    {73, 165, 3, kVtkTetra, "tetrahedron165"},
    {74, 220, 3, kVtkTetra, "tetrahedron220"},
    {75, 286, 3, kVtkTetra, "tetrahedron286"},
    {90, 40, 3, kVtkWedge, "prism40"},
    {91, 75, 3, kVtkWedge, "prism75"},
    {92, 64, 3, kVtkHexahedron, "hexahedron64"},
    {93, 125, 3, kVtkHexahedron, "hexahedron125"},
    {94, 216, 3, kVtkHexahedron, "hexahedron216"},
    {95, 343, 3, kVtkHexahedron, "hexahedron343"},
    {96, 512, 3, kVtkHexahedron, "hexahedron512"},
    {97, 729, 3, kVtkHexahedron, "hexahedron729"},
    {98, 1000, 3, kVtkHexahedron, "hexahedron1000"},
    {106, 126, 3, kVtkWedge, "prism126"},
    {107, 196, 3, kVtkWedge, "prism196"},
    {108, 288, 3, kVtkWedge, "prism288"},
    {109, 405, 3, kVtkWedge, "prism405"},
    {110, 550, 3, kVtkWedge, "prism550"},
};

const GmshType* findType(int64_t type) {
  for (const GmshType& t : kGmshTypes)
    if (t.type == type) return &t;
  return nullptr;
}

int corners(uint8_t vtk) {
  switch (vtk) {
    case kVtkTetra: return 4;
    case kVtkHexahedron: return 8;
    case kVtkWedge: return 6;
    default: return 5;  // pyramid
  }
}

// Tags (of nodes or elements) to their 0-based index in the order read: a table when the tags are
// dense enough, else a sorted list.
class TagMap {
 public:
  std::vector<int64_t> tags;  // in index order

  // Builds the lookup; false when a tag occurs twice (*duplicate gets it).
  bool build(int64_t* duplicate) {
    int64_t max_tag = 0;
    bool nonneg = true;
    for (int64_t t : tags) {
      max_tag = std::max(max_tag, t);
      nonneg = nonneg && t >= 0;
    }
    dense_ = nonneg && static_cast<uint64_t>(max_tag) <= 4 * static_cast<uint64_t>(tags.size()) + 1024;
    if (dense_) {
      table_.assign(static_cast<size_t>(max_tag) + 1, kNoIndex);
      for (size_t i = 0; i < tags.size(); ++i) {
        uint32_t& slot = table_[static_cast<size_t>(tags[i])];
        if (slot != kNoIndex) {
          *duplicate = tags[i];
          return false;
        }
        slot = static_cast<uint32_t>(i);
      }
      return true;
    }
    sorted_.resize(tags.size());
    for (size_t i = 0; i < tags.size(); ++i) sorted_[i] = {tags[i], static_cast<uint32_t>(i)};
    std::sort(sorted_.begin(), sorted_.end());
    for (size_t i = 1; i < sorted_.size(); ++i) {
      if (sorted_[i].first == sorted_[i - 1].first) {
        *duplicate = sorted_[i].first;
        return false;
      }
    }
    return true;
  }

  uint32_t find(int64_t tag) const {
    if (dense_)
      return tag >= 0 && static_cast<uint64_t>(tag) < table_.size() ? table_[static_cast<size_t>(tag)] : kNoIndex;
    auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<int64_t, uint32_t>{tag, 0});
    return it != sorted_.end() && it->first == tag ? it->second : kNoIndex;
  }

 private:
  bool dense_ = false;
  std::vector<uint32_t> table_;
  std::vector<std::pair<int64_t, uint32_t>> sorted_;
};

// One $NodeData or $ElementData section.
struct DataSection {
  bool nodes = true;
  std::string name;
  int64_t step = 0;
  uint32_t components = 1;
  size_t offset = 0;  // of the section, for messages
  std::vector<int64_t> tags;
  std::vector<double> values;
};

class MshReader {
 public:
  MshReader(std::string path, std::string_view text) : path_(std::move(path)), text_(text) {}

  StatusOr<ImportResult> read(const ImportOptions& options);

 private:
  // --- positions and messages
  size_t lineAt(size_t offset) const {
    return 1 + static_cast<size_t>(std::count(text_.begin(), text_.begin() + std::min(offset, text_.size()), '\n'));
  }
  Status errorAt(size_t offset, const std::string& reason) const {
    return invalidData(path_ + ":" + std::to_string(lineAt(offset)) + ": " + reason);
  }
  Status binaryErrorAt(size_t offset, const std::string& reason) const {
    return invalidData(path_ + ": at byte " + std::to_string(offset) + ": " + reason);
  }
  Status endError(const std::string& what) const {
    return invalidData(path_ + ":" + std::to_string(lineAt(text_.size())) + ": file ends where " + what +
                       " was expected (truncated?)");
  }
  size_t remaining() const { return text_.size() - pos_; }

  // --- text
  static bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
  void skipSpace() {
    while (pos_ < text_.size() && isSpace(text_[pos_])) ++pos_;
  }
  // Skips the rest of the current line, its line break included (binary data starts after it).
  void skipLineEnd() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    if (pos_ < text_.size()) ++pos_;
  }
  // Whether only blanks are left on the current line (text).
  bool atLineEnd() const {
    size_t p = pos_;
    while (p < text_.size() && (text_[p] == ' ' || text_[p] == '\t' || text_[p] == '\r')) ++p;
    return p >= text_.size() || text_[p] == '\n';
  }
  bool token(std::string_view* out) {
    skipSpace();
    if (pos_ >= text_.size()) return false;
    token_at_ = pos_;
    while (pos_ < text_.size() && !isSpace(text_[pos_])) ++pos_;
    *out = text_.substr(token_at_, pos_ - token_at_);
    return true;
  }
  StatusOr<int64_t> textInt(const std::string& what) {
    std::string_view t;
    if (!token(&t)) return endError(what);
    int64_t v;
    if (!parseInt(t, &v)) return errorAt(token_at_, "expected " + what + " (an integer), found " + quotedToken(t));
    return v;
  }
  StatusOr<double> textDouble(const std::string& what) {
    std::string_view t;
    if (!token(&t)) return endError(what);
    double v;
    if (!parseDouble(t, &v)) return errorAt(token_at_, "expected " + what + " (a number), found " + quotedToken(t));
    return v;
  }
  // A count in text, checked against the file: each item takes at least `min_bytes` of what is left.
  StatusOr<int64_t> textCount(const std::string& what, size_t min_bytes) {
    GTN_ASSIGN_OR_RETURN(const int64_t n, textInt(what));
    GTN_RETURN_IF_ERROR(checkCount(n, what, min_bytes, token_at_));
    return n;
  }
  Status checkCount(int64_t n, const std::string& what, size_t min_bytes, size_t at) const {
    if (n < 0) return errorAt(at, what + " " + std::to_string(n) + " is negative");
    if (static_cast<uint64_t>(n) > remaining() / min_bytes)
      return invalidData(where(at) + what + " " + std::to_string(n) + " needs at least " +
                         std::to_string(static_cast<uint64_t>(n) * min_bytes) + " bytes, but " +
                         std::to_string(remaining()) + " are left in the file (truncated or corrupt)");
    return Status::ok();
  }
  std::string where(size_t at) const {
    return binary_ ? path_ + ": at byte " + std::to_string(at) + ": " : path_ + ":" + std::to_string(lineAt(at)) + ": ";
  }
  // A quoted string (a name): the text between the quotes, on one line; an unquoted token is taken whole.
  StatusOr<std::string> quoted(const std::string& what) {
    skipSpace();
    if (pos_ >= text_.size()) return endError(what);
    token_at_ = pos_;
    if (text_[pos_] != '"') {
      std::string_view t;
      token(&t);
      return std::string(t);
    }
    const size_t end = text_.find_first_of("\"\n", pos_ + 1);
    if (end == std::string_view::npos || text_[end] != '"') return errorAt(token_at_, what + " has no closing quote");
    std::string s(text_.substr(pos_ + 1, end - pos_ - 1));
    pos_ = end + 1;
    return s;
  }
  Status expectEnd(const std::string& section) {
    std::string_view t;
    if (!token(&t)) return endError("$End" + section);
    if (t != "$End" + section)
      return errorAt(token_at_, "expected $End" + section + ", found " + quotedToken(t) +
                                    " (counts that do not match the data, or a damaged file)");
    return Status::ok();
  }

  // --- values: binary or text, by the file's type
  bool rawBytes(void* out, size_t n) {
    if (remaining() < n) return false;
    std::memcpy(out, text_.data() + pos_, n);
    if (swap_) std::reverse(static_cast<uint8_t*>(out), static_cast<uint8_t*>(out) + n);
    pos_ += n;
    return true;
  }
  StatusOr<int64_t> readInt(const std::string& what) {
    if (!binary_) return textInt(what);
    int32_t v;
    if (!rawBytes(&v, 4)) return endError(what);
    return v;
  }
  // size_t in MSH 4.1 (data-size bytes), int in MSH 2.
  StatusOr<int64_t> readSize(const std::string& what) {
    if (!binary_) return textInt(what);
    if (version_ == 2) return readInt(what);
    const size_t at = pos_;
    if (size_bytes_ == 4) {
      uint32_t v;
      if (!rawBytes(&v, 4)) return endError(what);
      return static_cast<int64_t>(v);
    }
    uint64_t v;
    if (!rawBytes(&v, 8)) return endError(what);
    if (v > static_cast<uint64_t>(INT64_MAX))
      return binaryErrorAt(at, what + " " + std::to_string(v) + " is too large");
    return static_cast<int64_t>(v);
  }
  StatusOr<double> readDouble(const std::string& what) {
    if (!binary_) return textDouble(what);
    double v;
    if (!rawBytes(&v, 8)) return endError(what);
    return v;
  }
  StatusOr<int64_t> readCount(const std::string& what, size_t min_bytes) {
    const size_t at = pos_;
    GTN_ASSIGN_OR_RETURN(const int64_t n, readSize(what));
    GTN_RETURN_IF_ERROR(checkCount(n, what, min_bytes, binary_ ? at : token_at_));
    return n;
  }
  size_t sizeBytes() const { return version_ == 2 ? 4 : size_bytes_; }

  // --- sections
  Status readFormat();
  Status readPhysicalNames();
  Status readEntities(bool partitioned);
  Status readNodes(bool parametric);
  Status readElements();
  Status readData(const std::string& section);
  Status addElement(int64_t tag, const GmshType& type, const int64_t* nodes, int32_t physical, int32_t geometrical,
                    size_t at);
  void dropRepeatedElements();
  Status buildFields(ImportResult* result, std::vector<Field>* cell_fields);

  std::string path_;
  std::string_view text_;
  size_t pos_ = 0;
  size_t token_at_ = 0;
  int version_ = 0;  // 2 or 4 (4.1)
  bool binary_ = false;
  bool swap_ = false;
  size_t size_bytes_ = 8;
  bool have_nodes_ = false, have_elements_ = false;

  std::vector<double> coords_;
  TagMap node_map_;
  TagMap element_map_;                  // all elements, in file order
  std::vector<uint32_t> element_cell_;  // per element: its volume cell, or kNoIndex when skipped
  VtkCells cells_;
  std::vector<int32_t> physical_, geometrical_;
  bool any_physical_ = false, any_geometrical_ = false;
  std::map<int, size_t> skipped_;               // lower-dimension elements by gmsh type
  std::map<int, size_t> higher_order_;          // volume elements with more nodes than corners, by gmsh type
  std::map<int64_t, int32_t> volume_physical_;  // MSH 4.1: volume entity -> its first physical tag
  std::map<int64_t, int32_t> volume_parent_;    // MSH 4.1: partitioned volume entity -> the volume it was cut from
  size_t multi_physical_ = 0;
  std::vector<std::pair<int64_t, std::string>> volume_names_;
  std::vector<DataSection> data_;
  std::vector<std::string> unread_sections_;
  size_t element_node_data_ = 0;
  size_t repeated_ = 0;
};

Status MshReader::readFormat() {
  std::string_view t;
  if (!token(&t)) return endError("the format version");
  double version;
  if (!parseDouble(t, &version)) return errorAt(token_at_, "expected the format version, found " + quotedToken(t));
  if (version >= 2.0 && version < 3.0) {
    version_ = 2;
  } else if (version == 4.1) {
    version_ = 4;
  } else {
    return unsupported(where(token_at_) + "MSH format version " + std::string(t) +
                       " is not read; only 2.x (2.0 to 2.2) and 4.1 are: save it again from gmsh with "
                       "-format msh41 or msh22");
  }
  GTN_ASSIGN_OR_RETURN(const int64_t file_type, textInt("the file type (0 ASCII, 1 binary)"));
  if (file_type != 0 && file_type != 1)
    return errorAt(token_at_, "file type " + std::to_string(file_type) + " is neither 0 (ASCII) nor 1 (binary)");
  GTN_ASSIGN_OR_RETURN(const int64_t data_size, textInt("the data size"));
  binary_ = file_type == 1;
  if (binary_) {
    // MSH 2: the size of a floating-point number (8 is the only one gmsh writes); MSH 4.1: of size_t.
    if (version_ == 2 ? data_size != 8 : data_size != 4 && data_size != 8)
      return unsupported(where(token_at_) + "data size " + std::to_string(data_size) + " is not read (" +
                         (version_ == 2 ? "MSH 2 binary files use 8-byte doubles" : "size_t of 4 or 8 bytes") + ")");
    size_bytes_ = static_cast<size_t>(data_size);
    skipLineEnd();
    const size_t at = pos_;
    uint8_t one[4];
    if (!rawBytes(one, 4)) return endError("the binary integer 1");
    if (one[0] == 1 && one[1] == 0 && one[2] == 0 && one[3] == 0) {
      swap_ = false;
    } else if (one[0] == 0 && one[1] == 0 && one[2] == 0 && one[3] == 1) {
      swap_ = true;
    } else {
      return binaryErrorAt(at,
                           "the binary integer 1 after the format line reads neither little- nor big-endian "
                           "(a binary file transferred as text?)");
    }
  }
  return expectEnd("MeshFormat");
}

Status MshReader::readPhysicalNames() {
  GTN_ASSIGN_OR_RETURN(const int64_t n, textCount("physical name count", 6));
  for (int64_t i = 0; i < n; ++i) {
    GTN_ASSIGN_OR_RETURN(const int64_t dim, textInt("physical dimension"));
    GTN_ASSIGN_OR_RETURN(const int64_t tag, textInt("physical tag"));
    GTN_ASSIGN_OR_RETURN(std::string name, quoted("physical name"));
    if (dim == 3) volume_names_.emplace_back(tag, std::move(name));
  }
  return expectEnd("PhysicalNames");
}

// $Entities, or with partitioned the $PartitionedEntities of a partitioned mesh: the entities gmsh made by
// cutting the model's, each naming the entity it was cut from (its parent) and carrying its physical tags.
Status MshReader::readEntities(bool partitioned) {
  const std::string section = partitioned ? "PartitionedEntities" : "Entities";
  if (partitioned) {
    GTN_RETURN_IF_ERROR(readSize("partition count").status());
    GTN_ASSIGN_OR_RETURN(const int64_t ghosts, readCount("ghost entity count", binary_ ? 8 : 4));
    for (int64_t g = 0; g < ghosts; ++g) {
      GTN_RETURN_IF_ERROR(readInt("ghost entity tag").status());
      GTN_RETURN_IF_ERROR(readInt("ghost entity partition").status());
    }
  }
  int64_t counts[4];
  const char* kinds[4] = {"point entity count", "curve entity count", "surface entity count", "volume entity count"};
  for (int d = 0; d < 4; ++d) {
    GTN_ASSIGN_OR_RETURN(counts[d], readCount(kinds[d], binary_ ? 4 + 24 + sizeBytes() : 8));
  }
  for (int d = 0; d < 4; ++d) {
    for (int64_t e = 0; e < counts[d]; ++e) {
      GTN_ASSIGN_OR_RETURN(const int64_t tag, readInt("entity tag"));
      if (partitioned) {
        GTN_ASSIGN_OR_RETURN(const int64_t parent_dim, readInt("parent entity dimension"));
        GTN_ASSIGN_OR_RETURN(const int64_t parent_tag, readInt("parent entity tag"));
        if (d == 3 && parent_dim == 3) volume_parent_[tag] = static_cast<int32_t>(parent_tag);
        GTN_ASSIGN_OR_RETURN(const int64_t num_partitions, readCount("partition tag count", binary_ ? 4 : 2));
        for (int64_t k = 0; k < num_partitions; ++k) GTN_RETURN_IF_ERROR(readInt("partition tag").status());
      }
      for (int k = 0; k < (d == 0 ? 3 : 6); ++k) GTN_RETURN_IF_ERROR(readDouble("entity bounding box").status());
      GTN_ASSIGN_OR_RETURN(const int64_t num_physical, readCount("physical tag count", binary_ ? 4 : 2));
      for (int64_t k = 0; k < num_physical; ++k) {
        GTN_ASSIGN_OR_RETURN(const int64_t physical, readInt("physical tag"));
        if (d == 3 && k == 0) volume_physical_[tag] = static_cast<int32_t>(physical);
      }
      if (d == 3 && num_physical > 1 && !partitioned) ++multi_physical_;  // counted once, in $Entities
      if (d > 0) {
        GTN_ASSIGN_OR_RETURN(const int64_t num_bounding, readCount("bounding entity count", binary_ ? 4 : 2));
        for (int64_t k = 0; k < num_bounding; ++k) GTN_RETURN_IF_ERROR(readInt("bounding entity tag").status());
      }
    }
  }
  return expectEnd(section);
}

// MSH 2 writes the nodes as $ParametricNodes when asked to save parametric coordinates (gmsh -save_parametric):
// after each node's coordinates its entity's dimension and tag, then 1 (curve) or 2 (surface) parameters,
// which are not kept. In text a node on no entity has none of these.
Status MshReader::readNodes(bool parametric) {
  if (have_nodes_) return errorAt(token_at_, "a second $Nodes or $ParametricNodes section (only one is read)");
  have_nodes_ = true;
  std::vector<int64_t>& tags = node_map_.tags;
  auto addNode = [&](int64_t tag, const double xyz[3], size_t at) -> Status {
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(xyz[a]))
        return invalidData(where(at) + "node " + std::to_string(tag) + " has a coordinate that is not finite");
    coords_.insert(coords_.end(), xyz, xyz + 3);
    return Status::ok();
  };
  if (version_ == 2) {
    GTN_ASSIGN_OR_RETURN(const int64_t n, textCount("node count", binary_ ? 28 : 8));
    if (n > kMaxItems) return errorAt(token_at_, "more nodes than 32-bit indices can address");
    if (binary_) skipLineEnd();
    tags.reserve(static_cast<size_t>(n));
    coords_.reserve(3 * static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      const size_t at = pos_;
      GTN_ASSIGN_OR_RETURN(const int64_t tag, readInt("node tag"));
      double xyz[3];
      for (double& c : xyz) {
        GTN_ASSIGN_OR_RETURN(c, readDouble("node coordinate"));
      }
      const size_t coords_at = binary_ ? at : token_at_;
      if (parametric && (binary_ || !atLineEnd())) {
        GTN_ASSIGN_OR_RETURN(const int64_t dim, readInt("node entity dimension"));
        if (dim < 0 || dim > 3) {
          const std::string reason =
              "node " + std::to_string(tag) + ": entity dimension " + std::to_string(dim) + " is not 0 to 3";
          return binary_ ? binaryErrorAt(pos_ - 4, reason) : errorAt(token_at_, reason);
        }
        GTN_RETURN_IF_ERROR(readInt("node entity tag").status());
        for (int64_t k = 0; k < (dim == 1 || dim == 2 ? dim : 0); ++k)
          GTN_RETURN_IF_ERROR(readDouble("node parametric coordinate").status());
      }
      tags.push_back(tag);
      GTN_RETURN_IF_ERROR(addNode(tag, xyz, coords_at));
    }
  } else {
    GTN_ASSIGN_OR_RETURN(const int64_t blocks, readCount("node block count", binary_ ? 12 + sizeBytes() : 8));
    const size_t header_at = binary_ ? pos_ : 0;
    GTN_ASSIGN_OR_RETURN(const int64_t n, readCount("node count", binary_ ? sizeBytes() + 24 : 8));
    if (n > kMaxItems) return errorAt(binary_ ? header_at : token_at_, "more nodes than 32-bit indices can address");
    GTN_RETURN_IF_ERROR(readSize("smallest node tag").status());
    GTN_RETURN_IF_ERROR(readSize("largest node tag").status());
    tags.reserve(static_cast<size_t>(n));
    coords_.reserve(3 * static_cast<size_t>(n));
    for (int64_t b = 0; b < blocks; ++b) {
      GTN_ASSIGN_OR_RETURN(const int64_t dim, readInt("entity dimension"));
      GTN_RETURN_IF_ERROR(readInt("entity tag").status());
      GTN_ASSIGN_OR_RETURN(const int64_t parametric, readInt("parametric flag"));
      const size_t count_at = binary_ ? pos_ : 0;
      const int extra = parametric ? static_cast<int>(std::clamp<int64_t>(dim, 0, 3)) : 0;
      GTN_ASSIGN_OR_RETURN(const int64_t count,
                           readCount("node count of a block", binary_ ? sizeBytes() + 8 * (3 + extra) : 8));
      if (count > n - static_cast<int64_t>(tags.size()))
        return invalidData(where(binary_ ? count_at : token_at_) + "the node blocks hold more nodes than the " +
                           std::to_string(n) + " the $Nodes header announces");
      // The block's tags, then its coordinates (with parametric ones after each point's x y z).
      const size_t first = tags.size();
      for (int64_t i = 0; i < count; ++i) {
        GTN_ASSIGN_OR_RETURN(const int64_t tag, readSize("node tag"));
        tags.push_back(tag);
      }
      for (int64_t i = 0; i < count; ++i) {
        const size_t at = pos_;
        double xyz[3];
        for (double& c : xyz) {
          GTN_ASSIGN_OR_RETURN(c, readDouble("node coordinate"));
        }
        for (int k = 0; k < extra; ++k) GTN_RETURN_IF_ERROR(readDouble("parametric coordinate").status());
        GTN_RETURN_IF_ERROR(addNode(tags[first + static_cast<size_t>(i)], xyz, binary_ ? at : token_at_));
      }
    }
    if (static_cast<int64_t>(tags.size()) != n)
      return errorAt(pos_, "the node blocks hold " + std::to_string(tags.size()) +
                               " nodes, the $Nodes header announces " + std::to_string(n));
  }
  int64_t duplicate = 0;
  if (!node_map_.build(&duplicate))
    return errorAt(pos_, "node tag " + std::to_string(duplicate) + " occurs twice in $Nodes");
  return expectEnd(parametric ? "ParametricNodes" : "Nodes");
}

Status MshReader::addElement(int64_t tag, const GmshType& type, const int64_t* nodes, int32_t physical,
                             int32_t geometrical, size_t at) {
  element_map_.tags.push_back(tag);
  if (type.dim < 3) {
    ++skipped_[type.type];
    element_cell_.push_back(kNoIndex);
    return Status::ok();
  }
  if (cells_.types.size() >= static_cast<size_t>(kMaxItems))
    return invalidData(where(at) + "more volume elements than 32-bit indices can address");
  const int c = corners(type.vtk);
  const size_t first = cells_.connectivity.size();
  for (int k = 0; k < type.nodes; ++k) {
    const uint32_t p = node_map_.find(nodes[k]);
    if (p == kNoIndex)
      return invalidData(where(at) + "element " + std::to_string(tag) + " (" + type.name + ") refers to node " +
                         std::to_string(nodes[k]) + ", which $Nodes does not define");
    if (k < c) cells_.connectivity.push_back(p);
  }
  // gmsh's prism turns its first triangle towards the second one (its reference corners (0, 0, 0),
  // (1, 0, 0), (0, 1, 0), then the same at z = 1); VTK's wedge turns it away. Its corners in VTK's
  // order, so that a prism gmsh stores positively is split into positive tetrahedra.
  if (type.vtk == kVtkWedge) {
    std::swap(cells_.connectivity[first + 1], cells_.connectivity[first + 2]);
    std::swap(cells_.connectivity[first + 4], cells_.connectivity[first + 5]);
  }
  element_cell_.push_back(static_cast<uint32_t>(cells_.types.size()));
  cells_.types.push_back(type.vtk);
  cells_.offsets.push_back(static_cast<int64_t>(cells_.connectivity.size()));
  physical_.push_back(physical);
  geometrical_.push_back(geometrical);
  if (type.nodes > c) ++higher_order_[type.type];
  return Status::ok();
}

Status MshReader::readElements() {
  if (have_elements_) return errorAt(token_at_, "a second $Elements section (only one is read)");
  if (!have_nodes_) return errorAt(token_at_, "$Elements comes before $Nodes");
  have_elements_ = true;
  std::vector<int64_t> nodes;
  auto typeOf = [&](int64_t t, size_t at) -> StatusOr<const GmshType*> {
    const GmshType* type = findType(t);
    if (!type)
      return unsupported(where(at) + "element type " + std::to_string(t) +
                         " is not a gmsh element type this reader knows (points, lines, triangles, quadrangles, "
                         "tetrahedra, hexahedra, prisms and pyramids up to the orders gmsh writes)");
    return type;
  };
  if (version_ == 2) {
    GTN_ASSIGN_OR_RETURN(const int64_t n, textCount("element count", 8));
    if (binary_) skipLineEnd();
    element_map_.tags.reserve(static_cast<size_t>(n));
    int64_t done = 0;
    std::vector<int64_t> tags;
    while (done < n) {
      // ASCII: one element a line, "tag type ntags tags... nodes..."; binary: a header (type, number of
      // elements that follow, ntags), then those elements as "tag tags... nodes..." int32 values.
      const size_t header_at = pos_;
      int64_t tag = 0, follow = 1;
      if (!binary_) {
        GTN_ASSIGN_OR_RETURN(tag, textInt("element tag"));
      }
      const size_t type_at = binary_ ? pos_ : 0;
      GTN_ASSIGN_OR_RETURN(const int64_t type_number, readInt("element type"));
      GTN_ASSIGN_OR_RETURN(const GmshType* type, typeOf(type_number, binary_ ? type_at : token_at_));
      if (binary_) {
        GTN_ASSIGN_OR_RETURN(follow, readInt("element count of a block"));
        if (follow < 1 || follow > n - done)
          return binaryErrorAt(header_at, "a block of " + std::to_string(follow) + " elements where " +
                                              std::to_string(n - done) + " remain of the announced " +
                                              std::to_string(n));
      }
      GTN_ASSIGN_OR_RETURN(const int64_t num_tags, readInt("element tag count"));
      if (num_tags < 0 || num_tags > 1000)
        return invalidData(where(binary_ ? header_at : token_at_) + "element tag count " + std::to_string(num_tags) +
                           " is out of range (0 to 1000)");
      if (binary_) {
        const uint64_t bytes = static_cast<uint64_t>(follow) * 4 * static_cast<uint64_t>(1 + num_tags + type->nodes);
        if (bytes > remaining())
          return binaryErrorAt(header_at, "a block of " + std::to_string(follow) + " elements needs " +
                                              std::to_string(bytes) + " bytes, but " + std::to_string(remaining()) +
                                              " are left in the file (truncated or corrupt)");
      }
      for (int64_t e = 0; e < follow; ++e) {
        const size_t at = binary_ ? pos_ : token_at_;
        if (binary_) {
          GTN_ASSIGN_OR_RETURN(tag, readInt("element tag"));
        }
        tags.resize(static_cast<size_t>(num_tags));
        for (int64_t& t : tags) {
          GTN_ASSIGN_OR_RETURN(t, readInt("element tag"));
        }
        nodes.resize(static_cast<size_t>(type->nodes));
        for (int64_t& v : nodes) {
          GTN_ASSIGN_OR_RETURN(v, readInt("element node"));
        }
        if (num_tags >= 1) any_physical_ = true;
        if (num_tags >= 2) any_geometrical_ = true;
        GTN_RETURN_IF_ERROR(addElement(tag, *type, nodes.data(), num_tags >= 1 ? static_cast<int32_t>(tags[0]) : 0,
                                       num_tags >= 2 ? static_cast<int32_t>(tags[1]) : 0, at));
      }
      done += follow;
    }
  } else {
    GTN_ASSIGN_OR_RETURN(const int64_t blocks, readCount("element block count", binary_ ? 12 + sizeBytes() : 8));
    GTN_ASSIGN_OR_RETURN(const int64_t n, readCount("element count", binary_ ? 2 * sizeBytes() : 4));
    GTN_RETURN_IF_ERROR(readSize("smallest element tag").status());
    GTN_RETURN_IF_ERROR(readSize("largest element tag").status());
    element_map_.tags.reserve(static_cast<size_t>(n));
    any_geometrical_ = true;
    for (int64_t b = 0; b < blocks; ++b) {
      GTN_ASSIGN_OR_RETURN(const int64_t dim, readInt("entity dimension"));
      GTN_ASSIGN_OR_RETURN(const int64_t entity, readInt("entity tag"));
      const size_t type_at = binary_ ? pos_ : 0;
      GTN_ASSIGN_OR_RETURN(const int64_t type_number, readInt("element type"));
      GTN_ASSIGN_OR_RETURN(const GmshType* type, typeOf(type_number, binary_ ? type_at : token_at_));
      if (dim != type->dim)
        return invalidData(where(binary_ ? type_at : token_at_) + "a block of " + type->name +
                           " elements in an entity of dimension " + std::to_string(dim));
      GTN_ASSIGN_OR_RETURN(const int64_t count,
                           readCount("element count of a block", (binary_ ? sizeBytes() : 2) * (1 + type->nodes)));
      int32_t physical = 0;
      int32_t geometrical = static_cast<int32_t>(entity);
      if (dim == 3) {
        auto it = volume_physical_.find(entity);
        if (it != volume_physical_.end()) {
          physical = it->second;
          any_physical_ = true;
        }
        auto parent = volume_parent_.find(entity);
        if (parent != volume_parent_.end()) geometrical = parent->second;
      }
      nodes.resize(static_cast<size_t>(type->nodes));
      for (int64_t e = 0; e < count; ++e) {
        const size_t at = pos_;
        GTN_ASSIGN_OR_RETURN(const int64_t tag, readSize("element tag"));
        const size_t line_at = binary_ ? at : token_at_;
        for (int64_t& v : nodes) {
          GTN_ASSIGN_OR_RETURN(v, readSize("element node"));
        }
        GTN_RETURN_IF_ERROR(addElement(tag, *type, nodes.data(), physical, geometrical, line_at));
      }
    }
    if (static_cast<int64_t>(element_map_.tags.size()) != n)
      return errorAt(pos_, "the element blocks hold " + std::to_string(element_map_.tags.size()) +
                               " elements, the $Elements header announces " + std::to_string(n));
  }
  return expectEnd("Elements");
}

// MSH 2 has no entities: gmsh writes an element that belongs to several physical groups once per
// group (same type, same nodes, another tag). The repetitions go; gmsh:physical keeps the first group.
void MshReader::dropRepeatedElements() {
  const size_t n = cells_.types.size();
  auto nodesOf = [&](uint32_t c) {
    return std::span<const int64_t>(cells_.connectivity.data() + cells_.offsets[c],
                                    static_cast<size_t>(cells_.offsets[c + 1] - cells_.offsets[c]));
  };
  auto same = [&](uint32_t a, uint32_t b) {
    return cells_.types[a] == cells_.types[b] && std::ranges::equal(nodesOf(a), nodesOf(b));
  };
  // Cells ordered by type and nodes, then by index: repetitions follow their first occurrence.
  std::vector<uint32_t> order(n);
  for (size_t c = 0; c < n; ++c) order[c] = static_cast<uint32_t>(c);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    if (cells_.types[a] != cells_.types[b]) return cells_.types[a] < cells_.types[b];
    const std::span<const int64_t> x = nodesOf(a), y = nodesOf(b);
    if (std::ranges::lexicographical_compare(x, y)) return true;
    if (std::ranges::lexicographical_compare(y, x)) return false;
    return a < b;
  });
  std::vector<uint32_t> keep_as(n);  // each cell's first occurrence
  for (size_t i = 0; i < n; ++i)
    keep_as[order[i]] = i > 0 && same(order[i - 1], order[i]) ? keep_as[order[i - 1]] : order[i];
  std::vector<uint32_t> new_index(n);
  VtkCells kept;
  kept.types.reserve(n);
  size_t out = 0;
  for (size_t c = 0; c < n; ++c) {
    if (keep_as[c] != c) {
      new_index[c] = new_index[keep_as[c]];
      continue;
    }
    new_index[c] = static_cast<uint32_t>(out);
    kept.types.push_back(cells_.types[c]);
    kept.connectivity.insert(kept.connectivity.end(), cells_.connectivity.begin() + cells_.offsets[c],
                             cells_.connectivity.begin() + cells_.offsets[c + 1]);
    kept.offsets.push_back(static_cast<int64_t>(kept.connectivity.size()));
    physical_[out] = physical_[c];
    geometrical_[out] = geometrical_[c];
    ++out;
  }
  repeated_ = n - out;
  if (repeated_ == 0) return;
  cells_ = std::move(kept);
  physical_.resize(out);
  geometrical_.resize(out);
  for (uint32_t& c : element_cell_)
    if (c != kNoIndex) c = new_index[c];
}

Status MshReader::readData(const std::string& section) {
  const size_t section_at = token_at_;
  DataSection data;
  data.nodes = section == "NodeData";
  data.offset = section_at;
  GTN_ASSIGN_OR_RETURN(const int64_t num_strings, textCount("string tag count", 2));
  std::vector<std::string> strings;
  for (int64_t i = 0; i < num_strings; ++i) {
    GTN_ASSIGN_OR_RETURN(std::string s, quoted("string tag"));
    strings.push_back(std::move(s));
  }
  GTN_ASSIGN_OR_RETURN(const int64_t num_reals, textCount("real tag count", 2));
  for (int64_t i = 0; i < num_reals; ++i) GTN_RETURN_IF_ERROR(textDouble("real tag").status());
  GTN_ASSIGN_OR_RETURN(const int64_t num_ints, textCount("integer tag count", 2));
  std::vector<int64_t> ints;
  for (int64_t i = 0; i < num_ints; ++i) {
    GTN_ASSIGN_OR_RETURN(const int64_t v, textInt("integer tag"));
    ints.push_back(v);
  }
  if (ints.size() < 3)
    return errorAt(section_at, "$" + section + " has " + std::to_string(ints.size()) +
                                   " integer tags; 3 are needed (time step, components, count)");
  data.name = strings.empty() ? "gmsh:" + section + std::to_string(data_.size()) : strings[0];
  data.step = ints[0];
  if (ints[1] < 1 || ints[1] > 9)
    return errorAt(section_at, "$" + section + " '" + data.name + "' has " + std::to_string(ints[1]) +
                                   " components per value (1 to 9 are read)");
  data.components = static_cast<uint32_t>(ints[1]);
  if (section == "ElementNodeData") {
    ++element_node_data_;
    const size_t end = text_.find("$EndElementNodeData", pos_);
    if (end == std::string_view::npos) return endError("$EndElementNodeData");
    pos_ = end;
    return expectEnd(section);
  }
  const int64_t count = ints[2];
  GTN_RETURN_IF_ERROR(checkCount(count, "value count of $" + section + " '" + data.name + "'",
                                 binary_ ? 4 + 8 * data.components : 2 * (1 + data.components), section_at));
  if (binary_) skipLineEnd();
  data.tags.reserve(static_cast<size_t>(count));
  data.values.reserve(static_cast<size_t>(count) * data.components);
  for (int64_t i = 0; i < count; ++i) {
    GTN_ASSIGN_OR_RETURN(const int64_t tag, readInt(data.nodes ? "node tag" : "element tag"));
    data.tags.push_back(tag);
    for (uint32_t c = 0; c < data.components; ++c) {
      GTN_ASSIGN_OR_RETURN(const double v, readDouble("value"));
      data.values.push_back(v);
    }
  }
  data_.push_back(std::move(data));
  return expectEnd(section);
}

Status MshReader::buildFields(ImportResult* result, std::vector<Field>* cell_fields) {
  const size_t num_cells = cells_.types.size();
  if (!data_.empty() && have_elements_) {
    int64_t duplicate = 0;
    if (!element_map_.build(&duplicate))
      return invalidData(path_ + ": element tag " + std::to_string(duplicate) + " occurs twice in $Elements");
  }
  // Per kind and name, the sections of the largest time step (in file order).
  std::vector<std::pair<bool, std::string>> names;
  for (const DataSection& d : data_)
    if (std::find(names.begin(), names.end(), std::make_pair(d.nodes, d.name)) == names.end())
      names.emplace_back(d.nodes, d.name);
  size_t skipped_values = 0;
  for (const auto& [nodes, name] : names) {
    const std::string kind = nodes ? "$NodeData" : "$ElementData";
    int64_t last = std::numeric_limits<int64_t>::min();
    std::vector<int64_t> steps;
    for (const DataSection& d : data_)
      if (d.nodes == nodes && d.name == name) {
        last = std::max(last, d.step);
        if (std::find(steps.begin(), steps.end(), d.step) == steps.end()) steps.push_back(d.step);
      }
    if (nodes && !have_nodes_) return invalidData(path_ + ": " + kind + " '" + name + "' but no $Nodes");
    if (!nodes && !have_elements_) return invalidData(path_ + ": " + kind + " '" + name + "' but no $Elements");
    const size_t items = nodes ? result->mesh.numPoints() : num_cells;
    Field field;
    size_t missing = items, conflicting = 0;
    std::vector<uint8_t> seen(items, 0);
    for (const DataSection& d : data_) {
      if (d.nodes != nodes || d.name != name || d.step != last) continue;
      if (field.bytes.empty() && items > 0) {
        field = Field(name, d.components, ScalarType::kFloat64, items);
        for (size_t i = 0; i < items * d.components; ++i) field.data<double>()[i] = std::nan("");
      }
      if (d.components != field.components)
        return errorAt(d.offset, kind + " '" + name + "' has " + std::to_string(d.components) +
                                     " components here and " + std::to_string(field.components) +
                                     " in another section of the same time step");
      for (size_t i = 0; i < d.tags.size(); ++i) {
        uint32_t item;
        if (nodes) {
          item = node_map_.find(d.tags[i]);
          if (item == kNoIndex)
            return errorAt(d.offset, kind + " '" + name + "' gives a value to node " + std::to_string(d.tags[i]) +
                                         ", which $Nodes does not define");
        } else {
          const uint32_t e = element_map_.find(d.tags[i]);
          if (e == kNoIndex)
            return errorAt(d.offset, kind + " '" + name + "' gives a value to element " + std::to_string(d.tags[i]) +
                                         ", which $Elements does not define");
          item = element_cell_[e];
          if (item == kNoIndex) {
            ++skipped_values;
            continue;
          }
        }
        const double* v = d.values.data() + i * field.components;
        if (!seen[item]) {
          seen[item] = 1;
          --missing;
        } else if (std::memcmp(field.data<double>() + size_t{item} * field.components, v,
                               field.components * sizeof(double)) != 0) {
          ++conflicting;  // given twice, differently (partitions repeat their shared nodes' values alike)
        }
        for (uint32_t c = 0; c < field.components; ++c) field.set<double>(item, c, v[c]);
      }
    }
    if (items == 0) continue;
    if (steps.size() > 1)
      result->report.warnings.push_back(kind + " '" + name + "': read time step " + std::to_string(last) +
                                        ", the last of its " + std::to_string(steps.size()) + " time steps");
    if (missing > 0)
      result->report.warnings.push_back(kind + " '" + name + "' has no value for " + std::to_string(missing) + " of " +
                                        std::to_string(items) + (nodes ? " points" : " volume cells") + " (NaN there)");
    if (conflicting > 0)
      result->report.warnings.push_back(kind + " '" + name + "' gives " + std::to_string(conflicting) +
                                        (nodes ? " points" : " volume cells") +
                                        " a second, different value in the same time step (the last one is kept)");
    (nodes ? result->mesh.point_fields : *cell_fields).push_back(std::move(field));
  }
  if (skipped_values > 0)
    result->report.warnings.push_back(std::to_string(skipped_values) +
                                      " $ElementData values of skipped lower-dimension elements not read");
  return Status::ok();
}

StatusOr<ImportResult> MshReader::read(const ImportOptions& options) {
  std::string_view t;
  if (!token(&t) || t != "$MeshFormat") {
    if (text_.substr(0, 4) == "$NOD")
      return unsupported(path_ +
                         ": MSH format version 1 ($NOD) is not read; only 2.x and 4.1 are: save it "
                         "again from gmsh with -format msh41 or msh22");
    return Status(StatusCode::kNotOurFile, path_ + ": not a gmsh .msh file (it does not start with $MeshFormat)");
  }
  skipLineEnd();
  GTN_RETURN_IF_ERROR(readFormat());
  while (true) {
    if (!token(&t)) break;
    if (t.empty() || t[0] != '$')
      return errorAt(token_at_, "expected a section ($Nodes, $Elements, ...), found " + quotedToken(t));
    const std::string section(t.substr(1));
    const size_t section_at = token_at_;
    skipLineEnd();
    if (section == "MeshFormat") return errorAt(section_at, "a second $MeshFormat");
    if (section == "PhysicalNames") {
      GTN_RETURN_IF_ERROR(readPhysicalNames());
    } else if ((section == "Entities" || section == "PartitionedEntities") && version_ == 4) {
      GTN_RETURN_IF_ERROR(readEntities(section == "PartitionedEntities"));
    } else if (section == "Nodes" || (section == "ParametricNodes" && version_ == 2)) {
      GTN_RETURN_IF_ERROR(readNodes(section == "ParametricNodes"));
    } else if (section == "Elements") {
      GTN_RETURN_IF_ERROR(readElements());
      if (version_ == 2) dropRepeatedElements();
    } else if (section == "NodeData" || section == "ElementData" || section == "ElementNodeData") {
      GTN_RETURN_IF_ERROR(readData(section));
    } else {
      if (section.rfind("End", 0) == 0) return errorAt(section_at, "$" + section + " without its section");
      const std::string end = "$End" + section;
      const size_t at = text_.find(end, pos_);
      if (at == std::string_view::npos) return errorAt(section_at, "section $" + section + " has no " + end);
      pos_ = at + end.size();
      if (section != "Comments") unread_sections_.push_back("$" + section);
    }
  }
  if (!have_nodes_) return invalidData(path_ + ": no $Nodes section");
  if (!have_elements_) return invalidData(path_ + ": no $Elements section");

  auto typeCounts = [](const std::map<int, size_t>& counts) {
    std::string s;
    for (const auto& [type, n] : counts)
      s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + findType(type)->name + " (type " + std::to_string(type) +
           ")";
    return s;
  };
  if (cells_.types.empty()) {
    return unsupported(path_ + ": no volume elements" + (skipped_.empty() ? "" : ", only " + typeCounts(skipped_)) +
                       ": a surface, line or point set is not a volume mesh");
  }
  ImportResult result;
  TetMesh& mesh = result.mesh;
  mesh.coord_type = ScalarType::kFloat64;
  mesh.coords = std::move(coords_);
  std::vector<Field> cell_fields;
  const size_t num_cells = cells_.types.size();
  if (any_physical_) {
    Field f("gmsh:physical", 1, ScalarType::kInt32, num_cells);
    std::memcpy(f.bytes.data(), physical_.data(), 4 * num_cells);
    cell_fields.push_back(std::move(f));
  }
  if (any_geometrical_) {
    Field f("gmsh:geometrical", 1, ScalarType::kInt32, num_cells);
    std::memcpy(f.bytes.data(), geometrical_.data(), 4 * num_cells);
    cell_fields.push_back(std::move(f));
  }
  GTN_RETURN_IF_ERROR(buildFields(&result, &cell_fields));
  std::vector<std::string>& warnings = result.report.warnings;
  if (!skipped_.empty()) {
    size_t total = 0;
    for (const auto& entry : skipped_) total += entry.second;
    warnings.push_back("skipped " + std::to_string(total) + " cells of lower dimension (" + typeCounts(skipped_) +
                       "): only volume cells become tetrahedra");
  }
  if (!higher_order_.empty()) {
    size_t total = 0;
    for (const auto& entry : higher_order_) total += entry.second;
    warnings.push_back(std::to_string(total) + " higher-order elements (" + typeCounts(higher_order_) +
                       ") reduced to their corners; their other nodes are kept as unreferenced points");
  }
  if (repeated_ > 0)
    warnings.push_back(std::to_string(repeated_) +
                       " volume elements repeated with the same nodes (MSH 2 lists an element once per physical "
                       "group) read once; gmsh:physical holds the first group of each");
  if (multi_physical_ > 0)
    warnings.push_back(std::to_string(multi_physical_) +
                       " volume entities belong to several physical groups; gmsh:physical holds the first of each");
  if (element_node_data_ > 0)
    warnings.push_back("skipped " + std::to_string(element_node_data_) +
                       " $ElementNodeData sections (values per node of each element are not read)");
  if (!unread_sections_.empty()) warnings.push_back("sections not read: " + joinNames(unread_sections_));
  for (const auto& [tag, name] : volume_names_) mesh.setMetadata("gmsh.physical_name." + std::to_string(tag), name);
  GTN_RETURN_IF_ERROR(finishVtkImport(path_, cells_, cell_fields, options, &result));
  mesh.setMetadata("source.format",
                   std::string("gmsh ") + (version_ == 2 ? "2.2" : "4.1") + (binary_ ? " binary" : " ASCII"));
  return result;
}

}  // namespace

StatusOr<ImportResult> importGmsh(const std::string& path, const ImportOptions& options) {
  GTN_ASSIGN_OR_RETURN(const std::string text, readWholeFile(path));
  MshReader reader(path, text);
  return reader.read(options);
}

}  // namespace gtn
