// gtn export FILE.gtn -o OUTPUT [--level I | --ratio R | --merges N] [--fields A,B] [--box ...]: decode
// a stored level, or the mesh simplified to a ratio or merge count (from the finest stored level not
// beyond it, the remaining merges applied on the fly), and write it as .vtu, legacy .vtk or TetGen;
// with --fields, only the named fields (the others are not decoded); with --box, only the level's
// pieces that meet the box.
#include <cstdint>
#include <memory>

#include "cli/commands.h"
#include "cli/level_view.h"
#include "cli/progress_line.h"
#include "convert/export.h"
#include "convert/import.h"
#include "format/decode_fields.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"
#include "simplify/levels.h"

namespace gtn::cli {

namespace {
struct ExportArgs {
  std::string input;
  std::string output;
  size_t level = 0;
  bool compress = false;
  double ratio = -1;                // < 0: not given
  int64_t merges = -1;              // < 0: not given
  std::vector<std::string> fields;  // empty: all
  std::string box;                  // --box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX; empty: the whole level
};

int runExport(const ExportArgs& a) {
  const OutputFormat out_format = detectOutputFormat(a.output);
  if (out_format != OutputFormat::kVtu && out_format != OutputFormat::kVtkLegacy && out_format != OutputFormat::kTetgen)
    return reportError(usageError(a.output + ": unknown output format for export (use .vtu, .vtk, .node or .ele)"));
  if (a.input == a.output || sameFile(a.input, a.output))
    return reportError(usageError(a.output + ": the output would overwrite the input"));
  HeldWarnings damage;  // said once the outcome is known: the error alone names a chunk export needed
  auto reader = openForView(a.input, "export",
                            "use 'gtn convert " + a.input + " -o " + a.output + "' to convert a mesh file", damage);
  if (!reader.isOk()) return reportError(reader.status());
  GtnReader& r = **reader;
  auto fail = [&](const Status& st) {
    damage.flush(st);
    return reportError(st);
  };
  TetMeshBuilder builder;
  // On a terminal, the share of the level decoded, then the write.
  ProgressLine progress("gtn export", true);
  ProgressMeshSink shown(builder, progress.callback(), "decode");
  MeshSink& sink = progress.active() ? static_cast<MeshSink&>(shown) : builder;
  ViewRequest view;
  view.level = a.level;
  view.ratio = a.ratio;
  view.merges = a.merges;
  view.fields = a.fields;
  if (!a.box.empty()) {
    if (Status b = parseBox(a.box, &view); !b.isOk())
      return reportError(Status(b.code(), a.input + ": " + b.message()));
  }
  DecodeFields fields;
  const Status st = decodeView(r, a.input, view, sink, &fields, nullptr);
  if (!st.isOk()) return fail(st);
  damage.flush();
  if (!a.fields.empty()) dropUndecodedFields(builder.mesh(), fields);
  progress.update("write " + a.output);
  ExportOptions eo;
  eo.compress = a.compress;
  const Status written = exportMesh(builder.mesh(), a.output, eo);
  if (!written.isOk()) return reportError(written);
  return 0;
}
}  // namespace

Command addExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub =
      app.add_subcommand("export", "Decode a level of a .gtn file and write it as .vtu, .vtk or TetGen .node/.ele");
  sub->add_option("input", args->input, "Input .gtn file ('-' for standard input)")->required();
  sub->add_option("-o,--output", args->output, "Output file: .vtu (VTK XML), .vtk (legacy VTK) or .node/.ele (TetGen)")
      ->required();
  CLI::Option* level = sub->add_option("--level", args->level, "Stored level to decode (0 = the lossless mesh)")
                           ->check(finiteAtLeastZero());
  CLI::Option* ratio =
      sub->add_option("--ratio", args->ratio,
                      "Simplification ratio: vertices merged away / vertices of level 0 that tetrahedra use (0 to 1)")
          ->check(ratioFromZeroToOne());
  CLI::Option* merges = sub->add_option("--merges", args->merges, "Number of merges of the merge tree to apply")
                            ->check(finiteAtLeastZero());
  level->excludes(ratio)->excludes(merges);
  ratio->excludes(merges);
  sub->add_flag("--compress", args->compress, ".vtu: zlib-compress the data arrays");
  sub->add_option("--fields", args->fields,
                  "Export only these point or cell fields (names, comma-separated); the others are not decoded")
      ->delimiter(',');
  CLI::Option* box = addBoxOption(sub, &args->box);
  box->excludes(ratio)->excludes(merges);
  return {sub, [args] { return runExport(*args); }};
}

}  // namespace gtn::cli
