// gtn export FILE.gtn -o OUTPUT [--level I | --ratio R | --merges N] [--fields A,B]: decode a stored
// level, or the mesh simplified to a ratio or merge count (from the finest stored level not beyond it,
// the remaining merges applied on the fly), and write it as .vtu, legacy .vtk or TetGen; with --fields,
// only the named fields (the others are not decoded).
#include <cstdint>
#include <memory>

#include "cli/commands.h"
#include "cli/progress_line.h"
#include "convert/import.h"
#include "convert/export.h"
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
  double ratio = -1;    // < 0: not given
  int64_t merges = -1;  // < 0: not given
  std::vector<std::string> fields;  // empty: all
};

int runExport(const ExportArgs& a) {
  const OutputFormat out_format = detectOutputFormat(a.output);
  if (out_format != OutputFormat::kVtu && out_format != OutputFormat::kVtkLegacy && out_format != OutputFormat::kTetgen)
    return reportError(usageError(a.output + ": unknown output format for export (use .vtu, .vtk, .node or .ele)"));
  if (a.input == a.output || sameFile(a.input, a.output)) return reportError(usageError(a.output + ": the output would overwrite the input"));
  GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  HeldWarnings damage;  // said once the outcome is known: the error alone names a chunk export needed
  auto reader = openGtnChecked(a.input, oo, damage.sink());
  if (!reader.isOk()) {
    // A mesh file given to export: say which command converts it.
    const InputFormat in_format = detectInputFormat(a.input);
    if (in_format != InputFormat::kGtn && in_format != InputFormat::kUnknown)
      return reportError(usageError(a.input + ": a " + inputFormatName(in_format) +
                                    " file, not .gtn: 'gtn export' reads .gtn files; use 'gtn convert " + a.input +
                                    " -o " + a.output + "' to convert a mesh file"));
    return reportError(reader.status());
  }
  GtnReader& r = **reader;
  auto fail = [&](const Status& st) {
    damage.flush(st);
    return reportError(st);
  };
  if (a.level >= r.levels())
    return fail(usageError(a.input + ": --level " + std::to_string(a.level) + ": the file holds " +
                           std::to_string(r.levels()) + " level(s), 0 to " + std::to_string(r.levels() - 1)));
  DecodeFields fields;  // every field unless --fields names some
  if (!a.fields.empty()) {
    auto selected = selectDecodeFields(r.level(a.level).header, a.fields, a.input, "--fields");
    if (!selected.isOk()) return fail(selected.status());
    fields = std::move(selected).value();
  }
  TetMeshBuilder builder;
  // On a terminal, the share of the level decoded, then the write.
  ProgressLine progress("gtn export", true);
  ProgressMeshSink shown(builder, progress.callback(), "decode");
  MeshSink& sink = progress.active() ? static_cast<MeshSink&>(shown) : builder;
  Status st;
  if (a.ratio >= 0 || a.merges >= 0) {
    StatusOr<uint64_t> target = uint64_t{0};
    if (a.merges >= 0) target = static_cast<uint64_t>(a.merges);
    else target = mergesForRatio(r, a.ratio);
    st = target.status();
    if (st.isOk()) st = streamSimplified(r, *target, sink, nullptr, /*clamp=*/a.merges < 0, &fields);
  } else {
    st = r.decodeLevel(a.level, sink, nullptr, &fields);
  }
  if (!st.isOk()) return fail(st);
  damage.flush();
  if (!a.fields.empty()) dropUndecodedFields(builder.mesh(), fields);
  progress.update("write " + a.output);
  ExportOptions eo;
  eo.compress = a.compress;
  st = exportMesh(builder.mesh(), a.output, eo);
  if (!st.isOk()) return reportError(st);
  return 0;
}
}  // namespace

Command addExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export", "Decode a level of a .gtn file and write it as .vtu, .vtk or TetGen .node/.ele");
  sub->add_option("input", args->input, "Input .gtn file ('-' for standard input)")->required();
  sub->add_option("-o,--output", args->output, "Output file: .vtu (VTK XML), .vtk (legacy VTK) or .node/.ele (TetGen)")->required();
  CLI::Option* level = sub->add_option("--level", args->level, "Stored level to decode (0 = the lossless mesh)");
  CLI::Option* ratio = sub->add_option("--ratio", args->ratio,
                                       "Simplification ratio: vertices merged away / vertices of level 0 (0 to 1)")
                           ->check(CLI::Range(0.0, 1.0));
  CLI::Option* merges = sub->add_option("--merges", args->merges, "Number of merges of the merge tree to apply")
                            ->check(finiteAtLeastZero());
  level->excludes(ratio)->excludes(merges);
  ratio->excludes(merges);
  sub->add_flag("--compress", args->compress, ".vtu: zlib-compress the data arrays");
  sub->add_option("--fields", args->fields,
                  "Export only these point or cell fields (names, comma-separated); the others are not decoded")
      ->delimiter(',');
  return {sub, [args] { return runExport(*args); }};
}

}  // namespace gtn::cli
