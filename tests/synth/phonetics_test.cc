// The phonetic front end through the real libespeak-ng (French voice).
#include "synth/phonetics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/build_paths.h"
#include "core/error.h"
#include "synth/cueing.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

std::string SpokenIpa(const Utterance& u) {
  std::string s;
  for (const Phone& p : u.phones)
    if (!p.ipa.empty()) s += (s.empty() ? "" : " ") + p.ipa;
  return s;
}

std::string Codes(const std::vector<Key>& keys) {
  std::string s;
  for (const Key& k : keys) s += (s.empty() ? "" : " ") + k.Code();
  return s;
}

// Phones contiguous from 0 to the end of the audio, each with start < end.
void ExpectContiguous(const Utterance& u) {
  ASSERT_FALSE(u.phones.empty());
  EXPECT_DOUBLE_EQ(u.phones.front().start_s, 0.0);
  for (size_t i = 0; i < u.phones.size(); ++i) {
    EXPECT_LT(u.phones[i].start_s, u.phones[i].end_s) << i;
    if (i > 0) {
      EXPECT_DOUBLE_EQ(u.phones[i].start_s, u.phones[i - 1].end_s) << i;
    }
    if (i > 0 && u.phones[i].ipa.empty()) {
      EXPECT_FALSE(u.phones[i - 1].ipa.empty()) << "pauses merged";
    }
  }
  if (!u.audio.samples.empty()) {
    EXPECT_NEAR(u.phones.back().end_s, u.audio.duration_s(), 1e-9);
  }
}

TEST(Phonetics, EspeakTable) {
  EXPECT_EQ(EspeakToIpa("O~"), "ɔ̃");
  EXPECT_EQ(EspeakToIpa("A~"), "ɑ̃");
  EXPECT_EQ(EspeakToIpa("E~"), "ɛ̃");
  EXPECT_EQ(EspeakToIpa("W~"), "œ̃");
  EXPECT_EQ(EspeakToIpa("r"), "ʁ");
  EXPECT_EQ(EspeakToIpa("Z"), "ʒ");
  EXPECT_EQ(EspeakToIpa("S"), "ʃ");
  EXPECT_EQ(EspeakToIpa("Y"), "ø");
  EXPECT_EQ(EspeakToIpa("W"), "œ");
  EXPECT_EQ(EspeakToIpa("@-"), "ə");
  EXPECT_EQ(EspeakToIpa("n^"), "ɲ");
  EXPECT_EQ(EspeakToIpa("g"), "ɡ");
  EXPECT_EQ(EspeakToIpa("z2"), "z");
  EXPECT_EQ(EspeakToIpa("dZ"), "d ʒ");
  EXPECT_EQ(EspeakToIpaPhones("tS"), (std::vector<std::string>{"t", "ʃ"}));
  EXPECT_EQ(EspeakToIpa("no-such"), "");
  EXPECT_EQ(EspeakToIpa("_:"), "");
  EXPECT_TRUE(IsEspeakPause("_|"));
  EXPECT_FALSE(IsEspeakPause("a"));
  // Every mapped phoneme is one the cueing rules know, except the uncued [h], [ʔ].
  for (const char* name :
       {"a", "e", "E", "i", "o", "O", "u", "y", "Y",  "W", "@", "A~", "E~", "O~", "W~", "p", "b", "t",  "d",  "k", "g",
        "f", "v", "s", "z", "S", "Z", "m", "n", "n^", "N", "l", "r",  "j",  "w",  "I",  "V", "0", "3:", "aI", "dZ"}) {
    for (const std::string& ipa : EspeakToIpaPhones(name))
      EXPECT_TRUE(IsVowel(ipa) || IsConsonant(ipa)) << name << " -> " << ipa;
  }
}

TEST(Phonetics, DocTableMatchesCode) {
  // docs/phonetics.md lists the table as rows of (`name` | IPA | espeak's IPA) triples.
  // CSW_SOURCE_DIR does not reach ctest (csw_add_test passes one ENVIRONMENT
  // entry only), so the source tree comes from a compile definition.
  std::ifstream in(std::filesystem::path(CSW_SYNTH_SOURCE_DIR) / "docs" / "phonetics.md");
  ASSERT_TRUE(in) << "docs/phonetics.md not found";
  std::map<std::string, std::string> documented;
  std::string line;
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("### espeak-ng", 0) == 0) in_table = true;
    if (line.rfind("Departures", 0) == 0) break;
    if (!in_table || line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    std::string cell;
    while (std::getline(ss, cell, '|')) {
      const size_t a = cell.find_first_not_of(' ');
      const size_t b = cell.find_last_not_of(' ');
      cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    for (size_t i = 0; i + 1 < cells.size(); i += 3) {
      if (cells[i].size() < 3) continue;
      documented[cells[i].substr(1, cells[i].size() - 2)] = cells[i + 1];
    }
  }
  const auto table = EspeakIpaTable();
  EXPECT_EQ(documented.size(), table.size());
  for (const auto& [name, ipa] : table) {
    ASSERT_TRUE(documented.count(name)) << name << " missing from docs/phonetics.md";
    EXPECT_EQ(documented[name], ipa) << name;
    EXPECT_EQ(EspeakToIpa(name), ipa);
  }
}

