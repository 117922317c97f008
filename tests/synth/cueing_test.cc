// LfPC rules on hand-worked examples. Phone lists are written out by hand so the
// expected keys do not depend on espeak-ng's version; the codes were worked out
// from the tables of ../shared/docs/cued-speech.md (placement first, then shape).
#include "synth/cueing.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

namespace csw {
namespace {

// "b ɔ̃ / ʒ u ʁ": tokens are IPA phones, "/" starts a new word, "#" is a pause.
// Each phone lasts 0.1 s, from t = 0.
std::vector<Phone> MakePhones(const std::string& spec) {
  std::vector<Phone> phones;
  std::istringstream in(spec);
  std::string tok;
  int word = 0;
  double t = 0.0;
  while (in >> tok) {
    if (tok == "/") {
      ++word;
      continue;
    }
    Phone p;
    p.ipa = tok == "#" ? "" : tok;
    p.start_s = t;
    p.end_s = t + 0.1;
    p.word = tok == "#" ? -1 : word;
    if (tok == "#") ++word;
    t += 0.1;
    phones.push_back(p);
  }
  return phones;
}

std::string Codes(const std::vector<Key>& keys) {
  std::string s;
  for (const Key& k : keys) s += (s.empty() ? "" : " ") + k.Code();
  return s;
}

std::string CodesOf(const std::string& spec) { return Codes(CueKeys(MakePhones(spec))); }

TEST(Cueing, ShapeTableMatchesCuedSpeechDoc) {
  const std::vector<std::pair<std::string, int>> shapes = {
      {"p", 1}, {"d", 1}, {"ʒ", 1}, {"k", 2}, {"v", 2}, {"z", 2}, {"s", 3}, {"ʁ", 3}, {"b", 4}, {"n", 4}, {"ɥ", 4},
      {"t", 5}, {"m", 5}, {"f", 5}, {"l", 6}, {"ʃ", 6}, {"ɲ", 6}, {"w", 6}, {"ɡ", 7}, {"j", 8}, {"ŋ", 8}};
  for (const auto& [ipa, shape] : shapes) {
    EXPECT_EQ(ConsonantShape(ipa), shape) << ipa;
    EXPECT_TRUE(IsConsonant(ipa)) << ipa;
    EXPECT_FALSE(IsVowel(ipa)) << ipa;
  }
  EXPECT_EQ(ConsonantShape("a"), 0);
  EXPECT_EQ(ConsonantShape("h"), 0);
  EXPECT_EQ(ConsonantShape(""), 0);
}

TEST(Cueing, PlacementTableMatchesCuedSpeechDoc) {
  const std::vector<std::pair<std::string, int>> placements = {{"a", 1}, {"o", 1}, {"œ", 1}, {"ə", 1}, {"ɛ̃", 2},
                                                               {"ø", 2}, {"i", 3}, {"ɔ̃", 3}, {"ɑ̃", 3}, {"ɛ", 4},
                                                               {"u", 4}, {"ɔ", 4}, {"y", 5}, {"e", 5}, {"œ̃", 5}};
  for (const auto& [ipa, placement] : placements) {
    EXPECT_EQ(VowelPlacement(ipa), placement) << ipa;
    EXPECT_TRUE(IsVowel(ipa)) << ipa;
    EXPECT_FALSE(IsConsonant(ipa)) << ipa;
  }
  EXPECT_EQ(VowelPlacement("ɥ"), 0);  // a semi-vowel is a consonant for cueing
  EXPECT_EQ(VowelPlacement("j"), 0);
  EXPECT_EQ(VowelPlacement("w"), 0);
}

TEST(Cueing, Bonjour) {
  // bɔ̃: shape 4 (b), placement 3 (ɔ̃) -> 34; ʒu: 1, 4 -> 41; final ʁ alone at the side -> 13.
  const std::vector<Key> keys = CueKeys(MakePhones("b ɔ̃ ʒ u ʁ"));
  EXPECT_EQ(Codes(keys), "00 34 41 13 00");
  ASSERT_EQ(keys.size(), 5u);
  EXPECT_EQ(keys[0].type, KeyType::kRest);
  EXPECT_EQ(keys[1].type, KeyType::kCV);
  EXPECT_EQ(keys[1].consonant_phone, 0);
  EXPECT_EQ(keys[1].vowel_phone, 1);
  EXPECT_DOUBLE_EQ(keys[1].a1_s, 0.0);
  EXPECT_DOUBLE_EQ(keys[1].end_s, 0.2);
  EXPECT_EQ(keys[2].consonant_phone, 2);
  EXPECT_DOUBLE_EQ(keys[2].a1_s, 0.2);
  EXPECT_EQ(keys[3].type, KeyType::kConsonantAlone);
  EXPECT_EQ(keys[3].consonant_phone, 4);
  EXPECT_EQ(keys[3].vowel_phone, -1);
  EXPECT_DOUBLE_EQ(keys[3].a1_s, 0.4);
  EXPECT_NEAR(keys[3].end_s, 0.5, 1e-12);
  EXPECT_EQ(keys[4].type, KeyType::kRest);
  EXPECT_NEAR(keys[4].a1_s, 0.5, 1e-12);
}

TEST(Cueing, LiaisonLesAmis) {
  // le: 6 on the throat (e) -> 56; liaison za: 2 at the side -> 12; mi: 5 at the mouth -> 35.
  EXPECT_EQ(CodesOf("l e / z a m i"), "00 56 12 35 00");
}

TEST(Cueing, Schwa) {
  // "le petit": lə 16, pə 11, ti 35 (ə is a side vowel).
  EXPECT_EQ(CodesOf("l ə / p ə t i"), "00 16 11 35 00");
}

TEST(Cueing, SemiVowelsAreConsonants) {
  EXPECT_EQ(CodesOf("w i"), "00 36 00");       // oui: w shape 6, i mouth
  EXPECT_EQ(CodesOf("ɥ i t"), "00 34 15 00");  // huit: ɥ shape 4; t alone at the side
  EXPECT_EQ(CodesOf("j ø"), "00 28 00");       // yeux: j shape 8, ø cheek bone
  // cuisinier k ɥ i z i n j e: k before a consonant alone (12), ɥi 34, zi 32,
  // n before j alone (14), je 58.
  EXPECT_EQ(CodesOf("k ɥ i z i n j e"), "00 12 34 32 14 58 00");
}

TEST(Cueing, LoneVowelAcrossWords) {
  // "il a": i with no consonant -> shape 5 at the mouth (35); la across the word
  // boundary (enchaînement) -> 16.
  const std::vector<Key> keys = CueKeys(MakePhones("i l / a"));
  EXPECT_EQ(Codes(keys), "00 35 16 00");
  EXPECT_EQ(keys[1].type, KeyType::kVowelAlone);
  EXPECT_EQ(keys[1].vowel_phone, 0);
  EXPECT_EQ(keys[1].consonant_phone, -1);
  EXPECT_EQ(keys[2].consonant_phone, 1);
  EXPECT_EQ(keys[2].vowel_phone, 2);
}

TEST(Cueing, ConsonantCluster) {
  // strict s t ʁ i k t: s alone 13, t alone 15, ʁi 33, k alone 12, t alone 15.
  EXPECT_EQ(CodesOf("s t ʁ i k t"), "00 13 15 33 12 15 00");
}

TEST(Cueing, VowelSequenceAndNasals) {
  EXPECT_EQ(CodesOf("k a o"), "00 12 15 00");         // chaos: o alone
  EXPECT_EQ(CodesOf("œ̃"), "00 55 00");                // un
  EXPECT_EQ(CodesOf("v ɛ̃"), "00 22 00");              // vin
  EXPECT_EQ(CodesOf("k ɑ̃ p i ŋ"), "00 32 31 18 00");  // camping
  EXPECT_EQ(CodesOf("a ɲ o"), "00 15 16 00");         // agneau
  EXPECT_EQ(CodesOf("ɡ a t o"), "00 17 15 00");       // gâteau
}

TEST(Cueing, PausesBreakSyllables) {
  // A consonant before a pause is cued alone; a vowel after it is cued alone.
  EXPECT_EQ(CodesOf("s a k # a"), "00 13 12 15 00");
  EXPECT_EQ(CodesOf("b ɔ̃ # a m i"), "00 34 15 35 00");
  // Without the pause the k takes the vowel.
  EXPECT_EQ(CodesOf("s a k a"), "00 13 12 00");
}

TEST(Cueing, UncuedSoundsAreSkipped) {
  // An [h] (English loanword) is not cued and does not break the syllable.
  EXPECT_EQ(CodesOf("h o l d œ p"), "00 15 16 11 11 00");
  EXPECT_EQ(CodesOf("t h a"), "00 15 00");
}

TEST(Cueing, EmptyAndSilentUtterances) {
  const std::vector<Key> none = CueKeys({});
  ASSERT_EQ(none.size(), 1u);
  EXPECT_EQ(none[0].Code(), "00");
  const std::vector<Key> silent = CueKeys(MakePhones("# #"));
  ASSERT_EQ(silent.size(), 1u);
  EXPECT_EQ(silent[0].type, KeyType::kRest);
  EXPECT_DOUBLE_EQ(silent[0].end_s, 0.2);
}

}  // namespace
}  // namespace csw
