// TetGen .node / .ele / .face exporter, 0-based. The three files appear together or not at all.
// The gtn- comments at the top of the .node and .ele (tetgen_layout.h) let the importer restore field
// names, component counts, types and coordinate precision exactly.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>

#include "convert/export.h"
#include "convert/tetgen_layout.h"
#include "format/file_io.h"
#include "mesh/faces.h"

namespace gtn {

namespace {
using tetgen::ColumnField;

// Text is gathered in a buffer and written in large blocks.
class BufferedWriter {
 public:
  BufferedWriter(std::FILE* file, const std::string& path) : file_(file), path_(path) {}
  std::string& text() { return text_; }
  Status maybeFlush() { return text_.size() >= (1u << 20) ? flush() : Status::ok(); }
  Status flush() {
    if (!text_.empty() && std::fwrite(text_.data(), 1, text_.size(), file_) != text_.size())
      return ioError(path_ + ": write failed");
    text_.clear();
    return Status::ok();
  }

 private:
  std::FILE* file_;
  const std::string& path_;
  std::string text_;
};

void appendInt(std::string* out, uint64_t v) {
  tetgen::appendValue(out, ScalarType::kUInt64, reinterpret_cast<const uint8_t*>(&v));
}

// Appends every attribute value of `item` for the fields in `fields` (components in order).
void appendAttributes(std::string* out, const std::vector<const Field*>& fields, size_t item) {
  for (const Field* f : fields) {
    const size_t size = f->valueSize();
    for (uint32_t c = 0; c < f->components; ++c) {
      out->push_back(' ');
      tetgen::appendValue(out, f->type, f->bytes.data() + (item * f->components + c) * size);
    }
  }
}

int32_t cellMarker(const Field& f, size_t t, int k) {
  int32_t m;
  std::memcpy(&m, f.bytes.data() + (4 * t + static_cast<size_t>(k)) * 4, 4);
  return m;
}

struct TetFace {
  std::array<uint32_t, 3> v;  // sorted
  uint64_t slot;              // 4 * tetrahedron + local face
  bool operator<(const TetFace& o) const { return v != o.v ? v < o.v : slot < o.slot; }
};

struct FaceRow {
  Triangle v;
  int32_t marker;
};

// The .face rows: the boundary triangles, then interior faces with a non-zero marker. Returns false
// when `markers` gives one face two different markers (from the tetrahedra on its two sides), which a
// .face cannot express; the field is then written as ordinary .ele attributes instead.
bool collectFaces(const TetMesh& mesh, const Field* markers, std::vector<FaceRow>* rows) {
  const FaceAdjacency adjacency = computeFaceAdjacency(mesh);
  const std::vector<Triangle> boundary = boundaryTriangles(mesh, adjacency);
  rows->clear();
  rows->reserve(boundary.size());
  if (!markers) {
    for (const Triangle& tri : boundary) rows->push_back({tri, 0});
    return true;
  }
  std::vector<TetFace> faces(4 * mesh.numTets());
  for (size_t t = 0; t < mesh.numTets(); ++t) {
    const Tet& tet = mesh.tets[t];
    for (int k = 0; k < 4; ++k)
      faces[4 * t + k] = {tetgen::sortedTriangle(tet[kTetFace[k][0]], tet[kTetFace[k][1]], tet[kTetFace[k][2]]),
                          4 * t + k};
  }
  std::sort(faces.begin(), faces.end());
  auto markerOf = [&](const TetFace& f) { return cellMarker(*markers, f.slot / 4, static_cast<int>(f.slot % 4)); };
  std::vector<FaceRow> interior;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].v == faces[i].v) {
      if (markerOf(faces[j]) != markerOf(faces[i])) return false;
      ++j;
    }
    const int32_t m = markerOf(faces[i]);
    if (j - i > 1 && m != 0) {
      const Tet& tet = mesh.tets[faces[i].slot / 4];
      const int k = static_cast<int>(faces[i].slot % 4);
      interior.push_back({Triangle{tet[kTetFace[k][0]], tet[kTetFace[k][1]], tet[kTetFace[k][2]]}, m});
    }
    i = j;
  }
  for (const Triangle& tri : boundary) {
    const std::array<uint32_t, 3> key = tetgen::sortedTriangle(tri[0], tri[1], tri[2]);
    auto it = std::lower_bound(faces.begin(), faces.end(), key,
                               [](const TetFace& f, const std::array<uint32_t, 3>& x) { return f.v < x; });
    rows->push_back({tri, markerOf(*it)});
  }
  rows->insert(rows->end(), interior.begin(), interior.end());
  return true;
}

void appendComment(std::string* out, std::string_view key, const std::string& value) {
  out->append("# ");
  out->append(key);
  if (!value.empty()) {
    out->push_back(' ');
    out->append(value);
  }
  out->push_back('\n');
}
}  // namespace

