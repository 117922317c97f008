// Encoding and number helpers shared by the text readers.
#include "io/formats/text_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "core/error.h"

namespace csw::formats_internal {
namespace {

TEST(Utf16, SurrogatePairsBothEndians) {
  // "A é € 😀" = U+0041 U+00E9 U+20AC U+1F600 (D83D DE00).
  const std::string expected = "A\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80";
  const std::string le("\x41\x00\xE9\x00\xAC\x20\x3D\xD8\x00\xDE", 10);
  const std::string be("\x00\x41\x00\xE9\x20\xAC\xD8\x3D\xDE\x00", 10);
  EXPECT_EQ(Utf16ToUtf8(le, false, "x"), expected);
  EXPECT_EQ(Utf16ToUtf8(be, true, "x"), expected);
  TextEncoding enc;
  EXPECT_EQ(DecodeText("\xFF\xFE" + le, "x", &enc), expected);
  EXPECT_EQ(enc, TextEncoding::kUtf16Le);
  EXPECT_EQ(DecodeText("\xFE\xFF" + be, "x", &enc), expected);
  EXPECT_EQ(enc, TextEncoding::kUtf16Be);
  // No BOM: detected from the zero byte of an ASCII first character.
  EXPECT_EQ(DecodeText(le, "x", &enc), expected);
  EXPECT_EQ(enc, TextEncoding::kUtf16Le);
  EXPECT_EQ(DecodeText(be, "x", &enc), expected);
  EXPECT_EQ(enc, TextEncoding::kUtf16Be);
}

TEST(Utf16, BrokenInputNamesTheOffset) {
  auto offset_of = [](const std::string& bytes, bool be) -> int64_t {
    try {
      Utf16ToUtf8(bytes, be, "f.TextGrid", 2);
    } catch (const ParseError& e) {
      EXPECT_EQ(e.where().file, "f.TextGrid");
      return e.where().offset.value_or(-1);
    }
    return -100;
  };
  EXPECT_EQ(offset_of(std::string("\x41\x00\x42", 3), false), 4);      // odd length: last byte
  EXPECT_EQ(offset_of(std::string("\x41\x00\x00\xDC", 4), false), 4);  // lone low surrogate
  EXPECT_EQ(offset_of(std::string("\x3D\xD8\x41\x00", 4), false), 2);  // high + non-low
  EXPECT_EQ(offset_of(std::string("\x41\x00\x3D\xD8", 4), false), 4);  // high at the end
}

TEST(Utf8, ValidationAndLatin1Fallback) {
  EXPECT_TRUE(IsValidUtf8("plain"));
  EXPECT_TRUE(IsValidUtf8("\xC3\xA9\xF0\x9F\x98\x80"));
  EXPECT_FALSE(IsValidUtf8("\xC0\xAF"));          // overlong
  EXPECT_FALSE(IsValidUtf8("\xED\xA0\x80"));      // surrogate
  EXPECT_FALSE(IsValidUtf8("\xF4\x90\x80\x80"));  // > U+10FFFF
  EXPECT_FALSE(IsValidUtf8("\xE2\x82"));          // truncated
  TextEncoding enc;
  EXPECT_EQ(DecodeText("caf\xE9", "x", &enc), "caf\xC3\xA9");
  EXPECT_EQ(enc, TextEncoding::kLatin1);
  EXPECT_EQ(DecodeText("\xEF\xBB\xBFok", "x", &enc), "ok");
  EXPECT_EQ(enc, TextEncoding::kUtf8Bom);
}

TEST(Numbers, ParseOnlyFiniteWholeTokens) {
  EXPECT_EQ(ParseFiniteDouble("1.5"), 1.5);
  EXPECT_EQ(ParseFiniteDouble("+2"), 2.0);
  EXPECT_EQ(ParseFiniteDouble(".5"), 0.5);
  EXPECT_EQ(ParseFiniteDouble("-1e-3"), -0.001);
  EXPECT_TRUE(std::signbit(*ParseFiniteDouble("-0")));
  for (const char* bad : {"", "+", "nan", "NaN", "inf", "-inf", "1e999", "0x10", "1.5x", " 1", "1,5", "--1"}) {
    EXPECT_FALSE(ParseFiniteDouble(bad).has_value()) << bad;
  }
  EXPECT_EQ(ParseInt("+42"), 42);
  EXPECT_EQ(ParseInt("-7"), -7);
  EXPECT_FALSE(ParseInt("4.0").has_value());
  EXPECT_FALSE(ParseInt("99999999999999999999").has_value());
}

TEST(Numbers, FormatIsShortestExactRoundTrip) {
  EXPECT_EQ(FormatDouble(0.1), "0.1");
  EXPECT_EQ(FormatDouble(-0.0), "0");
  EXPECT_EQ(FormatDouble(1.869687), "1.869687");
  EXPECT_EQ(FormatFloat(-171.03949f), "-171.03949");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> dist(-1e6, 1e6);
  for (int i = 0; i < 10000; ++i) {
    const double d = dist(rng) * std::pow(10.0, static_cast<int>(rng() % 20) - 10);
    ASSERT_EQ(*ParseFiniteDouble(FormatDouble(d)), d);
    const float f = static_cast<float>(d);
    ASSERT_EQ(static_cast<float>(*ParseFiniteDouble(FormatFloat(f))), f);
  }
}

TEST(Text, LineOfOffsetAndTrim) {
  EXPECT_EQ(LineOfOffset("a\nb\nc", 0), 1);
  EXPECT_EQ(LineOfOffset("a\nb\nc", 2), 2);
  EXPECT_EQ(LineOfOffset("a\nb\nc", 4), 3);
  EXPECT_EQ(LineOfOffset("a\nb\nc", 1000), 3);
  EXPECT_EQ(Trim(" \t x y \r\n"), "x y");
}

}  // namespace
}  // namespace csw::formats_internal