TEST(Phonetics, SemiVowelException) {
  // The one exception: espeak-ng's "y" before a vowel of the same word is [ɥ].
  std::vector<Phone> phones(4);
  const char* ipa[] = {"l", "y", "i", "y"};
  for (int i = 0; i < 4; ++i) {
    phones[i].ipa = ipa[i];
    phones[i].word = i < 3 ? 0 : 1;
  }
  ApplyIpaExceptions(phones);
  EXPECT_EQ(phones[1].ipa, "ɥ");  // lui
  EXPECT_EQ(phones[3].ipa, "y");  // final, no vowel after
  // Not across a word boundary: "tu as" keeps the vowel.
  std::vector<Phone> tu_as(3);
  tu_as[0] = {"t", "t", 0, 0, 0};
  tu_as[1] = {"y", "y", 0, 0, 0};
  tu_as[2] = {"a", "a", 0, 0, 1};
  ApplyIpaExceptions(tu_as);
  EXPECT_EQ(tu_as[1].ipa, "y");
}

TEST(Phonetics, Bonjour) {
  const Utterance u = Phonetise("bonjour");
  EXPECT_EQ(SpokenIpa(u), "b ɔ̃ ʒ u ʁ");
  EXPECT_DOUBLE_EQ(u.audio.rate_hz, 22050.0);
  EXPECT_EQ(u.audio.channels, 1);
  ExpectContiguous(u);
  ASSERT_EQ(u.words.size(), 1u);
  EXPECT_EQ(u.words[0].text, "bonjour");
  // The word spans exactly its phones.
  double first = -1, last = -1;
  for (const Phone& p : u.phones)
    if (p.word == 0) {
      if (first < 0) first = p.start_s;
      last = p.end_s;
    }
  EXPECT_DOUBLE_EQ(u.words[0].start_s, first);
  EXPECT_DOUBLE_EQ(u.words[0].end_s, last);
  for (const Phone& p : u.phones) EXPECT_EQ(p.word == -1, p.ipa.empty());
  // Real speech: non-silent audio, 0.2-1.5 s long.
  double energy = 0;
  for (float s : u.audio.samples) energy += double(s) * s;
  EXPECT_GT(std::sqrt(energy / u.audio.samples.size()), 0.01);
  EXPECT_GT(u.audio.duration_s(), 0.2);
  EXPECT_LT(u.audio.duration_s(), 1.5);
  EXPECT_TRUE(u.warnings.empty());
}

TEST(Phonetics, CuisinierGetsTheSemiVowel) {
  const Utterance u = Phonetise("cuisinier");
  EXPECT_EQ(SpokenIpa(u), "k ɥ i z i n j e");
  for (const Phone& p : u.phones)
    if (p.ipa == "ɥ") {
      EXPECT_EQ(p.espeak, "y");
    }
}

TEST(Phonetics, LiaisonAndWords) {
  const Utterance u = Phonetise("les amis");
  EXPECT_EQ(SpokenIpa(u), "l e z a m i");
  ASSERT_EQ(u.words.size(), 2u);
  EXPECT_EQ(u.words[0].text, "les");
  EXPECT_EQ(u.words[1].text, "amis");
  EXPECT_LE(u.words[0].end_s, u.words[1].start_s);
}

TEST(Phonetics, Utf8WordText) {
  const Utterance u = Phonetise("été père");
  ASSERT_EQ(u.words.size(), 2u);
  EXPECT_EQ(u.words[0].text, "été");
  EXPECT_EQ(u.words[1].text, "père");
  EXPECT_EQ(SpokenIpa(u), "e t e p ɛ ʁ");
}

