// csw cue (workbench/jobs/cue_job.h): option checks, the exact default text,
// and the job on a corpus and a TextGrid written here, whose phones (and so
// whose keys, derived by hand from ../shared/docs/cued-speech.md) the test knows.
#include "workbench/jobs/cue_job.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/labels.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "io/formats/textgrid.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

CueOptions Valid() {
  CueOptions o;
  o.input = "c.h5";
  return o;
}

TEST(CueOptionsCheck, AcceptsCorpusAndTextGridRequests) {
  CueOptions o = Valid();
  EXPECT_EQ(o.Check(), "");
  o.takes = {"s*"};
  o.symbols = "sppas";
  EXPECT_EQ(o.Check(), "");
  CueOptions t;
  t.input = "a.TextGrid";
  t.output = "b.TextGrid";
  t.symbols = "MFA";
  EXPECT_EQ(t.Check(), "");
}

TEST(CueOptionsCheck, RejectsEachBadRequestWithItsReason) {
  auto why = [](auto change) {
    CueOptions o = Valid();
    change(o);
    return o.Check();
  };
  EXPECT_EQ(why([](CueOptions& o) { o.input.clear(); }), "no input given: a corpus (.h5) or a TextGrid");
  EXPECT_EQ(why([](CueOptions& o) { o.input = "a.eaf"; }),
            "csw cue reads a corpus (.h5) or a TextGrid (.TextGrid), not 'a.eaf'");
  EXPECT_EQ(why([](CueOptions& o) { o.input = "a.TextGrid"; }), "csw cue FILE.TextGrid needs -o OUT.TextGrid");
  EXPECT_EQ(why([](CueOptions& o) {
              o.input = "a.TextGrid";
              o.output = "b.txt";
            }),
            "-o must name a .TextGrid file, not 'b.txt'");
  EXPECT_EQ(why([](CueOptions& o) {
              o.input = "a.TextGrid";
              o.output = "b.TextGrid";
              o.takes = {"t1"};
            }),
            "--takes selects takes of a corpus; a TextGrid is one take");
  EXPECT_EQ(why([](CueOptions& o) { o.output = "b.TextGrid"; }),
            "-o is for a TextGrid input; on a corpus csw cue writes the 'expected_keys' tier into each take");
  EXPECT_EQ(why([](CueOptions& o) { o.symbols = "arpabet"; }),
            "--symbols must be auto, ipa, mfa, xsampa or sppas, not 'arpabet'");
  EXPECT_EQ(why([](CueOptions& o) { o.phones.clear(); }), "--phones must name the phone tier");
  EXPECT_EQ(why([](CueOptions& o) { o.tier.clear(); }), "--tier must name the tier to write");
  EXPECT_EQ(why([](CueOptions& o) { o.tier = "phones"; }), "--tier must differ from --phones (the phone tier is kept)");
}

TEST(CueText, RendersEveryTakeAndWhatWasWritten) {
  const json r = {{"input", "c.h5"},
                  {"kind", "corpus"},
                  {"output", "c.h5"},
                  {"tier", "expected_keys"},
                  {"symbols", "auto"},
                  {"dry_run", false},
                  {"keys", 4},
                  {"warnings", 1},
                  {"takes",
                   {{{"take", "s01"},
                     {"phones_tier", "phones"},
                     {"symbols", "ipa"},
                     {"phones", 5},
                     {"pauses", 0},
                     {"keys", 3},
                     {"counts", {{"CV", 2}, {"V", 0}, {"C", 1}, {"rest", 2}}},
                     {"sequence", "00 34 41 13 00"},
                     {"warnings", json::array()}},
                    {{"take", "s02"},
                     {"phones_tier", "phones"},
                     {"symbols", "sppas"},
                     {"phones", 2},
                     {"pauses", 1},
                     {"keys", 1},
                     {"counts", {{"CV", 0}, {"V", 1}, {"C", 0}, {"rest", 2}}},
                     {"sequence", "00 15 00"},
                     {"warnings",
                      {"c.h5: take 's02': tier 'phones': unknown sppas phone symbol 'Q' (1 time, first at 0.000 s): "
                       "not cued"}}}}}};
  EXPECT_EQ(CueText(r),
            "take s01: 3 keys (CV 2, V 0, C 1) from 5 phones of tier 'phones' (ipa symbols): 00 34 41 13 00\n"
            "take s02: 1 keys (CV 0, V 1, C 0) from 2 phones of tier 'phones' (sppas symbols): 00 15 00\n"
            "  warning: c.h5: take 's02': tier 'phones': unknown sppas phone symbol 'Q' (1 time, first at 0.000 s): "
            "not cued\n"
            "wrote tier 'expected_keys' into 2 takes of c.h5\n");
  json t = r;
  t["kind"] = "textgrid";
  t["output"] = "b.TextGrid";
  t["takes"].erase(1);
  EXPECT_EQ(CueText(t).substr(CueText(t).find('\n') + 1), "wrote b.TextGrid with tier 'expected_keys'\n");
  t["dry_run"] = true;
  EXPECT_EQ(CueText(t).substr(CueText(t).find('\n') + 1), "dry run: nothing written\n");
}

