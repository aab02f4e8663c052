// Tetrahedral OFF importer, the format of the ZSweep and HAVS renderers: an optional keyword line
// ("OFF", "TOFF", ...), the point and tetrahedron counts (on one line or two), `x y z s...` rows with
// as many scalars per row as the first row has beyond x y z, then 0-based index rows, optionally
// prefixed by 4. The format is line-oriented; '#' starts a comment. A surface OFF (triangle or
// quadrilateral faces) is recognised and refused rather than read as meaningless tetrahedra.
#include <cctype>
#include <cmath>
#include <string>
#include <vector>

#include "convert/ascii_rows.h"
#include "convert/import.h"
#include "format/file_io.h"

namespace gtn {

namespace {
constexpr int64_t kMaxItems = 0xFFFFFFFDll;

bool isOffKeyword(std::string_view token) {
  if (token.size() < 3) return false;
  const std::string_view tail = token.substr(token.size() - 3);
  for (size_t i = 0; i < 3; ++i) {
    if (std::toupper(static_cast<unsigned char>(tail[i])) != "OFF"[i]) return false;
  }
  return true;
}
// Mixed rows of 4 and 5 values are what a surface OFF of triangles and quadrilaterals looks like.
std::string surfaceHint(const std::vector<std::string_view>& row) {
  if (!row.empty() && (row[0] == "3" || row[0] == "4") && row.size() == static_cast<size_t>(row[0][0] - '0') + 1)
    return " (rows of 4 and 5 values mixed are the faces of a surface OFF, which has no volume)";
  return "";
}
}  // namespace

StatusOr<ImportResult> importOff(const std::string& path, const ImportOptions&) {
  GTN_ASSIGN_OR_RETURN(const std::string text, readWholeFile(path));
  TextReader reader(path, text);
  std::vector<std::string_view> row;
  if (!readRow(reader, &row)) return reader.errorAtEnd("the point count");

  // Counts: after an optional keyword, on the same line or the following ones.
  size_t first = 0;
  int64_t probe;
  if (!parseInt(row[0], &probe)) {
    if (!isOffKeyword(row[0])) {
      return Status(StatusCode::kNotOurFile,
                    reader.error("expected the point count or an OFF keyword, found " + quotedToken(row[0])).message());
    }
    first = 1;
    // Geomview's binary OFF ("OFF BINARY", then big-endian counts and arrays) is a surface format.
    if (row.size() > 1 && sameKeyword(row[1], "BINARY")) {
      return Status(StatusCode::kUnsupported,
                    reader
                        .error("binary OFF ('" + std::string(row[0]) +
                               " BINARY', Geomview's) holds a surface of polygons, which has no volume; only the "
                               "ASCII tetrahedral OFF of ZSweep and HAVS is read")
                        .message());
    }
  }
  std::vector<int64_t> counts;
  while (true) {
    for (size_t j = first; j < row.size(); ++j) {
      GTN_ASSIGN_OR_RETURN(const int64_t c, parseIntToken(reader, row[j], 0, kMaxItems,
                                                          counts.empty() ? "point count" : "tetrahedron count"));
      counts.push_back(c);
    }
    if (counts.size() >= 2) break;
    if (!readRow(reader, &row)) return reader.errorAtEnd(counts.empty() ? "the point count" : "the tetrahedron count");
    first = 0;
  }
  if (counts.size() > 3) return reader.error("more than three counts (points, tetrahedra, edges) on the count line");
  const size_t count_line = reader.line();
  const int64_t np = counts[0], nt = counts[1];
  if (np == 0) return reader.error("no points");
  GTN_RETURN_IF_ERROR(checkCountFits(reader, np, 3, "points"));

  ImportResult result;
  TetMesh& mesh = result.mesh;
  size_t width = 0;
  Field scalars;
  size_t last_line = reader.line();
  for (int64_t i = 0; i < np; ++i) {
    if (!readRow(reader, &row)) return truncatedError(reader, last_line, i, np, "points");
    last_line = reader.line();
    if (i == 0) {
      width = row.size();
      if (width < 3) return reader.error("a point row needs x y z; found " + std::to_string(width) + " values");
      GTN_RETURN_IF_ERROR(checkRestFits(reader, np, static_cast<int64_t>(width), "points", count_line));
      mesh.coords.resize(3 * static_cast<size_t>(np));
      if (width > 3) scalars = Field("scalar", static_cast<uint32_t>(width - 3), ScalarType::kFloat64, np);
    } else if (row.size() != width) {
      return reader.error("point row has " + std::to_string(row.size()) + " values; the first point row has " +
                          std::to_string(width) + " (x y z and " + std::to_string(width - 3) + " scalars)");
    }
    for (size_t c = 0; c < width; ++c) {
      GTN_ASSIGN_OR_RETURN(const double v, parseDoubleToken(reader, row[c], c < 3 ? "a coordinate" : "a scalar"));
      if (c < 3) {
        if (!std::isfinite(v))
          return reader.error("point " + std::to_string(i) + " has a non-finite " + "xyz"[c] + " coordinate " +
                              quotedToken(row[c]));
        mesh.coords[3 * i + c] = v;
      } else {
        scalars.set<double>(static_cast<size_t>(i), static_cast<uint32_t>(c - 3), v);
      }
    }
  }
  if (width > 3) mesh.point_fields.push_back(std::move(scalars));

  size_t tet_width = 0, first_tet_line = 0;
  bool all_start_with_3 = true;
  for (int64_t t = 0; t < nt; ++t) {
    if (!readRow(reader, &row)) return truncatedError(reader, last_line, t, nt, "tetrahedra");
    last_line = reader.line();
    all_start_with_3 &= row[0] == "3";
    if (t == 0) {
      first_tet_line = reader.line();
      tet_width = row.size();
      if (tet_width != 4 && tet_width != 5) {
        return reader.error("a tetrahedron row has 4 indices, optionally after a leading 4; found " +
                            std::to_string(tet_width) + " values");
      }
      GTN_RETURN_IF_ERROR(checkRestFits(reader, nt, static_cast<int64_t>(tet_width), "tetrahedra", count_line));
      mesh.tets.resize(static_cast<size_t>(nt));
    } else if (row.size() != tet_width) {
      return reader.error("tetrahedron row has " + std::to_string(row.size()) + " values; the first one has " +
                          std::to_string(tet_width) + surfaceHint(row));
    }
    if (tet_width == 5) {
      GTN_RETURN_IF_ERROR(parseIntToken(reader, row[0], 4, 4, "vertex count of a tetrahedron").status());
    }
    for (int k = 0; k < 4; ++k) {
      GTN_ASSIGN_OR_RETURN(const int64_t v,
                           parseIntToken(reader, row[tet_width - 4 + k], INT64_MIN, INT64_MAX, "a point index"));
      if (v < 0 || v >= np) {
        return reader.error("tetrahedron " + std::to_string(t) + " refers to point " + std::to_string(v) +
                            "; points are numbered 0 to " + std::to_string(np - 1));
      }
      mesh.tets[static_cast<size_t>(t)][k] = static_cast<uint32_t>(v);
    }
  }
  if (readRow(reader, &row)) {
    return reader.error("more rows than the " + std::to_string(np) + " points and " + std::to_string(nt) +
                        " tetrahedra the header announces");
  }
  // The surface OFF of Geomview and the shape benchmarks shares the header and the point rows: its
  // triangles ("3 a b c") read as tetrahedra starting at point 3, its quadrilaterals ("4 a b c d")
  // as prefixed tetrahedra that are all flat. Either way the result would be meaningless.
  const std::string where = path + ":" + std::to_string(first_tet_line) + ": ";
  if (tet_width == 4 && nt >= 2 && all_start_with_3) {
    return Status(StatusCode::kUnsupported,
                  where + "every one of the " + std::to_string(nt) +
                      " element rows starts with 3: this is a surface OFF of triangles ('3 a b c'), not "
                      "tetrahedral OFF; it has no volume to import");
  }
  finishImport(result);
  if (nt > 0 && result.report.zero_volume == static_cast<size_t>(nt)) {
    return Status(StatusCode::kUnsupported,
                  where + "all " + std::to_string(nt) + " tetrahedra are flat (their 4 points are coplanar)" +
                      (tet_width == 5 ? ": this looks like a surface OFF of quadrilaterals ('4 a b c d'), not "
                                        "tetrahedral OFF"
                                      : "") +
                      "; it has no volume to import");
  }
  mesh.setMetadata("source.format", "off");
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  return result;
}

}  // namespace gtn
