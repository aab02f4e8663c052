#include "convert/import.h"

#include <sys/stat.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <numeric>

#include "codec/grid_coder.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"
#include "mesh/index.h"
#include "mesh/mesh_stats.h"
#include "mesh/utf8.h"

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

// The first n bytes of a regular file ("" for anything else: reading a pipe would consume what its
// importer reads, and opening a FIFO without a writer would wait forever).
std::string head(const std::string& path, size_t n) {
  if (!isRegularFile(path)) return "";
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
    case InputFormat::kVtu: return "VTK XML (.vtu, .vts, .vtr, .vti and their parallel forms)";
    case InputFormat::kMedit: return "Medit";
    case InputFormat::kMeshb: return "Medit binary (.meshb)";
    case InputFormat::kOff: return "tetrahedral OFF";
    case InputFormat::kGtn: return ".gtn";
    case InputFormat::kGmsh: return "gmsh (.msh)";
    case InputFormat::kExodus: return "Exodus II";
    default: return "unknown";
  }
}

InputFormat detectInputFormat(const std::string& path) {
  const std::string ext = lowerExtension(path);
  const std::string h = head(path, 256);
  if (h.size() >= 4 && static_cast<unsigned char>(h[0]) == 0x8E && h[1] == 'G' && h[2] == 'T' && h[3] == 'N')
    return InputFormat::kGtn;
  if (ext == "gtn") return InputFormat::kGtn;
  // Exodus II is netCDF: classic ("CDF" and 1, 2 or 5) or netCDF-4, an HDF5 file.
  if ((h.size() >= 4 && h.compare(0, 3, "CDF") == 0 && (h[3] == 1 || h[3] == 2 || h[3] == 5)) ||
      h.rfind("\x89HDF\r\n\x1a\n", 0) == 0 || ext == "exo" || ext == "e" || ext == "ex2" || ext == "exii" ||
      ext == "gen")
    return InputFormat::kExodus;
  if (h.rfind("# vtk DataFile", 0) == 0 || ext == "vtk") return InputFormat::kVtkLegacy;
  if (ext == "vtu" || ext == "vts" || ext == "vtr" || ext == "vti" || ext == "pvtu" || ext == "pvts" || ext == "pvtr" ||
      ext == "pvti" || h.find("<VTKFile") != std::string::npos)
    return InputFormat::kVtu;
  if (ext == "msh" || h.rfind("$MeshFormat", 0) == 0) return InputFormat::kGmsh;
  // Medit: the content tells ASCII from binary whatever the extension (gmsh 4.8 writes ASCII into a
  // file it names .meshb); binary starts with the code 1 in either byte order.
  const bool gmf_binary = h.size() >= 8 && (h.compare(0, 4, std::string("\x01\0\0\0", 4)) == 0 ||
                                            h.compare(0, 4, std::string("\0\0\0\x01", 4)) == 0);
  const bool medit_text = h.find("MeshVersionFormatted") != std::string::npos;
  if (ext == "meshb") return medit_text && !gmf_binary ? InputFormat::kMedit : InputFormat::kMeshb;
  if (ext == "mesh" && gmf_binary) return InputFormat::kMeshb;
  if (ext == "mesh" || medit_text) return InputFormat::kMedit;
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

namespace {
// Drops the tetrahedra that list a point twice, with their cell values; returns how many went.
size_t dropFlatTets(TetMesh& mesh) {
  size_t out = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& q = mesh.tets[t];
    if (q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] || q[2] == q[3]) continue;
    if (out != t) {
      for (Field& f : mesh.cell_fields) f.copyItem(f, t, out);
      mesh.tets[out] = q;
    }
    ++out;
  }
  const size_t dropped = mesh.tets.size() - out;
  mesh.tets.resize(out);
  for (Field& f : mesh.cell_fields) f.bytes.resize(out * f.components * f.valueSize());
  return dropped;
}
}  // namespace

void finishImport(ImportResult& result) {
  // A cell listing one point twice is no tetrahedron (a tetrahedron cell with a repeated index; the
  // split of other cells leaves such pieces out itself): it goes, instead of failing the encoder.
  if (const size_t flat = dropFlatTets(result.mesh)) {
    result.report.dropped_cells += flat;
    result.report.warnings.push_back(std::to_string(flat) +
                                     " tetrahedra that list a point twice (flat, no tetrahedra) dropped");
  }
  size_t zero = 0;
  result.report.flipped += normalizeOrientation(result.mesh, &zero);
  result.report.zero_volume = zero;
  if (const size_t turned = zero ? orientFlatTets(result.mesh) : 0)
    result.report.warnings.push_back(std::to_string(turned) +
                                     " tetrahedra of zero volume reoriented to agree with their neighbours");
}