// One 0.1 s interval per token from t = 0; the tier's domain is [0, end].
LabelTier PhoneTier(const std::string& name, const std::vector<std::string>& tokens, double end) {
  LabelTier t{name, LabelTier::Kind::kInterval, 0.0, end, {}};
  double time = 0;
  for (const std::string& tok : tokens) {
    t.labels.push_back({time, time + 0.1, tok});
    time += 0.1;
  }
  return t;
}

// A take of `seconds` at 100 Hz with one marker, and the given tiers.
Take TakeWith(const std::string& name, double seconds, std::vector<LabelTier> tiers) {
  Take t;
  t.name = name;
  t.rate_hz = 100.0;
  t.marker_names = {"M0"};
  t.markers.Resize(static_cast<int64_t>(seconds * 100.0 + 0.5), 1);
  for (int64_t f = 0; f < t.markers.frames(); ++f) t.markers.at(f, 0)[0] = t.markers.at(f, 0)[1] = 1.0f;
  for (int64_t f = 0; f < t.markers.frames(); ++f) t.markers.at(f, 0)[2] = 1.0f;
  t.tiers = std::move(tiers);
  return t;
}

const LabelTier* Find(const Take& t, const std::string& name) {
  for (const LabelTier& x : t.tiers)
    if (x.name == name) return &x;
  return nullptr;
}

std::string Texts(const LabelTier& t) {
  std::string s;
  for (const Label& l : t.labels) s += (s.empty() ? "" : " ") + (l.text.empty() ? std::string("_") : l.text);
  return s;
}

