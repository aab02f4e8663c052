// Validating (include/gatun/validate.h): the reference validator as `gtn validate` runs it.
#include <utility>

#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "gatun/validate.h"
#include "internal.h"
#include "validate/issues.h"
#include "validate/validator.h"

namespace gatun {

Result<ValidationReport> validate(const std::vector<std::string>& files, const ValidateOptions& options) {
  if (files.empty()) return Error(ErrorCode::kUsage, "validate: a FILE to validate is required");
  if (options.quick && !options.against.empty())
    return Error(ErrorCode::kUsage, "validate: quick and against exclude each other");
  gtn::ValidateOptions o;
  o.quick = options.quick;
  o.max_issues = options.max_issues;
  o.against = options.against;
  o.import_options = gtn::api::toImportOptions(options.import);
  // As the command without --split and --weld: the source's split and weld as the .gtn file records them.
  o.split_from_file = options.import.split == ImportOptions{}.split;
  o.weld_from_file = !options.import.weld;
  // A .gtn file (or a file no importer knows, which the container checks then describe), else mesh files.
  const gtn::InputFormat format = gtn::detectInputFormat(files.front());
  const bool gtn_file = format == gtn::InputFormat::kGtn || format == gtn::InputFormat::kUnknown;
  if (gtn_file && files.size() > 1)
    return Error(ErrorCode::kUsage, "validate: one .gtn file at a time (" + std::to_string(files.size()) + " given)");
  if (!gtn_file && (options.quick || !options.against.empty()))
    return Error(ErrorCode::kUsage, "validate: " + files.front() +
                                        ": quick and against apply to .gtn files, not to a " +
                                        gtn::inputFormatName(format) + " file");
  auto checked = gtn_file ? gtn::validateGtnFile(files.front(), o) : gtn::validateMeshFiles(files, o);
  if (!checked.isOk()) return gtn::api::toError(checked.status());
  const gtn::ValidationReport& r = checked.value();
  std::string name = files.front();
  for (size_t i = 1; i < files.size(); ++i) name += " + " + files[i];
  ValidationReport report;
  for (const gtn::ReportedIssue& issue : r.issues()) {
    const gtn::IssueInfo& info = gtn::issueInfo(issue.code);
    Issue out;
    out.code = info.code;
    out.severity = static_cast<Severity>(info.severity);
    out.scope = issue.scope;
    out.message = issue.message();
    out.count = issue.count;
    report.issues.push_back(std::move(out));
  }
  report.errors = r.count(gtn::Severity::kError);
  report.warnings = r.count(gtn::Severity::kWarning);
  report.infos = r.count(gtn::Severity::kInfo);
  report.truncated = r.truncated();
  report.text = r.toText(name);
  report.json = r.toJson(name).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  return report;
}

}  // namespace gatun
