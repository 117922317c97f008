// ELAN EAF reader/writer: the pympi samples (times read by eye in the XML:
// TIME_ORDER values and the ALIGNABLE/REF annotation chains), round trips and
// hostile inputs.
#include "io/formats/eaf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <ctime>
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

void ExpectLabel(const Label& l, double start, double end, const std::string& text) {
  EXPECT_NEAR(l.start_s, start, 1e-9);
  EXPECT_NEAR(l.end_s, end, 1e-9);
  EXPECT_EQ(l.text, text);
}

bool HasWarning(const std::vector<std::string>& warnings, const std::string& needle) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

class EafSample : public ::testing::TestWithParam<const char*> {};

TEST_P(EafSample, TiersCountsAndTimes) {
  const std::string rel = std::string("eaf/pympi/") + GetParam();
  CSW_REQUIRE_SHARED_DATA(rel);
  std::vector<std::string> warnings;
  auto tiers = ReadEaf(SharedData(rel).string(), &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  ASSERT_EQ(tiers.size(), 6u);
  const char* names[] = {"text", "words-timesub", "words-symsub", "gestures", "gest_included", "words-pos"};
  const size_t counts[] = {399, 1995, 1995, 1197, 1197, 1995};
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(tiers[i].name, names[i]);
    EXPECT_EQ(tiers[i].labels.size(), counts[i]) << names[i];
    EXPECT_EQ(tiers[i].kind, LabelTier::Kind::kInterval);
    EXPECT_EQ(tiers[i].start_s, 0.0);
    EXPECT_EQ(tiers[i].end_s, 1199.0);  // largest TIME_VALUE is 1199000 ms
    EXPECT_TRUE(std::is_sorted(tiers[i].labels.begin(), tiers[i].labels.end(),
                               [](const Label& a, const Label& b) { return a.start_s < b.start_s; }));
  }
  // text a1: ts2 (2000) .. ts19 (5000).
  ExpectLabel(tiers[0].labels[0], 2.0, 5.0, "The quick brown fox 001");
  ExpectLabel(tiers[0].labels[1], 5.0, 8.0, "The quick brown fox 002");
  // words-timesub a400 ts2..ts6 (2470), a401 ts6..ts9 (3520).
  ExpectLabel(tiers[1].labels[0], 2.0, 2.47, "The");
  ExpectLabel(tiers[1].labels[1], 2.47, 3.52, "quick");
  // a410..a414: ts38 (8000), ts39..ts42 unaligned, ts55 (11000) -> 600 ms steps.
  ExpectLabel(tiers[1].labels[10], 8.0, 8.6, "The");
  ExpectLabel(tiers[1].labels[11], 8.6, 9.2, "quick");
  ExpectLabel(tiers[1].labels[12], 9.2, 9.8, "brown");
  ExpectLabel(tiers[1].labels[13], 9.8, 10.4, "fox");
  ExpectLabel(tiers[1].labels[14], 10.4, 11.0, "003");
  // words-symsub: five REF_ANNOTATIONs under a1 (2 s .. 5 s) share it equally.
  ExpectLabel(tiers[2].labels[0], 2.0, 2.6, "The");
  ExpectLabel(tiers[2].labels[1], 2.6, 3.2, "quick");
  ExpectLabel(tiers[2].labels[4], 4.4, 5.0, "001");
  // gestures a4390: ts1 (1800) .. ts4 (2400); gest_included a5587: ts3 (2000) .. ts5 (2400).
  ExpectLabel(tiers[3].labels[0], 1.8, 2.4, "prep");
  ExpectLabel(tiers[4].labels[0], 2.0, 2.4, "hold");
  // words-pos refers to words-symsub (a reference tier on a reference tier).
  ExpectLabel(tiers[5].labels[0], 2.0, 2.6, "");
  ExpectLabel(tiers[5].labels[1], 2.6, 3.2, "adj");
  ExpectLabel(tiers[5].labels[3], 3.8, 4.4, "n");
}

INSTANTIATE_TEST_SUITE_P(Versions, EafSample, ::testing::Values("sample_2.7.eaf", "sample_2.8.eaf", "sample_3.0.eaf"));

TEST(EafRoundTrip, SampleWriteReadKeepsNonEmptyLabels) {
  CSW_REQUIRE_SHARED_DATA("eaf/pympi/sample_2.8.eaf");
  auto tiers = ReadEaf(SharedData("eaf/pympi/sample_2.8.eaf").string());
  TempDir dir;
  const std::string out = (dir / "rt.eaf").string();
  WriteEaf(out, tiers, "bobby.wav");
  std::vector<std::string> warnings;
  auto back = ReadEaf(out, &warnings);
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(back.size(), tiers.size());
  for (size_t t = 0; t < tiers.size(); ++t) {
    std::vector<Label> expected;
    for (const Label& l : tiers[t].labels) {
      if (!l.text.empty()) expected.push_back(l);
    }
    EXPECT_EQ(back[t].name, tiers[t].name);
    ASSERT_EQ(back[t].labels.size(), expected.size()) << tiers[t].name;
    for (size_t i = 0; i < expected.size(); ++i) {
      // Times are stored in whole milliseconds.
      EXPECT_NEAR(back[t].labels[i].start_s, expected[i].start_s, 0.0005);
      EXPECT_NEAR(back[t].labels[i].end_s, expected[i].end_s, 0.0005);
      EXPECT_EQ(back[t].labels[i].text, expected[i].text);
    }
  }
  const std::string xml = ReadBytes(out);
  EXPECT_NE(xml.find("MEDIA_URL=\"file:///"), std::string::npos);
  EXPECT_NE(xml.find("MIME_TYPE=\"audio/x-wav\""), std::string::npos);
}