TEST(CueJob, WritesExpectedKeysIntoEachTakeAndKeepsTheOtherTiers) {
  testing::TempDir dir;
  const std::string path = (dir / "c.h5").string();
  {
    CorpusTransaction tx(path);
    // bonjour in IPA: bɔ̃ 34, ʒu 41, ʁ alone 13; the take lasts 1 s, the phones 0.5 s.
    tx.WriteTake(TakeWith("s01", 1.0,
                          {PhoneTier("phones", {"b", "ɔ̃", "ʒ", "u", "ʁ"}, 0.5),
                           {"keys", LabelTier::Kind::kPoint, 0.0, 1.0, {{0.05, 0.05, "34"}}}}));
    // "Sac. Avec." in SPPAS: sa 13, k alone 12 | a alone 15, vE 42, k alone 12; an unknown "Q".
    tx.WriteTake(TakeWith("s02", 1.0, {PhoneTier("phones", {"s", "a", "k", "#", "a", "v", "E", "k", "Q"}, 1.0)}));
    tx.Commit();
  }
  CueOptions o;
  o.input = path;
  Progress progress;
  const json r = Cue(o, progress);
  EXPECT_EQ(r["kind"], "corpus");
  EXPECT_EQ(r["keys"].get<int64_t>(), 3 + 5);
  EXPECT_EQ(r["warnings"].get<int64_t>(), 1);
  ASSERT_EQ(r["takes"].size(), 2u);
  const json& a = r["takes"][0];
  EXPECT_EQ(a["take"], "s01");
  EXPECT_EQ(a["symbols"], "ipa");
  EXPECT_EQ(a["sequence"], "00 34 41 13 00");
  EXPECT_EQ(a["counts"], (json{{"CV", 2}, {"V", 0}, {"C", 1}, {"rest", 2}}));
  EXPECT_EQ(a["phones"].get<int64_t>(), 5);
  EXPECT_EQ(a["pauses"].get<int64_t>(), 1);  // the take's last 0.5 s beyond the phone tier
  const json& b = r["takes"][1];
  EXPECT_EQ(b["symbols"], "sppas");
  EXPECT_EQ(b["sequence"], "00 13 12 15 42 12 00");
  EXPECT_EQ(b["counts"], (json{{"CV", 2}, {"V", 1}, {"C", 2}, {"rest", 2}}));
  EXPECT_EQ(b["warnings"], (json{"" + path +
                                 ": take 's02': tier 'phones': unknown sppas phone symbol 'Q' (1 time, first at "
                                 "0.800 s): not cued"}));

  const Corpus c = Corpus::Open(path);
  const Take t1 = c.LoadTake("s01");
  ASSERT_EQ(t1.tiers.size(), 3u);
  ASSERT_NE(Find(t1, "keys"), nullptr);  // kept
  ASSERT_NE(Find(t1, "phones"), nullptr);
  const LabelTier* e = Find(t1, "expected_keys");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->kind, LabelTier::Kind::kInterval);
  // 34 over bɔ̃ [0, 0.2], 41 over ʒu [0.2, 0.4], 13 over ʁ [0.4, 0.5], rest to the take's end.
  EXPECT_EQ(Texts(*e), "34 41 13 00");
  EXPECT_NEAR(e->labels[1].start_s, 0.2, 1e-9);
  EXPECT_NEAR(e->labels[1].end_s, 0.4, 1e-9);
  EXPECT_NEAR(e->labels[3].end_s, 1.0, 1e-9);
  EXPECT_NEAR(e->end_s, 1.0, 1e-9);
  // The pause of s02 is an empty interval between 12 and 15.
  EXPECT_EQ(Texts(*Find(c.LoadTake("s02"), "expected_keys")), "13 12 _ 15 42 12 00");

  // Running again replaces the tier (no second copy); --dry-run writes nothing.
  o.takes = {"s01"};
  // IPA read as X-SAMPA: ɔ̃ ʒ ʁ are unknown and transparent, so b takes u: 44.
  o.symbols = "xsampa";
  o.dry_run = true;
  const json d = Cue(o, progress);
  EXPECT_EQ(d["takes"][0]["sequence"], "00 44 00");
  EXPECT_EQ(Texts(*Find(Corpus::Open(path).LoadTake("s01"), "expected_keys")), "34 41 13 00");
  o.dry_run = false;
  Cue(o, progress);
  const Take again = Corpus::Open(path).LoadTake("s01");
  EXPECT_EQ(again.tiers.size(), 3u);
  EXPECT_EQ(Texts(*Find(again, "expected_keys")), "44 00");
}

TEST(CueJob, MissingPhoneTierNamesTheTakeAndItsTiersAndWritesNothing) {
  testing::TempDir dir;
  const std::string path = (dir / "c.h5").string();
  {
    CorpusTransaction tx(path);
    tx.WriteTake(TakeWith("s01", 0.5, {PhoneTier("phones", {"a"}, 0.5)}));
    tx.WriteTake(TakeWith("s02", 0.5, {PhoneTier("words", {"a"}, 0.5), PhoneTier("PhonAlign", {"a"}, 0.5)}));
    tx.Commit();
  }
  CueOptions o;
  o.input = path;
  Progress progress;
  try {
    Cue(o, progress);
    ADD_FAILURE() << "no error";
  } catch (const UsageError&) {
    ADD_FAILURE() << "bad data is not a usage error";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": take 's02': no phone tier 'phones' (tiers: 'words', 'PhonAlign'); "
                                         "name it with --phones");
  }
  EXPECT_EQ(Find(Corpus::Open(path).LoadTake("s01"), "expected_keys"), nullptr);
  // A frame range is refused: cue works on whole takes.
  o.takes = {"s01@0:10"};
  EXPECT_THROW(Cue(o, progress), UsageError);
}

