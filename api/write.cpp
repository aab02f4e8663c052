// Writing and converting (include/gatun/write.h, include/gatun/convert.h): the path `gtn convert` and
// the Python package's gatun.write take, through validate/write_gtn.h.
#include <filesystem>
#include <utility>

#include "codec/pieces.h"
#include "convert/export.h"
#include "convert/import.h"
#include "format/file_io.h"
#include "format/gtn_file.h"
#include "gatun/convert.h"
#include "gatun/write.h"
#include "internal.h"
#include "validate/write_gtn.h"

namespace gatun {

namespace {
// Writes an imported mesh (orientation normalised) as `gtn convert` does; `source` names it in messages.
Error writeImported(const std::string& path, const gtn::TetMesh& mesh, const WriteOptions& options,
                    const std::string& source, const std::string& default_command_line,
                    std::vector<std::string>* warnings) {
  if (options.piece_tets < gtn::kMinPieceTets)
    return Error(ErrorCode::kUsage, source + ": piece_tets " + std::to_string(options.piece_tets) +
                                        " is below the smallest piece, " + std::to_string(gtn::kMinPieceTets) +
                                        " tetrahedra");
  gtn::GtnConvertOptions o;
  o.levels = options.levels;
  o.merge_tree = options.merge_tree;
  o.level_storage = options.level_storage;
  o.keep_invalid = options.keep_invalid;
  o.ranking.field = options.simplify_field;
  o.ranking.w_density = options.w_density;
  o.ranking.w_geometry = options.w_geometry;
  if (options.greedy_ranking) {
    o.ranking.lazy = false;
    o.ranking.parts = 1;
  }
  gtn::GtnWriteOptions wo;
  wo.tool_version = GTN_VERSION_STRING;
  wo.command_line = options.command_line.empty() ? default_command_line : options.command_line;
  wo.verify = options.verify;
  wo.piece_tets = options.piece_tets;
  wo.chain_levels = !options.independent_levels;
  return gtn::api::toError(gtn::writeGtnWithLevels(path, mesh, o, wo, source, warnings));
}

// The provenance of an API call: the file name only, as `gtn convert` stores no directories.
std::string callName(const char* function, const std::string& path) {
  return std::string(function) + "(" + std::filesystem::path(path).filename().string() + ")";
}
}  // namespace

Error write(const std::string& path, const Mesh& mesh, const WriteOptions& options,
            std::vector<std::string>* warnings) {
  const std::string source = "gatun::write(" + path + ")";
  gtn::ImportResult imported{gtn::api::toTetMesh(mesh), {}};
  if (gtn::Status st = imported.mesh.checkConsistency(source); !st.isOk())
    return Error(ErrorCode::kUsage, st.message());
  // What an importer does last (orientation by exact predicates), as `gtn convert` has it done.
  gtn::finishImport(imported);
  std::vector<std::string> said;
  gtn::api::appendImportWarnings(source, imported.report, &said);
  Error error = writeImported(path, imported.mesh, options, source, callName("gatun::write", path), &said);
  if (warnings) warnings->insert(warnings->end(), said.begin(), said.end());
  return error;
}

Result<Mesh> importMesh(const std::vector<std::string>& inputs, const ImportOptions& options,
                        std::vector<std::string>* warnings) {
  if (inputs.empty()) return Error(ErrorCode::kUsage, "gatun::importMesh: no input file");
  auto imported = gtn::importMesh(inputs, gtn::api::toImportOptions(options));
  if (!imported.isOk()) return gtn::api::toError(imported.status());
  gtn::api::appendImportWarnings(inputs[0], imported->report, warnings);
  return gtn::api::fromTetMesh(std::move(imported->mesh));
}

Error convert(const std::vector<std::string>& inputs, const std::string& output, const ConvertOptions& options,
              std::vector<std::string>* warnings) {
  if (inputs.empty()) return Error(ErrorCode::kUsage, "gatun::convert: no input file");
  const gtn::OutputFormat format = gtn::detectOutputFormat(output);
  if (format == gtn::OutputFormat::kUnknown)
    return Error(ErrorCode::kUsage, output + ": unknown output format (use .gtn, .vtu, .vtk, .node or .ele)");
  for (const std::string& in : inputs)
    if (in == output || gtn::sameFile(in, output))
      return Error(ErrorCode::kUsage, output + ": the output would overwrite an input");
  auto imported = gtn::importMesh(inputs, gtn::api::toImportOptions(options.import));
  if (!imported.isOk()) return gtn::api::toError(imported.status());
  gtn::api::appendImportWarnings(inputs[0], imported->report, warnings);
  if (format != gtn::OutputFormat::kGtn) {
    gtn::ExportOptions eo;
    eo.compress = options.compress;
    return gtn::api::toError(gtn::exportMesh(imported->mesh, output, eo));
  }
  Error error =
      writeImported(output, imported->mesh, options.write, inputs[0], callName("gatun::convert", output), warnings);
  // The encoder's refusals are about the mesh: say where to see the details.
  if (!error.ok() && error.message().rfind(inputs[0] + ": cannot be encoded: ", 0) == 0)
    return Error(error.code(), error.message() + " (gatun::validate of " + inputs[0] + " lists the problems)");
  return error;
}

}  // namespace gatun