std::vector<uint32_t> weldIdentities(const TetMesh& mesh) {
  const size_t n = mesh.numPoints();
  auto bits = [&](size_t p, int a) { return std::bit_cast<uint64_t>(mesh.coords[3 * p + a]); };
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    for (int a = 0; a < 3; ++a)
      if (bits(x, a) != bits(y, a)) return bits(x, a) < bits(y, a);
    return x < y;
  });
  std::vector<uint32_t> rep(n);
  for (size_t r = 0; r < n;) {
    size_t e = r + 1;
    while (e < n && bits(order[e], 0) == bits(order[r], 0) && bits(order[e], 1) == bits(order[r], 1) &&
           bits(order[e], 2) == bits(order[r], 2))
      ++e;
    for (size_t q = r; q < e; ++q) rep[order[q]] = order[r];
    r = e;
  }
  return rep;
}

std::vector<uint32_t> keepPoints(TetMesh& mesh, const std::vector<uint8_t>& keep) {
  const size_t n = mesh.numPoints();
  std::vector<uint32_t> new_index(n, kNoIndex);
  uint32_t kept = 0;
  for (size_t p = 0; p < n; ++p) {
    if (!keep[p]) continue;
    if (kept != p) {
      for (int a = 0; a < 3; ++a) mesh.coords[3 * size_t{kept} + a] = mesh.coords[3 * p + a];
      for (Field& f : mesh.point_fields) f.copyItem(f, p, kept);
    }
    new_index[p] = kept++;
  }
  mesh.coords.resize(3 * size_t{kept});
  for (Field& f : mesh.point_fields) f.bytes.resize(size_t{kept} * f.components * f.valueSize());
  return new_index;
}

void weldPoints(TetMesh& mesh, ImportReport& report) {
  const size_t n = mesh.numPoints();
  const std::vector<uint32_t> rep = weldIdentities(mesh);
  // A welded point whose values differ from those of the point it is merged into (a solver's values
  // discontinuous across its pieces' seams) loses them: the first point's are kept. Said per field.
  std::string differ;
  for (const Field& f : mesh.point_fields) {
    const size_t item = f.components * f.valueSize();
    if (item == 0 || f.bytes.size() < n * item) continue;
    size_t count = 0;
    for (size_t p = 0; p < n; ++p)
      count += rep[p] != p && std::memcmp(f.bytes.data() + p * item, f.bytes.data() + rep[p] * item, item) != 0;
    if (count > 0) differ += (differ.empty() ? "" : ", ") + std::string("'") + f.name + "' at " + std::to_string(count);
  }
  if (!differ.empty())
    report.warnings.push_back("--weld merged points whose values differ (" + differ +
                              " of the welded points); each keeps the values of the first point at its position");
  std::vector<uint8_t> keep(n);
  for (size_t p = 0; p < n; ++p) keep[p] = rep[p] == p;
  const std::vector<uint32_t> new_index = keepPoints(mesh, keep);
  const size_t kept = mesh.numPoints();
  report.welded_points += n - kept;
  if (kept == n) return;
  // A block's nodes welded into earlier ones become its aliases (the other nodes keep their order).
  if (mesh.blocks.size() == 1 && mesh.blocks[0].first_point == 0 && mesh.blocks[0].aliases.empty()) {
    StructuredBlock& b = mesh.blocks[0];
    const uint64_t nodes = uint64_t{b.dims[0]} * b.dims[1] * b.dims[2];
    for (uint64_t p = 0; p < nodes && p < n; ++p)
      if (rep[p] != p) b.aliases.emplace_back(static_cast<uint32_t>(p), rep[p]);
  } else {
    mesh.blocks.clear();
  }
  for (Tet& q : mesh.tets)
    for (uint32_t& v : q) v = new_index[rep[v]];
  report.collapsed_tets += dropFlatTets(mesh);
}

