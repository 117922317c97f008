// Key-code labels and the undoable label model (core/labels.h).
#include "core/labels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"

namespace csw {
namespace {

LabelTier Points(const std::string& name, std::vector<std::pair<double, std::string>> marks, double end = 3.0) {
  LabelTier t{name, LabelTier::Kind::kPoint, 0.0, end, {}};
  for (const auto& [time, text] : marks) t.labels.push_back({time, time, text});
  return t;
}

// The model's marks as "time:code" strings, for whole-state comparisons.
std::string State(const LabelModel& m) {
  std::string s;
  for (size_t i = 0; i < m.size(); ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.3f:%s", i ? " " : "", m.at(i).start_s, m.at(i).text.c_str());
    s += buf;
  }
  return s;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "no error";
}

TEST(KeyCodes, ParsesEveryValidCodeAndNothingElse) {
  int valid = 0;
  for (int p = 0; p <= 9; ++p) {
    for (int s = 0; s <= 9; ++s) {
      const std::string text = std::to_string(p) + std::to_string(s);
      KeyCode c;
      const bool ok = TryParseKeyCode(text, &c);
      EXPECT_EQ(ok, p <= 5 && s <= 8) << text;
      if (ok) {
        EXPECT_EQ(c.placement, p);
        EXPECT_EQ(c.shape, s);
        EXPECT_EQ(c.Text(), text);
        ++valid;
      }
    }
  }
  EXPECT_EQ(valid, 6 * 9);  // placements 0-5 x shapes 0-8
  KeyCode c;
  EXPECT_TRUE(TryParseKeyCode(" 24 ", &c));
  EXPECT_EQ(c, (KeyCode{2, 4}));
  EXPECT_TRUE(TryParseKeyCode("00", &c));
  EXPECT_TRUE(c.IsRest());
  EXPECT_TRUE(TryParseKeyCode("03", &c));
  EXPECT_TRUE(c.IsFreeSpaceShape());
  for (const char* bad : {"", "2", "245", "a4", "2-", "-1", "2 4"}) EXPECT_FALSE(TryParseKeyCode(bad, &c)) << bad;
  EXPECT_EQ(KeyCodeProblem("69"), "placement 6 is not 0-5");
  EXPECT_EQ(KeyCodeProblem("19"), "shape 9 is not 0-8");
  EXPECT_EQ(KeyCodeProblem("x7"), "not two digits");
  EXPECT_EQ(KeyCodeProblem(" "), "empty label");
}

TEST(KeyCodes, BadLabelGivesOneClearError) {
  const LabelTier t = Points("keys", {{0.5, "00"}, {1.0, "24"}, {1.25, "x7"}, {2.0, "99"}});
  EXPECT_EQ(ErrorOf([&] { ReadKeyTier(t, "c.h5: take 's01'"); }),
            "c.h5: take 's01': tier 'keys': label 3 at 1.250 s: bad key code 'x7': not two digits (a key code is "
            "two digits PS: placement 0-5 then shape 0-8, 00 = rest)");
}

TEST(KeyCodes, IntervalTiersFromElanGiveMarksAtMidpoints) {
  // ELAN annotations of one or two frames around each target; gaps are empty intervals.
  LabelTier t{"keys",
              LabelTier::Kind::kInterval,
              0.0,
              2.0,
              {{0.0, 0.49, ""}, {0.49, 0.51, "00"}, {0.51, 1.0, ""}, {1.0, 1.2, "24"}, {1.2, 2.0, " "}}};
  const std::vector<KeyMark> m = ReadKeyTier(t, "a.eaf");
  ASSERT_EQ(m.size(), 2u);
  EXPECT_DOUBLE_EQ(m[0].time_s, 0.5);
  EXPECT_TRUE(m[0].code.IsRest());
  EXPECT_DOUBLE_EQ(m[1].time_s, 1.1);
  EXPECT_EQ(m[1].code, (KeyCode{2, 4}));
  t.labels[3].text = "2 4";
  EXPECT_EQ(ErrorOf([&] { ReadKeyTier(t, "a.eaf"); }),
            "a.eaf: tier 'keys': label 4 at 1.100 s: bad key code '2 4': not two digits (a key code is two digits "
            "PS: placement 0-5 then shape 0-8, 00 = rest)");
}

TEST(KeyCodes, ExpectedKeyTierReadsBackTheKeysWithTheirSpans) {
  const LabelTier t{"expected_keys",
                    LabelTier::Kind::kInterval,
                    0.0,
                    1.0,
                    {{0.0, 0.1, "00"}, {0.1, 0.3, "34"}, {0.3, 0.4, ""}, {0.4, 0.5, "15"}, {0.5, 1.0, "00"}}};
  const std::vector<ExpectedKey> k = ReadExpectedKeyTier(t, "c.h5: take 'a'");
  ASSERT_EQ(k.size(), 4u);
  EXPECT_EQ(k[1].code, (KeyCode{3, 4}));
  EXPECT_DOUBLE_EQ(k[1].start_s, 0.1);
  EXPECT_DOUBLE_EQ(k[1].end_s, 0.3);
  EXPECT_EQ(k[2].code, (KeyCode{1, 5}));
  EXPECT_DOUBLE_EQ(k[2].start_s, 0.4);
  EXPECT_TRUE(k[3].code.IsRest());
  LabelTier p = t;
  p.kind = LabelTier::Kind::kPoint;
  EXPECT_EQ(ErrorOf([&] { ReadExpectedKeyTier(p, "w"); }),
            "w: tier 'expected_keys' is a point tier; expected keys are an interval tier");
}

TEST(KeyTargets, ShapeAtKeysPlacementAtItsOwnTierWhenPresent) {
  Take take;
  take.tiers.push_back(Points("words", {}));
  take.tiers.push_back(Points("keys", {{0.2, "00"}, {0.61, "34"}, {1.02, "41"}}));
  take.tiers.push_back(Points("placement_targets", {{0.2, "00"}, {0.66, "34"}, {1.1, "41"}}));
  const KeyTargets t = ReadKeyTargets(take, "c.h5: take 'a'");
  EXPECT_TRUE(t.placement_from_own_tier);
  ASSERT_EQ(t.shape.size(), 3u);
  ASSERT_EQ(t.placement.size(), 3u);
  EXPECT_DOUBLE_EQ(t.shape[1].time_s, 0.61);
  EXPECT_EQ(t.shape[1].value, 4);  // shape of 34
  EXPECT_DOUBLE_EQ(t.placement[1].time_s, 0.66);
  EXPECT_EQ(t.placement[1].value, 3);  // placement of 34
  EXPECT_EQ(t.placement[2].value, 4);
  EXPECT_EQ(t.shape[2].value, 1);
  // Without the placement tier both components are at the keys tier's marks.
  take.tiers.pop_back();
  const KeyTargets u = ReadKeyTargets(take, "w");
  EXPECT_FALSE(u.placement_from_own_tier);
  ASSERT_EQ(u.placement.size(), 3u);
  EXPECT_DOUBLE_EQ(u.placement[1].time_s, 0.61);
  EXPECT_EQ(u.placement[1].value, 3);
  // A missing keys tier names the take and the tiers present.
  EXPECT_EQ(ErrorOf([&] {
              ReadKeyTargets(take, "c.h5: take 'a'", {"targets", ""});
            }),
            "c.h5: take 'a': no key label tier 'targets' (tiers: 'words', 'keys')");
  // A bad code in the placement tier is reported like one in the keys tier.
  take.tiers.push_back(Points("placement_targets", {{0.2, "00"}, {0.7, "3"}}));
  EXPECT_EQ(ErrorOf([&] { ReadKeyTargets(take, "w"); }),
            "w: tier 'placement_targets': label 2 at 0.700 s: bad key code '3': not two digits (a key code is two "
            "digits PS: placement 0-5 then shape 0-8, 00 = rest)");
}

TEST(LabelModel, EditsUndoAndRedoRoundTrip) {
  LabelModel m(Points("keys", {{1.0, "41"}, {0.5, "34"}, {2.0, "00"}}), true, "t");
  // Sorted by time on construction.
  const std::string s0 = "0.500:34 1.000:41 2.000:00";
  EXPECT_EQ(State(m), s0);
  LabelHistory h(&m);
  EXPECT_FALSE(h.CanUndo());
  EXPECT_TRUE(h.IsClean());

  h.Push(MakeAddLabel(1.5, "13"));
  const std::string s1 = "0.500:34 1.000:41 1.500:13 2.000:00";
  EXPECT_EQ(State(m), s1);
  EXPECT_EQ(h.UndoText(), "add key 13 at 1.500 s");

  h.Push(MakeMoveLabel(0, 1.2));  // 34 from 0.5 to 1.2: now after 41
  const std::string s2 = "1.000:41 1.200:34 1.500:13 2.000:00";
  EXPECT_EQ(State(m), s2);
  EXPECT_EQ(h.UndoText(), "move key 34 from 0.500 s to 1.200 s");

  h.Push(MakeRelabel(2, "15"));
  const std::string s3 = "1.000:41 1.200:34 1.500:15 2.000:00";
  EXPECT_EQ(State(m), s3);
  EXPECT_EQ(h.UndoText(), "relabel key 13 as 15 at 1.500 s");

  h.Push(MakeDeleteLabel(0));
  const std::string s4 = "1.200:34 1.500:15 2.000:00";
  EXPECT_EQ(State(m), s4);
  EXPECT_EQ(h.UndoText(), "delete key 41 at 1.000 s");
  EXPECT_FALSE(h.IsClean());

  // Undo everything, state by state, then redo everything.
  const std::vector<std::string> states = {s0, s1, s2, s3, s4};
  for (int i = 3; i >= 0; --i) {
    h.Undo();
    EXPECT_EQ(State(m), states[static_cast<size_t>(i)]) << "after undo to " << i;
  }
  EXPECT_FALSE(h.CanUndo());
  EXPECT_TRUE(h.IsClean());
  h.Undo();  // nothing to undo: no change
  EXPECT_EQ(State(m), s0);
  for (int i = 1; i <= 4; ++i) {
    h.Redo();
    EXPECT_EQ(State(m), states[static_cast<size_t>(i)]) << "after redo to " << i;
  }
  EXPECT_FALSE(h.CanRedo());

  // A new edit after undos drops the redo branch.
  h.Undo();
  h.Undo();
  EXPECT_EQ(State(m), s2);
  EXPECT_EQ(h.RedoText(), "relabel key 13 as 15 at 1.500 s");
  h.Push(MakeAddLabel(0.1, "00"));
  EXPECT_EQ(State(m), "0.100:00 " + s2);
  EXPECT_FALSE(h.CanRedo());
  EXPECT_EQ(h.count(), 3u);
  h.Undo();
  EXPECT_EQ(State(m), s2);
}

TEST(LabelModel, EqualTimesUndoToTheSameOrder) {
  // Two marks at one time (a shape target and a free-space shape): moving the
  // second and undoing restores the exact order.
  LabelModel m(Points("keys", {{1.0, "24"}, {1.0, "03"}, {1.0, "51"}}));
  LabelHistory h(&m);
  const std::string before = State(m);
  h.Push(MakeMoveLabel(1, 1.0));  // same time: goes after the equal marks
  EXPECT_EQ(State(m), "1.000:24 1.000:51 1.000:03");
  h.Undo();
  EXPECT_EQ(State(m), before);
}

TEST(LabelModel, BadEditsChangeNothingAndSayWhy) {
  LabelModel m(Points("keys", {{0.5, "34"}}), true, "c.h5: take 'a'");
  LabelHistory h(&m);
  const long rev = m.revision();
  EXPECT_EQ(ErrorOf([&] { h.Push(MakeAddLabel(1.0, "96")); }),
            "c.h5: take 'a': tier 'keys': bad key code '96': placement 9 is not 0-5 (a key code is two digits PS: "
            "placement 0-5 then shape 0-8, 00 = rest)");
  EXPECT_EQ(ErrorOf([&] { h.Push(MakeRelabel(0, "1")); }),
            "c.h5: take 'a': tier 'keys': bad key code '1': not two digits (a key code is two digits PS: placement "
            "0-5 then shape 0-8, 00 = rest)");
  EXPECT_EQ(ErrorOf([&] { h.Push(MakeMoveLabel(0, 4.0)); }),
            "c.h5: take 'a': tier 'keys': time 4.000 s is outside [0.000 s, 3.000 s]");
  EXPECT_EQ(ErrorOf([&] { h.Push(MakeAddLabel(std::nan(""), "11")); }),
            "c.h5: take 'a': tier 'keys': time nan s is outside [0.000 s, 3.000 s]");
  EXPECT_EQ(ErrorOf([&] { h.Push(MakeDeleteLabel(3)); }), "c.h5: take 'a': tier 'keys': no label 4 (1 labels)");
  EXPECT_EQ(State(m), "0.500:34");
  EXPECT_EQ(m.revision(), rev);
  EXPECT_FALSE(h.CanUndo());
  // A tier with a bad code cannot be opened with key codes checked, but can without.
  const LabelTier bad = Points("keys", {{0.5, "3x"}});
  EXPECT_EQ(ErrorOf([&] { LabelModel x(bad, true, "f.TextGrid"); }),
            "f.TextGrid: tier 'keys': label 1 at 0.500 s: bad key code '3x': not two digits (a key code is two "
            "digits PS: placement 0-5 then shape 0-8, 00 = rest)");
  LabelModel free_text(bad, false);
  LabelHistory fh(&free_text);
  fh.Push(MakeRelabel(0, "35"));
  EXPECT_EQ(State(free_text), "0.500:35");
  EXPECT_EQ(free_text.Find(0.52, 0.05), 0);
  EXPECT_EQ(free_text.Find(0.6, 0.05), -1);
}

}  // namespace
}  // namespace csw
