// gtn convert INPUT... -o OUTPUT [--split 5|6] [--weld] [--time-step N] [--compress] [--levels K] [--no-merge-tree]
//   [--no-verify] [--keep-invalid] [--level-storage X] [--independent-levels] [--simplify-field NAME] [--w-density W] [--w-geometry W] [--greedy-ranking] [-q]
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <memory>

#include "cli/commands.h"
#include "cli/convert_summary.h"
#include "cli/progress_line.h"
#include "convert/export.h"
#include "convert/import.h"
#include "format/file_io.h"
#include "format/gtn_file.h"
#include "validate/write_gtn.h"

namespace gtn::cli {

namespace {
struct ConvertArgs {
  std::vector<std::string> inputs;
  std::string output;
  int split = 6;
  bool weld = false;
  int time_step = 0;
  bool compress = false;
  int levels = -1;  // mip levels beyond level 0, -1 = automatic
  bool no_merge_tree = false;
  bool independent_levels = false;  // .gtn: every level stores all its vertices (GtnWriteOptions::chain_levels)
  bool no_verify = false;           // .gtn: skip decoding every written level back (GtnWriteOptions::verify)
  bool keep_invalid = false;        // .gtn: write a mesh with errors of its own (GtnConvertOptions::keep_invalid)
  double level_storage = 2.0;       // automatic levels: all levels within this multiple of level 0's bytes
  uint64_t piece_tets = kDefaultPieceTets;  // .gtn: the bound on a piece's tetrahedra
  RankingOptions ranking;
  bool quiet = false;  // -q: no progress line, no summary
};

// Level 0, its mip levels and merge trees as the options ask (validate/write_gtn.h).
// `mesh` the writer may change while it works (a large grid's tetrahedra released while the merges are
// ranked, GtnConvertOptions::release_grid_tets); as it was when this returns.
Status writeGtnWithLevels(const ConvertArgs& a, TetMesh& mesh, const GtnWriteOptions& wo) {
  GtnConvertOptions o;
  o.levels = a.levels;
  o.merge_tree = !a.no_merge_tree;
  o.level_storage = a.level_storage;
  o.ranking = a.ranking;
  o.keep_invalid = a.keep_invalid;
  std::vector<std::string> warnings;
  Status st = gtn::writeGtnWithLevels(a.output, &mesh, o, wo, a.inputs[0], &warnings);
  for (const std::string& w : warnings) warn(w);
  return st;
}

int runConvert(const ConvertArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  const OutputFormat out_format = detectOutputFormat(a.output);
  if (out_format == OutputFormat::kUnknown)
    return reportError(usageError(a.output + ": unknown output format (use .gtn, .vtu, .vtk, .node or .ele)"));
  for (const std::string& in : a.inputs) {
    if (in == a.output || sameFile(in, a.output))
      return reportError(usageError(a.output + ": the output would overwrite an input"));
  }
  // An output that cannot be written fails now, not after the import, ranking and encoding.
  if (Status w = checkOutputWritable(a.output); !w.isOk()) return reportError(w);
  if (a.compress && out_format != OutputFormat::kVtu)
    warn(a.output + ": --compress applies to .vtu outputs only; ignored");
  ProgressLine progress("gtn convert", !a.quiet);
  progress.update("import");
  ImportOptions options;
  options.split = a.split;
  options.weld = a.weld;
  options.exodus_time_step = a.time_step;
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
      wo.piece_tets = a.piece_tets;
      wo.chain_levels = !a.independent_levels;
      st = writeGtnWithLevels(a, mesh, wo);
      // The encoder's refusals are about the mesh: say where to see the details.
      if (!st.isOk() && st.message().rfind(a.inputs[0] + ": cannot be encoded: ", 0) == 0)
        st = Status(st.code(), st.message() + " (gtn validate " + a.inputs[0] + " lists the problems)");
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
    printConvertSummary(a.inputs, a.output, mesh.numTets(),
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}
}  // namespace

Command addConvertCommand(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* sub = app.add_subcommand(
      "convert", "Import a mesh (PLOT3D, TetGen, VTK, Medit, OFF, gmsh, Exodus II) and write .gtn, .vtu or TetGen");
  sub->add_option("inputs", args->inputs,
                  "Input files (PLOT3D: grid [Q] [function] or .p3d; TetGen: basename or .node/.ele; Medit: "
                  ".mesh/.meshb [.sol/.solb ...]; VTK; OFF; gmsh .msh; Exodus II .exo/.e/.ex2; .gtn: its level 0)")
      ->required();
  sub->add_option("-o,--output", args->output,
                  "Output file: .gtn, .vtu (VTK XML), .vtk (legacy VTK) or .node/.ele (TetGen)")
      ->required();
  sub->add_option("--split", args->split, "Hexahedra into 5 (alternating) or 6 (consistent diagonals) tetrahedra")
      ->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld,
                "merge bit-identical points (seams between PLOT3D blocks or VTK pieces) and drop collapsed tetrahedra");
  sub->add_option("--time-step", args->time_step,
                  "Exodus II: the time step (1, 2, ...) whose variables become fields (default: the last)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--compress", args->compress, ".vtu: zlib-compress the data arrays");
  sub->add_option(
         "--levels", args->levels,
         ".gtn: mip levels beyond level 0 (default: down to a level of 256 points or 4096 tetrahedra; 0 = none)")
      ->check(CLI::Range(0, 62));
  sub->add_option("--level-storage", args->level_storage,
                  ".gtn: automatic levels leave out the coarsest ones while all levels together would take more "
                  "than this multiple of level 0's bytes alone, with its merge tree (default 2, the paper's "
                  "bound; 0 = no bound)")
      ->check(finiteAtLeastZero());
  sub->add_option("--piece-tets", args->piece_tets,
                  ".gtn: the most tetrahedra a piece holds (default " + std::to_string(kDefaultPieceTets) +
                      "): a level is cut into pieces that encode, decode and are read by region apart (at the "
                      "default, a level stored as a grid stays one piece)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            char* end = nullptr;
            errno = 0;
            const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
            if (text.empty() || text[0] == '-' || end == text.c_str() || *end != '\0' || errno == ERANGE ||
                v < kMinPieceTets)
              return "'" + text + "' is not a piece size: expected a whole number of tetrahedra of at least " +
                     std::to_string(kMinPieceTets);
            return "";
          },
          "N >= " + std::to_string(kMinPieceTets)));
  sub->add_flag("--no-merge-tree", args->no_merge_tree,
                ".gtn: store no merge tree: level 0 alone, no mip levels (they are checked against the tree) and no "
                "on-the-fly simplification");
  sub->add_flag("--independent-levels", args->independent_levels,
                ".gtn: every level stores all of its vertices' values and the rest of the merge tree, so that each "
                "level decodes alone (larger); by default a level names the next coarser level's vertices instead");
  sub->add_flag(
      "--no-verify", args->no_verify,
      ".gtn: do not decode each level back and compare it with its mesh, nor check that each mip level is a valid "
      "mesh, before the file is written (faster; the checks guard against encoder and simplifier bugs)");
  sub->add_flag(
      "--keep-invalid", args->keep_invalid,
      ".gtn: write a mesh that has errors of its own (overlapping tetrahedra, say), which `gtn validate` then "
      "reports; by default such a mesh is refused and nothing is written");
  sub->add_option("--simplify-field", args->ranking.field,
                  ".gtn: point field whose first component is the density of the simplification error "
                  "(default: the first point field that is not constant; 'none' = volume only)");
  sub->add_option("--w-density", args->ranking.w_density, ".gtn: weight of the density (mass) error")
      ->check(finiteAtLeastZero());
  sub->add_option("--w-geometry", args->ranking.w_geometry, ".gtn: weight of the boundary geometry error")
      ->check(finiteAtLeastZero());
  sub->add_flag_callback(
      "--greedy-ranking",
      [args] {
        args->ranking.lazy = false;
        args->ranking.parts = 1;
      },
      ".gtn: rank the whole mesh in one queue, and after each merge rank again every vertex whose neighbourhood it "
      "changed (the greedy order, about 1.4 times the ranking's time); by default such a vertex is ranked again when "
      "it comes to the top of the queue, and meshes of 2^20 tetrahedra or more are first ranked in rounds of parts "
      "in parallel (P, P - 1, ... parts, P one per 2^18 tetrahedra, 8 to 256; where P is 16 or more, more series "
      "on the mesh left, the last in 8, 7, ... 3 parts)");
  sub->add_flag("-q,--quiet", args->quiet,
                "no progress line (shown while standard error is a terminal) and no summary line at the end");
  return {sub, [args] { return runConvert(*args); }};
}

}  // namespace gtn::cli
