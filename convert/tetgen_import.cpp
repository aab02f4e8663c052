// TetGen .node / .ele / .face importer. The files are line-oriented: a header row of counts, then one
// row per item; '#' comments and blank lines may appear anywhere. The gtn- comments that Gatun's
// exporter writes (tetgen_layout.h) name the attribute columns; without them, attributes are float64
// fields named after their column.
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "convert/ascii_rows.h"
#include "convert/import.h"
#include "convert/tetgen_layout.h"
#include "format/file_io.h"

namespace gtn {

namespace {
using tetgen::ColumnField;

// Node indices are uint32 in a TetMesh, and the two highest values are sentinels in faces.h.
constexpr int64_t kMaxItems = 0xFFFFFFFDll;
constexpr int64_t kMaxAttributes = 1 << 20;

bool pathExists(const std::string& path) {
  struct stat sb;
  return ::stat(path.c_str(), &sb) == 0;
}

// What the gtn- comments at the top of one file say.
struct Layout {
  bool has_fields = false;
  size_t fields_line = 0;
  std::vector<ColumnField> fields;
  bool float32_coords = false;
  std::vector<std::pair<std::string, std::string>> metadata;
};

StatusOr<Layout> readLayout(const std::string& path, std::string_view text, std::string_view fields_key,
                            std::string_view tag) {
  Layout layout;
  for (const tetgen::Comment& c : tetgen::leadingComments(text)) {
    auto fail = [&](const std::string& why) { return invalidData(path + ":" + std::to_string(c.line) + ": " + why); };
    if (c.key == tetgen::kCoordinatesKey) {
      if (c.value == "float32") {
        layout.float32_coords = true;
      } else if (c.value != "float64") {
        return fail("gtn-coordinates must be float32 or float64, not " + quotedToken(c.value));
      }
    } else if (c.key == fields_key) {
      std::string why;
      if (!tetgen::parseFieldList(c.value, tag, &layout.fields, &why)) return fail(why);
      layout.has_fields = true;
      layout.fields_line = c.line;
    } else if (c.key == tetgen::kMetadataKey) {
      const size_t space = c.value.find(' ');
      std::string key, value;
      if (!tetgen::unescapeText(c.value.substr(0, space), &key) ||
          !tetgen::unescapeText(space == std::string_view::npos ? std::string_view() : c.value.substr(space + 1),
                                &value))
        return fail("malformed %-escape in gtn-metadata");
      layout.metadata.emplace_back(std::move(key), std::move(value));
    }
  }
  return layout;
}

// Where the values of each attribute column go, and which field is fed from elsewhere (the node
// boundary-marker column, or the .face markers).
struct ColumnMap {
  std::vector<Field> fields;                          // in the mesh's field order
  std::vector<std::pair<uint32_t, uint32_t>> column;  // attribute column -> (field, component)
  std::vector<ScalarType> column_type;
  int tagged = -1;
};

// `tagged_type`/`tagged_components`: what the field held outside the columns must be; `allow_tagged`
// whether the file has such a place; `default_name(j)` names attribute column j without a layout.
template <class DefaultName>
StatusOr<ColumnMap> mapColumns(const std::string& path, const Layout& layout, std::string_view fields_key,
                               int64_t attributes, size_t items, uint32_t tagged_components, bool allow_tagged,
                               const char* tagged_place, DefaultName default_name) {
  ColumnMap map;
  if (!layout.has_fields) {
    for (int64_t j = 0; j < attributes; ++j) {
      map.fields.emplace_back(default_name(j), 1, ScalarType::kFloat64, items);
      map.column.emplace_back(static_cast<uint32_t>(j), 0);
      map.column_type.push_back(ScalarType::kFloat64);
    }
    return map;
  }
  auto fail = [&](const std::string& why) {
    return invalidData(path + ":" + std::to_string(layout.fields_line) + ": " + why);
  };
  uint64_t values = 0;
  for (const ColumnField& f : layout.fields) {
    if (!f.tagged) values += f.components;
  }
  if (values != static_cast<uint64_t>(attributes)) {
    return fail("the " + std::string(fields_key) + " comment describes " + std::to_string(values) +
                " attribute values per row, but the header announces " + std::to_string(attributes));
  }
  for (const ColumnField& f : layout.fields) {
    const uint32_t index = static_cast<uint32_t>(map.fields.size());
    if (f.tagged) {
      if (map.tagged >= 0) return fail("two fields are tagged to be held in " + std::string(tagged_place));
      if (!allow_tagged)
        return fail("field '" + f.name + "' is said to be held in " + tagged_place + ", which is absent");
      if (f.type != ScalarType::kInt32 || f.components != tagged_components)
        return fail("field '" + f.name + "' held in " + tagged_place + " must be int32 with " +
                    std::to_string(tagged_components) + " component(s)");
      map.tagged = static_cast<int>(index);
    } else {
      for (uint32_t c = 0; c < f.components; ++c) {
        map.column.emplace_back(index, c);
        map.column_type.push_back(f.type);
      }
    }
    map.fields.emplace_back(f.name, f.components, f.type, items);
  }
  return map;
}

// Parses row[first + j] into the attribute columns of item `item`.
Status readAttributes(const TextReader& reader, const std::vector<std::string_view>& row, size_t first, ColumnMap& map,
                      size_t item) {
  for (size_t j = 0; j < map.column.size(); ++j) {
    Field& f = map.fields[map.column[j].first];
    uint8_t* dst = f.bytes.data() + (item * f.components + map.column[j].second) * f.valueSize();
    if (!tetgen::parseValue(row[first + j], map.column_type[j], dst)) {
      return reader.error("expected attribute " + std::to_string(j + 1) + " (field '" + f.name + "', " +
                          scalarTypeName(map.column_type[j]) + "), found " + quotedToken(row[first + j]));
    }
  }
  return Status::ok();
}

// The header row: 1..max_tokens non-negative integers.
Status readHeader(TextReader& reader, std::vector<std::string_view>* row, size_t max_tokens, const char* what) {
  if (!readRow(reader, row)) return reader.errorAtEnd(what);
  if (row->size() > max_tokens) {
    return reader.error("the header row has " + std::to_string(row->size()) + " values; at most " +
                        std::to_string(max_tokens) + " were expected");
  }
  return Status::ok();
}

Status wrongWidth(const TextReader& reader, size_t found, int64_t expected, const std::string& layout) {
  return reader.error("row has " + std::to_string(found) + " values; the header announces " + std::to_string(expected) +
                      " (" + layout + ")");
}

struct Nodes {
  int64_t base = 0;
  Layout layout;
  std::string warning;  // for the import report, or empty
};

// The marker-column name that meshio's TetGen writer records in its comment ("# attribute and marker
// names: a b m": the last one), or "".
std::string meshioMarkerName(std::string_view text) {
  const std::string_view key = "# attribute and marker names:";
  const size_t at = text.substr(0, 4096).find(key);
  if (at == std::string_view::npos) return "";
  std::string_view line = text.substr(at + key.size());
  line = line.substr(0, line.find_first_of("\r\n"));
  const size_t end = line.find_last_not_of(" \t");
  if (end == std::string_view::npos) return "";
  const size_t space = line.find_last_of(" \t", end);
  const size_t begin = space == std::string_view::npos ? 0 : space + 1;
  return std::string(line.substr(begin, end + 1 - begin));
}

StatusOr<Nodes> readNodes(const std::string& path, std::string_view text, TetMesh& mesh) {
  Nodes nodes;
  GTN_ASSIGN_OR_RETURN(nodes.layout, readLayout(path, text, tetgen::kPointFieldsKey, tetgen::kMarkerTag));
  TextReader reader(path, text);
  std::vector<std::string_view> row;
  GTN_RETURN_IF_ERROR(readHeader(reader, &row, 4, "the .node header (node count)"));
  GTN_ASSIGN_OR_RETURN(const int64_t count, parseIntToken(reader, row[0], 0, kMaxItems, "node count"));
  int64_t dimension = 3, attributes = 0, markers = 0;
  if (row.size() > 1) {
    GTN_ASSIGN_OR_RETURN(dimension, parseIntToken(reader, row[1], 0, 1 << 20, "dimension"));
  }
  if (row.size() > 2) {
    GTN_ASSIGN_OR_RETURN(attributes, parseIntToken(reader, row[2], 0, kMaxAttributes, "attribute count"));
  }
  if (row.size() > 3) {
    GTN_ASSIGN_OR_RETURN(markers, parseIntToken(reader, row[3], 0, 1, "boundary marker flag"));
  }
  if (dimension != 3)
    return reader.error("dimension " + std::to_string(dimension) + ": only 3-dimensional TetGen meshes are supported");
  if (count == 0)
    return reader.error("no nodes (a .node with 0 nodes refers to the nodes of a .poly file, which is not supported)");
  const int64_t width = 4 + attributes + markers;
  GTN_RETURN_IF_ERROR(checkCountFits(reader, count, width, "nodes"));
  const size_t n = static_cast<size_t>(count);
  GTN_ASSIGN_OR_RETURN(ColumnMap map, mapColumns(path, nodes.layout, tetgen::kPointFieldsKey, attributes, n, 1,
                                                 markers == 1, "the boundary-marker column",
                                                 [](int64_t j) { return "attribute_" + std::to_string(j); }));
  const bool plain_marker = markers == 1 && map.tagged < 0;  // not a field the layout comment names
  if (plain_marker) {
    map.tagged = static_cast<int>(map.fields.size());
    map.fields.emplace_back(tetgen::kBoundaryMarkerName, 1, ScalarType::kInt32, n);
  }
  const std::string layout_text =
      "number, x, y, z, " + std::to_string(attributes) + " attribute(s)" + (markers ? ", boundary marker" : "");
  mesh.coord_type = nodes.layout.float32_coords ? ScalarType::kFloat32 : ScalarType::kFloat64;
  mesh.coords.resize(3 * n);
  size_t last_line = reader.line();
  for (size_t i = 0; i < n; ++i) {
    if (!readRow(reader, &row)) return truncatedError(reader, last_line, i, count, "nodes");
    last_line = reader.line();
    if (row.size() != static_cast<size_t>(width)) return wrongWidth(reader, row.size(), width, layout_text);
    GTN_ASSIGN_OR_RETURN(const int64_t number, parseIntToken(reader, row[0], INT64_MIN, INT64_MAX, "node number"));
    if (i == 0) {
      if (number != 0 && number != 1)
        return reader.error("the first node is numbered " + std::to_string(number) + "; TetGen numbers from 0 or 1");
      nodes.base = number;
    } else if (number != nodes.base + static_cast<int64_t>(i)) {
      return reader.error("node numbered " + std::to_string(number) + " where " +
                          std::to_string(nodes.base + static_cast<int64_t>(i)) +
                          " was expected: only contiguous node numbers (as TetGen writes them) are supported");
    }
    for (int c = 0; c < 3; ++c) {
      const std::string_view tok = row[1 + c];
      double v;
      float f;
      const bool ok = nodes.layout.float32_coords ? parseFloat(tok, &f) : parseDouble(tok, &v);
      if (!ok) {
        return reader.error(std::string("expected the ") + "xyz"[c] + " coordinate (a " +
                            (nodes.layout.float32_coords ? "float32" : "number") + "), found " + quotedToken(tok));
      }
      mesh.coords[3 * i + c] = nodes.layout.float32_coords ? static_cast<double>(f) : v;
      if (!std::isfinite(mesh.coords[3 * i + c]))
        return reader.error("node " + std::to_string(number) + " has a non-finite " + "xyz"[c] + " coordinate " +
                            quotedToken(tok));
    }
    GTN_RETURN_IF_ERROR(readAttributes(reader, row, 4, map, i));
    if (markers) {
      Field& f = map.fields[map.tagged];
      const std::string_view tok = row[4 + attributes];
      double v;
      if (f.type == ScalarType::kInt32 && !tetgen::parseValue(tok, ScalarType::kInt32, f.bytes.data() + 4 * i)) {
        // meshio writes a point field into the marker column (naming it in a comment): a column of
        // reals is read as that field, in float64.
        if (!plain_marker || !parseDouble(tok, &v))
          return reader.error("expected the boundary marker (an int32), found " + quotedToken(tok));
        const std::string name = meshioMarkerName(text);
        Field real(name.empty() ? tetgen::kBoundaryMarkerName : name, 1, ScalarType::kFloat64, n);
        for (size_t j = 0; j < i; ++j) real.set<double>(j, 0, static_cast<double>(f.data<int32_t>()[j]));
        f = std::move(real);
        nodes.warning =
            "the boundary-marker column holds reals (a point field, as meshio writes one there): read "
            "as the float64 field '" +
            f.name + "'";
      }
      if (f.type == ScalarType::kFloat64) {
        if (!parseDouble(tok, &v))
          return reader.error("expected a number in the marker column, found " + quotedToken(tok));
        f.set<double>(i, 0, v);
      }
    }
  }
  if (readRow(reader, &row))
    return reader.error("more rows than the " + std::to_string(n) + " nodes the header announces");
  mesh.point_fields = std::move(map.fields);
  return nodes;
}

struct Tets {
  int face_field = -1;  // the cell field to be filled from the .face markers (-1: none asked for)
  bool quadratic = false;
};

StatusOr<Tets> readTets(const std::string& path, std::string_view text, int64_t base, ImportResult& result) {
  TetMesh& mesh = result.mesh;
  GTN_ASSIGN_OR_RETURN(const Layout layout, readLayout(path, text, tetgen::kCellFieldsKey, tetgen::kFaceTag));
  TextReader reader(path, text);
  std::vector<std::string_view> row;
  GTN_RETURN_IF_ERROR(readHeader(reader, &row, 3, "the .ele header (tetrahedron count)"));
  GTN_ASSIGN_OR_RETURN(const int64_t count, parseIntToken(reader, row[0], 0, kMaxItems, "tetrahedron count"));
  int64_t per_tet = 4, attributes = 0;
  if (row.size() > 1) {
    GTN_ASSIGN_OR_RETURN(per_tet, parseIntToken(reader, row[1], 0, 1 << 20, "nodes per tetrahedron"));
  }
  if (row.size() > 2) {
    GTN_ASSIGN_OR_RETURN(attributes, parseIntToken(reader, row[2], 0, kMaxAttributes, "attribute count"));
  }
  if (per_tet != 4 && per_tet != 10) {
    return reader.error(std::to_string(per_tet) +
                        " nodes per tetrahedron: only 4 (linear) and 10 (quadratic) are supported");
  }
  if (per_tet == 10) {
    result.report.warnings.push_back(path +
                                     ": 10-node (quadratic) tetrahedra: only the 4 corner nodes are kept; "
                                     "the 6 edge nodes remain as unreferenced points");
  }
  const int64_t width = 1 + per_tet + attributes;
  GTN_RETURN_IF_ERROR(checkCountFits(reader, count, width, "tetrahedra"));
  const size_t nt = static_cast<size_t>(count);
  GTN_ASSIGN_OR_RETURN(
      ColumnMap map,
      mapColumns(path, layout, tetgen::kCellFieldsKey, attributes, nt, 4, true, "the .face markers", [](int64_t j) {
        return j == 0 ? std::string(tetgen::kRegionName) : "attribute_" + std::to_string(j);
      }));
  const std::string layout_text =
      "number, " + std::to_string(per_tet) + " node numbers, " + std::to_string(attributes) + " attribute(s)";
  const int64_t np = static_cast<int64_t>(mesh.numPoints());
  mesh.tets.resize(nt);
  size_t last_line = reader.line();
  for (size_t t = 0; t < nt; ++t) {
    if (!readRow(reader, &row)) return truncatedError(reader, last_line, t, count, "tetrahedra");
    last_line = reader.line();
    if (row.size() != static_cast<size_t>(width)) return wrongWidth(reader, row.size(), width, layout_text);
    GTN_ASSIGN_OR_RETURN(const int64_t number,
                         parseIntToken(reader, row[0], INT64_MIN, INT64_MAX, "tetrahedron number"));
    const std::string which = "tetrahedron " + std::to_string(number);  // as the file numbers it
    for (int k = 0; k < 4; ++k) {
      int64_t v;
      if (!parseInt(row[1 + k], &v)) {
        return reader.error("expected a node number (an integer), found " + quotedToken(row[1 + k]));
      }
      if (v < base || v - base >= np) {
        return reader.error(which + " refers to node " + std::to_string(v) +
                            ", which the .node does not have (its nodes are numbered " + std::to_string(base) + " to " +
                            std::to_string(base + np - 1) + ")");
      }
      mesh.tets[t][k] = static_cast<uint32_t>(v - base);
    }
    for (int k = 4; k < per_tet; ++k) {
      int64_t v;
      if (!parseInt(row[1 + k], &v) || v < base || v - base >= np)
        return reader.error(which + " has a bad edge node " + quotedToken(row[1 + k]));
    }
    GTN_RETURN_IF_ERROR(readAttributes(reader, row, 1 + per_tet, map, t));
  }
  if (readRow(reader, &row))
    return reader.error("more rows than the " + std::to_string(nt) + " tetrahedra the header announces");
  mesh.cell_fields = std::move(map.fields);
  return Tets{map.tagged, per_tet == 10};
}

struct FaceEntry {
  std::array<uint32_t, 3> v;  // sorted
  int32_t marker = 0;
  size_t line = 0;
};

// The .face, sorted by vertex triple, duplicates removed. `has_markers`: the header's marker flag.
// `quadratic`: the mesh has 10-node tetrahedra, so each face row may list 3 edge nodes after its
// corners (TetGen -o2 does for the faces of a -p mesh, not for the convex hull of a point set); the
// first row tells which, and the others must agree.
StatusOr<std::vector<FaceEntry>> readFaces(const std::string& path, std::string_view text, int64_t base, int64_t np,
                                           bool quadratic, bool* has_markers) {
  TextReader reader(path, text);
  std::vector<std::string_view> row;
  GTN_RETURN_IF_ERROR(readHeader(reader, &row, 2, "the .face header (face count)"));
  GTN_ASSIGN_OR_RETURN(const int64_t count, parseIntToken(reader, row[0], 0, INT64_MAX, "face count"));
  int64_t markers = 0;
  if (row.size() > 1) {
    GTN_ASSIGN_OR_RETURN(markers, parseIntToken(reader, row[1], 0, 1, "boundary marker flag"));
  }
  *has_markers = markers == 1;
  int64_t edge_nodes = quadratic ? -1 : 0;  // -1: not known before the first row
  GTN_RETURN_IF_ERROR(checkCountFits(reader, count, 4 + markers, "faces"));
  std::vector<FaceEntry> faces(static_cast<size_t>(count));
  size_t last_line = reader.line();
  for (FaceEntry& face : faces) {
    const size_t i = static_cast<size_t>(&face - faces.data());
    if (!readRow(reader, &row)) return truncatedError(reader, last_line, i, count, "faces");
    last_line = reader.line();
    // TetGen's -nn switch appends the two adjacent tetrahedra to each row; they are recomputed here.
    if (edge_nodes < 0) {
      const size_t plain = static_cast<size_t>(4 + markers);
      edge_nodes = row.size() == plain || row.size() == plain + 2 ? 0 : 3;
    }
    const int64_t width = 4 + edge_nodes + markers;
    if (row.size() != static_cast<size_t>(width) && row.size() != static_cast<size_t>(width + 2)) {
      std::string edges;
      if (quadratic && i == 0) edges = " [, 3 edge nodes]";
      if (quadratic && i > 0)
        edges = edge_nodes ? ", 3 edge nodes (as on the first row)" : " (no edge nodes, as on the first row)";
      return wrongWidth(reader, row.size(), width,
                        "number, 3 node numbers" + edges + (markers ? ", marker" : "") + " [, 2 adjacent tetrahedra]");
    }
    GTN_ASSIGN_OR_RETURN(const int64_t number, parseIntToken(reader, row[0], INT64_MIN, INT64_MAX, "face number"));
    uint32_t v[3];
    for (int k = 0; k < 3; ++k) {
      int64_t x;
      if (!parseInt(row[1 + k], &x))
        return reader.error("expected a node number (an integer), found " + quotedToken(row[1 + k]));
      if (x < base || x - base >= np) {
        return reader.error("face " + std::to_string(number) + " refers to node " + std::to_string(x) +
                            ", which the .node does not have");
      }
      v[k] = static_cast<uint32_t>(x - base);
    }
    face.v = tetgen::sortedTriangle(v[0], v[1], v[2]);
    face.line = reader.line();
    if (markers) {
      GTN_ASSIGN_OR_RETURN(const int64_t m,
                           parseIntToken(reader, row[4 + edge_nodes], INT32_MIN, INT32_MAX, "face marker"));
      face.marker = static_cast<int32_t>(m);
    }
  }
  if (readRow(reader, &row))
    return reader.error("more rows than the " + std::to_string(count) + " faces the header announces");
  std::sort(faces.begin(), faces.end(),
            [](const FaceEntry& a, const FaceEntry& b) { return a.v != b.v ? a.v < b.v : a.line < b.line; });
  size_t out = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    if (out > 0 && faces[out - 1].v == faces[i].v) {
      if (faces[out - 1].marker != faces[i].marker) {
        return invalidData(path + ":" + std::to_string(faces[i].line) + ": the face is also listed on line " +
                           std::to_string(faces[out - 1].line) + " with a different marker");
      }
      continue;
    }
    faces[out++] = faces[i];
  }
  faces.resize(out);
  return faces;
}

// Checks that every listed face belongs to a tetrahedron and stores the markers per local face.
// Runs after orientation normalisation, which swaps vertices 2 and 3 of flipped tetrahedra and so
// changes which local face is which.
// `interior` gets the number of listed faces that two tetrahedra share.
Status applyFaces(const std::string& path, const std::vector<FaceEntry>& faces, int64_t base, Field* marker_field,
                  TetMesh& mesh, size_t* interior) {
  std::vector<uint8_t> found(faces.size(), 0);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    for (int k = 0; k < 4; ++k) {
      const auto key = tetgen::sortedTriangle(tet[(k + 1) & 3], tet[(k + 2) & 3], tet[(k + 3) & 3]);
      auto it = std::lower_bound(faces.begin(), faces.end(), key,
                                 [](const FaceEntry& e, const std::array<uint32_t, 3>& x) { return e.v < x; });
      if (it == faces.end() || it->v != key) continue;
      uint8_t& seen = found[it - faces.begin()];
      if (seen < 2 && ++seen == 2) ++*interior;
      if (marker_field) marker_field->set<int32_t>(t, static_cast<uint32_t>(k), it->marker);
    }
  }
  const FaceEntry* first_missing = nullptr;
  for (size_t i = 0; i < faces.size(); ++i) {
    if (!found[i] && (!first_missing || faces[i].line < first_missing->line)) first_missing = &faces[i];
  }
  if (first_missing) {
    auto num = [&](uint32_t v) { return std::to_string(static_cast<int64_t>(v) + base); };
    return invalidData(path + ":" + std::to_string(first_missing->line) + ": face " + num(first_missing->v[0]) + " " +
                       num(first_missing->v[1]) + " " + num(first_missing->v[2]) +
                       " is not a face of any tetrahedron of the .ele");
  }
  return Status::ok();
}
}  // namespace

