// Exporters: a TetMesh into TetGen (.node/.ele/.face), VTK XML (.vtu) or legacy VTK (.vtk). Outputs
// are atomic.
#pragma once

#include <string>

#include "mesh/tet_mesh.h"

namespace gtn {

struct ExportOptions {
  bool compress = false;  // .vtu: zlib-compressed data blocks
};

enum class OutputFormat { kUnknown, kGtn, kVtu, kVtkLegacy, kTetgen };
// From the extension: .gtn, .vtu, .vtk, .node or .ele (TetGen: the basename gets .node, .ele and .face).
OutputFormat detectOutputFormat(const std::string& path);

// TetGen: `path` ends in .node or .ele (or is a basename); writes base.node, base.ele, base.face.
// Point fields become .node attributes in field order, components in order, printed with enough
// digits to read back bit-exact; the attribute layout is recorded in a comment line of the .node.
Status exportTetgen(const TetMesh& mesh, const std::string& path);
Status exportVtu(const TetMesh& mesh, const std::string& path, const ExportOptions& options);
// Legacy VTK, BINARY, file version 4.2 (read by every VTK release and by meshio): an UNSTRUCTURED_GRID
// of tetrahedra, coordinates in their type, fields as FIELD arrays of their type.
Status exportVtkLegacy(const TetMesh& mesh, const std::string& path);
// The exporter that `path`'s extension names (.vtu, .vtk, .node, .ele); not .gtn.
Status exportMesh(const TetMesh& mesh, const std::string& path, const ExportOptions& options);

}  // namespace gtn
