// csw dict build (workbench/jobs/dict_job.h): option checks, the text report,
// and the job end to end on virtual-cuer sentences whose key tiers are the
// truth: the dictionary holds exactly the corpus's key successions, the
// coverage report says so, phasing matches the simulator's, and bad input
// (missing tier, models without a hand model, other models) gives one clear
// error.
#include "workbench/jobs/dict_job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/error.h"
#include "io/dictionary/dictionary_file.h"
#include "io/models/model_file.h"
#include "tests/keys_job/cuer_corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

DictBuildOptions Valid() {
  DictBuildOptions o;
  o.corpus = "c.h5";
  o.models = "m.h5";
  o.output = "d.h5";
  return o;
}

TEST(DictBuildOptions, RequiredOptionsAndReasons) {
  EXPECT_EQ(Valid().Check(), "");
  DictBuildOptions o = Valid();
  o.corpus.clear();
  EXPECT_EQ(o.Check(), "no corpus given");
  o = Valid();
  o.models.clear();
  EXPECT_EQ(o.Check(), "no model file given (--models)");
  o = Valid();
  o.output.clear();
  EXPECT_EQ(o.Check(), "no output file given (-o)");
  o = Valid();
  o.output = "m.h5";
  EXPECT_EQ(o.Check(), "the output file must not be an input file");
  o = Valid();
  o.tier.clear();
  EXPECT_EQ(o.Check(), "--tier must name a key tier");
  o = Valid();
  o.threads = -1;
  EXPECT_EQ(o.Check(), "--threads must be >= 0");
  o = Valid();
  o.dikeys.max_unsolved_fraction = 1.5;
  EXPECT_EQ(o.Check(), "max_unsolved_fraction must be in [0, 1]");
}

TEST(DictBuildText, RendersTheReport) {
  dict::Coverage c;
  c.placement(0, 2) = 1;
  c.placement(2, 0) = 1;
  c.shape(0, 5) = 1;
  c.shape(5, 0) = 1;
  c.dikeys = {{"00-25", 1}, {"25-00", 1}};
  c.units = 2;
  dict::Coverage d = c;
  d.placement(2, 0) = 0;
  d.shape(5, 0) = 0;
  d.dikeys = {{"00-25", 1}};
  d.units = 1;
  const json r = {
      {"output", "d.h5"},
      {"models_fingerprint", "abc"},
      {"takes", json::array({json::object()})},
      {"dikeys", {{"kept", 1}, {"successions", 2}, {"rejected_unsolved", 1}, {"rejected_outside", 0}, {"frames", 40}}},
      {"coverage",
       {{"corpus", CoverageJson(c)},
        {"dictionary", CoverageJson(d)},
        {"complete", false},
        {"missing_dikeys", {"25-00"}}}}};
  EXPECT_EQ(DictBuildText(r),
            "dictionary d.h5: 1 dikeys of 2 key successions in 1 takes (1 left out for unsolved frames, 0 outside "
            "the takes), 40 frames\n"
            "models fingerprint abc\n"
            "placement successions: corpus 2, dictionary 1 of 35 possible\n"
            "shape successions: corpus 2, dictionary 1 of 80 possible\n"
            "key successions: corpus 2, dictionary 1; missing: 25-00\n");
  const json j = CoverageJson(d);
  EXPECT_EQ(j["placement"]["present"], 1);
  EXPECT_EQ(j["placement"]["missing"].size(), 34u);
  EXPECT_EQ(j["placement"]["counts"][0][2], 1);
  EXPECT_EQ(j["dikeys"]["00-25"], 1);
}

// A virtual-cuer corpus with face and hand models fitted on it.
struct DictFixture : testing::CuerCorpus {
  std::string models;
  DictFixture() : CuerCorpus(3) {  // 3 even under the sanitizers: 2 sentences repeat too few keys
    models = (dir / "models.h5").string();
    Progress progress;
    for (const char* kind : {"face", "hand"}) {
      FitOptions fo;
      fo.corpus = corpus;
      fo.kind = kind;
      fo.output = models;
      Fit(fo, progress);
    }
  }
};

// One corpus and one model file for the suite (simulation and fits are the slow part).
class DictJob : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fixture_ = new DictFixture(); }
  static void TearDownTestSuite() {
    delete fixture_;
    fixture_ = nullptr;
  }
  static DictFixture* fixture_;
};
DictFixture* DictJob::fixture_ = nullptr;

