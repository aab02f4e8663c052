// UTF-8 checking and the Latin-1 fallback that names from files pass through.
#include <gtest/gtest.h>

#include "mesh/utf8.h"

namespace gtn {
namespace {

TEST(Utf8, WellFormedTextIsKept) {
  for (const char* s : {"", "plain", "caf\xC3\xA9", "\xE2\x82\xAC", "\xF0\x9F\x98\x80", "\xF4\x8F\xBF\xBF"}) {
    EXPECT_TRUE(isValidUtf8(s)) << s;
    EXPECT_EQ(toUtf8(s), s);
  }
}

TEST(Utf8, MalformedTextIsReadAsLatin1) {
  // A lone Latin-1 byte, a truncated sequence, an overlong form, a surrogate, beyond U+10FFFF.
  for (const char* s : {"caf\xE9", "\xC3", "\xC0\xAF", "\xED\xA0\x80", "\xF4\x90\x80\x80", "ab\xFF"})
    EXPECT_FALSE(isValidUtf8(s)) << s;
  EXPECT_EQ(toUtf8("caf\xE9"), "caf\xC3\xA9");
  EXPECT_EQ(toUtf8("ab\xFF"), "ab\xC3\xBF");
  EXPECT_TRUE(isValidUtf8(toUtf8("\xC0\xAF\xED\xA0\x80")));
}

}  // namespace
}  // namespace gtn
