// Text from files as UTF-8 (issue 16): C3D labels, units and parameter names are bytes, usually
// ASCII or Latin-1; the outputs (JSON, CSV) need UTF-8.
#include <s2kf/body/label_text.hpp>

#include <gtest/gtest.h>

#include <string>

namespace {

using s2kf::is_utf8;
using s2kf::utf8_from_file_text;

TEST(LabelText, RecognisesWellFormedUtf8Only) {
  EXPECT_TRUE(is_utf8(""));
  EXPECT_TRUE(is_utf8("LASI"));
  EXPECT_TRUE(is_utf8("\xC3\x89paule"));      // É, two bytes
  EXPECT_TRUE(is_utf8("\xE2\x82\xAC"));       // €, three bytes
  EXPECT_TRUE(is_utf8("\xF0\x9F\x98\x80"));   // an emoji, four bytes
  EXPECT_FALSE(is_utf8("\xC9paule"));         // Latin-1 É: a lead byte without its continuation
  EXPECT_FALSE(is_utf8("C7\xC9"));            // ... at the end
  EXPECT_FALSE(is_utf8("\xB5m"));             // Latin-1 µ: a lone continuation byte
  EXPECT_FALSE(is_utf8("\xC0\xAF"));          // overlong '/'
  EXPECT_FALSE(is_utf8("\xE0\x80\xAF"));      // overlong, three bytes
  EXPECT_FALSE(is_utf8("\xED\xA0\x80"));      // a UTF-16 surrogate
  EXPECT_FALSE(is_utf8("\xF4\x90\x80\x80"));  // beyond U+10FFFF
  EXPECT_FALSE(is_utf8("\xE2\x82"));          // cut short
}

TEST(LabelText, DecodesLatin1AndKeepsUtf8) {
  // Latin-1 byte b is code point U+00bb: 0xC9 -> U+00C9 (C3 89), 0xB5 -> U+00B5 (C2 B5).
  EXPECT_EQ(utf8_from_file_text("C7\xC9"), "C7\xC3\x89");
  EXPECT_EQ(utf8_from_file_text("\xB5m"), "\xC2\xB5m");
  EXPECT_EQ(utf8_from_file_text("\xFF"), "\xC3\xBF");
  EXPECT_EQ(utf8_from_file_text("K\xF6rper"), "K\xC3\xB6rper");  // German ö
  // Already UTF-8 (or ASCII): unchanged, so decoding twice changes nothing.
  EXPECT_EQ(utf8_from_file_text("C7\xC3\x89"), "C7\xC3\x89");
  EXPECT_EQ(utf8_from_file_text(utf8_from_file_text("Gen\xE8ve")), "Gen\xC3\xA8ve");
  EXPECT_EQ(utf8_from_file_text(std::string("A\0B", 3)), std::string("A\0B", 3));
  // Every byte sequence decodes to UTF-8: all 256 bytes in one string.
  std::string all;
  for (int b = 0; b < 256; ++b) all += static_cast<char>(b);
  const std::string decoded = utf8_from_file_text(all);
  EXPECT_TRUE(is_utf8(decoded));
  EXPECT_EQ(decoded.size(), 128u + 2u * 128u);
}

}  // namespace