TEST(EafRoundTrip, MillisecondTiersAreExact) {
  LabelTier words{"words",
                  LabelTier::Kind::kInterval,
                  0,
                  3,
                  {{0.1, 0.25, "a<b & \"c\""}, {0.25, 0.9, "\xC3\xA9t\xC3\xA9"}, {1.5, 2.0, "x"}}};
  LabelTier points{"keys", LabelTier::Kind::kPoint, 0, 3, {{0.5, 0.5, "k1"}, {1.25, 1.25, "k2"}}};
  LabelTier unnamed{"", LabelTier::Kind::kInterval, 0, 3, {{0, 1, "u"}}};
  LabelTier dup = words;
  dup.labels = {{2.5, 3.0, "late"}};
  TempDir dir;
  const std::string out = (dir / "ms.eaf").string();
  WriteEaf(out, {words, points, dup, unnamed});
  auto back = ReadEaf(out);
  ASSERT_EQ(back.size(), 4u);
  EXPECT_EQ(back[3].name, "tier 4");
  EXPECT_EQ(back[0].name, "words");
  EXPECT_EQ(back[1].name, "keys");
  EXPECT_EQ(back[2].name, "words (2)");  // TIER_ID must be unique
  EXPECT_EQ(back[1].kind, LabelTier::Kind::kPoint);
  ASSERT_EQ(back[0].labels.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back[0].labels[i].start_s, words.labels[i].start_s);
    EXPECT_EQ(back[0].labels[i].end_s, words.labels[i].end_s);
    EXPECT_EQ(back[0].labels[i].text, words.labels[i].text);
  }
  ASSERT_EQ(back[1].labels.size(), 2u);
  ExpectLabel(back[1].labels[1], 1.25, 1.25, "k2");
  ExpectLabel(back[2].labels[0], 2.5, 3.0, "late");
  EXPECT_EQ(back[0].end_s, 3.0);
  // Adjacent labels share a slot: 0.1, 0.25, 0.9, 1.5, 2.0 + 0.5 x2, 1.25 x2 + 2.5, 3.0 + 0, 1.
  const std::string xml = ReadBytes(out);
  size_t slots = 0;
  for (size_t p = xml.find("<TIME_SLOT "); p != std::string::npos; p = xml.find("<TIME_SLOT ", p + 1)) ++slots;
  EXPECT_EQ(slots, 13u);
}

// The header's DATE is the writing time in UTC, in the "+00:00" form ELAN writes.
TEST(EafWrite, HeaderDateIsTheWritingTimeInUtc) {
  TempDir dir;
  const std::string out = (dir / "d.eaf").string();
  const std::time_t before = std::time(nullptr);
  WriteEaf(out, {LabelTier{"t", LabelTier::Kind::kInterval, 0, 1, {{0, 1, "x"}}}});
  const std::time_t after = std::time(nullptr);
  const std::string xml = ReadBytes(out);
  const size_t p = xml.find("DATE=\"");
  ASSERT_NE(p, std::string::npos) << xml;
  const std::string date = xml.substr(p + 6, xml.find('"', p + 6) - (p + 6));
  auto stamp = [](std::time_t t) {
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[40];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S+00:00", &tm);
    return std::string(buf);
  };
  EXPECT_TRUE(date == stamp(before) || date == stamp(after)) << date;
}

TEST(EafWrite, RejectsBadTimes) {
  TempDir dir;
  LabelTier t{"t", LabelTier::Kind::kInterval, 0, 1, {{-0.5, 0.5, "neg"}}};
  EXPECT_THROW(WriteEaf((dir / "x.eaf").string(), {t}), InvalidInput);
  t.labels = {{0.7, 0.5, "reversed"}};
  EXPECT_THROW(WriteEaf((dir / "x.eaf").string(), {t}), InvalidInput);
}

