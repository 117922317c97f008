// Take selection (--takes / fit --train) on plain lists of take names and
// frame counts: every syntax, escapes, fill versions and errors.
#include "workbench/jobs/take_selection.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"

namespace csw::jobs {
namespace {

const std::vector<TakeInfo> kTakes = {{"h001", 100},
                                      {"h002", 200},
                                      {"h010", 50},
                                      {"sentence_01a", 10},
                                      {"sentence_03", 10},
                                      {"sentence_06", 10},
                                      {"subj@home", 300},
                                      {"a,b", 40},
                                      {"star*", 7},
                                      {"h001.filled", 100},
                                      {"h001.filled-2", 100},
                                      {"x.filled", 20},
                                      {"notes.filled-up", 30},
                                      {"h002.filled-02", 200}};

// (take, first, count) of each selected range.
struct Sel {
  std::string take;
  int64_t first, count;
  bool operator==(const Sel&) const = default;
};
std::vector<Sel> Select(const std::vector<std::string>& args) {
  std::vector<Sel> out;
  for (const TakeRange& r : SelectTakes(kTakes, args, "corpus.h5")) out.push_back({r.take, r.first, r.count});
  return out;
}
std::string ErrorOf(const std::vector<std::string>& args) {
  try {
    SelectTakes(kTakes, args, "corpus.h5");
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TakeSelection, NamesAndFrameRanges) {
  EXPECT_EQ(Select({"h002"}), (std::vector<Sel>{{"h002", 0, 200}}));
  EXPECT_EQ(Select({"h002@10:30"}), (std::vector<Sel>{{"h002", 10, 20}}));
  EXPECT_EQ(Select({"h002@150:"}), (std::vector<Sel>{{"h002", 150, 50}}));
  EXPECT_EQ(Select({"h002@:5"}), (std::vector<Sel>{{"h002", 0, 5}}));
  EXPECT_EQ(Select({"h002@:"}), (std::vector<Sel>{{"h002", 0, 200}}));
}

TEST(TakeSelection, PercentagesRoundDown) {
  EXPECT_EQ(Select({"h002@:50%"}), (std::vector<Sel>{{"h002", 0, 100}}));
  EXPECT_EQ(Select({"h002@50%:"}), (std::vector<Sel>{{"h002", 100, 100}}));
  // 7 frames: 33 % → frame 2 (2.31 rounded down), 66 % → 4 (4.62).
  EXPECT_EQ(Select({"star\\*@33%:66%"}), (std::vector<Sel>{{"star*", 2, 2}}));
  EXPECT_EQ(Select({"h010@10:100%"}), (std::vector<Sel>{{"h010", 10, 40}}));
}

TEST(TakeSelection, CommaSeparatedListsAndRepeatedArguments) {
  EXPECT_EQ(Select({"h001,h010@:10", "sentence_03"}),
            (std::vector<Sel>{{"h001", 0, 100}, {"h010", 0, 10}, {"sentence_03", 0, 10}}));
  // The same take and frames twice: selected once, at its first place.
  EXPECT_EQ(Select({"h010,h001,h010"}), (std::vector<Sel>{{"h010", 0, 50}, {"h001", 0, 100}}));
}

TEST(TakeSelection, GlobPatterns) {
  // Generated fill versions are left out; h002.filled-02 is an ordinary take.
  EXPECT_EQ(Select({"h00*"}), (std::vector<Sel>{{"h001", 0, 100}, {"h002", 0, 200}, {"h002.filled-02", 0, 200}}));
  EXPECT_EQ(Select({"h0?0"}), (std::vector<Sel>{{"h010", 0, 50}}));
  EXPECT_EQ(Select({"sentence_0[1-5]*"}), (std::vector<Sel>{{"sentence_01a", 0, 10}, {"sentence_03", 0, 10}}));
  EXPECT_EQ(Select({"sentence_0[!1-5]"}), (std::vector<Sel>{{"sentence_06", 0, 10}}));
  EXPECT_EQ(Select({"sentence_0[^1-5]"}), (std::vector<Sel>{{"sentence_06", 0, 10}}));
  EXPECT_EQ(Select({"sentence_0[36]"}), (std::vector<Sel>{{"sentence_03", 0, 10}, {"sentence_06", 0, 10}}));
  // A range applies to every match.
  EXPECT_EQ(Select({"h00?@:10%"}), (std::vector<Sel>{{"h001", 0, 10}, {"h002", 0, 20}}));
  // A pattern naming .filled also matches fill versions; so does any pattern
  // that mentions "fill" (what a user types to mean them).
  EXPECT_EQ(Select({"h001.filled*"}), (std::vector<Sel>{{"h001.filled", 0, 100}, {"h001.filled-2", 0, 100}}));
  EXPECT_EQ(Select({"h001*filled"}), (std::vector<Sel>{{"h001.filled", 0, 100}}));
  EXPECT_EQ(Select({"h001.fill*"}), (std::vector<Sel>{{"h001.filled", 0, 100}, {"h001.filled-2", 0, 100}}));
  // A pattern that matches only fill versions without saying so names them.
  EXPECT_EQ(ErrorOf({"h001?*"}),
            "corpus.h5: no take matches the pattern 'h001?*' (2 generated fill version(s) do: patterns without "
            "\"fill\" skip them)");
  // '*' alone: every take but the generated fill versions.
  EXPECT_EQ(Select({"*"}).size(), kTakes.size() - 2);
}

TEST(TakeSelection, EscapesAndNamesWithSpecialCharacters) {
  // The exact name of a take selects it, whatever it contains.
  EXPECT_EQ(Select({"subj@home"}), (std::vector<Sel>{{"subj@home", 0, 300}}));
  EXPECT_EQ(Select({"star*"}), (std::vector<Sel>{{"star*", 0, 7}}));
  // Escaped: the same takes, and ranges of them.
  EXPECT_EQ(Select({"subj\\@home"}), (std::vector<Sel>{{"subj@home", 0, 300}}));
  EXPECT_EQ(Select({"subj\\@home@:10%"}), (std::vector<Sel>{{"subj@home", 0, 30}}));
  EXPECT_EQ(Select({"subj@home@100:200"}), (std::vector<Sel>{{"subj@home", 100, 100}}));
  EXPECT_EQ(Select({"a\\,b,h010"}), (std::vector<Sel>{{"a,b", 0, 40}, {"h010", 0, 50}}));
  EXPECT_EQ(Select({"a\\,b@:1"}), (std::vector<Sel>{{"a,b", 0, 1}}));
  // An escaped '*' is literal: "star\*" is the take "star*", not a pattern.
  EXPECT_EQ(Select({"star\\*"}), (std::vector<Sel>{{"star*", 0, 7}}));
  EXPECT_EQ(Select({"s*\\@*"}), (std::vector<Sel>{{"subj@home", 0, 300}}));
}

TEST(TakeSelection, CanonicalSpecsParseBackToTheSameFrames) {
  const std::vector<TakeRange> ranges = SelectTakes(kTakes, {"subj@home@:50%,a\\,b,star\\*@1:3,h00?"}, "");
  ASSERT_EQ(ranges.size(), 5u);
  EXPECT_EQ(ranges[0].spec, "subj\\@home@:50%");
  EXPECT_EQ(ranges[1].spec, "a\\,b");
  EXPECT_EQ(ranges[2].spec, "star\\*@1:3");
  EXPECT_EQ(ranges[3].spec, "h001");
  for (const TakeRange& r : ranges) {
    const std::vector<TakeRange> again = SelectTakes(kTakes, {r.spec}, "");
    ASSERT_EQ(again.size(), 1u) << r.spec;
    EXPECT_EQ(again[0].take, r.take);
    EXPECT_EQ(again[0].first, r.first);
    EXPECT_EQ(again[0].count, r.count);
  }
  EXPECT_EQ(EscapeTakeName("a\\b*?[x]@,"), "a\\\\b\\*\\?\\[x\\]\\@\\,");
  EXPECT_EQ(SplitTakeList({"a,b\\,c", "", "d"}), (std::vector<std::string>{"a", "b\\,c", "d"}));
}

TEST(TakeSelection, DefaultIsEveryTakeButGeneratedFillVersions) {
  const std::vector<Sel> all = Select({});
  std::vector<std::string> names;
  for (const Sel& s : all) names.push_back(s.take);
  // h001.filled and h001.filled-2 are fill versions of h001; x.filled has no
  // take "x", notes.filled-up and h002.filled-02 are not names --fill makes.
  EXPECT_EQ(names,
            (std::vector<std::string>{"h001", "h002", "h010", "sentence_01a", "sentence_03", "sentence_06", "subj@home",
                                      "a,b", "star*", "x.filled", "notes.filled-up", "h002.filled-02"}));
  // A fill version named explicitly is selected.
  EXPECT_EQ(Select({"h001.filled-2"}), (std::vector<Sel>{{"h001.filled-2", 0, 100}}));
}

TEST(TakeSelection, GeneratedFillVersionRule) {
  const std::set<std::string> names = {"t", "t.filled", "a.filled", "b"};
  EXPECT_TRUE(IsGeneratedFillVersion("t.filled", names));
  EXPECT_TRUE(IsGeneratedFillVersion("t.filled-2", names));
  EXPECT_TRUE(IsGeneratedFillVersion("t.filled-17", names));
  EXPECT_TRUE(IsGeneratedFillVersion("t.filled.filled", names));  // a fill of the fill version t.filled
  EXPECT_FALSE(IsGeneratedFillVersion("t.filled-1", names));      // --fill never makes -1
  EXPECT_FALSE(IsGeneratedFillVersion("t.filled-02", names));
  EXPECT_FALSE(IsGeneratedFillVersion("t.filled-x", names));
  EXPECT_FALSE(IsGeneratedFillVersion("t.filledx", names));
  EXPECT_FALSE(IsGeneratedFillVersion("a.filled", names));  // no take "a"
  EXPECT_FALSE(IsGeneratedFillVersion("b.unfilled", names));
  EXPECT_FALSE(IsGeneratedFillVersion(".filled", {""}));
  EXPECT_EQ(FilledTakeName({"t"}, "t"), "t.filled");
  EXPECT_EQ(FilledTakeName({"t", "t.filled", "t.filled-2"}, "t"), "t.filled-3");
  // Every name FilledTakeName makes is recognised.
  std::set<std::string> existing = {"t"};
  for (int i = 0; i < 5; ++i) {
    const std::string n = FilledTakeName(existing, "t");
    EXPECT_TRUE(IsGeneratedFillVersion(n, existing)) << n;
    existing.insert(n);
  }
}

TEST(TakeSelection, ErrorsNameTheItem) {
  EXPECT_EQ(ErrorOf({"nope"}), "corpus.h5: no take named 'nope'");
  EXPECT_EQ(ErrorOf({"no\\@pe"}), "corpus.h5: no take named 'no@pe' (item 'no\\@pe')");
  EXPECT_EQ(ErrorOf({"z*"}), "corpus.h5: no take matches the pattern 'z*'");
  EXPECT_EQ(ErrorOf({"h001.filled-9"}), "corpus.h5: no take named 'h001.filled-9'");
  EXPECT_EQ(ErrorOf({"h002@9:3"}), "corpus.h5: take 'h002@9:3': end is not after first");
  EXPECT_EQ(ErrorOf({"h002@0:201"}),
            "corpus.h5: take 'h002@0:201': frames [0, 201) are not inside the take's 200 "
            "frames");
  EXPECT_EQ(ErrorOf({"h002@100%:"}),
            "corpus.h5: take 'h002@100%:': frames [200, 200) are not inside the take's 200 "
            "frames");
  EXPECT_EQ(ErrorOf({"h002@x:"}),
            "corpus.h5: take 'h002@x:': 'x' is not a frame number or a percentage (expected name@first:end)");
  EXPECT_EQ(ErrorOf({"h002@:101%"}), "corpus.h5: take 'h002@:101%': percentage above 100");
  EXPECT_NE(ErrorOf({"h002@5"}).find("expected name@first:end"), std::string::npos);
  EXPECT_NE(ErrorOf({"@1:2"}).find("no take name"), std::string::npos);
  EXPECT_NE(ErrorOf({"h00[1"}).find("without a closing ']'"), std::string::npos);
  EXPECT_NE(ErrorOf({"h00\\"}).find("lone backslash"), std::string::npos);
  EXPECT_NE(ErrorOf({"h001,,h002"}).find("empty item"), std::string::npos);
  EXPECT_NE(ErrorOf({"h001,"}).find("empty item"), std::string::npos);
  EXPECT_NE(ErrorOf({"sentence_0[5-1]"}).find("reversed"), std::string::npos);
}

TEST(TakeSelection, EmptyCorpusIsAnError) {
  try {
    SelectTakes({}, {}, "empty.h5");
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "empty.h5: no take to use");
  }
}

TEST(TakeSelection, TrainingSpecsMarkOverlappingRanges) {
  TakeRange second_half{"h002@50%:", "h002", 100, 100};
  EXPECT_TRUE(TrainingSpecOverlaps("h002", second_half, 200));
  EXPECT_TRUE(TrainingSpecOverlaps("h002@90:110", second_half, 200));
  EXPECT_FALSE(TrainingSpecOverlaps("h002@:50%", second_half, 200));
  EXPECT_FALSE(TrainingSpecOverlaps("h001", second_half, 200));
  EXPECT_TRUE(TrainingSpecOverlaps("h00*", second_half, 200));
  TakeRange home{"subj\\@home", "subj@home", 0, 300};
  EXPECT_TRUE(TrainingSpecOverlaps("subj\\@home", home, 300));
  EXPECT_TRUE(TrainingSpecOverlaps("subj@home", home, 300));  // stored unescaped by older versions
  EXPECT_FALSE(TrainingSpecOverlaps("subj", home, 300));
}

}  // namespace
}  // namespace csw::jobs
