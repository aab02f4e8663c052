// gtn convert INPUT... -o OUTPUT [--split 5|6] [--weld] [--compress] [--levels K] [--no-merge-tree]
//   [--no-verify] [--level-storage X] [--simplify-field NAME] [--w-density W] [--w-geometry W] [-q]
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <memory>
#include <utility>

#include "cli/commands.h"
#include "cli/progress_line.h"
#include "convert/export.h"
#include "convert/import.h"
#include "convert/tetgen_layout.h"
#include "format/file_io.h"
#include "format/gtn_file.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"

namespace gtn::cli {

namespace {
struct ConvertArgs {
  std::vector<std::string> inputs;
  std::string output;
  int split = 6;
  bool weld = false;
  bool compress = false;
  int levels = -1;  // mip levels beyond level 0, -1 = automatic
  bool no_merge_tree = false;
  bool no_verify = false;  // .gtn: skip decoding every written level back (GtnWriteOptions::verify)
  double level_storage = 2.0;  // automatic levels: all levels within this multiple of level 0's bytes
  RankingOptions ranking;
  bool quiet = false;  // -q: no progress line, no summary
};

// Level 0, its mip levels and merge trees as the options ask (simplify/levels.h).
Status writeGtnWithLevels(const ConvertArgs& a, const TetMesh& mesh, const GtnWriteOptions& wo) {
  if (a.levels == 0 && a.no_merge_tree) {
    GtnLevelInput level0;
    level0.mesh = &mesh;
    return writeGtnFile(a.output, {level0}, wo);
  }
  reportProgress(wo.progress, "rank merges", 0.0);
  GTN_ASSIGN_OR_RETURN(MergeTree tree, rankMerges(mesh, a.ranking, nullptr, wo.progress));
  reportProgress(wo.progress, "build levels");
  LevelOptions lo;
  lo.levels = a.levels;
  lo.merge_tree = !a.no_merge_tree;
  GTN_ASSIGN_OR_RETURN(MipLevels levels, buildMipLevels(mesh, tree, lo));
  // Levels stop where the merge tree does (a small or flat mesh has few merges): say so rather than
  // write fewer levels than --levels asked for without a word.
  if (a.levels > 0 && levels.merges.size() - 1 < static_cast<size_t>(a.levels))
    warn(a.inputs[0] + ": --levels " + std::to_string(a.levels) + ": the merge tree has " +
         std::to_string(tree.merges) + " merge(s) of " + std::to_string(mesh.numPoints()) + " points, enough for " +
         std::to_string(levels.merges.size() - 1) + " level(s) beyond level 0");
  GtnWriteOptions bounded = wo;
  if (a.levels < 0) bounded.level_storage_limit = a.level_storage;
  return writeGtnFile(a.output, levels.inputs(mesh), bounded);
}

// The size of a file, or -1 when it has none (standard input, a pipe) or cannot be read.
int64_t fileBytes(const std::string& path) {
  struct stat sb;
  if (path == "-" || ::stat(path.c_str(), &sb) != 0 || !S_ISREG(sb.st_mode)) return -1;
  return static_cast<int64_t>(sb.st_size);
}

// The files a TetGen mesh named by `path` (a basename, .node or .ele) takes that exist: .node, .ele
// and .face; other paths as they are.
std::vector<std::string> meshFiles(const std::string& path, bool tetgen) {
  if (!tetgen) return {path};
  const std::string base = tetgen::basePath(path);
  std::vector<std::string> files;
  for (const char* ext : {".node", ".ele", ".face"})
    if (isRegularFile(base + ext)) files.push_back(base + ext);
  return files;
}

// Names and total size of the files (-1: unknown, e.g. standard input or a .p3d meta-file, whose
// data files it names).
std::pair<std::string, int64_t> describeFiles(const std::vector<std::string>& files) {
  std::string names;
  int64_t bytes = files.empty() ? -1 : 0;
  for (const std::string& f : files) {
    names += (names.empty() ? "" : " + ") + f;
    std::string ext = f.size() > 4 ? f.substr(f.size() - 4) : "";
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const int64_t b = ext == ".p3d" ? -1 : fileBytes(f);
    bytes = bytes < 0 || b < 0 ? -1 : bytes + b;
  }
  return {names, bytes};
}

// The one line a finished conversion prints on standard error: what was read and written, their
// sizes and ratio, bits per tetrahedron of the output, the time taken.
void printSummary(const ConvertArgs& a, size_t tets, double seconds) {
  std::vector<std::string> inputs;
  for (const std::string& in : a.inputs)
    for (const std::string& f : meshFiles(in, in != "-" && detectInputFormat(in) == InputFormat::kTetgen))
      if (std::find(inputs.begin(), inputs.end(), f) == inputs.end()) inputs.push_back(f);
  const auto [in_names, in_bytes] = describeFiles(inputs);
  const auto [out_names, out_bytes] =
      describeFiles(meshFiles(a.output, detectOutputFormat(a.output) == OutputFormat::kTetgen));
  std::string line = "gtn: " + in_names;
  if (in_bytes >= 0) line += " (" + std::to_string(in_bytes) + " bytes)";
  line += " -> " + out_names;
  if (out_bytes >= 0) line += " (" + std::to_string(out_bytes) + " bytes)";
  char buf[160];
  if (in_bytes > 0 && out_bytes >= 0) {
    std::snprintf(buf, sizeof buf, ": %.2f%% of the input", 100.0 * static_cast<double>(out_bytes) / static_cast<double>(in_bytes));
    line += buf;
  }
  if (tets > 0 && out_bytes >= 0) {
    std::snprintf(buf, sizeof buf, ", %.2f bits/tet (%zu tetrahedra)", 8.0 * static_cast<double>(out_bytes) / static_cast<double>(tets),
                  tets);
    line += buf;
  }
  std::snprintf(buf, sizeof buf, ", %.2f s", seconds);
  line += buf;
  std::fprintf(stderr, "%s\n", line.c_str());
}

int runConvert(const ConvertArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  const OutputFormat out_format = detectOutputFormat(a.output);
  if (out_format == OutputFormat::kUnknown)
    return reportError(usageError(a.output + ": unknown output format (use .gtn, .vtu, .vtk, .node or .ele)"));
  for (const std::string& in : a.inputs) {
    if (in == a.output || sameFile(in, a.output)) return reportError(usageError(a.output + ": the output would overwrite an input"));
  }
  if (a.compress && out_format != OutputFormat::kVtu)
    warn(a.output + ": --compress applies to .vtu outputs only; ignored");
  ProgressLine progress("gtn convert", !a.quiet);
  progress.update("import");
  ImportOptions options;
  options.split = a.split;
  options.weld = a.weld;
  auto imported = importMesh(a.inputs, options);
  if (!imported.isOk()) return reportError(imported.status());
  printImportReport(a.inputs[0], imported->report);
  TetMesh& mesh = imported->mesh;
  Status st;
  switch (out_format) {
    case OutputFormat::kGtn: {
      GtnWriteOptions wo;
      wo.tool_version = GTN_VERSION_STRING;
      std::vector<std::string> paths = a.inputs;
      paths.push_back(a.output);
      wo.command_line = commandLineWithFileNames(paths);  // file names only: no directories in the file
      wo.progress = progress.callback();
      wo.verify = !a.no_verify;
      st = writeGtnWithLevels(a, mesh, wo);
      // The encoder's refusals are about the mesh: name its input and where to see the details.
      if (!st.isOk() && st.message().rfind("encodeLevel: ", 0) == 0)
        st = Status(st.code(), a.inputs[0] + ": cannot be encoded: " + st.message().substr(13) + " (gtn validate " +
                                   a.inputs[0] + " lists the problems)");
      break;
    }
    default: {
      progress.update("write " + a.output);
      ExportOptions eo;
      eo.compress = a.compress;
      st = exportMesh(mesh, a.output, eo);
    }
  }
  if (!st.isOk()) return reportError(st);
  progress.clear();
  if (!a.quiet)
    printSummary(a, mesh.numTets(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}
}  // namespace

Command addConvertCommand(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* sub = app.add_subcommand("convert", "Import a mesh (PLOT3D, TetGen, VTK, Medit, OFF) and write .gtn, .vtu or TetGen");
  sub->add_option("inputs", args->inputs, "Input files (PLOT3D: grid [Q] [function] or .p3d; TetGen: basename or .node/.ele; Medit: .mesh/.meshb [.sol/.solb ...]; VTK; OFF; .gtn: its level 0)")
      ->required();
  sub->add_option("-o,--output", args->output, "Output file: .gtn, .vtu (VTK XML), .vtk (legacy VTK) or .node/.ele (TetGen)")->required();
  sub->add_option("--split", args->split, "Hexahedra into 5 (alternating) or 6 (consistent diagonals) tetrahedra")
      ->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld, "merge bit-identical points (seams between PLOT3D blocks or VTK pieces) and drop collapsed tetrahedra");
  sub->add_flag("--compress", args->compress, ".vtu: zlib-compress the data arrays");
  sub->add_option("--levels", args->levels, ".gtn: mip levels beyond level 0 (default: down to a small mesh; 0 = none)")
      ->check(CLI::Range(0, 62));
  sub->add_option("--level-storage", args->level_storage,
                  ".gtn: automatic levels stop before all levels together would take more than this multiple "
                  "of level 0's bytes (default 2, the paper's bound; 0 = no bound)")
      ->check(finiteAtLeastZero());
  sub->add_flag("--no-merge-tree", args->no_merge_tree, ".gtn: store no merge tree (no on-the-fly simplification)");
  sub->add_flag("--no-verify", args->no_verify,
                ".gtn: do not decode each level back and compare it with its mesh before the file is written (faster; the check guards against encoder bugs)");
  sub->add_option("--simplify-field", args->ranking.field,
                  ".gtn: point field whose first component is the density of the simplification error "
                  "(default: the first point field; 'none' = volume only)");
  sub->add_option("--w-density", args->ranking.w_density, ".gtn: weight of the density (mass) error")
      ->check(finiteAtLeastZero());
  sub->add_option("--w-geometry", args->ranking.w_geometry, ".gtn: weight of the boundary geometry error")
      ->check(finiteAtLeastZero());
  sub->add_flag("-q,--quiet", args->quiet,
                "no progress line (shown while standard error is a terminal) and no summary line at the end");
  return {sub, [args] { return runConvert(*args); }};
}

}  // namespace gtn::cli
