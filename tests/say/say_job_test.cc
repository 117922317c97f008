// csw say (workbench/jobs/say_job.h): option checks, the sentence-file
// reader, the text report, and the job end to end on a dictionary built from
// three virtual-cuer sentences: a sentence of the corpus is synthesised from
// whole dikeys into a WAV, a TextGrid, a C3D and a video that read back with
// the expected sizes, and the key recogniser finds the intended keys; bad
// input (other models, a text without keys) gives one clear error.
#include "workbench/jobs/say_job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "io/c3d/c3d.h"
#include "io/formats/textgrid.h"
#include "io/formats/wav.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "synth/cueing.h"
#include "synth/marker_synthesis.h"
#include "synth/phonetics.h"
#include "tests/keys_job/cuer_corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/keys_job.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
// The message holds `part`.
::testing::AssertionResult Holds(const std::string& message, const std::string& part) {
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not hold '" << part << "'";
}

SayOptions Valid() {
  SayOptions o;
  o.texts = {"bonjour"};
  o.dict = "d.h5";
  o.models = "m.h5";
  o.output = "out";
  return o;
}

TEST(SayOptions, RequiredOptionsAndReasons) {
  EXPECT_EQ(Valid().Check(), "");
  SayOptions o = Valid();
  o.texts.clear();
  EXPECT_EQ(o.Check(), "no text given (a sentence, or --text-file)");
  o.text_file = "s.txt";
  EXPECT_EQ(o.Check(), "");
  o = Valid();
  o.texts = {"  "};
  EXPECT_EQ(o.Check(), "an empty text was given");
  o = Valid();
  o.dict.clear();
  EXPECT_EQ(o.Check(), "no dictionary given (--dict)");
  o = Valid();
  o.models.clear();
  EXPECT_EQ(o.Check(), "no model file given (--models)");
  o = Valid();
  o.output.clear();
  EXPECT_EQ(o.Check(), "no output folder given (-o)");
  o = Valid();
  o.rate_wpm = 50;
  EXPECT_EQ(o.Check(), "--rate must be in [80, 450] words per minute");
  o = Valid();
  o.phasing = "local";
  EXPECT_EQ(o.Check(), "--phasing must be dikey or global");
  o = Valid();
  o.rate_hz = 5;
  EXPECT_EQ(o.Check(), "--frame-rate must be 0 or in [10, 2000] Hz");
  o = Valid();
  o.fps = 0;
  EXPECT_EQ(o.Check(), "--fps must be in [1, 240]");
  o = Valid();
  o.check = true;
  EXPECT_EQ(o.Check(), "--check needs the key model (--keys)");
  o = Valid();
  o.corpus_phasing = "p.json";
  EXPECT_EQ(o.Check(), "--corpus-phasing applies with --check");
  o = Valid();
  o.target_weight = -1;
  EXPECT_EQ(o.Check(), "--target-weight must be >= 0");
  o = Valid();
  o.posture_radius = std::nan("");
  EXPECT_EQ(o.Check(), "--posture-radius must be >= 0");
  o = Valid();
  o.face_units = "triphones";
  EXPECT_EQ(o.Check(), "--face-units must be diphones or fragments");
  o = Valid();
  o.resampling = "cubic";
  EXPECT_EQ(o.Check(), "--resampling must be rbf or linear");
  o = Valid();
  o.blend = 2;
  EXPECT_EQ(o.Check(), "--blend must be in [0, 1]");
  o = Valid();
  o.rbf_shape = 0;
  EXPECT_EQ(o.Check(), "--rbf-shape must be in (0, 100]");
  o = Valid();
  o.max_onset_overlap = 1.5;
  EXPECT_EQ(o.Check(), "--max-overlap must be in [0, 1]");
}

TEST(ReadSentences, TrimsSkipsCommentsAndNamesBadLines) {
  testing::TempDir dir;
  const std::string good = (dir / "good.txt").string();
  std::ofstream(good) << "\xEF\xBB\xBF# a comment\n  Il fait beau.  \r\n\n\t# indented comment\nLa nuit tombe.\n";
  EXPECT_EQ(ReadSentences(good), (std::vector<std::string>{"Il fait beau.", "La nuit tombe."}));
  const std::string bad = (dir / "bad.txt").string();
  std::ofstream(bad) << "Il fait beau.\nL\xE9t\xE9\n";  // Latin-1 on line 2
  try {
    ReadSentences(bad);
    FAIL() << "no error for a Latin-1 line";
  } catch (const InvalidInput& e) {
    EXPECT_TRUE(Holds(e.what(), bad + ":2: not UTF-8"));
  }
  const std::string empty = (dir / "empty.txt").string();
  std::ofstream(empty) << "# nothing\n\n";
  EXPECT_THROW(ReadSentences(empty), InvalidInput);
  EXPECT_THROW(ReadSentences((dir / "absent.txt").string()), IoError);
}