// espeak-ng's linking glide ";" between a word-final [i] and a vowel-initial
// word ("bougie ; éclaire", "Marie ; a") is no phoneme of the words: kept as
// its own phone ";" (espeak-ng's timing) without a warning, and not cued: the
// keys are those of the phones without it.
TEST(Phonetics, LinkingGlideIsNotCued) {
  EXPECT_TRUE(IsEspeakLinking(";"));
  EXPECT_FALSE(IsEspeakLinking("j"));
  for (const auto& [text, ipa] : std::vector<std::pair<std::string, std::string>>{
           {"La bougie éclaire la chambre.", "l a b u ʒ i ; e k l ɛ ʁ l a ʃ ɑ̃ b ʁ"},
           {"Marie a un ami.", "m a ʁ i ; a œ̃ n a m i"}}) {
    const Utterance u = Phonetise(text);
    EXPECT_EQ(SpokenIpa(u), ipa) << text;
    EXPECT_TRUE(u.warnings.empty()) << text << ": " << (u.warnings.empty() ? "" : u.warnings[0]);
    ExpectContiguous(u);
    // The same keys as the phones without ";" (its time given to the phone before).
    std::vector<Phone> without;
    for (const Phone& p : u.phones) {
      if (p.ipa == ";") {
        without.back().end_s = p.end_s;
        continue;
      }
      without.push_back(p);
    }
    EXPECT_EQ(Codes(CueKeys(u.phones)), Codes(CueKeys(without))) << text;
  }
  // Hand-derived: "Marie a" -> ma 15, ʁi 33, a alone 15 (the glide cues nothing).
  const Utterance m = Phonetise("Marie a");
  EXPECT_EQ(Codes(CueKeys(m.phones)), "00 15 33 15 00");
}

TEST(Phonetics, AffricateIsSplit) {
  const Utterance u = Phonetise("tchèque");
  EXPECT_EQ(SpokenIpa(u), "t ʃ ɛ k");
  ExpectContiguous(u);
}

TEST(Phonetics, SentenceKeysThroughEspeak) {
  // Worked by hand: bɔ̃ 34, ʒu 41, ʁ (before the comma's pause) 13, i alone 35,
  // la 16, œ̃ alone 55, liaison na 14, mi 35.
  const Utterance u = Phonetise("Bonjour, il a un ami.");
  EXPECT_EQ(SpokenIpa(u), "b ɔ̃ ʒ u ʁ i l a œ̃ n a m i");
  const std::vector<Key> keys = CueKeys(u.phones);
  EXPECT_EQ(keys.size(), 10u);
  EXPECT_EQ(Codes(keys), "00 34 41 13 35 16 55 14 35 00");
  // CV keys' A1 is the consonant's onset.
  EXPECT_DOUBLE_EQ(keys[1].a1_s, u.phones[keys[1].consonant_phone].start_s);
  for (size_t i = 1; i + 1 < keys.size(); ++i) EXPECT_LT(keys[i].a1_s, keys[i].end_s);
}

TEST(Phonetics, SecondSentenceKeysThroughEspeak) {
  // l ə ʃ a d ə m a s œ ʁ d ɔ ʁ s y ʁ l ə l i
  const Utterance u = Phonetise("Le chat de ma sœur dort sur le lit.");
  EXPECT_EQ(SpokenIpa(u), "l ə ʃ a d ə m a s œ ʁ d ɔ ʁ s y ʁ l ə l i");
  EXPECT_EQ(Codes(CueKeys(u.phones)), "00 16 16 11 15 13 13 41 13 53 13 16 36 00");
}

TEST(Phonetics, NoAudioOption) {
  PhonetiseOptions options;
  options.synthesize_audio = false;
  const Utterance without = Phonetise("le petit chat", options);
  const Utterance with = Phonetise("le petit chat");
  EXPECT_TRUE(without.audio.samples.empty());
  ASSERT_EQ(without.phones.size(), with.phones.size());
  for (size_t i = 0; i < with.phones.size(); ++i) {
    EXPECT_EQ(without.phones[i].ipa, with.phones[i].ipa);
    // espeak-ng keeps its pitch-jitter state between calls: times differ by
    // under a millisecond from one call to the next.
    EXPECT_NEAR(without.phones[i].end_s, with.phones[i].end_s, 0.002);
  }
}

TEST(Phonetics, RateChangesDuration) {
  PhonetiseOptions slow, fast;
  slow.rate_wpm = 100;
  fast.rate_wpm = 300;
  const Utterance a = Phonetise("le petit chat est là", slow);
  const Utterance b = Phonetise("le petit chat est là", fast);
  EXPECT_EQ(SpokenIpa(a), SpokenIpa(b));
  EXPECT_GT(a.duration_s(), 1.5 * b.duration_s());
}

