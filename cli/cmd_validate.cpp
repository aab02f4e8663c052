// gtn validate FILE [--against SOURCE...] [--json] [--quick] [--max-issues N]: the reference validator.
// gtn validate --list-issues [--markdown]: every issue code it can report.
// Exit codes: 0 no error, 1 an error was found, 2 usage, 3 the file cannot be read.
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "validate/issues.h"
#include "validate/validator.h"

namespace gtn::cli {

namespace {
struct ValidateArgs {
  std::string file;
  std::vector<std::string> against;
  int split = 6;
  bool weld = false;
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
  if (a.file.empty()) return reportError(usageError("validate: a FILE to validate is required"));
  if (a.quick && !a.against.empty()) return reportError(usageError("validate: --quick and --against exclude each other"));
  ValidateOptions options;
  options.quick = a.quick;
  options.max_issues = a.max_issues;
  options.against = a.against;
  options.import_options.split = a.split;
  options.import_options.weld = a.weld;
  StatusOr<ValidationReport> report = validateGtnFile(a.file, options);
  if (!report.isOk()) return reportError(report.status());
  if (a.json) {
    std::printf("%s\n", jsonText(report->toJson(a.file)).c_str());
  } else {
    std::fputs(report->toText(a.file).c_str(), stdout);
  }
  return report->hasErrors() ? 1 : 0;
}
}  // namespace

Command addValidateCommand(CLI::App& app) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* sub = app.add_subcommand("validate", "Check a .gtn file: container, decoding, mesh, merge tree, levels");
  sub->add_option("file", args->file, "The .gtn file to check");
  sub->add_option("--against", args->against, "Source file(s) that level 0 must equal (up to renumbering)");
  sub->add_option("--split", args->split, "--against: hexahedra into 5 or 6 tetrahedra")->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld, "--against: merge bit-identical points (seams between PLOT3D blocks or VTK pieces)");
  sub->add_flag("--json", args->json, "Print the report as one JSON document on standard output");
  sub->add_flag("--quick", args->quick, "Check the container and checksums only");
  sub->add_option("--max-issues", args->max_issues, "Keep at most N messages (counts stay exact)")
      ->check(CLI::Range(size_t{1}, size_t{1000000}));
  sub->add_flag("--list-issues", args->list_issues, "List every issue code the validator can report");
  sub->add_flag("--markdown", args->markdown, "--list-issues: as the Markdown page docs/validation-issues.md");
  return {sub, [args] { return runValidate(*args); }};
}

}  // namespace gtn::cli