TEST(SayText, RendersTheReport) {
  const json r = {
      {"corpus", "out/synthesis.h5"},
      {"fallback", {{"whole", 5}, {"closest placement", 1}, {"two streams", 0}, {"interpolated", 0}}},
      {"sentences",
       {{{"take", "say_001"},
         {"duration_s", 2.5},
         {"keys", 4},
         {"rate_wpm", 162},
         {"folder", "out"},
         {"warnings", {"no ffmpeg"}}}}},
      {"check",
       {{"keys", {{"correct", 3}, {"intended", 4}, {"accuracy", 0.75}}},
        {"continuity",
         {{"p99_jump_mm", 5.5}, {"max_jump_mm", 12.25}, {"corpus_p99_jump_mm", 6.0}, {"corpus_max_jump_mm", 20.0}}},
        {"timing",
         {{"CV",
           {{"placement_target_ms", 12.4},
            {"corpus_placement_target_ms", nullptr},
            {"shape_target_ms", -20.0},
            {"corpus_shape_target_ms", -18.0},
            {"placement_onset_difference_ms", 33.6},
            {"placement_onset_difference_ci95_ms", 24.5},
            {"placement_target_difference_ms", nullptr},
            {"placement_target_difference_ci95_ms", nullptr},
            {"shape_onset_difference_ms", -2.4},
            {"shape_onset_difference_ci95_ms", 8.0},
            {"shape_target_difference_ms", 15.3},
            {"shape_target_difference_ci95_ms", 6.2},
            {"placement_count", 45},
            {"shape_count", 220}}}}}}}};
  EXPECT_EQ(SayText(r),
            "say_001: 2.50 s, 4 keys, 162 wpm -> out\n"
            "  warning: no ffmpeg\n"
            "1 sentences; keys reached by whole dikeys 5, closest placement 1, two streams 0, interpolated 0\n"
            "corpus of the synthesised takes: out/synthesis.h5\n"
            "recognised keys: 3 of 4 (75.0 %)\n"
            "marker jumps: p99 5.50 mm, max 12.25 mm (corpus: p99 6.00 mm, max 20.00 mm)\n"
            "CV targets re A1: placement 12 ms (corpus nan), shape -20 ms (corpus -18)\n"
            "CV synthesis - corpus: placement onset +34 ± 24, target n/a; shape onset -2 ± 8, target +15 ± 6 ms "
            "(95 % CI; 45 / 220 keys)\n");
  json g = {{"sentences", json::array()},
            {"fallback", {{"whole", 2}}},
            {"corpus", "o/synthesis.h5"},
            {"fragments",
             {{"count", 4}, {"mean_diphones", 2.25}, {"longest", 5}, {"interpolated", 1}, {"resampling", "rbf"}}}};
  EXPECT_EQ(SayText(g),
            "0 sentences; keys reached by whole dikeys 2, closest placement 0, two streams 0, interpolated 0\n"
            "face from 4 fragments (mean 2.2 diphones, longest 5, 1 interpolated; rbf resampling)\n"
            "corpus of the synthesised takes: o/synthesis.h5\n");
}

// Three virtual-cuer sentences, face and hand models, a key model and a
// dictionary built from the labelled key tiers.
struct SayFixture : testing::CuerCorpus {
  std::string models, dictionary;
  SayFixture() : CuerCorpus(3) {
    models = (dir / "models.h5").string();
    dictionary = (dir / "dict.h5").string();
    Progress progress;
    for (const char* kind : {"face", "hand"}) {
      FitOptions fo;
      fo.corpus = corpus;
      fo.kind = kind;
      fo.output = models;
      Fit(fo, progress);
    }
    KeysTrainOptions t;
    t.corpus = corpus;
    t.takes = {"s*"};
    t.output = keys;
    KeysTrain(t, progress);
    DictBuildOptions d;
    d.corpus = corpus;
    d.models = models;
    d.keys = keys;
    d.output = dictionary;
    d.tier = "keys";
    DictBuild(d, progress);
  }
};

class SayJob : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fixture_ = new SayFixture(); }
  static void TearDownTestSuite() {
    delete fixture_;
    fixture_ = nullptr;
  }
  static SayFixture* fixture_;
};
SayFixture* SayJob::fixture_ = nullptr;