namespace {
// importMesh without the final check.
// A .gtn file as an input: its lossless level 0, decoded whole (gtn convert x.gtn -o y.vtu is gtn
// export's level 0; -o y.gtn re-encodes it, with other levels or none). Mip levels and the merge tree
// are not read: a .gtn output gets its own from level 0.
StatusOr<ImportResult> importGtn(const std::string& path) {
  ImportResult result;
  GtnOpenOptions oo;
  oo.verify = false;  // level 0 is read, checksummed as it is; damage elsewhere is a warning
  GTN_ASSIGN_OR_RETURN(std::unique_ptr<GtnReader> reader,
                       openGtnChecked(path, oo, [&](const std::string& w) { result.report.warnings.push_back(w); }));
  if (reader->levels() == 0) return invalidData(path + ": the file holds no level");
  TetMeshBuilder builder;
  GTN_RETURN_IF_ERROR(reader->decodeLevel(0, builder));
  result.mesh = std::move(builder.mesh());
  if (reader->levels() > 1)
    result.report.warnings.push_back("read level 0, the lossless mesh, of its " + std::to_string(reader->levels()) +
                                     " levels (the mip levels and the merge tree are not read)");
  finishImport(result);
  GTN_RETURN_IF_ERROR(result.mesh.checkConsistency(path));
  return result;
}

StatusOr<ImportResult> importMeshOnce(const std::vector<std::string>& inputs, const ImportOptions& options) {
  if (inputs.empty()) return usageError("no input given");
  if (options.split != 5 && options.split != 6)
    return usageError("--split must be 5 or 6, not " + std::to_string(options.split));
  // Standard input carries a .gtn stream (the one format that can be read front to back without
  // knowing its kind from a name; mesh formats are named by their files).
  if (inputs.size() == 1 && inputs[0] == "-") {
    StatusOr<ImportResult> r = importGtn("-");
    if (!r.isOk() && r.status().code() == StatusCode::kNotOurFile)
      return Status(r.status().code(), r.status().message() +
                                           "; standard input is read as a .gtn stream: name a "
                                           "mesh file instead");
    return r;
  }
  // A pipe (a FIFO, or the shell's <(...)) can be read once, but an input is read twice: its first bytes
  // tell its format, then its importer reads it from the start.
  for (const std::string& p : inputs) {
    struct stat sb;
    if (::stat(p.c_str(), &sb) == 0 && (S_ISFIFO(sb.st_mode) || S_ISSOCK(sb.st_mode)))
      return ioError(p +
                     ": is a pipe, not a file: an input is read more than once (its first bytes tell its format); "
                     "save it to a file first");
  }
  // A repository cloned without Git LFS holds a short text pointer in place of each large file; every
  // importer would misread one as a malformed file of its own format.
  for (const std::string& p : inputs)
    if (head(p, 64).rfind("version https://git-lfs.github.com/spec/", 0) == 0)
      return Status(StatusCode::kNotOurFile, p + ": a Git LFS pointer (the placeholder a clone without Git LFS "
                                                 "holds), not the file itself: fetch it, e.g. with 'git lfs pull'");
  if (const std::string ext = lowerExtension(inputs[0]); ext == "sol" || ext == "solb")
    return usageError(inputs[0] +
                      ": a Medit solution file holds values, not a mesh: give it after its mesh "
                      "(gtn convert u.mesh " +
                      inputs[0] + " ...)");
  const InputFormat first = detectInputFormat(inputs[0]);
  if (first == InputFormat::kPlot3d) return importPlot3d(inputs, options);
  ImportOptions opts = options;
  if (inputs.size() != 1 && (first == InputFormat::kMedit || first == InputFormat::kMeshb)) {
    // A Medit mesh and its solution files.
    for (size_t i = 1; i < inputs.size(); ++i) {
      const std::string ext = lowerExtension(inputs[i]);
      if (ext != "sol" && ext != "solb")
        return usageError(inputs[i] + ": a Medit mesh takes solution files (.sol, .solb) besides it, not this");
      opts.medit_solutions.push_back(inputs[i]);
    }
  } else if (inputs.size() != 1) {
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
    } else if (first != InputFormat::kUnknown) {
      return usageError(inputs[1] + ": " + inputs[0] + " is a " + inputFormatName(first) +
                        " mesh, which is one file; this is an input too many");
    }
    // Of an unknown format, the first input's own error says why (its format cannot be told).
  }
  const std::string& path = inputs[0];
  if (first != InputFormat::kTetgen && !isRegularFile(path)) {
    auto probe = readWholeFile(path, 1);
    if (!probe.isOk()) return probe.status();
  }
  StatusOr<ImportResult> result = usageError("");
  switch (first) {
    case InputFormat::kTetgen: result = importTetgen(path, opts); break;
    case InputFormat::kVtkLegacy: result = importVtkLegacy(path, opts); break;
    case InputFormat::kVtu: result = importVtu(path, opts); break;
    case InputFormat::kMedit: result = importMedit(path, opts); break;
    case InputFormat::kMeshb: result = importMeshb(path, opts); break;
    case InputFormat::kOff: result = importOff(path, opts); break;
    case InputFormat::kGtn: result = importGtn(path); break;
    case InputFormat::kGmsh: result = importGmsh(path, opts); break;
    case InputFormat::kExodus: result = importExodus(path, opts); break;
    default:
      return Status(StatusCode::kNotOurFile,
                    path +
                        ": cannot tell its format from the extension or content (known: PLOT3D .xyz/.q/.bin/.p3d, "
                        "TetGen .node/.ele, VTK .vtk/.vtu/.vts/.vtr/.vti and parallel .pvtu/.pvts/.pvtr/.pvti, Medit "
                        ".mesh/.meshb, tetrahedral .off, gmsh .msh, Exodus II .exo/.e/.ex2)");
  }
  if (result.isOk() && (first == InputFormat::kMedit || first == InputFormat::kMeshb) && opts.medit_solutions.empty()) {
    // Medit and MMG load u.sol or u.solb beside u.mesh by themselves; say so rather than guess.
    const size_t dot = path.find_last_of('.');
    const std::string base =
        dot == std::string::npos || path.find('/', dot) != std::string::npos ? path : path.substr(0, dot);
    for (const char* ext : {".sol", ".solb"})
      if (isRegularFile(base + ext))
        result->report.warnings.push_back(base + ext +
                                          " beside it holds solution values that were not read; name it "
                                          "after the mesh to import them as fields (gtn convert " +
                                          path + " " + base + ext + " ...)");
  }
  if (result.isOk() && options.weld) {
    weldPoints(result->mesh, result->report);
    finishImport(*result);  // recounts zero-volume cells: some of them may have collapsed away
  }
  return result;
}
}  // namespace