TEST_F(DictJob, HoldsExactlyTheCorpusKeySuccessions) {
  ASSERT_NE(fixture_, nullptr);
  DictFixture& fx = *fixture_;
  DictBuildOptions o;
  o.corpus = fx.corpus;
  o.models = fx.models;
  o.output = (fx.dir / "dict.h5").string();
  o.tier = "keys";
  Progress progress;
  const json r = DictBuild(o, progress);

  // The truth: successions of each sentence's cued keys (rests at both ends).
  std::map<std::string, int> truth;
  int successions = 0;
  for (const SimulationResult& s : fx.sims) {
    ASSERT_GE(s.keys.size(), 3u);
    EXPECT_EQ(s.keys.front().key.Code(), "00");
    EXPECT_EQ(s.keys.back().key.Code(), "00");
    for (size_t i = 0; i + 1 < s.keys.size(); ++i) {
      truth[s.keys[i].key.Code() + "-" + s.keys[i + 1].key.Code()] += 1;
      ++successions;
    }
  }
  EXPECT_EQ(r["dikeys"]["successions"], successions);
  EXPECT_EQ(r["dikeys"]["kept"], successions);
  // The corpus's continuity, as stored: the hand moves up to ~2 m/s (the
  // virtual cuer's fastest keys), i.e. under 25 mm a frame at 120 Hz, and
  // faster than 1 mm a frame for more than 1 % of the samples.
  const dict::Dictionary stored = LoadDictionaryFile(o.output);
  EXPECT_EQ(stored.corpus_p99_jump_mm, r["continuity"]["p99_jump_mm"].get<double>());
  EXPECT_EQ(stored.corpus_max_jump_mm, r["continuity"]["max_jump_mm"].get<double>());
  EXPECT_EQ(stored.corpus_rate_hz, fx.sims.front().take.rate_hz);
  EXPECT_GT(stored.corpus_p99_jump_mm, 1.0);
  EXPECT_LT(stored.corpus_p99_jump_mm, 25.0);
  EXPECT_GE(stored.corpus_max_jump_mm, stored.corpus_p99_jump_mm);
  EXPECT_EQ(r["dikeys"]["rejected_unsolved"], 0);
  EXPECT_EQ(r["dikeys"]["rejected_outside"], 0);
  EXPECT_TRUE(r["coverage"]["complete"].get<bool>());
  std::map<std::string, int> corpus_cov, dict_cov;
  for (const auto& [k, v] : r["coverage"]["corpus"]["dikeys"].items()) corpus_cov[k] = v.get<int>();
  for (const auto& [k, v] : r["coverage"]["dictionary"]["dikeys"].items()) dict_cov[k] = v.get<int>();
  EXPECT_EQ(corpus_cov, truth);
  EXPECT_EQ(dict_cov, truth);

  // The file: the same units, the fingerprint of the models used.
  const dict::Dictionary d = LoadDictionaryFile(o.output);
  const ModelFile m = LoadModelFile(fx.models);
  EXPECT_EQ(d.models_fingerprint, dict::ModelsFingerprint(&*m.face, &*m.hand));
  EXPECT_EQ(r["models_fingerprint"], d.models_fingerprint);
  EXPECT_EQ(d.hand_parameter_names.size(), static_cast<size_t>(m.hand->num_parameters()));
  EXPECT_EQ(d.key_tier, "keys");
  std::map<std::string, int> in_file;
  for (const dict::DikeyUnit& u : d.dikeys) in_file[dict::SuccessionCode(u.from, u.to)] += 1;
  EXPECT_EQ(in_file, truth);

  // Per unit: times are the simulator's target times; every frame solved;
  // phasing = the arriving key's shape target − its syllable's onset (A1).
  std::map<std::string, const SimulationResult*> sims;
  for (const SimulationResult& s : fx.sims) sims[s.take.name] = &s;
  for (const json& t : r["takes"]) EXPECT_TRUE(t["phasing"].get<bool>()) << t;
  int phased = 0;
  // The key tier the simulator wrote: shape target times, each at least
  // 0.1 ms after the previous one (overlapping gestures can reach their
  // targets out of order).
  std::map<std::string, std::vector<KeyMark>> tiers;
  for (const SimulationResult& s : fx.sims) {
    for (const LabelTier& t : s.take.tiers)
      if (t.name == "keys") tiers[s.take.name] = ReadKeyTier(t, s.take.name);
    ASSERT_EQ(tiers[s.take.name].size(), s.keys.size());
  }
  for (const dict::DikeyUnit& u : d.dikeys) {
    const SimulationResult& s = *sims.at(u.take);
    const GestureTruth& b = s.keys[static_cast<size_t>(u.index) + 1];
    const std::vector<KeyMark>& marks = tiers.at(u.take);
    EXPECT_NEAR(u.start_s, marks[static_cast<size_t>(u.index)].time_s, 1e-9);
    EXPECT_NEAR(u.end_s, marks[static_cast<size_t>(u.index) + 1].time_s, 1e-9);
    EXPECT_LE(std::abs(u.end_s - b.timing.shape_target_s), 0.5);
    EXPECT_EQ(u.frames(), std::llround(u.end_s * 120.0) - std::llround(u.start_s * 120.0) + 1);
    EXPECT_TRUE(u.hand_params.allFinite());
    EXPECT_TRUE(u.forearm_in_head.allFinite());
    EXPECT_TRUE(u.head_pose.allFinite());
    // The type of the key reached is the simulator's (whose A1 it is).
    ASSERT_TRUE(u.to_type.has_value()) << u.take << " " << u.index;
    EXPECT_EQ(*u.to_type, b.key.type) << u.take << " " << u.index;
    if (b.key.Code() == "00") {
      EXPECT_TRUE(std::isnan(u.phasing_s));
    } else {
      EXPECT_NEAR(u.phasing_s, u.end_s - b.key.a1_s, 1e-6) << u.take << " " << u.index;
      ++phased;
    }
  }
  EXPECT_EQ(phased, successions - static_cast<int>(fx.sims.size()));

  // Diphones: every succession of two (non-pause) phones of the simulator's
  // utterance, middle to middle, in order, with solved face parameters.
  ASSERT_EQ(d.face_parameter_names.size(), static_cast<size_t>(m.face->num_parameters()));
  EXPECT_EQ(r["diphones"]["rejected_unsolved"], 0);
  EXPECT_EQ(r["diphones"]["kept"], r["diphones"]["successions"]);
  for (const SimulationResult& s : fx.sims) {
    std::vector<std::string> want, got;
    const auto& ph = s.utterance.phones;
    for (size_t i = 0; i + 1 < ph.size(); ++i) {
      if (ph[i].ipa.empty() || ph[i + 1].ipa.empty()) continue;
      char buf[96];
      std::snprintf(buf, sizeof(buf), "%s+%s %.6f %.6f", ph[i].ipa.c_str(), ph[i + 1].ipa.c_str(),
                    0.5 * (ph[i].start_s + ph[i].end_s), 0.5 * (ph[i + 1].start_s + ph[i + 1].end_s));
      want.push_back(buf);
    }
    for (const dict::DiphoneUnit& u : d.diphones) {
      if (u.take != s.take.name || u.phone1 == "_" || u.phone2 == "_") continue;
      EXPECT_TRUE(u.face_params.allFinite());
      EXPECT_EQ(u.frames(), std::llround(u.end_s * 120.0) - std::llround(u.start_s * 120.0) + 1);
      char buf[96];
      std::snprintf(buf, sizeof(buf), "%s+%s %.6f %.6f", u.phone1.c_str(), u.phone2.c_str(), u.start_s, u.end_s);
      got.push_back(buf);
    }
    EXPECT_FALSE(want.empty());
    EXPECT_EQ(got, want) << s.take.name;
  }
}