StatusOr<ImportResult> importTetgen(const std::string& path, const ImportOptions&) {
  const std::string base_path = tetgen::basePath(path);
  const std::string node_path = base_path + ".node", ele_path = base_path + ".ele", face_path = base_path + ".face";
  GTN_ASSIGN_OR_RETURN(const std::string node_text, readWholeFile(node_path));
  GTN_ASSIGN_OR_RETURN(const std::string ele_text, readWholeFile(ele_path));
  std::string face_text;
  const bool has_face_file = pathExists(face_path);
  if (has_face_file) {
    GTN_ASSIGN_OR_RETURN(face_text, readWholeFile(face_path));
  }

  ImportResult result;
  TetMesh& mesh = result.mesh;
  GTN_ASSIGN_OR_RETURN(const Nodes nodes, readNodes(node_path, node_text, mesh));
  if (!nodes.warning.empty()) result.report.warnings.push_back(node_path + ": " + nodes.warning);
  GTN_ASSIGN_OR_RETURN(const Tets tets, readTets(ele_path, ele_text, nodes.base, result));
  const int face_field = tets.face_field;
  std::vector<FaceEntry> faces;
  bool face_markers = false;
  if (has_face_file) {
    GTN_ASSIGN_OR_RETURN(faces, readFaces(face_path, face_text, nodes.base, static_cast<int64_t>(mesh.numPoints()),
                                          tets.quadratic, &face_markers));
  }
  if (face_field >= 0 && !face_markers) {
    return invalidData(ele_path + ": its gtn-cell-fields comment puts field '" + mesh.cell_fields[face_field].name +
                       "' in the markers of " + face_path + ", which " +
                       (has_face_file ? "has no markers" : "is missing"));
  }

  finishImport(result);

  Field* marker_field = nullptr;
  if (face_markers) {
    if (face_field < 0) {
      mesh.cell_fields.emplace_back(tetgen::kFaceMarkerName, 4, ScalarType::kInt32, mesh.numTets());
      marker_field = &mesh.cell_fields.back();
    } else {
      marker_field = &mesh.cell_fields[face_field];
    }
  }
  if (has_face_file) {
    size_t interior = 0;
    GTN_RETURN_IF_ERROR(applyFaces(face_path, faces, nodes.base, marker_field, mesh, &interior));
    // Without markers the list itself is kept nowhere: that is no loss where it lists boundary faces
    // (the tetrahedra have them), but faces inside the mesh are a choice the file made.
    if (!face_markers && interior > 0)
      result.report.warnings.push_back(face_path + ": " + std::to_string(interior) + " of its " +
                                       std::to_string(faces.size()) +
                                       " faces lie inside the mesh; without markers, which faces it lists is not kept");
  }
  // Files of the mesh that are not read, each named: TetGen's edges (-e, boundary edges with their
  // markers), volume constraints (-a) and metric (-m). Adjacency (.neigh) is recomputed.
  for (const auto& [ext, what] :
       {std::pair{".edge", "edges"}, std::pair{".vol", "volume constraints"}, std::pair{".mtr", "metric values"}}) {
    const std::string p = base_path + ext;
    if (!pathExists(p)) continue;
    std::string count;
    if (StatusOr<std::string> text = readWholeFile(p); text.isOk()) {
      TextReader reader(p, *text);
      std::vector<std::string_view> row;
      int64_t n = 0;
      if (readRow(reader, &row) && parseInt(row[0], &n)) count = std::to_string(n) + " ";
    }
    result.report.warnings.push_back(p + " beside it (" + count + what + ") is not read");
  }

  mesh.metadata = nodes.layout.metadata;
  mesh.setMetadata("source.format", "tetgen");
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(node_path));
  return result;
}

}  // namespace gtn
