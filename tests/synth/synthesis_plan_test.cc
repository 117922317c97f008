// The timing plan of synthesis (synth/synthesis_plan.h): target times from the
// seed's global rule and from per-dikey phasing, rests, lead-in, pushing.
// Phones and dictionaries are built by hand, so every expected time is
// computed here from the rule's definition.
#include "synth/synthesis_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace csw::dict {
namespace {

Phone P(const std::string& ipa, double a, double b) {
  Phone p;
  p.ipa = ipa;
  p.start_s = a;
  p.end_s = b;
  return p;
}

// "_ p a i t _": a CV key (p a), a lone vowel (i), a lone consonant (t).
std::vector<Phone> Phones() {
  return {P("", 0.0, 0.5), P("p", 0.5, 0.6), P("a", 0.6, 0.75), P("i", 0.75, 0.9), P("t", 0.9, 1.0), P("", 1.0, 1.2)};
}

DikeyUnit Unit(KeyCode from, KeyCode to, double duration, double phasing) {
  DikeyUnit u;
  u.from = from;
  u.to = to;
  u.start_s = 1.0;
  u.end_s = 1.0 + duration;
  u.phasing_s = phasing;
  return u;
}

TEST(SynthesisPlan, GlobalRuleTargetsMiddleOfConsonantVowelOnsetConsonantOnset) {
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  ASSERT_EQ(keys.size(), 5u);  // rest, CV, V, C, rest
  ASSERT_EQ(keys[1].type, KeyType::kCV);
  ASSERT_EQ(keys[2].type, KeyType::kVowelAlone);
  ASSERT_EQ(keys[3].type, KeyType::kConsonantAlone);
  Dictionary d;
  d.dikeys.push_back(Unit(KeyCode{}, KeyCode{keys[1].placement, keys[1].shape}, 0.3, 0.0));  // leave rest: 0.3 s
  d.dikeys.push_back(Unit(KeyCode{1, 5}, KeyCode{}, 0.45, NAN));                             // reach rest: 0.45 s
  PlanOptions o;
  o.shrinkage_units = 0;    // each succession's own mean (shrinkage: its own test)
  o.min_slot_fraction = 0;  // min_interval_s only (slots: their own test)
  o.rule = PhasingRule::kGlobal;
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  ASSERT_EQ(plan.keys.size(), 5u);
  EXPECT_DOUBLE_EQ(plan.lead_in_s, 0.0);            // first target 0.55 > 0.3
  EXPECT_NEAR(plan.keys[1].target_s, 0.55, 1e-12);  // middle of [p]
  EXPECT_NEAR(plan.keys[2].target_s, 0.75, 1e-12);  // onset of [i]
  EXPECT_NEAR(plan.keys[3].target_s, 0.90, 1e-12);  // onset of [t]
  EXPECT_NEAR(plan.keys[0].target_s, 0.25, 1e-12);  // 0.55 - 0.3
  EXPECT_NEAR(plan.keys[4].target_s, 1.35, 1e-12);  // 0.90 + 0.45
  EXPECT_TRUE(plan.keys[0].code.IsRest());
  EXPECT_TRUE(plan.keys[4].code.IsRest());
  EXPECT_NEAR(plan.duration_s, 1.35, 1e-12);  // the return to rest outlasts the audio
  for (int i = 1; i <= 3; ++i) EXPECT_EQ(plan.keys[static_cast<size_t>(i)].source, "global");
}

TEST(SynthesisPlan, PerDikeyPhasingUsesTheSuccessionThenTheCodeThenTheGlobalRule) {
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  const KeyCode cv{keys[1].placement, keys[1].shape}, v{keys[2].placement, keys[2].shape};
  Dictionary d;
  // Rest → CV: phasing -0.02 and -0.04 (mean -0.03); CV → V absent as a
  // succession but V reached from elsewhere with phasing +0.06; the lone
  // consonant never reached: the global rule.
  d.dikeys.push_back(Unit(KeyCode{}, cv, 0.2, -0.02));
  d.dikeys.push_back(Unit(KeyCode{}, cv, 0.4, -0.04));
  d.dikeys.push_back(Unit(KeyCode{2, 3}, v, 0.2, 0.06));
  PlanOptions o;
  o.shrinkage_units = 0;    // each succession's own mean (shrinkage: its own test)
  o.min_slot_fraction = 0;  // min_interval_s only (slots: their own test)
  o.rule = PhasingRule::kPerDikey;
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  EXPECT_NEAR(plan.keys[1].target_s, 0.5 - 0.03, 1e-12);  // A1 = onset of [p]
  EXPECT_EQ(plan.keys[1].source, "dikey");
  EXPECT_NEAR(plan.keys[2].target_s, 0.75 + 0.06, 1e-12);  // A1 = onset of [i]
  EXPECT_EQ(plan.keys[2].source, "code");
  EXPECT_NEAR(plan.keys[3].target_s, 0.90, 1e-12);
  EXPECT_EQ(plan.keys[3].source, "global");
  // Leaving rest: median of 0.2 and 0.4 = 0.3 s; nothing reaches rest: 0.4 s.
  EXPECT_NEAR(plan.keys[0].target_s, 0.47 - 0.3, 1e-12);
  EXPECT_NEAR(plan.keys[4].target_s, 0.90 + 0.4, 1e-12);
}

TEST(SynthesisPlan, PerDikeyPhasingPoolsUnitsOfTheKeysOwnTypeOnly) {
  // "_ m i i _": [m] has shape 5 and [i] placement 3, so "m i" is the CV
  // key 35 and the second [i] a lone vowel, also 35. Their A1 differ
  // (consonant onset, vowel onset), so a dictionary whose code-35 units are
  // of both types must not mix their phasing.
  const std::vector<Phone> phones = {P("", 0.0, 0.5), P("m", 0.5, 0.6), P("i", 0.6, 0.8), P("i", 0.8, 1.0),
                                     P("", 1.0, 1.2)};
  const std::vector<Key> keys = CueKeys(phones);
  ASSERT_EQ(keys.size(), 4u);  // rest, CV 35, V 35, rest
  ASSERT_EQ(keys[1].type, KeyType::kCV);
  ASSERT_EQ(keys[2].type, KeyType::kVowelAlone);
  ASSERT_EQ(keys[1].Code(), "35");
  ASSERT_EQ(keys[2].Code(), "35");
  const KeyCode k35{3, 5};
  PlanOptions o;
  o.shrinkage_units = 0;
  o.min_slot_fraction = 0;
  o.rule = PhasingRule::kPerDikey;
  auto typed = [](DikeyUnit u, KeyType t) {
    u.to_type = t;
    return u;
  };
  {
    // Rest → 35: a CV unit at -0.02 s, a lone-V unit at +0.09 s; 35 → 35: a
    // lone-V unit at +0.07 s and a CV unit at +0.01 s.
    Dictionary d;
    d.dikeys.push_back(typed(Unit(KeyCode{}, k35, 0.3, -0.02), KeyType::kCV));
    d.dikeys.push_back(typed(Unit(KeyCode{}, k35, 0.3, 0.09), KeyType::kVowelAlone));
    d.dikeys.push_back(typed(Unit(k35, k35, 0.3, 0.07), KeyType::kVowelAlone));
    d.dikeys.push_back(typed(Unit(k35, k35, 0.3, 0.01), KeyType::kCV));
    const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
    EXPECT_NEAR(plan.keys[1].target_s - plan.keys[1].a1_s, -0.02, 1e-12);  // the CV unit alone
    EXPECT_EQ(plan.keys[1].source, "dikey");
    EXPECT_NEAR(plan.keys[2].target_s - plan.keys[2].a1_s, 0.07, 1e-12);  // the lone-V 35 → 35 unit alone
    EXPECT_EQ(plan.keys[2].source, "dikey");
  }
  {
    // No lone-V unit reaches 35, but lone vowels reach other codes (+0.10,
    // +0.06): the lone vowel takes their mean, not the CV units' phasing.
    Dictionary d;
    d.dikeys.push_back(typed(Unit(KeyCode{}, k35, 0.3, -0.02), KeyType::kCV));
    d.dikeys.push_back(typed(Unit(k35, k35, 0.3, 0.01), KeyType::kCV));
    d.dikeys.push_back(typed(Unit(KeyCode{}, KeyCode{1, 5}, 0.3, 0.10), KeyType::kVowelAlone));
    d.dikeys.push_back(typed(Unit(KeyCode{}, KeyCode{4, 5}, 0.3, 0.06), KeyType::kVowelAlone));
    const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
    EXPECT_NEAR(plan.keys[2].target_s - plan.keys[2].a1_s, 0.08, 1e-12);
    EXPECT_EQ(plan.keys[2].source, "type");
  }
  {
    // A dictionary without types (files before them): units pool by code, as before.
    Dictionary d;
    d.dikeys.push_back(Unit(KeyCode{}, k35, 0.3, -0.02));
    d.dikeys.push_back(Unit(KeyCode{}, k35, 0.3, 0.06));
    d.dikeys.push_back(Unit(k35, k35, 0.3, 0.04));
    const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
    EXPECT_NEAR(plan.keys[1].target_s - plan.keys[1].a1_s, 0.02, 1e-12);  // mean of -0.02 and 0.06
    EXPECT_EQ(plan.keys[1].source, "dikey");
    EXPECT_NEAR(plan.keys[2].target_s - plan.keys[2].a1_s, 0.04, 1e-12);
    EXPECT_EQ(plan.keys[2].source, "dikey");
  }
}

TEST(SynthesisPlan, LeadInWhenTheFirstMovementWouldStartBeforeTimeZero) {
  std::vector<Phone> phones = {P("p", 0.0, 0.1), P("a", 0.1, 0.3), P("", 0.3, 0.5)};
  const std::vector<Key> keys = CueKeys(phones);
  Dictionary d;
  d.dikeys.push_back(Unit(KeyCode{}, KeyCode{keys[1].placement, keys[1].shape}, 0.5, 0.0));
  PlanOptions o;
  o.shrinkage_units = 0;    // each succession's own mean (shrinkage: its own test)
  o.min_slot_fraction = 0;  // min_interval_s only (slots: their own test)
  o.rule = PhasingRule::kGlobal;
  const SynthesisPlan plan = PlanKeys(keys, phones, 0.5, d, o);
  // First target 0.05 (middle of [p]) needs 0.5 s from rest: lead-in 0.45 s.
  EXPECT_NEAR(plan.lead_in_s, 0.45, 1e-12);
  EXPECT_NEAR(plan.keys[0].target_s, 0.0, 1e-12);
  EXPECT_NEAR(plan.keys[1].target_s, 0.5, 1e-12);
  EXPECT_NEAR(plan.keys[1].a1_s, 0.45, 1e-12);
}

TEST(SynthesisPlan, TargetsArePushedApartByTheMinimumInterval) {
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  Dictionary d;
  // The CV key's succession says +0.3 s (after the vowel's onset at 0.75).
  d.dikeys.push_back(Unit(KeyCode{}, KeyCode{keys[1].placement, keys[1].shape}, 0.3, 0.3));
  PlanOptions o;
  o.shrinkage_units = 0;    // each succession's own mean (shrinkage: its own test)
  o.min_slot_fraction = 0;  // min_interval_s only (slots: their own test)
  o.min_interval_s = 0.05;
  o.least_squares_spacing = false;  // later targets pushed
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  EXPECT_NEAR(plan.keys[1].target_s, 0.8, 1e-12);
  EXPECT_NEAR(plan.keys[2].target_s, 0.85, 1e-12);  // pushed from 0.75
  EXPECT_EQ(plan.keys[2].source, "global+pushed");
  EXPECT_NEAR(plan.keys[3].target_s, 0.90, 1e-12);  // 0.90 already 0.05 after
  for (size_t i = 1; i < plan.keys.size(); ++i) EXPECT_GT(plan.keys[i].target_s, plan.keys[i - 1].target_s);
}

TEST(SynthesisPlan, LeastSquaresSpacingOpensAShortSlotOnBothSides) {
  // As above: wanted 0.80, 0.75, 0.90 with gaps of at least 0.05 s. The
  // targets closest to those in the least-squares sense are 0.75, 0.80,
  // 0.90 (each of the first two moved 0.05: Σ squares 0.005, against 0.01
  // for pushing the second alone to 0.85); the third keeps its time.
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  Dictionary d;
  d.dikeys.push_back(Unit(KeyCode{}, KeyCode{keys[1].placement, keys[1].shape}, 0.3, 0.3));
  PlanOptions o;
  o.shrinkage_units = 0;
  o.min_slot_fraction = 0;
  o.min_interval_s = 0.05;
  ASSERT_TRUE(o.least_squares_spacing);  // the default
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  EXPECT_NEAR(plan.keys[1].target_s, 0.75, 1e-12);
  EXPECT_EQ(plan.keys[1].source, "dikey+advanced");
  EXPECT_NEAR(plan.keys[2].target_s, 0.80, 1e-12);
  EXPECT_EQ(plan.keys[2].source, "global+pushed");
  EXPECT_NEAR(plan.keys[3].target_s, 0.90, 1e-12);
  EXPECT_EQ(plan.keys[3].source, "global");
  // Two targets wanted at the same time, 0.75 (the CV key at A1 0.5 +
  // 0.25, the lone vowel at its onset): 0.725 and 0.775, the gap opened
  // around the time they share.
  Dictionary same;
  same.dikeys.push_back(Unit(KeyCode{}, KeyCode{keys[1].placement, keys[1].shape}, 0.3, 0.25));
  const SynthesisPlan chain = PlanKeys(keys, phones, 1.2, same, o);
  EXPECT_NEAR(chain.keys[1].target_s, 0.725, 1e-12);
  EXPECT_NEAR(chain.keys[2].target_s, 0.775, 1e-12);
  EXPECT_NEAR(chain.keys[3].target_s, 0.90, 1e-12);
}

TEST(SynthesisPlan, SuccessionMeansAreShrunkTowardsTheArrivingCodesMean) {
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  const KeyCode cv{keys[1].placement, keys[1].shape};
  Dictionary d;
  // Rest → CV once at -0.06; CV reached from elsewhere three times at +0.02.
  // Code mean over the four units: (-0.06 + 3 × 0.02) / 4 = 0; with k = 2:
  // (-0.06 + 2 × 0) / (1 + 2) = -0.02.
  d.dikeys.push_back(Unit(KeyCode{}, cv, 0.2, -0.06));
  for (int i = 0; i < 3; ++i) d.dikeys.push_back(Unit(KeyCode{2, 3}, cv, 0.2, 0.02));
  PlanOptions o;
  o.min_slot_fraction = 0;
  o.shrinkage_units = 2;
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  EXPECT_NEAR(plan.keys[1].target_s, 0.5 - 0.02, 1e-12);
  EXPECT_EQ(plan.keys[1].source, "dikey");
  o.shrinkage_units = 0;
  EXPECT_NEAR(PlanKeys(keys, phones, 1.2, d, o).keys[1].target_s, 0.5 - 0.06, 1e-12);
}

TEST(SynthesisPlan, SlotsAreAtLeastAFractionOfTheSuccessionsMedianDuration) {
  const std::vector<Phone> phones = Phones();
  const std::vector<Key> keys = CueKeys(phones);
  const KeyCode cv{keys[1].placement, keys[1].shape}, v{keys[2].placement, keys[2].shape};
  Dictionary d;
  // CV → V units of 0.3, 0.5 and 0.6 s: median 0.5; 0.6 × 0.5 = 0.3 s. The
  // global rule puts CV at 0.55 (middle of [p]) and V at 0.75: pushed to 0.85.
  for (double dur : {0.3, 0.5, 0.6}) d.dikeys.push_back(Unit(cv, v, dur, NAN));
  PlanOptions o;
  o.rule = PhasingRule::kGlobal;
  o.min_slot_fraction = 0.6;
  o.least_squares_spacing = false;  // later targets pushed
  const SynthesisPlan plan = PlanKeys(keys, phones, 1.2, d, o);
  EXPECT_NEAR(plan.keys[1].target_s, 0.55, 1e-12);
  EXPECT_NEAR(plan.keys[2].target_s, 0.85, 1e-12);
  EXPECT_EQ(plan.keys[2].source, "global+pushed");
  // V → C has no unit: the median of all units (0.5) gives 0.3 s too.
  EXPECT_NEAR(plan.keys[3].target_s, 1.15, 1e-12);
  PlanOptions bad = o;
  bad.min_slot_fraction = 1.5;
  EXPECT_THROW(PlanKeys(keys, phones, 1.2, d, bad), InvalidInput);
}

TEST(SynthesisPlan, MeanPhoneDurationOfPhonesAndOfADictionary) {
  EXPECT_NEAR(MeanPhoneDuration(Phones()), (0.1 + 0.15 + 0.15 + 0.1) / 4, 1e-12);
  Dictionary d;
  DiphoneUnit a;
  a.take = "t";
  a.phone1 = "p";
  a.phone1_start_s = 0.5;
  a.phone1_end_s = 0.6;
  a.phone2 = "a";
  a.phone2_start_s = 0.6;
  a.phone2_end_s = 0.8;
  DiphoneUnit b = a;  // a + _: [a] again (counted once) and a pause (not counted)
  b.phone1 = "a";
  b.phone1_start_s = 0.6;
  b.phone1_end_s = 0.8;
  b.phone2 = "_";
  b.phone2_start_s = 0.8;
  b.phone2_end_s = 1.0;
  d.diphones = {a, b};
  EXPECT_NEAR(MeanPhoneDuration(d), (0.1 + 0.2) / 2, 1e-12);
  EXPECT_TRUE(std::isnan(MeanPhoneDuration(Dictionary{})));
}

TEST(SynthesisPlan, BadInputGivesOneClearError) {
  std::vector<Key> keys = CueKeys(Phones());
  keys[1].consonant_phone = 42;
  try {
    PlanKeys(keys, Phones(), 1.2, Dictionary{}, PlanOptions{.rule = PhasingRule::kGlobal});
    FAIL() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("key 2: consonant phone index 42 outside the 6 phones"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(PlanKeys(CueKeys(Phones()), Phones(), 0.0, Dictionary{}), InvalidInput);
  PhasingRule r;
  EXPECT_TRUE(ParsePhasingRule("global", &r));
  EXPECT_EQ(r, PhasingRule::kGlobal);
  EXPECT_FALSE(ParsePhasingRule("seed", &r));
}

}  // namespace
}  // namespace csw::dict
