// TextGrid reader/writer: the praatio edge-case files (values read by eye in
// the files), cross-format agreement, exact round trips and hostile inputs.
#include "io/formats/textgrid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/io/formats/test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

using testing::ExpectParseError;
using testing::ReadBytes;
using testing::SharedData;
using testing::TempDir;
using testing::WriteBytes;

std::string Praatio(const std::string& name) { return SharedData("textgrid/praatio/" + name).string(); }

void ExpectSameTiers(const std::vector<LabelTier>& a, const std::vector<LabelTier>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t t = 0; t < a.size(); ++t) {
    SCOPED_TRACE("tier " + std::to_string(t));
    EXPECT_EQ(a[t].name, b[t].name);
    EXPECT_EQ(a[t].kind, b[t].kind);
    EXPECT_EQ(a[t].start_s, b[t].start_s);
    EXPECT_EQ(a[t].end_s, b[t].end_s);
    ASSERT_EQ(a[t].labels.size(), b[t].labels.size());
    for (size_t i = 0; i < a[t].labels.size(); ++i) {
      EXPECT_EQ(a[t].labels[i].start_s, b[t].labels[i].start_s) << i;
      EXPECT_EQ(a[t].labels[i].end_s, b[t].labels[i].end_s) << i;
      EXPECT_EQ(a[t].labels[i].text, b[t].labels[i].text) << i;
    }
  }
}

void ExpectLabel(const Label& l, double start, double end, const std::string& text) {
  EXPECT_EQ(l.start_s, start);
  EXPECT_EQ(l.end_s, end);
  EXPECT_EQ(l.text, text);
}

// mary.TextGrid (short format, CRLF, UTF-8 IPA), as read by eye.
void ExpectMary(const std::vector<LabelTier>& tiers) {
  ASSERT_EQ(tiers.size(), 3u);
  EXPECT_EQ(tiers[0].name, "phone");
  EXPECT_EQ(tiers[0].kind, LabelTier::Kind::kInterval);
  ASSERT_EQ(tiers[0].labels.size(), 16u);
  ExpectLabel(tiers[0].labels[0], 0, 0.3154201182247563, "");
  ExpectLabel(tiers[0].labels[1], 0.3154201182247563, 0.38526757369599995, "m");
  ExpectLabel(tiers[0].labels[2], 0.38526757369599995, 0.4906833231456586, "\xC9\x99");  // U+0259
  EXPECT_EQ(tiers[1].name, "word");
  EXPECT_EQ(tiers[1].labels.size(), 6u);
  EXPECT_EQ(tiers[2].name, "pitch");
  EXPECT_EQ(tiers[2].kind, LabelTier::Kind::kPoint);
  ASSERT_EQ(tiers[2].labels.size(), 4u);
  ExpectLabel(tiers[2].labels[0], 0.5978689404359245, 0.5978689404359245, "120");
  ExpectLabel(tiers[2].labels[3], 1.2008760470242699, 1.2008760470242699, "104");
  EXPECT_EQ(tiers[2].end_s, 1.869687);
}

TEST(TextGridRead, MaryShortCrlfUtf8) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/mary.TextGrid");
  double xmin = -1, xmax = -1;
  auto tiers = ReadTextGrid(Praatio("mary.TextGrid"), &xmin, &xmax);
  EXPECT_EQ(xmin, 0.0);
  EXPECT_EQ(xmax, 1.869687);
  ExpectMary(tiers);
}

TEST(TextGridRead, MaryLongUtf16BeEqualsShortUtf8) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/mary_longfile.TextGrid", "textgrid/praatio/mary.TextGrid");
  auto tiers = ReadTextGrid(Praatio("mary_longfile.TextGrid"));
  ExpectMary(tiers);
  ExpectSameTiers(tiers, ReadTextGrid(Praatio("mary.TextGrid")));
}

TEST(TextGridRead, NegativeZeroReadsAsZero) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/mary_with_negative_zero.TextGrid",
                          "textgrid/praatio/mary_longfile_with_negative_zero.TextGrid",
                          "textgrid/praatio/mary.TextGrid");
  for (const char* name : {"mary_with_negative_zero.TextGrid", "mary_longfile_with_negative_zero.TextGrid"}) {
    double xmin = 1;
    auto tiers = ReadTextGrid(Praatio(name), &xmin);
    EXPECT_EQ(xmin, 0.0);
    EXPECT_FALSE(std::signbit(xmin)) << name;
    EXPECT_FALSE(std::signbit(tiers[0].start_s)) << name;
    EXPECT_FALSE(std::signbit(tiers[0].labels[0].start_s)) << name;
    ExpectSameTiers(tiers, ReadTextGrid(Praatio("mary.TextGrid")));
  }
}