TEST_F(SayJob, SynthesisesACorpusSentenceFromWholeDikeys) {
  ASSERT_NE(fixture_, nullptr);
  SayFixture& fx = *fixture_;
  const std::string text = ShippedSentences()[0];
  SayOptions o;
  o.texts = {text};
  o.dict = fx.dictionary;
  o.models = fx.models;
  o.keys = fx.keys;
  o.check = true;
  o.output = (fx.dir / "say").string();
  Progress progress;
  const json r = Say(o, progress);
  ASSERT_EQ(r["sentences"].size(), 1u);
  const json& s = r["sentences"][0];

  // The intended keys, computed here from espeak-ng's phones and the LfPC rules.
  const std::vector<Key> keys = CueKeys(Phonetise(text).phones);
  std::vector<std::string> intended;
  for (const Key& k : keys)
    if (k.type != KeyType::kRest) intended.push_back(k.Code());
  ASSERT_GE(intended.size(), 4u);
  EXPECT_EQ(s["keys"], static_cast<int>(intended.size()));
  EXPECT_EQ(s["check"]["intended"].get<std::vector<std::string>>(), intended);
  // The sentence is in the corpus: every succession exists whole.
  EXPECT_EQ(s["fallback"]["whole"], static_cast<int>(keys.size()) - 1);
  EXPECT_EQ(s["fallback"]["interpolated"], 0);
  // The key posture pull (on by default) reports every key: its distance
  // from its code's mean posture in the code's standard deviations (null
  // for codes with fewer than 5 instances) and whether it was moved, only
  // ever when farther than the radius 0.5.
  ASSERT_EQ(s["key_plan"].size(), keys.size());
  int measured = 0;
  for (size_t i = 0; i < keys.size(); ++i) {
    // Each key's type and its syllable's acoustic onset (A1) on the output
    // clock: the keys the LfPC rules gave the sentence, rests without A1.
    const json& k = s["key_plan"][i];
    EXPECT_EQ(k["code"], keys[i].Code()) << i;
    if (keys[i].type == KeyType::kRest) {
      EXPECT_EQ(k["type"], "rest") << i;
      EXPECT_TRUE(k["a1_s"].is_null()) << i;
    } else {
      EXPECT_EQ(k["type"], keys[i].type == KeyType::kCV ? "CV" : keys[i].type == KeyType::kVowelAlone ? "V" : "C") << i;
      ASSERT_TRUE(k["a1_s"].is_number()) << i;
      EXPECT_GT(k["a1_s"].get<double>(), 0.0) << i;
      EXPECT_LT(k["a1_s"].get<double>(), s["duration_s"].get<double>()) << i;
      EXPECT_LT(std::abs(k["target_s"].get<double>() - k["a1_s"].get<double>()), 0.4) << i;
    }
  }
  for (const json& k : s["key_plan"]) {
    ASSERT_TRUE(k.contains("posture_distance") && k.contains("posture_pulled")) << k.dump();
    if (k["posture_distance"].is_number()) {
      ++measured;
      EXPECT_GE(k["posture_distance"].get<double>(), 0.0);
      if (k["posture_pulled"].get<bool>()) {
        EXPECT_GT(k["posture_distance"].get<double>(), 0.5) << k.dump();
      }
    } else {
      EXPECT_FALSE(k["posture_pulled"].get<bool>());
    }
  }
  EXPECT_GE(measured, 1);
  // At least 90 % of the keys recognised at their targets (a key model trained on 3 sentences).
  EXPECT_GE(r["check"]["keys"]["accuracy"].get<double>(), 0.9) << r["check"].dump() << "\n" << s.dump();
  // The speed limit: the corpus's largest jump (same frame rate), which the
  // synthesised markers do not exceed.
  ASSERT_TRUE(s["speed_limit"]["limit_mm"].is_number()) << s["speed_limit"].dump();
  EXPECT_NEAR(s["speed_limit"]["limit_mm"].get<double>(), r["check"]["continuity"]["corpus_max_jump_mm"].get<double>(),
              1e-9);
  EXPECT_LE(r["check"]["continuity"]["max_jump_mm"].get<double>(), s["speed_limit"]["limit_mm"].get<double>() + 1e-6);
  EXPECT_LE(s["speed_limit"]["max_jump_after_mm"].get<double>(), s["speed_limit"]["limit_mm"].get<double>() + 1e-6);

  // Files read back: the C3D holds every model marker, one frame per
  // 1 / rate; the WAV and the video last as long (± 1 frame).
  const ModelFile m = LoadModelFile(fx.models);
  const std::vector<std::string> names = SynthesisMarkerNames(*m.face, *m.hand);
  const fs::path out(o.output);
  const Take c3d = ReadC3d((out / "markers.c3d").string());
  EXPECT_EQ(c3d.marker_names, names);
  const double rate = fx.sims.front().take.rate_hz;  // the corpus's rate by default
  EXPECT_DOUBLE_EQ(c3d.rate_hz, rate);
  const double duration = s["duration_s"].get<double>();
  EXPECT_EQ(c3d.frames(), std::llround(duration * rate));
  int64_t missing = 0;
  for (int64_t f = 0; f < c3d.frames(); ++f)
    for (int64_t j = 0; j < static_cast<int64_t>(names.size()); ++j) missing += c3d.markers.Visible(f, j) ? 0 : 1;
  EXPECT_EQ(missing, 0);
  const Audio wav = ReadWav((out / "speech.wav").string());
  EXPECT_NEAR(wav.duration_s(), duration, 1.0 / rate);
  double xmin = 0, xmax = 0;
  const std::vector<LabelTier> tiers = ReadTextGrid((out / "cues.TextGrid").string(), &xmin, &xmax);
  std::vector<std::string> tier_names, key_codes;
  for (const LabelTier& t : tiers) {
    tier_names.push_back(t.name);
    if (t.name == "keys")
      for (const Label& l : t.labels) key_codes.push_back(l.text);
  }
  EXPECT_EQ(tier_names,
            (std::vector<std::string>{"words", "phones", "expected_keys", "keys", "placement_targets", "gestures"}));
  ASSERT_EQ(key_codes.size(), intended.size() + 2);  // rests at both ends
  EXPECT_EQ(key_codes.front(), "00");
  EXPECT_EQ(std::vector<std::string>(key_codes.begin() + 1, key_codes.end() - 1), intended);
  cv::VideoCapture video((out / "pointlight.mp4").string());
  ASSERT_TRUE(video.isOpened());
  int frames = 0;
  cv::Mat image;
  while (video.read(image)) ++frames;
  EXPECT_NEAR(frames, wav.duration_s() * 25.0, 1.0);
  EXPECT_TRUE(fs::exists(out / "synthesis.h5"));
  EXPECT_TRUE(fs::exists(out / "say.json"));
  EXPECT_EQ(r["dikey_warp"], "linear");
  EXPECT_TRUE(r["max_overlap"].is_null());

  // --keep-movement-durations: the same keys reached, the warp named. With a
  // corpus phasing file that holds only the CV shape target (mean 40 ms,
  // 95 % half-width 5 ms): that difference and its half-width, the others
  // unknown.
  o.keep_movement_durations = true;
  o.video = false;
  o.output = (fx.dir / "say-kept").string();
  o.corpus_phasing = (fx.dir / "corpus_phasing.json").string();
  std::ofstream(o.corpus_phasing) << R"({"kinematic": {"CV": {"shape": {"target": {"mean_ms": 40, "ci95_ms": 5}}}}})";
  const json kept = Say(o, progress);
  const json& cv = kept["check"]["timing"]["CV"];
  ASSERT_TRUE(cv["shape_target_ms"].is_number() && cv["shape_target_ci95_ms"].is_number()) << cv.dump();
  EXPECT_EQ(cv["corpus_shape_target_ms"], 40.0);
  EXPECT_NEAR(cv["shape_target_difference_ms"].get<double>(), cv["shape_target_ms"].get<double>() - 40.0, 1e-9);
  EXPECT_NEAR(cv["shape_target_difference_ci95_ms"].get<double>(),
              std::sqrt(std::pow(cv["shape_target_ci95_ms"].get<double>(), 2) + 25.0), 1e-9);
  EXPECT_TRUE(cv["placement_target_difference_ms"].is_null()) << cv.dump();
  EXPECT_TRUE(cv["shape_onset_difference_ms"].is_null()) << cv.dump();
  EXPECT_EQ(kept["dikey_warp"], "movements kept");
  EXPECT_TRUE(kept["max_overlap"].is_null());
  EXPECT_GE(kept["check"]["keys"]["accuracy"].get<double>(), 0.9) << kept["check"].dump();
  EXPECT_LE(kept["check"]["continuity"]["max_jump_mm"].get<double>(),
            kept["sentences"][0]["speed_limit"]["limit_mm"].get<double>() + 1e-6);

  // --movement-onsets: the warp and its overlap named, the keys still read,
  // the speed limit kept; with --keep-movement-durations the kept durations
  // win (above: "movements kept").
  o.keep_movement_durations = false;
  o.movement_onsets = true;
  o.max_onset_overlap = 0.25;
  o.output = (fx.dir / "say-onsets").string();
  const json onsets = Say(o, progress);
  EXPECT_EQ(onsets["dikey_warp"], "movement onsets");
  EXPECT_EQ(onsets["max_overlap"], 0.25);
  EXPECT_GE(onsets["check"]["keys"]["accuracy"].get<double>(), 0.9) << onsets["check"].dump();
  EXPECT_LE(onsets["check"]["continuity"]["max_jump_mm"].get<double>(),
            onsets["sentences"][0]["speed_limit"]["limit_mm"].get<double>() + 1e-6);
}