TEST(CueJob, TextGridInCopyOutWithEveryTier) {
  testing::TempDir dir;
  const std::string in = (dir / "a.TextGrid").string(), out = (dir / "b.TextGrid").string();
  // "Oui, le roi." in X-SAMPA with a "_" pause: wi 36 | lə 16, ʁ alone 13, wa 16.
  WriteTextGrid(in,
                {PhoneTier("phones", {"w", "i", "_", "l", "@", "R", "w", "a"}, 0.8),
                 {"words", LabelTier::Kind::kInterval, 0.0, 0.8, {{0.0, 0.8, "oui le roi"}}}},
                0.0, 0.8);
  CueOptions o;
  o.input = in;
  o.output = out;
  Progress progress;
  const json r = Cue(o, progress);
  EXPECT_EQ(r["kind"], "textgrid");
  ASSERT_EQ(r["takes"].size(), 1u);
  EXPECT_EQ(r["takes"][0]["take"], "a");
  EXPECT_EQ(r["takes"][0]["symbols"], "xsampa");
  EXPECT_EQ(r["takes"][0]["sequence"], "00 36 16 13 16 00");
  double xmin = -1, xmax = -1;
  const std::vector<LabelTier> tiers = ReadTextGrid(out, &xmin, &xmax);
  EXPECT_EQ(xmin, 0.0);
  EXPECT_EQ(xmax, 0.8);
  ASSERT_EQ(tiers.size(), 3u);
  EXPECT_EQ(tiers[0].name, "phones");
  EXPECT_EQ(tiers[1].name, "words");
  EXPECT_EQ(tiers[2].name, "expected_keys");
  EXPECT_EQ(Texts(tiers[2]), "36 _ 16 13 16");
  EXPECT_NEAR(tiers[2].labels[1].start_s, 0.2, 1e-9);  // the pause [0.2, 0.3]
  EXPECT_NEAR(tiers[2].labels[1].end_s, 0.3, 1e-9);
  EXPECT_NEAR(tiers[2].labels[4].end_s, 0.8, 1e-9);
  // The recogniser reads the tier back as keys with their spans (core/labels.h).
  const std::vector<ExpectedKey> keys = ReadExpectedKeyTier(tiers[2], out);
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[0].code, (KeyCode{3, 6}));
  EXPECT_EQ(keys[2].code, (KeyCode{1, 3}));
  EXPECT_NEAR(keys[1].start_s, 0.3, 1e-9);
  EXPECT_NEAR(keys[1].end_s, 0.5, 1e-9);
}

// The virtual cuer writes its phones (IPA, from espeak-ng) and a "keys" point
// tier with the code of every key it cued, rests included. csw cue on those
// phones must give the same key sequence for every sentence.
TEST(CueJob, VirtualCuerPhonesGiveTheKeysItCued) {
  testing::TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const int sentences = csw::testing::kSanitized ? 2 : 8;
  const std::vector<std::string> texts = ShippedSentences();
  ASSERT_GE(static_cast<int>(texts.size()), sentences);
  {
    VirtualCuer cuer{SimulateOptions()};
    CorpusTransaction tx(path);
    for (int i = 0; i < sentences; ++i)
      tx.WriteTake(cuer.SimulateSentence("s" + std::to_string(i), texts[static_cast<size_t>(i)]).take);
    tx.Commit();
  }
  CueOptions o;
  o.input = path;
  Progress progress;
  const json r = Cue(o, progress);
  ASSERT_EQ(r["takes"].size(), static_cast<size_t>(sentences));
  const Corpus c = Corpus::Open(path);
  int64_t keys = 0;
  for (const json& t : r["takes"]) {
    const Take take = c.LoadTake(t["take"].get<std::string>());
    const LabelTier* cued = Find(take, "keys");
    ASSERT_NE(cued, nullptr);
    std::string truth;
    for (const Label& l : cued->labels) truth += (truth.empty() ? "" : " ") + l.text;
    EXPECT_EQ(t["sequence"].get<std::string>(), truth) << t["take"];
    EXPECT_EQ(t["symbols"], "ipa");
    // Every phone the virtual cuer writes is a known symbol (espeak-ng's
    // linking glide ";" is dropped by Phonetise, docs/phonetics.md).
    EXPECT_TRUE(t["warnings"].empty()) << t["warnings"].dump();
    keys += t["keys"].get<int64_t>();
  }
  EXPECT_GE(keys, 10 * sentences);  // sentences of several words each
}

}  // namespace
}  // namespace csw::jobs
