// gtn export FILE.gtn -o OUTPUT [--level I]: decode a stored level and write it as .vtu or TetGen.
#include <memory>

#include "cli/commands.h"
#include "convert/export.h"
#include "format/gtn_reader.h"

namespace gtn::cli {

namespace {
struct ExportArgs {
  std::string input;
  std::string output;
  size_t level = 0;
  bool compress = false;
};

int runExport(const ExportArgs& a) {
  const OutputFormat out_format = detectOutputFormat(a.output);
  if (out_format != OutputFormat::kVtu && out_format != OutputFormat::kTetgen)
    return reportError(usageError(a.output + ": unknown output format for export (use .vtu, .node or .ele)"));
  if (a.input == a.output) return reportError(usageError(a.output + ": the output would overwrite the input"));
  GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  auto reader = GtnReader::open(a.input, oo);
  if (!reader.isOk()) return reportError(reader.status());
  GtnReader& r = **reader;
  if (a.level >= r.levels())
    return reportError(usageError(a.input + ": --level " + std::to_string(a.level) + ": the file holds " +
                                  std::to_string(r.levels()) + " level(s), 0 to " + std::to_string(r.levels() - 1)));
  TetMeshBuilder builder;
  Status st = r.decodeLevel(a.level, builder);
  if (!st.isOk()) return reportError(st);
  if (out_format == OutputFormat::kVtu) {
    ExportOptions eo;
    eo.compress = a.compress;
    st = exportVtu(builder.mesh(), a.output, eo);
  } else {
    st = exportTetgen(builder.mesh(), a.output);
  }
  if (!st.isOk()) return reportError(st);
  return 0;
}
}  // namespace

Command addExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export", "Decode a level of a .gtn file and write it as .vtu or TetGen .node/.ele");
  sub->add_option("input", args->input, "Input .gtn file ('-' for standard input)")->required();
  sub->add_option("-o,--output", args->output, "Output file: .vtu, or .node/.ele (TetGen)")->required();
  sub->add_option("--level", args->level, "Stored level to decode (0 = the lossless mesh)");
  sub->add_flag("--compress", args->compress, ".vtu: zlib-compress the data arrays");
  return {sub, [args] { return runExport(*args); }};
}

}  // namespace gtn::cli
