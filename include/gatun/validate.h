// <gatun/validate.h>: the reference validator of `gtn validate`.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gatun/convert.h"
#include "gatun/result.h"

namespace gatun {

/*-************************************
 *  Validating
 **************************************/

/*! Severity : of an issue; a file with an error is invalid. */
enum class Severity { kError = 0, kWarning = 1, kInfo = 2 };

/*! Issue : one message of a validation report: the occurrences of one issue code within one scope.
 *  `code` is the stable name (`gtn validate --list-issues` lists them), `scope` the logical path
 *  that groups the occurrences ("/levels/0"), `message` the text `gtn validate` prints. */
struct Issue {
  std::string code;
  Severity severity = Severity::kError;
  std::string scope;
  std::string message;
  uint64_t count = 0; /* occurrences */
};

/*! ValidationReport : what the validator found. `issues` are errors first, then warnings, then infos,
 *  at most ValidateOptions::max_issues of them (`truncated` then); the counts are exact. `text` and
 *  `json` are the reports of `gtn validate` and `gtn validate --json`. */
struct ValidationReport {
  std::vector<Issue> issues;
  uint64_t errors = 0, warnings = 0, infos = 0;
  bool truncated = false;
  std::string text;
  std::string json;

  /*! ok() : no error (`gtn validate` exits with 0). */
  bool ok() const { return errors == 0; }
};

/*! ValidateOptions : the options of `gtn validate`.
 *  `quick`: a .gtn file's container and checksums only.
 *  `max_issues`: messages kept in the report (counts stay exact).
 *  `against`: source files of a .gtn file; its level 0 must equal the imported source (bit-exact, up
 *     to renumbering). They are imported with `import`, or with the split and weld the .gtn file
 *     records when `import` is left at its defaults. */
struct ValidateOptions {
  bool quick = false;
  size_t max_issues = 100;
  std::vector<std::string> against{};
  ImportOptions import{};
};

/*! validate() : `gtn validate FILES...`: one .gtn file (container, decoding, mesh, merge tree, levels,
 *  and `against`), or mesh files as importMesh() takes them (what the import changed, then the mesh
 *  checks). Problems of the data are issues of the report, not errors: check report.ok().
 *  Errors: kUsage (no file, several .gtn files, quick or against with mesh files), kIo (a file cannot
 *  be read). */
Result<ValidationReport> validate(const std::vector<std::string>& files, const ValidateOptions& options = {});

}  // namespace gatun
