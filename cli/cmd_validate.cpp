// gtn validate FILE [--against SOURCE...] [--json] [--quick] [--max-issues N]: the reference validator.
// gtn validate MESHFILE... [--split 5|6] [--weld] [--time-step N] [--json] [--max-issues N]: the same report for a mesh
// that `gtn convert` reads (what the importer changed, then the mesh checks).
// gtn validate --list-issues [--markdown]: every issue code it can report.
// Exit codes: 0 no error, 1 an error was found, 2 usage, 3 the file cannot be read.
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "convert/import.h"
#include "validate/issues.h"
#include "validate/validator.h"

namespace gtn::cli {

namespace {
struct ValidateArgs {
  std::vector<std::string> files;
  std::vector<std::string> against;
  int split = 6;
  bool weld = false;
  bool split_given = false;  // --split on the command line (otherwise --against takes the file's)
  int time_step = 0;
  bool json = false;
  bool quick = false;
  size_t max_issues = 100;
  bool list_issues = false;
  bool markdown = false;
};

int runValidate(const ValidateArgs& a) {
  if (a.list_issues) {
    std::fputs(issueListText(a.markdown).c_str(), stdout);
    return 0;
  }
  if (a.files.empty()) return reportError(usageError("validate: a FILE to validate is required"));
  if (a.quick && !a.against.empty())
    return reportError(usageError("validate: --quick and --against exclude each other"));
  ValidateOptions options;
  options.quick = a.quick;
  options.max_issues = a.max_issues;
  options.against = a.against;
  options.import_options.split = a.split;
  options.import_options.weld = a.weld;
  options.split_from_file = !a.split_given;
  options.weld_from_file = !a.weld;
  options.import_options.exodus_time_step = a.time_step;
  // A .gtn file (or a file no importer knows, which the container checks then describe), else mesh files.
  const InputFormat format = detectInputFormat(a.files.front());
  const bool gtn = format == InputFormat::kGtn || format == InputFormat::kUnknown;
  if (gtn && a.files.size() > 1)
    return reportError(usageError("validate: one .gtn file at a time (" + std::to_string(a.files.size()) + " given)"));
  if (!gtn && (a.quick || !a.against.empty()))
    return reportError(usageError("validate: " + a.files.front() +
                                  ": --quick and --against apply to .gtn files, not to a " + inputFormatName(format) +
                                  " file"));
  StatusOr<ValidationReport> report =
      gtn ? validateGtnFile(a.files.front(), options) : validateMeshFiles(a.files, options);
  if (!report.isOk()) return reportError(report.status());
  std::string name = a.files.front();
  for (size_t i = 1; i < a.files.size(); ++i) name += " + " + a.files[i];
  if (a.json) {
    std::printf("%s\n", jsonText(report->toJson(name)).c_str());
  } else {
    std::fputs(report->toText(name).c_str(), stdout);
  }
  return report->hasErrors() ? 1 : 0;
}
}  // namespace

Command addValidateCommand(CLI::App& app) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* sub = app.add_subcommand(
      "validate",
      "Check a .gtn file (container, decoding, mesh, merge tree, levels) or the mesh that mesh files describe");
  sub->add_option("files", args->files,
                  "The .gtn file to check, or mesh files as 'gtn convert' takes them (PLOT3D grid [Q], TetGen, VTK, "
                  "Medit, OFF, gmsh, Exodus II)");
  sub->add_option("--against", args->against, "Source file(s) that level 0 must equal (up to renumbering)");
  CLI::Option* split =
      sub->add_option("--split", args->split,
                      "mesh files and --against: hexahedra into 5 or 6 tetrahedra (--against: default as the "
                      ".gtn file records it, else 6)")
          ->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld,
                "mesh files and --against: merge bit-identical points (seams between PLOT3D blocks or VTK pieces); "
                "--against: also when the .gtn file records it");
  sub->add_option("--time-step", args->time_step,
                  "Exodus II: the time step (1, 2, ...) whose variables become fields (default: the last)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--json", args->json, "Print the report as one JSON document on standard output");
  sub->add_flag("--quick", args->quick, "Check the container and checksums only");
  sub->add_option("--max-issues", args->max_issues, "Keep at most N messages (counts stay exact)")
      ->check(CLI::Range(size_t{1}, size_t{1000000}));
  sub->add_flag("--list-issues", args->list_issues, "List every issue code the validator can report");
  sub->add_flag("--markdown", args->markdown, "--list-issues: as the Markdown page docs/validation-issues.md");
  return {sub, [args, split] {
            args->split_given = split->count() > 0;
            return runValidate(*args);
          }};
}

}  // namespace gtn::cli