StatusOr<ImportResult> importMesh(const std::vector<std::string>& inputs, const ImportOptions& options) {
  StatusOr<ImportResult> result = importMeshOnce(inputs, options);
  if (result.isOk() && !inputs.empty() && inputs[0] != "-" && detectInputFormat(inputs[0]) != InputFormat::kGtn) {
    // How the mesh was made, where it differs from the defaults: `gtn validate --against` imports
    // the source again the same way (spec/gtn-format.md, "Metadata keys").
    if (options.split != 6) result->mesh.setMetadata(kMetadataSplit, std::to_string(options.split));
    if (options.weld) result->mesh.setMetadata(kMetadataWeld, "yes");
  }
  if (result.isOk() && options.exodus_time_step != 0 && !inputs.empty() && inputs[0] != "-" &&
      detectInputFormat(inputs[0]) != InputFormat::kExodus)
    result->report.warnings.push_back("--time-step " + std::to_string(options.exodus_time_step) +
                                      " applies to Exodus II files only; ignored");
  if (result.isOk()) {
    // Names and metadata become the .gtn format's UTF-8 strings (and JSON): a name in another
    // encoding (Latin-1 in older files) is transcoded.
    TetMesh& m = result->mesh;
    for (std::vector<Field>* fields : {&m.point_fields, &m.cell_fields})
      for (Field& f : *fields) f.name = toUtf8(f.name);
    for (auto& kv : m.metadata) {
      kv.first = toUtf8(kv.first);
      kv.second = toUtf8(kv.second);
    }
  }
  if (result.isOk() && !result->mesh.blocks.empty()) {
    // The structured block an importer read: offered only when the mesh is exactly that one block.
    TetMesh& m = result->mesh;
    if (m.blocks.size() != 1 || m.blocks[0].first_point != 0 ||
        !matchGridLayout(m, m.blocks[0].dims, m.blocks[0].aliases).isOk())
      m.blocks.clear();
  }
  if (result.isOk() && result->mesh.tets.empty()) {
    const ImportReport& r = result->report;
    std::string why;
    if (r.dropped_cells > 0) why = ": all " + std::to_string(r.dropped_cells) + " cells were dropped (IBLANK holes)";
    else if (r.collapsed_tets > 0) why = ": --weld collapsed all " + std::to_string(r.collapsed_tets) + " tetrahedra";
    result->report.warnings.push_back("the mesh has no tetrahedra left" + why);
  }
  return result;
}

}  // namespace gtn