TEST(TextGridRead, ConstrainedTierTimes) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/mary_with_constrained_tier_times.TextGrid");
  double xmin = -1, xmax = -1;
  auto tiers = ReadTextGrid(Praatio("mary_with_constrained_tier_times.TextGrid"), &xmin, &xmax);
  EXPECT_EQ(xmin, 0.0);
  EXPECT_EQ(xmax, 1.869687);
  ASSERT_EQ(tiers.size(), 3u);
  EXPECT_EQ(tiers[0].start_s, 0.3154201182247563);
  EXPECT_EQ(tiers[0].end_s, 1.5182538944627297);
  ASSERT_EQ(tiers[0].labels.size(), 14u);
  ExpectLabel(tiers[0].labels[0], 0.3154201182247563, 0.38526757369599995, "m");
  EXPECT_EQ(tiers[1].labels.size(), 4u);
  EXPECT_EQ(tiers[2].labels.size(), 4u);
}

TEST(TextGridRead, WordsWithNewlinesAndEscapedQuotes) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/bobby_words_with_newlines.TextGrid");
  auto tiers = ReadTextGrid(Praatio("bobby_words_with_newlines.TextGrid"));
  ASSERT_EQ(tiers.size(), 3u);
  EXPECT_EQ(tiers[0].name, "\"word\"");
  ASSERT_EQ(tiers[0].labels.size(), 6u);
  ExpectLabel(tiers[0].labels[1], 0.06469123242311078, 0.41156462585, "\"\"\"BOBBY\"\"\"\nNoun");
  ExpectLabel(tiers[0].labels[2], 0.41156462585, 0.6576881808447274, "RIPPED\nVerb");
  EXPECT_EQ(tiers[1].name, "phrase");
  ASSERT_EQ(tiers[1].labels.size(), 3u);
  EXPECT_EQ(tiers[1].labels[1].text, "BOBBY RIPPED THE LEDGER");
  EXPECT_EQ(tiers[2].name, "");
  EXPECT_EQ(tiers[2].kind, LabelTier::Kind::kPoint);
  ASSERT_EQ(tiers[2].labels.size(), 4u);
  ExpectLabel(tiers[2].labels[0], 0.23290458517889742, 0.23290458517889742, "133\n\"\"\"p1\"\"\"\np1");
  ExpectLabel(tiers[2].labels[1], 0.5304541883551366, 0.5304541883551366, "0\np2");
}

TEST(TextGridRead, LongAndElanExportsEqualShortFormat) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/bobby_words_with_newlines.TextGrid",
                          "textgrid/praatio/bobby_words_with_newlines_longfile.TextGrid",
                          "textgrid/praatio/bobby_words_with_newlines_longfile_elan.TextGrid",
                          "textgrid/praatio/textgrid_to_merge.TextGrid",
                          "textgrid/praatio/textgrid_to_merge_longfile.TextGrid");
  // The interval tiers agree; the point marks differ between the files (the
  // short file has quotes in them, the long ones not), as read by eye.
  auto reference = ReadTextGrid(Praatio("bobby_words_with_newlines.TextGrid"));
  auto long_file = ReadTextGrid(Praatio("bobby_words_with_newlines_longfile.TextGrid"));
  auto elan = ReadTextGrid(Praatio("bobby_words_with_newlines_longfile_elan.TextGrid"));
  ASSERT_EQ(long_file.size(), 3u);
  ExpectSameTiers({long_file[0], long_file[1]}, {reference[0], reference[1]});
  ExpectSameTiers(elan, long_file);
  ASSERT_EQ(long_file[2].labels.size(), 4u);
  ExpectLabel(long_file[2].labels[0], 0.23290458517889742, 0.23290458517889742, "133\np1");
  ExpectLabel(long_file[2].labels[2], 0.6966964767693916, 0.6966964767693916, "93\np3");
  EXPECT_EQ(reference[2].labels[2].text, "93\n\"p3\"");
  ExpectSameTiers(ReadTextGrid(Praatio("textgrid_to_merge_longfile.TextGrid")),
                  ReadTextGrid(Praatio("textgrid_to_merge.TextGrid")));
}

