// The issue registry and the report: stable codes, the generated documentation, aggregation, limits
// and the JSON schema.
#include <gtest/gtest.h>

#include <cctype>
#include <set>

#include <nlohmann/json.hpp>

#include "test_util.h"
#include "validate/issues.h"
#include "validate/report.h"

namespace gtn::test {
namespace {

TEST(IssueRegistry, CodesAreUniqueScreamingCaseAndIndexed) {
  std::set<std::string> seen;
  size_t i = 0;
  for (const IssueInfo& info : allIssues()) {
    EXPECT_EQ(static_cast<size_t>(info.id), i++);
    const std::string code = info.code;
    EXPECT_TRUE(seen.insert(code).second) << code;
    for (char ch : code) EXPECT_TRUE(std::isupper(static_cast<unsigned char>(ch)) || ch == '_') << code;
    EXPECT_FALSE(std::string(info.description).empty());
    EXPECT_EQ(issueFromName(code), info.id);
  }
  EXPECT_GE(seen.size(), 40u);
  EXPECT_FALSE(issueFromName("NO_SUCH_CODE").has_value());
}

TEST(IssueRegistry, DocsPageEqualsGeneratedText) {
  const std::string doc = readFile(std::string(GTN_SOURCE_DIR) + "/docs/validation-issues.md");
  EXPECT_EQ(doc, issueListText(true))
      << "regenerate with: gtn validate --list-issues --markdown > docs/validation-issues.md";
  const RunResult r = runGtn("validate --list-issues --markdown");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, doc);
  for (const IssueInfo& info : allIssues()) EXPECT_NE(doc.find(std::string("`") + info.code + "`"), std::string::npos);
}

TEST(Report, AggregatesCountsTruncatesAndSerialises) {
  ValidationReport r(2);
  for (int t = 0; t < 412; ++t) r.add(IssueCode::kInvertedTet, "/levels/0", "/levels/0/tets/" + std::to_string(t));
  r.setTotal(IssueCode::kInvertedTet, "/levels/0", 187395);
  r.add(IssueCode::kZeroVolumeTet, "/levels/0", "/levels/0/tets/9");
  r.add(IssueCode::kUnreferencedPoint, "/levels/0", "/levels/0/points/3");  // beyond max_issues
  ASSERT_EQ(r.issues().size(), 2u);
  EXPECT_TRUE(r.truncated());
  EXPECT_EQ(r.count(Severity::kError), 412u);
  EXPECT_EQ(r.count(Severity::kWarning), 1u);
  EXPECT_EQ(r.count(Severity::kInfo), 1u);
  EXPECT_EQ(r.issues()[0].message(),
            "412 inverted tetrahedra (negative volume, exact predicate) out of 187395 in /levels/0");
  EXPECT_EQ(r.issues()[0].paths.size(), ValidationReport::kMaxPaths);

  const nlohmann::json j = r.toJson("f.gtn");
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_TRUE(j["truncated"].get<bool>());
  EXPECT_EQ(j["counts"]["error"].get<int>(), 412);
  EXPECT_EQ(j["messages"][0]["code"], "INVERTED_TET");
  EXPECT_EQ(j["messages"][0]["severity"], "error");
  EXPECT_EQ(j["messages"][0]["count"].get<int>(), 412);
  EXPECT_EQ(j["messages"][0]["total"].get<int>(), 187395);
  EXPECT_EQ(j["messages"][0]["path"], "/levels/0/tets/0");
  EXPECT_EQ(j["messages"][1]["severity"], "warning");
  EXPECT_TRUE(j["info"].is_object());
  const std::string text = r.toText("f.gtn");
  EXPECT_NE(text.find("error: INVERTED_TET: 412 inverted"), std::string::npos) << text;
  // The summary counts the lines, one per kind of finding, and the items they cover.
  EXPECT_NE(text.find("f.gtn: INVALID (1 error (412 items), 1 warning, 1 info)"), std::string::npos) << text;
  EXPECT_EQ(r.errorCodes(), std::vector<std::string>{"INVERTED_TET"});

  ValidationReport single(10);
  single.add(IssueCode::kChecksumMismatch, "/container", "/container", "chunk 'GEOM' checksum mismatch", 1234);
  const nlohmann::json s = single.toJson("g.gtn");
  EXPECT_EQ(s["messages"][0]["message"], "chunk 'GEOM' checksum mismatch");
  EXPECT_EQ(s["messages"][0]["offset"].get<int>(), 1234);
  EXPECT_FALSE(s["truncated"].get<bool>());
}

TEST(Report, ReclassifyMovesOccurrencesCountsAndTotals) {
  ValidationReport r;
  for (int t = 0; t < 3; ++t) r.add(IssueCode::kZeroVolumeTet, "/levels/1", "/levels/1/tets/" + std::to_string(t));
  r.setTotal(IssueCode::kZeroVolumeTet, "/levels/1", 100);
  r.add(IssueCode::kZeroVolumeTet, "/levels/2", "/levels/2/tets/7");
  r.reclassify(IssueCode::kZeroVolumeTet, IssueCode::kZeroVolumeTetFromSource, "/levels/1");
  r.reclassify(IssueCode::kZeroVolumeTet, IssueCode::kZeroVolumeTetFromSource, "/levels/5");  // none there
  EXPECT_EQ(r.count(Severity::kWarning), 1u);
  EXPECT_EQ(r.count(Severity::kInfo), 3u);
  EXPECT_EQ(r.count(IssueCode::kZeroVolumeTetFromSource), 3u);
  EXPECT_EQ(r.count(IssueCode::kZeroVolumeTet), 1u);
  const std::vector<ReportedIssue> shown = r.issues();
  ASSERT_EQ(shown.size(), 2u);
  EXPECT_EQ(shown[0].code, IssueCode::kZeroVolumeTet);
  EXPECT_EQ(shown[0].scope, "/levels/2");
  EXPECT_EQ(shown[1].code, IssueCode::kZeroVolumeTetFromSource);
  EXPECT_EQ(shown[1].count, 3u);
  EXPECT_EQ(shown[1].total, 100u);
  EXPECT_EQ(shown[1].paths.size(), 3u);
  // Later occurrences of the old code in that scope start a new message under the old code.
  r.add(IssueCode::kZeroVolumeTet, "/levels/1", "/levels/1/tets/50");
  EXPECT_EQ(r.count(IssueCode::kZeroVolumeTet), 2u);
}

TEST(Report, ErrorsComeFirstAndAreNeverDisplacedByEarlierInfos) {
  ValidationReport r(1);
  r.add(IssueCode::kUnreferencedPoint, "/levels/0", "/levels/0/points/3");
  r.add(IssueCode::kZeroVolumeTet, "/levels/0", "/levels/0/tets/9");
  r.add(IssueCode::kInvertedTet, "/levels/0", "/levels/0/tets/4");
  ASSERT_EQ(r.issues().size(), 1u);
  EXPECT_EQ(r.issues()[0].code, IssueCode::kInvertedTet);
  EXPECT_TRUE(r.truncated());
  ValidationReport all(10);
  all.add(IssueCode::kUnreferencedPoint, "/levels/0", "/levels/0/points/3");
  all.add(IssueCode::kZeroVolumeTet, "/levels/0", "/levels/0/tets/9");
  all.add(IssueCode::kInvertedTet, "/levels/0", "/levels/0/tets/4");
  const std::vector<ReportedIssue> shown = all.issues();
  ASSERT_EQ(shown.size(), 3u);
  EXPECT_EQ(shown[0].code, IssueCode::kInvertedTet);
  EXPECT_EQ(shown[1].code, IssueCode::kZeroVolumeTet);
  EXPECT_EQ(shown[2].code, IssueCode::kUnreferencedPoint);
  EXPECT_FALSE(all.truncated());
}

}  // namespace
}  // namespace gtn::test