Status exportTetgen(const TetMesh& mesh, const std::string& path) {
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  if (mesh.coord_type != ScalarType::kFloat32 && mesh.coord_type != ScalarType::kFloat64)
    return unsupported(path + ": coordinates of type " + scalarTypeName(mesh.coord_type) + " cannot be written");
  const std::string base = tetgen::basePath(path);
  const std::string node_path = base + ".node", ele_path = base + ".ele", face_path = base + ".face";

  // The point field that TetGen's boundary-marker column can hold, and the cell field its .face markers can.
  const Field* node_marker = nullptr;
  for (const Field& f : mesh.point_fields) {
    if (f.name == tetgen::kBoundaryMarkerName && f.type == ScalarType::kInt32 && f.components == 1) {
      node_marker = &f;
      break;
    }
  }
  const Field* face_marker = nullptr;
  for (const Field& f : mesh.cell_fields) {
    if (f.name == tetgen::kFaceMarkerName && f.type == ScalarType::kInt32 && f.components == 4) {
      face_marker = &f;
      break;
    }
  }
  std::vector<FaceRow> face_rows;
  if (!collectFaces(mesh, face_marker, &face_rows)) {
    face_marker = nullptr;
    collectFaces(mesh, nullptr, &face_rows);
  }

  std::vector<ColumnField> point_layout, cell_layout;
  std::vector<const Field*> point_columns, cell_columns;
  size_t point_values = 0, cell_values = 0;
  for (const Field& f : mesh.point_fields) {
    point_layout.push_back({f.name, f.components, f.type, &f == node_marker});
    if (&f != node_marker) {
      point_columns.push_back(&f);
      point_values += f.components;
    }
  }
  for (const Field& f : mesh.cell_fields) {
    cell_layout.push_back({f.name, f.components, f.type, &f == face_marker});
    if (&f != face_marker) {
      cell_columns.push_back(&f);
      cell_values += f.components;
    }
  }

  AtomicFileGroup group;
  GTN_RETURN_IF_ERROR(group.add(node_path, [&](std::FILE* file) -> Status {
    BufferedWriter w(file, node_path);
    std::string& s = w.text();
    s += "# Written by Gatun. The gtn- comments name the attribute columns for a lossless round trip.\n";
    appendComment(&s, tetgen::kCoordinatesKey, scalarTypeName(mesh.coord_type));
    appendComment(&s, tetgen::kPointFieldsKey, tetgen::formatFieldList(point_layout, tetgen::kMarkerTag));
    for (const auto& [key, value] : mesh.metadata)
      appendComment(&s, tetgen::kMetadataKey, tetgen::escapeText(key) + " " + tetgen::escapeText(value));
    appendInt(&s, mesh.numPoints());
    s += "  3  ";
    appendInt(&s, point_values);
    s += node_marker ? "  1\n" : "  0\n";
    for (size_t i = 0; i < mesh.numPoints(); ++i) {
      appendInt(&s, i);
      for (int c = 0; c < 3; ++c) {
        s.push_back(' ');
        const double v = mesh.coords[3 * i + c];
        if (mesh.coord_type == ScalarType::kFloat32) {
          const float f = static_cast<float>(v);
          tetgen::appendValue(&s, ScalarType::kFloat32, reinterpret_cast<const uint8_t*>(&f));
        } else {
          tetgen::appendValue(&s, ScalarType::kFloat64, reinterpret_cast<const uint8_t*>(&v));
        }
      }
      appendAttributes(&s, point_columns, i);
      if (node_marker) {
        s.push_back(' ');
        tetgen::appendValue(&s, ScalarType::kInt32, node_marker->bytes.data() + 4 * i);
      }
      s.push_back('\n');
      GTN_RETURN_IF_ERROR(w.maybeFlush());
    }
    return w.flush();
  }));
  GTN_RETURN_IF_ERROR(group.add(ele_path, [&](std::FILE* file) -> Status {
    BufferedWriter w(file, ele_path);
    std::string& s = w.text();
    appendComment(&s, tetgen::kCellFieldsKey, tetgen::formatFieldList(cell_layout, tetgen::kFaceTag));
    appendInt(&s, mesh.numTets());
    s += "  4  ";
    appendInt(&s, cell_values);
    s.push_back('\n');
    for (size_t t = 0; t < mesh.numTets(); ++t) {
      appendInt(&s, t);
      for (uint32_t v : mesh.tets[t]) {
        s.push_back(' ');
        appendInt(&s, v);
      }
      appendAttributes(&s, cell_columns, t);
      s.push_back('\n');
      GTN_RETURN_IF_ERROR(w.maybeFlush());
    }
    return w.flush();
  }));
  GTN_RETURN_IF_ERROR(group.add(face_path, [&](std::FILE* file) -> Status {
    BufferedWriter w(file, face_path);
    std::string& s = w.text();
    appendInt(&s, face_rows.size());
    s += face_marker ? "  1\n" : "  0\n";
    for (size_t i = 0; i < face_rows.size(); ++i) {
      appendInt(&s, i);
      for (uint32_t v : face_rows[i].v) {
        s.push_back(' ');
        appendInt(&s, v);
      }
      if (face_marker) {
        s.push_back(' ');
        tetgen::appendValue(&s, ScalarType::kInt32, reinterpret_cast<const uint8_t*>(&face_rows[i].marker));
      }
      s.push_back('\n');
      GTN_RETURN_IF_ERROR(w.maybeFlush());
    }
    return w.flush();
  }));
  return group.commit();
}

}  // namespace gtn