TEST(TextGridRead, ElanPhonesWithLeadingGap) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/bobby_phones_elan.TextGrid");
  double xmax = 0;
  auto tiers = ReadTextGrid(Praatio("bobby_phones_elan.TextGrid"), nullptr, &xmax);
  EXPECT_EQ(xmax, 1.194625);
  ASSERT_EQ(tiers.size(), 1u);
  EXPECT_EQ(tiers[0].name, "phone");
  EXPECT_EQ(tiers[0].end_s, 1.18979591837);
  ASSERT_EQ(tiers[0].labels.size(), 15u);
  ExpectLabel(tiers[0].labels[0], 0.0124716553288, 0.06469123242311078, "");
  ExpectLabel(tiers[0].labels[1], 0.06469123242311078, 0.08438971390281873, "B");
  ExpectLabel(tiers[0].labels[14], 1.1171482864527198, 1.18979591837, "");
}

TEST(TextGridRead, SameNameTiersAndMergeFile) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/all_tiers_have_the_same_name.TextGrid",
                          "textgrid/praatio/textgrid_to_merge.TextGrid");
  auto same = ReadTextGrid(Praatio("all_tiers_have_the_same_name.TextGrid"));
  ASSERT_EQ(same.size(), 3u);
  for (const LabelTier& t : same) {
    EXPECT_EQ(t.name, "Mary");
    ASSERT_EQ(t.labels.size(), 3u);
  }
  ExpectLabel(same[0].labels[1], 0.06588581304037375, 0.2342878321396945, "Mary");
  auto merge = ReadTextGrid(Praatio("textgrid_to_merge.TextGrid"));
  ASSERT_EQ(merge.size(), 3u);
  EXPECT_EQ(merge[0].name, "bob");
  EXPECT_EQ(merge[1].name, "mary");
  EXPECT_EQ(merge[2].name, "sarah");
  EXPECT_EQ(merge[0].labels.size(), 8u);
  EXPECT_EQ(merge[1].labels.size(), 7u);
  EXPECT_EQ(merge[2].labels.size(), 7u);
  ExpectLabel(merge[0].labels[1], 0.7363043110515426, 1.559821858449687, "01a");
}

const char* const kAllFiles[] = {"all_tiers_have_the_same_name.TextGrid",
                                 "bobby_phones_elan.TextGrid",
                                 "bobby_words_with_newlines.TextGrid",
                                 "bobby_words_with_newlines_longfile.TextGrid",
                                 "bobby_words_with_newlines_longfile_elan.TextGrid",
                                 "mary.TextGrid",
                                 "mary_longfile.TextGrid",
                                 "mary_longfile_with_negative_zero.TextGrid",
                                 "mary_with_constrained_tier_times.TextGrid",
                                 "mary_with_negative_zero.TextGrid",
                                 "textgrid_to_merge.TextGrid",
                                 "textgrid_to_merge_longfile.TextGrid"};

TEST(TextGridRoundTrip, EveryPraatioFileBothFormats) {
  for (const char* name : kAllFiles) CSW_REQUIRE_SHARED_DATA(std::string("textgrid/praatio/") + name);
  TempDir dir;
  for (const char* name : kAllFiles) {
    SCOPED_TRACE(name);
    double xmin = 0, xmax = 0;
    auto tiers = ReadTextGrid(Praatio(name), &xmin, &xmax);
    for (bool short_format : {false, true}) {
      const std::string out = (dir / "rt.TextGrid").string();
      WriteTextGrid(out, tiers, xmin, xmax, short_format);
      double xmin2 = -1, xmax2 = -1;
      auto back = ReadTextGrid(out, &xmin2, &xmax2);
      EXPECT_EQ(xmin2, xmin);
      EXPECT_EQ(xmax2, xmax);
      ExpectSameTiers(back, tiers);
    }
  }
}

