#include "convert/import.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>

#include "format/file_io.h"
#include "mesh/mesh_stats.h"

namespace gtn {

namespace {
std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string head(const std::string& path, size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return "";
  std::string s(n, '\0');
  s.resize(std::fread(s.data(), 1, n, f));
  std::fclose(f);
  return s;
}
}  // namespace

const char* inputFormatName(InputFormat f) {
  switch (f) {
    case InputFormat::kPlot3d: return "PLOT3D";
    case InputFormat::kTetgen: return "TetGen";
    case InputFormat::kVtkLegacy: return "legacy VTK";
    case InputFormat::kVtu: return "VTK XML (.vtu, .vts, .vtr, .vti)";
    case InputFormat::kMedit: return "Medit";
    case InputFormat::kMeshb: return "Medit binary (.meshb)";
    case InputFormat::kOff: return "tetrahedral OFF";
    case InputFormat::kGtn: return ".gtn";
    default: return "unknown";
  }
}

InputFormat detectInputFormat(const std::string& path) {
  const std::string ext = lowerExtension(path);
  const std::string h = head(path, 256);
  if (h.size() >= 4 && static_cast<unsigned char>(h[0]) == 0x8E && h[1] == 'G' && h[2] == 'T' && h[3] == 'N')
    return InputFormat::kGtn;
  if (ext == "gtn") return InputFormat::kGtn;
  if (h.rfind("# vtk DataFile", 0) == 0 || ext == "vtk") return InputFormat::kVtkLegacy;
  if (ext == "vtu" || ext == "pvtu" || ext == "vts" || ext == "vtr" || ext == "vti" || h.find("<VTKFile") != std::string::npos)
    return InputFormat::kVtu;
  if (ext == "meshb") return InputFormat::kMeshb;
  if (ext == "mesh" || h.find("MeshVersionFormatted") != std::string::npos) return InputFormat::kMedit;
  if (ext == "off" || ext == "toff") return InputFormat::kOff;
  if (ext == "node" || ext == "ele" || ext == "face") return InputFormat::kTetgen;
  // A TetGen basename such as "foo.1" has an extension of its own but names no file.
  if ((ext.empty() || !isRegularFile(path)) && (isRegularFile(path + ".node") || isRegularFile(path + ".ele")))
    return InputFormat::kTetgen;
  if (ext == "p3d" || ext == "xyz" || ext == "x" || ext == "g" || ext == "grd" || ext == "q" || ext == "f" ||
      ext == "fun" || ext == "bin" || ext == "p3d.json" || ext == "fmt")
    return InputFormat::kPlot3d;
  return InputFormat::kUnknown;
}

void finishImport(ImportResult& result) {
  size_t zero = 0;
  result.report.flipped += normalizeOrientation(result.mesh, &zero);
  result.report.zero_volume = zero;
}

StatusOr<ImportResult> importMesh(const std::vector<std::string>& inputs, const ImportOptions& options) {
  if (inputs.empty()) return usageError("no input given");
  if (options.split != 5 && options.split != 6)
    return usageError("--split must be 5 or 6, not " + std::to_string(options.split));
  // A repository cloned without Git LFS holds a short text pointer in place of each large file; every
  // importer would misread one as a malformed file of its own format.
  for (const std::string& p : inputs)
    if (head(p, 64).rfind("version https://git-lfs.github.com/spec/", 0) == 0)
      return Status(StatusCode::kNotOurFile, p + ": a Git LFS pointer (the placeholder a clone without Git LFS "
                                                 "holds), not the file itself: fetch it, e.g. with 'git lfs pull'");
  const InputFormat first = detectInputFormat(inputs[0]);
  if (first == InputFormat::kPlot3d) return importPlot3d(inputs, options);
  if (inputs.size() != 1) {
    // A TetGen mesh may be named by several of its files (x.node x.ele): they must share a basename.
    if (first == InputFormat::kTetgen) {
      auto base = [](const std::string& p) {
        const size_t dot = p.find_last_of('.');
        return dot == std::string::npos ? p : p.substr(0, dot);
      };
      for (const std::string& p : inputs) {
        if (detectInputFormat(p) != InputFormat::kTetgen || base(p) != base(inputs[0]))
          return usageError(p + ": TetGen inputs must all be files of one mesh (" + base(inputs[0]) + ".*)");
      }
      return importTetgen(inputs[0], options);
    }
    return usageError(std::string("a ") + inputFormatName(first) + " mesh is one file; got " +
                      std::to_string(inputs.size()) + " inputs");
  }
  const std::string& path = inputs[0];
  if (first != InputFormat::kTetgen && !isRegularFile(path)) {
    auto probe = readWholeFile(path, 1);
    if (!probe.isOk()) return probe.status();
  }
  switch (first) {
    case InputFormat::kTetgen: return importTetgen(path, options);
    case InputFormat::kVtkLegacy: return importVtkLegacy(path, options);
    case InputFormat::kVtu: return importVtu(path, options);
    case InputFormat::kMedit: return importMedit(path, options);
    case InputFormat::kMeshb: return importMeshb(path, options);
    case InputFormat::kOff: return importOff(path, options);
    case InputFormat::kGtn:
      return usageError(path + ": is a .gtn file; use 'gtn export' or 'gtn info' to read it");
    default:
      return Status(StatusCode::kNotOurFile,
                    path + ": cannot tell its format from the extension or content (known: PLOT3D .xyz/.q/.bin/.p3d, "
                           "TetGen .node/.ele, VTK .vtk/.vtu/.vts/.vtr/.vti, Medit .mesh/.meshb, tetrahedral .off)");
  }
}

}  // namespace gtn