TEST_F(DictJob, ForearmPoseRelativeToTheHeadRepeatsPerKey) {
  // The forearm in the head frame at a key's placement target: keys held at
  // the same placement with the same shape land within the simulator's
  // per-key variability, whatever the head does. Bound: the fingertip's
  // 3 mm sd and the forearm's 2° orientation sd, both truncated at 2.5 sd,
  // move the forearm cluster (~250 mm from the fingertip) by at most
  // 7.5 + 250 · tan(5°) ≈ 29.4 mm from the key's mean pose; 35 mm allows
  // for the inversion's error.
  ASSERT_NE(fixture_, nullptr);
  DictFixture& fx = *fixture_;
  DictBuildOptions o;
  o.corpus = fx.corpus;
  o.models = fx.models;
  o.output = (fx.dir / "dict2.h5").string();
  o.tier = "keys";
  Progress progress;
  DictBuild(o, progress);
  const dict::Dictionary d = LoadDictionaryFile(o.output);
  std::map<std::string, const SimulationResult*> sims;
  for (const SimulationResult& s : fx.sims) sims[s.take.name] = &s;
  // At the arriving key's placement target (the simulator's), when the unit
  // holds that frame.
  std::map<std::string, std::vector<Eigen::Vector3d>> ends;
  // The placement lags are the placement_targets tier's times minus the keys
  // tier's, mark by mark (the simulator's true targets, except where it
  // keeps a tier increasing: a placement reached before the previous one).
  int arrivals = 0, lags = 0, true_lags = 0;
  for (const dict::DikeyUnit& u : d.dikeys) {
    if (u.to.IsRest()) continue;
    const GestureTruth& b = sims.at(u.take)->keys[static_cast<size_t>(u.index) + 1];
    ++arrivals;
    if (std::isfinite(u.to_placement_lag_s)) {
      ++lags;
      const std::vector<LabelTier> tiers = SimulationTiers(*sims.at(u.take));
      const LabelTier* keys_tier = FindTier(tiers, "keys");
      const LabelTier* places = FindTier(tiers, "placement_targets");
      ASSERT_TRUE(keys_tier && places);
      const size_t k = static_cast<size_t>(u.index) + 1;
      EXPECT_NEAR(u.to_placement_lag_s, places->labels[k].start_s - keys_tier->labels[k].start_s, 1e-9) << u.take;
      if (std::abs(u.to_placement_lag_s - (b.timing.placement_target_s - b.timing.shape_target_s)) < 1e-6) ++true_lags;
    }
    const int64_t row = std::llround(b.timing.placement_target_s * u.rate_hz) - u.first_frame;
    if (row < 0 || row >= u.frames()) continue;
    ends[u.to.Text()].push_back(u.forearm_in_head.row(row).rightCols(3).transpose());
  }
  int groups = 0;
  double worst = 0;
  for (const auto& [code, v] : ends) {
    if (v.size() < 2) continue;
    ++groups;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : v) mean += p;
    mean /= static_cast<double>(v.size());
    for (const auto& p : v) worst = std::max(worst, (p - mean).norm());
  }
  EXPECT_EQ(lags, arrivals);
  EXPECT_GE(true_lags, 0.8 * arrivals);
  std::printf("placement lags: %d of %d arrivals, %d the true lag\n", lags, arrivals, true_lags);
  ASSERT_GE(groups, 2);
  EXPECT_LT(worst, 35.0);
  std::printf("forearm-in-head spread at repeated keys: max %.1f mm over %d keys\n", worst, groups);
}

