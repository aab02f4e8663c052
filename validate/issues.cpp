#include "validate/issues.h"

#include <array>

namespace gtn {

namespace {
constexpr IssueInfo kIssues[] = {
#define GTN_ISSUE_ROW(name, code, severity, layer, description) \
  {IssueCode::name, code, Severity::severity, layer, description},
    GTN_VALIDATION_ISSUES(GTN_ISSUE_ROW)
#undef GTN_ISSUE_ROW
};
}  // namespace

const char* severityName(Severity severity) {
  switch (severity) {
    case Severity::kError: return "error";
    case Severity::kWarning: return "warning";
    case Severity::kInfo: return "info";
  }
  return "?";
}

const IssueInfo& issueInfo(IssueCode code) { return kIssues[static_cast<size_t>(code)]; }

std::span<const IssueInfo> allIssues() { return kIssues; }

std::optional<IssueCode> issueFromName(const std::string& name) {
  for (const IssueInfo& info : kIssues) {
    if (name == info.code) return info.id;
  }
  return std::nullopt;
}

std::string issueListText(bool markdown) {
  std::string out;
  if (markdown) {
    out +=
        "# Validation issues\n\n"
        "Generated from the registry in `validate/issues.h` by `gtn validate --list-issues --markdown`;\n"
        "do not edit by hand (a test checks that this page equals the generated text).\n\n"
        "Every check of `gtn validate` reports one of these stable codes. Severity `error` makes the file\n"
        "invalid (exit code 1); `warning` and `info` are reported but keep the file valid.\n\n"
        "Zero-volume tetrahedra: a level may contain zero-volume tetrahedra only when the source had them\n"
        "(PLOT3D grids with collapsed cells do). A merge that turns a tetrahedron of positive volume into a\n"
        "flat one is the error `MERGE_FLATTENS_TET`, and every stored level must equal level 0 after its\n"
        "merges (`LEVEL_MISMATCH`), so a mip level holds no zero-volume tetrahedra beyond those inherited\n"
        "from level 0. Zero-volume tetrahedra are `ZERO_VOLUME_TET` warnings, except where the validator\n"
        "can tell that the source had them: in a mip level whose merge-tree replay found no error, and in\n"
        "level 0 when `--against` finds it equal to the source. There they are the info\n"
        "`ZERO_VOLUME_TET_FROM_SOURCE`.\n";
    const char* layer = "";
    for (const IssueInfo& info : kIssues) {
      if (std::string(layer) != info.layer) {
        layer = info.layer;
        out += std::string("\n## ") + layer + "\n\n| code | severity | what it reports |\n|---|---|---|\n";
      }
      out += std::string("| `") + info.code + "` | " + severityName(info.severity) + " | " + info.description + " |\n";
    }
  } else {
    for (const IssueInfo& info : kIssues) {
      std::string line = info.code;
      line.resize(32, ' ');
      std::string sev = severityName(info.severity);
      sev.resize(8, ' ');
      out += line + " " + sev + " " + info.layer + ": " + info.description + "\n";
    }
  }
  return out;
}

}  // namespace gtn