TEST_F(SayJob, FragmentsTakeACorpusSentencesFaceFromItsOwnTake) {
  // Seed-003 fragments for a sentence of the corpus (take s0): its phones
  // are a run of that take's diphones, so the greedy longest match takes
  // them in one fragment (measured: 21 diphones). The last diphone, into the
  // final pause, may be missing from a 3-take dictionary (a unit whose pause
  // middle lies past the take's last frame is not kept): then it alone is
  // interpolated.
  ASSERT_NE(fixture_, nullptr);
  SayFixture& fx = *fixture_;
  SayOptions o;
  o.texts = {ShippedSentences()[0]};
  o.dict = fx.dictionary;
  o.models = fx.models;
  o.video = false;
  o.face_units = "fragments";
  o.output = (fx.dir / "say_fragments").string();
  Progress progress;
  const json r = Say(o, progress);
  EXPECT_EQ(r["face_units"], "fragments");
  EXPECT_EQ(r["fragments"]["resampling"], "rbf");
  EXPECT_EQ(r["fragments"]["rbf_shape"], 2.0);
  const json& list = r["sentences"][0]["fragments"];
  ASSERT_GE(list.size(), 1u);
  EXPECT_EQ(list[0]["take"], "s0");
  EXPECT_GE(list[0]["diphones"].get<int>(), 20);
  int covered = 0, interpolated = 0;
  for (size_t i = 0; i < list.size(); ++i) {
    const json& f = list[i];
    covered += f["diphones"].get<int>();
    if (!f["interpolated"].get<bool>()) continue;
    ++interpolated;
    EXPECT_EQ(i + 1, list.size()) << f.dump();
    const std::string phones = f["phones"];
    EXPECT_EQ(phones.substr(phones.size() - 2), " _") << f.dump();
  }
  EXPECT_LE(interpolated, 1);
  EXPECT_EQ(r["fragments"]["interpolated"], interpolated);
  EXPECT_EQ(r["fragments"]["count"], static_cast<int>(list.size()));
  EXPECT_NEAR(r["fragments"]["mean_diphones"].get<double>(), double(covered) / list.size(), 1e-9);
  EXPECT_EQ(r["fragments"]["longest"], list[0]["diphones"]);
  EXPECT_EQ(r["fragments"]["linear_fallback"], 0);
}