TEST(TextGridWrite, LongFormatLayoutMatchesPraat) {
  TempDir dir;
  LabelTier words{"words", LabelTier::Kind::kInterval, 0, 1, {{0, 0.5, "say \"hi\""}, {0.5, 1, ""}}};
  LabelTier marks{"marks", LabelTier::Kind::kPoint, 0, 1, {{0.25, 0.25, "p"}}};
  const std::string out = (dir / "w.TextGrid").string();
  WriteTextGrid(out, {words, marks}, 0, 1);
  const std::string expected =
      "File type = \"ooTextFile\"\nObject class = \"TextGrid\"\n\nxmin = 0 \nxmax = 1 \n"
      "tiers? <exists> \nsize = 2 \nitem []: \n"
      "    item [1]:\n        class = \"IntervalTier\" \n        name = \"words\" \n"
      "        xmin = 0 \n        xmax = 1 \n        intervals: size = 2 \n"
      "        intervals [1]:\n            xmin = 0 \n            xmax = 0.5 \n"
      "            text = \"say \"\"hi\"\"\" \n"
      "        intervals [2]:\n            xmin = 0.5 \n            xmax = 1 \n            text = "
      "\"\" \n"
      "    item [2]:\n        class = \"TextTier\" \n        name = \"marks\" \n"
      "        xmin = 0 \n        xmax = 1 \n        points: size = 1 \n"
      "        points [1]:\n            number = 0.25 \n            mark = \"p\" \n";
  EXPECT_EQ(ReadBytes(out), expected);
  WriteTextGrid(out, {words, marks}, 0, 1, true);
  EXPECT_EQ(ReadBytes(out),
            "File type = \"ooTextFile\"\nObject class = \"TextGrid\"\n\n0\n1\n<exists>\n2\n"
            "\"IntervalTier\"\n\"words\"\n0\n1\n2\n0\n0.5\n\"say \"\"hi\"\"\"\n0.5\n1\n\"\"\n"
            "\"TextTier\"\n\"marks\"\n0\n1\n1\n0.25\n\"p\"\n");
}

TEST(TextGridWrite, NoTiersAndRejectedInput) {
  TempDir dir;
  const std::string out = (dir / "e.TextGrid").string();
  WriteTextGrid(out, {}, 0, 2.5);
  double xmax = 0;
  EXPECT_TRUE(ReadTextGrid(out, nullptr, &xmax).empty());
  EXPECT_EQ(xmax, 2.5);
  EXPECT_THROW(WriteTextGrid(out, {}, 2, 1), InvalidInput);
  EXPECT_THROW(WriteTextGrid(out, {}, 0, NAN), InvalidInput);
  LabelTier bad{"b", LabelTier::Kind::kInterval, 0, 1, {{0.6, 0.2, "x"}}};
  EXPECT_THROW(WriteTextGrid(out, {bad}, 0, 1), InvalidInput);
}

TEST(TextGridFill, GapsBecomeEmptyIntervals) {
  LabelTier t{"w", LabelTier::Kind::kInterval, 0, 3, {{0.5, 1, "a"}, {1, 1.5, "b"}, {2, 2.5, "c"}}};
  LabelTier f = FillIntervalGaps(t);
  ASSERT_EQ(f.labels.size(), 6u);
  ExpectLabel(f.labels[0], 0, 0.5, "");
  ExpectLabel(f.labels[1], 0.5, 1, "a");
  ExpectLabel(f.labels[2], 1, 1.5, "b");
  ExpectLabel(f.labels[3], 1.5, 2, "");
  ExpectLabel(f.labels[4], 2, 2.5, "c");
  ExpectLabel(f.labels[5], 2.5, 3, "");
}

// UTF-8 -> UTF-16 (test-side encoder) with a BOM.
std::string ToUtf16(const std::string& utf8, bool big_endian) {
  std::string out = big_endian ? std::string("\xFE\xFF") : std::string("\xFF\xFE");
  auto put = [&](uint32_t u) {
    char hi = static_cast<char>(u >> 8), lo = static_cast<char>(u & 0xFF);
    out += big_endian ? std::string{hi, lo} : std::string{lo, hi};
  };
  for (size_t i = 0; i < utf8.size();) {
    auto c = static_cast<unsigned char>(utf8[i]);
    uint32_t cp;
    int len;
    if (c < 0x80) {
      cp = c;
      len = 1;
    } else if (c < 0xE0) {
      cp = c & 0x1F;
      len = 2;
    } else if (c < 0xF0) {
      cp = c & 0x0F;
      len = 3;
    } else {
      cp = c & 0x07;
      len = 4;
    }
    for (int k = 1; k < len; ++k) cp = (cp << 6) | (static_cast<unsigned char>(utf8[i + k]) & 0x3F);
    i += static_cast<size_t>(len);
    if (cp >= 0x10000) {
      put(0xD800 + ((cp - 0x10000) >> 10));
      put(0xDC00 + ((cp - 0x10000) & 0x3FF));
    } else {
      put(cp);
    }
  }
  return out;
}

