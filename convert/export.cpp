#include "convert/export.h"

#include <cctype>

namespace gtn {

OutputFormat detectOutputFormat(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return OutputFormat::kUnknown;
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "gtn") return OutputFormat::kGtn;
  if (ext == "vtu") return OutputFormat::kVtu;
  if (ext == "vtk") return OutputFormat::kVtkLegacy;
  if (ext == "node" || ext == "ele") return OutputFormat::kTetgen;
  return OutputFormat::kUnknown;
}

Status exportMesh(const TetMesh& mesh, const std::string& path, const ExportOptions& options) {
  switch (detectOutputFormat(path)) {
    case OutputFormat::kVtu: return exportVtu(mesh, path, options);
    case OutputFormat::kVtkLegacy: return exportVtkLegacy(mesh, path);
    case OutputFormat::kTetgen: return exportTetgen(mesh, path);
    default: return usageError(path + ": unknown output format (use .vtu, .vtk, .node or .ele)");
  }
}

}  // namespace gtn