std::string Doc(const std::string& slots, const std::string& tiers) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<ANNOTATION_DOCUMENT FORMAT=\"3.0\">\n"
         "<HEADER TIME_UNITS=\"milliseconds\"/>\n<TIME_ORDER>\n" +
         slots + "</TIME_ORDER>\n" + tiers + "</ANNOTATION_DOCUMENT>\n";
}
std::string Slot(const std::string& id, const std::string& value) {
  return "<TIME_SLOT TIME_SLOT_ID=\"" + id + "\"" + (value.empty() ? "" : " TIME_VALUE=\"" + value + "\"") + "/>\n";
}
std::string Aligned(const std::string& id, const std::string& s1, const std::string& s2, const std::string& v) {
  return "<ANNOTATION><ALIGNABLE_ANNOTATION ANNOTATION_ID=\"" + id + "\" TIME_SLOT_REF1=\"" + s1 +
         "\" TIME_SLOT_REF2=\"" + s2 + "\"><ANNOTATION_VALUE>" + v +
         "</ANNOTATION_VALUE></ALIGNABLE_ANNOTATION></ANNOTATION>\n";
}
std::string Ref(const std::string& id, const std::string& parent, const std::string& v) {
  return "<ANNOTATION><REF_ANNOTATION ANNOTATION_ID=\"" + id + "\" ANNOTATION_REF=\"" + parent +
         "\"><ANNOTATION_VALUE>" + v + "</ANNOTATION_VALUE></REF_ANNOTATION></ANNOTATION>\n";
}
std::string Tier(const std::string& name, const std::string& body) {
  return "<TIER TIER_ID=\"" + name + "\" LINGUISTIC_TYPE_REF=\"lt\">\n" + body + "</TIER>\n";
}

TEST(EafRead, UnalignableReferencesAreWarnedAndSkipped) {
  TempDir dir;
  const std::string path = (dir / "refs.eaf").string();
  WriteBytes(
      path,
      Doc(Slot("t1", "1000") + Slot("t2", "3000") + Slot("u1", "") + Slot("u2", ""),
          Tier("main", Aligned("a1", "t1", "t2", "whole")) + Tier("float", Aligned("a2", "u1", "u2", "nowhere")) +
              Tier("cycle", Ref("c1", "c2", "x") + Ref("c2", "c1", "y")) + Tier("orphan", Ref("o1", "missing", "z")) +
              Tier("assoc", Ref("r1", "a1", "tr")) + Tier("empty", "")));
  std::vector<std::string> warnings;
  auto tiers = ReadEaf(path, &warnings);
  ASSERT_EQ(tiers.size(), 3u);  // main, assoc, empty
  EXPECT_EQ(tiers[0].name, "main");
  ExpectLabel(tiers[0].labels[0], 1.0, 3.0, "whole");
  EXPECT_EQ(tiers[1].name, "assoc");
  ExpectLabel(tiers[1].labels[0], 1.0, 3.0, "tr");
  EXPECT_EQ(tiers[2].name, "empty");
  EXPECT_TRUE(tiers[2].labels.empty());
  EXPECT_TRUE(HasWarning(warnings, "tier 'float'"));
  EXPECT_TRUE(HasWarning(warnings, "reference cycle"));
  EXPECT_TRUE(HasWarning(warnings, "unknown annotation 'missing'"));
}

TEST(EafRead, HostileInputsGiveOneParseErrorWithOffset) {
  TempDir dir;
  const std::string path = (dir / "bad.eaf").string();
  const std::string ok_tier = Tier("t", Aligned("a1", "t1", "t2", "v"));
  for (const std::string& content :
       {std::string("not xml at all"), std::string(""), std::string("<A><B></A>"),
        std::string("<?xml version=\"1.0\"?><TEXTGRID/>"), Doc(Slot("t1", "nan") + Slot("t2", "10"), ok_tier),
        Doc(Slot("t1", "-5") + Slot("t2", "10"), ok_tier), Doc(Slot("t1", "1e999") + Slot("t2", "10"), ok_tier),
        Doc(Slot("t1", "inf") + Slot("t2", "10"), ok_tier),
        Doc(Slot("t1", "0") + Slot("t2", "10"), Tier("t", Aligned("a1", "t1", "t9", "v"))),
        Doc(Slot("t1", "500") + Slot("t2", "10"), ok_tier)}) {
    WriteBytes(path, content);
    SCOPED_TRACE(content);
    ExpectParseError([&] { ReadEaf(path); }, path);
  }
}

TEST(EafRead, EveryTruncationOfASampleFailsCleanly) {
  CSW_REQUIRE_SHARED_DATA("eaf/pympi/sample_3.0.eaf");
  const std::string full = ReadBytes(SharedData("eaf/pympi/sample_3.0.eaf").string());
  TempDir dir;
  const std::string path = (dir / "cut.eaf").string();
  int errors = 0, tries = 0;
  for (size_t n = 0; n + 20 < full.size(); n += full.size() / 97) {
    WriteBytes(path, full.substr(0, n));
    ++tries;
    try {
      ReadEaf(path);
    } catch (const ParseError& e) {
      ++errors;
      EXPECT_TRUE(e.where().offset.has_value());
    }
  }
  EXPECT_EQ(errors, tries);  // a cut XML document is never well-formed
}

}  // namespace
}  // namespace csw