TEST(TextGridRead, Utf16LeAndBeWithSurrogatePairs) {
  TempDir dir;
  // "cued ✋ 😀 é" : BMP and astral characters.
  LabelTier t{"hand \xE2\x9C\x8B",
              LabelTier::Kind::kInterval,
              0,
              2,
              {{0, 1, "\xF0\x9F\x98\x80 smile"}, {1, 2, "caf\xC3\xA9\nline2"}}};
  const std::string utf8_path = (dir / "u8.TextGrid").string();
  WriteTextGrid(utf8_path, {t}, 0, 2);
  const std::string utf8 = ReadBytes(utf8_path);
  for (bool be : {false, true}) {
    const std::string path = (dir / (be ? "be.TextGrid" : "le.TextGrid")).string();
    WriteBytes(path, ToUtf16(utf8, be));
    auto tiers = ReadTextGrid(path);
    ExpectSameTiers(tiers, {t});
  }
  // CRLF line ends everywhere, including inside the multi-line text.
  std::string crlf;
  for (char c : utf8) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  const std::string crlf_path = (dir / "crlf.TextGrid").string();
  WriteBytes(crlf_path, crlf);
  ExpectSameTiers(ReadTextGrid(crlf_path), {t});
}

TEST(TextGridRead, HostileInputsGiveOneParseErrorWithLine) {
  TempDir dir;
  const std::string path = (dir / "bad.TextGrid").string();
  const std::string head = "File type = \"ooTextFile\"\nObject class = \"TextGrid\"\n\n";
  struct Case {
    std::string content;
    int64_t line;
  };
  const Case cases[] = {
      {"garbage\n", 1},
      {"File type = \"ooTextFile\"\nObject class = \"Sound\"\n", 2},
      {head + "xmin = nan \nxmax = 1\n", 4},
      {head + "xmin = 0 \nxmax = inf\n", 5},
      {head + "xmin = 0 \nxmax = 1e999\n", 5},
      {head + "xmin = 2 \nxmax = 1\n", 5},
      {head + "0\n1\n<exists>\n-1\n", 7},
      {head + "0\n1\n<exists>\n1.5\n", 7},
      {head + "0\n1\n<exists>\n1000000000\n", 7},
      {head + "0\n1\n<maybe>\n", 6},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n0\n1\n4000000000\n", 12},
      {head + "0\n1\n<exists>\n1\n\"Polygon\"\n\"a\"\n          ", 8},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n1\n0\n", 11},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n0\n1\n1\n0.6\n0.5\n\"x\"\n", 14},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n0\n1\n1\n0\n1\n\"unterminated\n\n", 15},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n0\n1\n2\n0\n1\n\"x\"          \n", 16},
      {head + "0\n1\n<exists>\n1\n\"IntervalTier\"\n\"a\"\n0\n1\n1\n0\n\"x\"\n\"y\"\n", 14},
  };
  for (const Case& c : cases) {
    WriteBytes(path, c.content);
    SCOPED_TRACE(c.content);
    ExpectParseError([&] { ReadTextGrid(path); }, path, c.line);
  }
  // Binary and broken UTF-16 are reported with an offset.
  for (const std::string& bytes : {std::string("ooBinaryFile\x08TextGrid", 21), std::string("\xFF\xFE\x41\x00\x42", 5),
                                   std::string("\xFE\xFF\xDC\x00\x00\x41", 6), std::string("", 0)}) {
    WriteBytes(path, bytes);
    ExpectParseError([&] { ReadTextGrid(path); }, path);
  }
}

// Every truncation of a real file either fails with a ParseError or (when only
// trailing whitespace was cut) reads the same tiers.
TEST(TextGridRead, EveryTruncationOfMaryFailsCleanly) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/mary.TextGrid", "textgrid/praatio/mary_longfile.TextGrid");
  TempDir dir;
  const std::string path = (dir / "cut.TextGrid").string();
  for (const char* name : {"mary.TextGrid", "mary_longfile.TextGrid"}) {
    const std::string full = ReadBytes(Praatio(name));
    const auto reference = ReadTextGrid(Praatio(name));
    int errors = 0;
    for (size_t n = 0; n < full.size(); n += 7) {
      WriteBytes(path, full.substr(0, n));
      try {
        ExpectSameTiers(ReadTextGrid(path), reference);
      } catch (const ParseError& e) {
        ++errors;
        EXPECT_NE(std::string(e.what()).find("cut.TextGrid"), std::string::npos);
      }
    }
    EXPECT_GT(errors, static_cast<int>(full.size() / 7) - 10) << name;
  }
}

}  // namespace
}  // namespace csw