TEST_F(DictJob, BadInputGivesOneClearError) {
  ASSERT_NE(fixture_, nullptr);
  DictFixture& fx = *fixture_;
  Progress progress;
  DictBuildOptions o;
  o.corpus = fx.corpus;
  o.models = fx.models;
  o.output = (fx.dir / "dict3.h5").string();
  // No keys_aligned tier (csw keys score was not run).
  try {
    DictBuild(o, progress);
    FAIL();
  } catch (const InvalidInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(fx.corpus + ": take 's0': no key tier 'keys_aligned' (tiers: "), std::string::npos) << m;
    EXPECT_NE(m.find("run csw keys score"), std::string::npos) << m;
  }
  EXPECT_FALSE(std::filesystem::exists(o.output));
  // A key model file without a key model.
  o.tier = "keys";
  o.keys = fx.models;
  try {
    DictBuild(o, progress);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), fx.models + ": no key model (/keys) in the file (csw keys train)");
  }
  o.keys.clear();
  // Models without a hand model.
  const std::string face_only = (fx.dir / "face.h5").string();
  {
    FitOptions fo;
    fo.corpus = fx.corpus;
    fo.kind = "face";
    fo.output = face_only;
    Fit(fo, progress);
  }
  o.models = face_only;
  try {
    DictBuild(o, progress);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), face_only +
                                         ": a dictionary needs a face model and a hand model (csw fit face, csw fit "
                                         "hand); the file has a face model only");
  }
  // A dictionary built with some models is refused for others (a hand model
  // fitted on one sentence only).
  o.models = fx.models;
  DictBuild(o, progress);
  const dict::Dictionary d = LoadDictionaryFile(o.output);
  {
    FitOptions fo;
    fo.corpus = fx.corpus;
    fo.kind = "hand";
    fo.takes = {"s0"};
    fo.output = face_only;
    Fit(fo, progress);
  }
  const ModelFile other = LoadModelFile(face_only);
  const std::string fp = dict::ModelsFingerprint(&*other.face, &*other.hand);
  EXPECT_NE(fp, d.models_fingerprint);
  try {
    dict::CheckModelsMatch(d, fp, o.output);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(o.output + ": the dictionary was built with models "), std::string::npos);
  }
}

}  // namespace
}  // namespace csw::jobs