TEST_F(SayJob, RefusesOtherModelsAndTextsWithoutKeys) {
  ASSERT_NE(fixture_, nullptr);
  SayFixture& fx = *fixture_;
  Progress progress;
  // Models fitted on another selection of takes have another fingerprint.
  const std::string other = (fx.dir / "other.h5").string();
  for (const char* kind : {"face", "hand"}) {
    FitOptions fo;
    fo.corpus = fx.corpus;
    fo.kind = kind;
    fo.takes = {"s0", "s1"};
    fo.output = other;
    Fit(fo, progress);
  }
  SayOptions o;
  o.texts = {"Il fait beau."};
  o.dict = fx.dictionary;
  o.models = other;
  o.video = false;
  o.output = (fx.dir / "other_out").string();
  try {
    Say(o, progress);
    FAIL() << "synthesis with other models";
  } catch (const InvalidInput& e) {
    EXPECT_TRUE(Holds(e.what(), fx.dictionary));
    EXPECT_TRUE(Holds(e.what(), "was built with models"));
  }
  o.models = fx.models;
  o.texts = {"!!!"};
  try {
    Say(o, progress);
    FAIL() << "a text without keys";
  } catch (const InvalidInput& e) {
    EXPECT_TRUE(Holds(e.what(), "say_001"));
  }
}

}  // namespace
}  // namespace csw::jobs
