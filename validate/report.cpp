#include "validate/report.h"

#include <algorithm>

namespace gtn {

std::string ReportedIssue::message() const {
  const IssueInfo& info = issueInfo(code);
  if (count <= 1 && total == 0) return detail.empty() ? std::string(info.description) : detail;
  std::string m = std::to_string(count) + " " + info.description;
  if (total > 0) m += " out of " + std::to_string(total);
  if (!scope.empty()) m += " in " + scope;
  if (!detail.empty()) m += (count == 1 ? ": " : "; first: ") + detail;
  return m;
}

ReportedIssue* ValidationReport::find(IssueCode code, const std::string& scope, bool create) {
  const auto key = std::make_pair(static_cast<uint16_t>(code), scope);
  auto it = index_.find(key);
  if (it != index_.end()) return &issues_[it->second];
  if (!create) return nullptr;
  if (issues_.size() >= kMaxKept) {
    truncated_ = true;
    return nullptr;
  }
  ReportedIssue issue;
  issue.code = code;
  issue.scope = scope;
  auto pending = pending_totals_.find(key);
  if (pending != pending_totals_.end()) issue.total = pending->second;
  index_.emplace(key, issues_.size());
  issues_.push_back(std::move(issue));
  return &issues_.back();
}

void ValidationReport::add(IssueCode code, const std::string& scope, const std::string& path, const std::string& detail,
                           std::optional<uint64_t> offset) {
  ++counts_[static_cast<int>(issueInfo(code).severity)];
  ++per_code_[code];
  ReportedIssue* issue = find(code, scope, true);
  if (!issue) return;
  if (issue->count == 0) {
    issue->detail = detail;
    issue->offset = offset;
  }
  ++issue->count;
  if (issue->paths.size() < kMaxPaths && !path.empty()) issue->paths.push_back(path);
}

void ValidationReport::addMany(IssueCode code, const std::string& scope, uint64_t count,
                               const std::vector<std::string>& paths, const std::string& detail) {
  if (count == 0) return;
  counts_[static_cast<int>(issueInfo(code).severity)] += count;
  per_code_[code] += count;
  ReportedIssue* issue = find(code, scope, true);
  if (!issue) return;
  if (issue->count == 0) issue->detail = detail;
  issue->count += count;
  for (const std::string& p : paths) {
    if (issue->paths.size() >= kMaxPaths) break;
    issue->paths.push_back(p);
  }
}

void ValidationReport::setTotal(IssueCode code, const std::string& scope, uint64_t total) {
  const auto key = std::make_pair(static_cast<uint16_t>(code), scope);
  pending_totals_[key] = total;
  if (ReportedIssue* issue = find(code, scope, false)) issue->total = total;
}

void ValidationReport::reclassify(IssueCode from, IssueCode to, const std::string& scope) {
  const auto from_key = std::make_pair(static_cast<uint16_t>(from), scope);
  const auto to_key = std::make_pair(static_cast<uint16_t>(to), scope);
  auto it = index_.find(from_key);
  if (it == index_.end() || index_.count(to_key)) return;
  ReportedIssue& issue = issues_[it->second];
  counts_[static_cast<int>(issueInfo(from).severity)] -= issue.count;
  counts_[static_cast<int>(issueInfo(to).severity)] += issue.count;
  per_code_[from] -= issue.count;
  per_code_[to] += issue.count;
  issue.code = to;
  index_.emplace(to_key, it->second);
  index_.erase(it);
  auto total = pending_totals_.find(from_key);
  if (total != pending_totals_.end()) pending_totals_[to_key] = total->second;
}

uint64_t ValidationReport::count(IssueCode code) const {
  auto it = per_code_.find(code);
  return it == per_code_.end() ? 0 : it->second;
}

std::vector<std::string> ValidationReport::errorCodes() const {
  std::vector<std::string> out;
  for (const auto& [code, n] : per_code_) {
    if (n > 0 && issueInfo(code).severity == Severity::kError) out.push_back(issueInfo(code).code);
  }
  return out;
}

std::vector<ReportedIssue> ValidationReport::issues() const {
  std::vector<ReportedIssue> shown = issues_;
  std::stable_sort(shown.begin(), shown.end(), [](const ReportedIssue& a, const ReportedIssue& b) {
    return issueInfo(a.code).severity < issueInfo(b.code).severity;
  });
  if (shown.size() > max_issues_) shown.resize(max_issues_);
  return shown;
}

std::string ValidationReport::toText(const std::string& file) const {
  std::string out;
  for (const ReportedIssue& issue : issues()) {
    const IssueInfo& info = issueInfo(issue.code);
    out += std::string(severityName(info.severity)) + ": " + info.code + ": " + issue.message();
    if (!issue.paths.empty()) {
      out += " [";
      for (size_t i = 0; i < issue.paths.size(); ++i) out += (i ? ", " : "") + issue.paths[i];
      if (issue.count > issue.paths.size()) out += ", ...";
      out += "]";
    }
    if (issue.offset) out += " (byte " + std::to_string(*issue.offset) + ")";
    out += "\n";
  }
  if (truncated()) out += "(more messages left out: --max-issues)\n";
  // One finding per line above, each with its count: the summary counts those lines, and the items
  // (cells, faces, points...) they cover where that is more.
  auto summary = [&](Severity severity, const char* one, const char* many) {
    uint64_t lines = 0;
    for (const ReportedIssue& issue : issues_)
      if (issueInfo(issue.code).severity == severity) ++lines;
    const uint64_t items = count(severity);
    std::string t = std::to_string(lines) + " " + (lines == 1 ? one : many);
    if (items != lines) t += " (" + std::to_string(items) + " items)";
    return t;
  };
  out += file + ": " + (hasErrors() ? "INVALID" : "valid") + " (" + summary(Severity::kError, "error", "errors") +
         ", " + summary(Severity::kWarning, "warning", "warnings") + ", " + summary(Severity::kInfo, "info", "infos") +
         ")\n";
  return out;
}

nlohmann::json ValidationReport::toJson(const std::string& file) const {
  nlohmann::json j;
  j["file"] = file;
  j["valid"] = !hasErrors();
  j["counts"] = {
      {"error", count(Severity::kError)}, {"warning", count(Severity::kWarning)}, {"info", count(Severity::kInfo)}};
  j["truncated"] = truncated();
  nlohmann::json messages = nlohmann::json::array();
  for (const ReportedIssue& issue : issues()) {
    const IssueInfo& info = issueInfo(issue.code);
    nlohmann::json m;
    m["code"] = info.code;
    m["severity"] = severityName(info.severity);
    m["message"] = issue.message();
    m["count"] = issue.count;
    if (issue.total) m["total"] = issue.total;
    m["path"] = issue.paths.empty() ? issue.scope : issue.paths.front();
    m["paths"] = issue.paths;
    if (issue.offset) m["offset"] = *issue.offset;
    messages.push_back(std::move(m));
  }
  j["messages"] = std::move(messages);
  j["info"] = info_;
  return j;
}

}  // namespace gtn
