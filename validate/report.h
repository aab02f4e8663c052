// ValidationReport: what `gtn validate` found, aggregated by issue code and scope, rendered as text or
// as the JSON document of `gtn validate --json`.
//
// Repeated defects of one kind within one scope (say 412 inverted tetrahedra of /levels/0) become one
// message with a count ("412 inverted tetrahedra out of 187395") and the logical paths of the first
// few occurrences. Severity counts are counts of occurrences and stay exact when the message list is
// truncated by max_issues.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "validate/issues.h"

namespace gtn {

struct ReportedIssue {
  IssueCode code;
  std::string scope;               // the logical path that groups occurrences (e.g. "/levels/0")
  std::string detail;              // what the first occurrence says beyond the registry's description
  uint64_t count = 0;              // occurrences
  uint64_t total = 0;              // "out of" this many items checked; 0 when not meaningful
  std::vector<std::string> paths;  // logical paths of the first occurrences (at most kMaxPaths)
  std::optional<uint64_t> offset;  // byte offset in the file of the first occurrence, where known

  // The human message: the detail for a single occurrence, "<count> <description> out of <total>"
  // plus the first detail for aggregated ones.
  std::string message() const;
};

class ValidationReport {
 public:
  static constexpr size_t kMaxPaths = 5;

  explicit ValidationReport(size_t max_issues = 100) : max_issues_(max_issues) {}

  // Records one occurrence of `code` at logical `path`, grouped with the other occurrences of the same
  // code within `scope`. `detail` is kept for the first occurrence only.
  void add(IssueCode code, const std::string& scope, const std::string& path, const std::string& detail = "",
           std::optional<uint64_t> offset = std::nullopt);
  // Records `count` occurrences at once (first paths given) for checks that count before they locate.
  void addMany(IssueCode code, const std::string& scope, uint64_t count, const std::vector<std::string>& paths,
               const std::string& detail = "");
  // Moves the occurrences of `from` within `scope` to code `to` (counts, paths and totals follow), for a
  // finding that a later check explains; nothing happens when there are none.
  void reclassify(IssueCode from, IssueCode to, const std::string& scope);
  // Sets the number of items the check of `code` examined within `scope` ("out of N"); applies to an
  // aggregated message whether it is recorded before or after.
  void setTotal(IssueCode code, const std::string& scope, uint64_t total);

  // The messages shown: errors first, then warnings, then infos, each in order of first appearance, at
  // most max_issues of them (an info found early never displaces an error found later).
  std::vector<ReportedIssue> issues() const;
  uint64_t count(Severity severity) const { return counts_[static_cast<int>(severity)]; }
  uint64_t count(IssueCode code) const;
  bool hasErrors() const { return count(Severity::kError) > 0; }
  // True when some messages were dropped because of max_issues (the counts still include them).
  bool truncated() const { return truncated_ || issues_.size() > max_issues_; }
  // Codes of the messages with severity error, in order of first appearance, without repeats.
  std::vector<std::string> errorCodes() const;

  // Free-form statistics (the `info` block of the JSON report).
  nlohmann::json& info() { return info_; }
  const nlohmann::json& info() const { return info_; }

  std::string toText(const std::string& file) const;
  nlohmann::json toJson(const std::string& file) const;

 private:
  ReportedIssue* find(IssueCode code, const std::string& scope, bool create);

  // Aggregated messages kept before sorting and truncation: one per code and scope, so a real file has
  // a few dozen; the cap bounds what a hostile file with many scopes can make the report hold.
  static constexpr size_t kMaxKept = 4096;

  size_t max_issues_;
  std::vector<ReportedIssue> issues_;
  std::map<std::pair<uint16_t, std::string>, size_t> index_;
  std::map<std::pair<uint16_t, std::string>, uint64_t> pending_totals_;
  std::map<IssueCode, uint64_t> per_code_;
  uint64_t counts_[3] = {0, 0, 0};
  bool truncated_ = false;
  nlohmann::json info_ = nlohmann::json::object();
};

}  // namespace gtn