TEST(Phonetics, ThreadSafe) {
  const std::string text = "Je ne sais pas.";
  const Utterance ref = Phonetise(text);
  std::vector<Utterance> results(4);
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i) threads.emplace_back([&, i] { results[i] = Phonetise(text); });
  for (auto& t : threads) t.join();
  for (const Utterance& r : results) {
    EXPECT_EQ(SpokenIpa(r), SpokenIpa(ref));
    ASSERT_EQ(r.phones.size(), ref.phones.size());
    for (size_t i = 0; i < r.phones.size(); ++i) EXPECT_NEAR(r.phones[i].start_s, ref.phones[i].start_s, 0.002);
    EXPECT_NEAR(r.audio.duration_s(), ref.audio.duration_s(), 0.002);
    ASSERT_EQ(r.words.size(), 4u);
    EXPECT_EQ(r.words[3].text, "pas");  // espeak-ng word lengths exclude punctuation
  }
}

TEST(Phonetics, FlutterFreeVariantIsBitReproducible) {
  // The "michel" variant has flutter, roughness and echo 0: same text, same
  // samples and times, whatever was spoken in between.
  PhonetiseOptions o;
  o.voice = "fr+michel";
  const Utterance a = Phonetise("le petit chat", o);
  Phonetise("bonjour", o);
  Phonetise("il fait beau");
  const Utterance b = Phonetise("le petit chat", o);
  EXPECT_EQ(SpokenIpa(a), "l ə p ə t i ʃ a");
  EXPECT_EQ(a.audio.samples, b.audio.samples);
  ASSERT_EQ(a.phones.size(), b.phones.size());
  for (size_t i = 0; i < a.phones.size(); ++i) EXPECT_EQ(a.phones[i].start_s, b.phones[i].start_s);
}

TEST(Phonetics, BadOptions) {
  PhonetiseOptions o;
  o.pitch = 120;
  EXPECT_FALSE(o.Check().empty());
  EXPECT_THROW(Phonetise("a", o), InvalidInput);
  PhonetiseOptions v;
  v.voice = "no-such-voice-xyz";
  EXPECT_TRUE(v.Check().empty());
  EXPECT_THROW(Phonetise("a", v), Error);
  EXPECT_TRUE(PhonetiseOptions{}.Check().empty());
  // The session still works after a failure.
  EXPECT_EQ(SpokenIpa(Phonetise("oui")), "w i");
}

TEST(Phonetics, EmptyAndHostileText) {
  const Utterance empty = Phonetise("");
  EXPECT_TRUE(empty.words.empty());
  for (const Phone& p : empty.phones) EXPECT_TRUE(p.ipa.empty());
  std::mt19937_64 rng(7);
  for (int round = 0; round < 5; ++round) {
    std::string junk;
    for (int i = 0; i < 60; ++i) junk += static_cast<char>(1 + rng() % 255);  // invalid UTF-8 included
    const Utterance u = Phonetise(junk);
    if (!u.phones.empty()) ExpectContiguous(u);
    for (const Phone& p : u.phones)
      if (p.word >= 0) {
        EXPECT_LT(p.word, static_cast<int>(u.words.size()));
      }
    EXPECT_EQ(CueKeys(u.phones).front().Code(), "00");
  }
}

TEST(Phonetics, Tiers) {
  const Utterance u = Phonetise("les amis");
  const std::vector<LabelTier> tiers = UtteranceTiers(u);
  ASSERT_EQ(tiers.size(), 2u);
  EXPECT_EQ(tiers[0].name, "words");
  EXPECT_EQ(tiers[1].name, "phones");
  for (const LabelTier& t : tiers) {
    EXPECT_EQ(t.kind, LabelTier::Kind::kInterval);
    EXPECT_DOUBLE_EQ(t.start_s, 0.0);
    EXPECT_NEAR(t.end_s, u.audio.duration_s(), 1e-9);
    ASSERT_FALSE(t.labels.empty());
    EXPECT_DOUBLE_EQ(t.labels.front().start_s, 0.0);
    EXPECT_DOUBLE_EQ(t.labels.back().end_s, t.end_s);
    for (size_t i = 1; i < t.labels.size(); ++i) EXPECT_DOUBLE_EQ(t.labels[i].start_s, t.labels[i - 1].end_s);
  }
  std::string words, phones;
  for (const Label& l : tiers[0].labels)
    if (!l.text.empty()) words += l.text + "|";
  for (const Label& l : tiers[1].labels)
    if (!l.text.empty()) phones += l.text;
  EXPECT_EQ(words, "les|amis|");
  EXPECT_EQ(phones, "lezami");
  EXPECT_EQ(tiers[1].labels.size(), u.phones.size());
}

}  // namespace
}  // namespace csw
