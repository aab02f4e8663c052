// Replays the fuzz corpora as ordinary tests (no clang needed): every seed and every regression file
// found by the fuzzers goes through the validator (reader, decoders, checks). Seeds named fail.* are
// must-fail conformance files (container defects): they must be reported invalid. The valid seeds
// were written by the codec of their day; the codec's own conformance tests pin its bitstream, so
// here they only have to come back with a report.
// Regression files must simply come back with a report (no crash, hang or sanitizer finding). The
// sealed target's corpus (tests/fuzz/corpus-sealed, minimised with -merge=1) has checksums that
// match, so most of it reaches the layers behind the container. The decoder target's corpus
// (tests/fuzz/corpus-decoder) goes through the decoders directly.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>

#include "fuzz/fuzz_decoder_input.h"
#include "fuzz/reseal.h"
#include "validate/validate_fixtures.h"

namespace gtn::test {
namespace {

std::vector<std::filesystem::path> filesIn(const std::string& dir) {
  std::vector<std::filesystem::path> out;
  if (!std::filesystem::is_directory(dir)) return out;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && e.path().filename().string()[0] != '.' && e.path().extension() != ".md")
      out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(FuzzCorpus, SeedsValidateAsExpected) {
  const auto files = filesIn(std::string(GTN_SOURCE_DIR) + "/tests/fuzz/corpus");
  ASSERT_GE(files.size(), 8u);
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const ValidationReport r = validateBytesForTest(readBytes(f.string()));
    const bool must_fail = f.filename().string().rfind("fail.", 0) == 0;
    if (must_fail) {
      EXPECT_TRUE(r.hasErrors()) << r.toText(f.string());
    }
  }
}

TEST(FuzzCorpus, RegressionsComeBackWithAReport) {
  for (const std::string dir : {"/tests/fuzz/regressions", "/tests/fuzz/corpus", "/tests/fuzz/corpus-sealed"}) {
    for (const auto& f : filesIn(std::string(GTN_SOURCE_DIR) + dir)) {
      SCOPED_TRACE(f.string());
      ValidateOptions options;
      options.max_issues = 16;
      const ValidationReport r = validateBytesForTest(readBytes(f.string()), options);
      EXPECT_LE(r.issues().size(), 16u);
    }
  }
}

// The decoder target's corpus (inputs laid out as in fuzz_decoder_input.h) through the level and
// merge-tree decoders: each comes back with a Status. Most are rejected; some decode.
TEST(FuzzCorpus, DecoderCorpusDecodesOrIsRejected) {
  const auto files = filesIn(std::string(GTN_SOURCE_DIR) + "/tests/fuzz/corpus-decoder");
  ASSERT_GE(files.size(), 100u);
  size_t accepted = 0;
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const Bytes b = readBytes(f.string());
    accepted += fuzz::decodeFuzzInput(b.data(), b.size());
  }
  EXPECT_LT(accepted, files.size());
}

TEST(FuzzCorpus, SealedCorpusGetsPastTheChecksums) {
  const auto files = filesIn(std::string(GTN_SOURCE_DIR) + "/tests/fuzz/corpus-sealed");
  ASSERT_GE(files.size(), 100u);
  size_t past = 0;
  for (const auto& f : files) {
    const std::set<std::string> codes = errorCodeSet(validateBytesForTest(readBytes(f.string())));
    past += !codes.count("CHECKSUM_MISMATCH") && !codes.count("BAD_MAGIC") && !codes.count("FILE_TOO_SMALL");
  }
  EXPECT_GT(past, files.size() / 2) << past << " of " << files.size();
}

// The sealed target's mutator: resealing an intact file changes nothing; after a bit flip in a chunk
// it makes the checksums agree again, so that the damage reaches the layers behind them.
TEST(FuzzReseal, ResealedFlipsGetPastTheChecksums) {
  const Bytes intact = readBytes(std::string(GTN_SOURCE_DIR) + "/samples/conformance/cube.f64.fields.dir.v2.0-d6.gtn");
  ASSERT_GT(intact.size(), 200u);
  Bytes same = intact;
  EXPECT_GE(fuzz::resealGtn(same.data(), same.size()), 5u);  // GHDR, LHDR, PIEC, DIRC, GEND
  EXPECT_EQ(same, intact);

  std::mt19937_64 rng(7);
  int unsealed = 0, deeper = 0;
  const int kFlips = 300;
  for (int i = 0; i < kFlips; ++i) {
    Bytes b = intact;
    const size_t at = kGtnPrefixSize + rng() % (b.size() - kGtnPrefixSize);
    b[at] ^= static_cast<uint8_t>(1u << (rng() % 8));
    fuzz::resealGtn(b.data(), b.size());
    const ValidationReport r = validateBytesForTest(b);
    for (const std::string& code : errorCodeSet(r)) {
      if (code == "CHECKSUM_MISMATCH") ++unsealed;
      if (issueInfo(*issueFromName(code)).layer != std::string("container")) {
        ++deeper;
        break;
      }
    }
  }
  // A flip in a size field shifts the walk, so a few stay unsealed; most get through.
  EXPECT_LT(unsealed, kFlips / 20) << unsealed << " of " << kFlips;
  EXPECT_GT(deeper, kFlips / 2) << deeper << " of " << kFlips;
}

}  // namespace
}  // namespace gtn::test
