// csw keys suggest and csw phasing (workbench/jobs/keys_suggest_job.h,
// phasing_job.h): option checks, the text output, and both jobs end to end on
// virtual-cuer sentences whose true key targets and gesture times are known.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/error.h"
#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "tests/keys_job/cuer_corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/keys_suggest_job.h"
#include "workbench/jobs/phasing_job.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

TEST(KeysSuggestOptionsCheck, ReasonsForBadRequests) {
  KeysSuggestOptions o;
  EXPECT_EQ(o.Check(), "no corpus given");
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "");
  o.symbols = "klingon";
  EXPECT_EQ(o.Check(), "--symbols must be auto, ipa, mfa, xsampa or sppas, not 'klingon'");
  o.symbols = "auto";
  o.tier = "keys";
  EXPECT_EQ(o.Check(), "the suggestion tier 'keys' would replace the phone or label tier of that name");
  o.tier = "placement_suggested";
  EXPECT_EQ(o.Check(), "the shape and placement suggestion tiers must differ");
  o.tier = "keys_suggested";
  o.suggest.search_s = -1;
  EXPECT_EQ(o.Check(), "the search half-width must be a positive number of seconds");
}

TEST(PhasingOptionsCheck, ReasonsForBadRequests) {
  PhasingOptions o;
  EXPECT_EQ(o.Check(), "no corpus given");
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "--keys must name a model file with a key model (csw keys train)");
  o.keys = "k.h5";
  EXPECT_EQ(o.Check(), "");
  o.phones = "";
  EXPECT_EQ(o.Check(), "--phones must name the phone tier");
}

TEST(KeysSuggestText, RendersMissingKeysAndTheComparison) {
  const json r = {
      {"takes",
       {{{"take", "s1"},
         {"keys", 3},
         {"shape",
          {{"suggested", 2},
           {"missing", {{{"key", 2}, {"code", "31"}, {"expected_s", 1.25}, {"why", "no valid samples"}}}}}},
         {"placement", {{"suggested", 3}, {"missing", json::array()}}},
         {"labels",
          {{"shape", {{"matched", 2}, {"suggested", 2}, {"within_40ms", 1}, {"mean", 25.0}, {"max", 41.5}}},
           {"placement",
            {{"matched", 0}, {"suggested", 3}, {"within_40ms", 0}, {"mean", nullptr}, {"max", nullptr}}}}}}}},
      {"keys", 3},
      {"suggested", 2},
      {"tiers", {"keys_suggested", "placement_suggested"}},
      {"tiers_written", true}};
  EXPECT_EQ(KeysSuggestText(r),
            "take s1: 3 keys; shape targets 2, placement targets 3 suggested\n"
            "  no shape target for key 2 (31, expected at 1.25 s): no valid samples\n"
            "  shape vs labels: 2 of 2 matched, 1 within 40 ms, error 25 ms mean, 41.5 ms max\n"
            "  placement vs labels: 0 of 3 matched, 0 within 40 ms, error -\n"
            "2 of 3 keys have a suggested shape target; tiers 'keys_suggested' and 'placement_suggested' written\n");
}

// Six virtual-cuer sentences (four under the sanitizers) with their truth files.
struct Fixture : testing::CuerCorpus {
  Fixture() : CuerCorpus(testing::kSanitized ? 4 : 6) {}
};

TEST(KeysSuggestJob, SuggestionsLandNearTheTrueTargetsAndAreWritten) {
  Fixture fx;
  Progress progress;
  KeysSuggestOptions o;
  o.corpus = fx.corpus;
  const json r = KeysSuggest(o, progress);
  ASSERT_EQ(r["takes"].size(), fx.sims.size());
  EXPECT_TRUE(r["tiers_written"].get<bool>());
  const Corpus c = Corpus::Open(fx.corpus);
  std::vector<double> errors;
  int64_t within = 0, compared = 0;
  for (size_t i = 0; i < fx.sims.size(); ++i) {
    const SimulationResult& sim = fx.sims[i];
    const Take take = c.LoadTake(sim.take.name);
    std::map<std::string, const LabelTier*> tiers;
    for (const auto& t : take.tiers) tiers[t.name] = &t;
    ASSERT_EQ(tiers.count("keys_suggested"), 1u);
    ASSERT_EQ(tiers.count("placement_suggested"), 1u);
    ASSERT_EQ(tiers.count("phones"), 1u);  // the other tiers are kept
    // Every suggested shape target against the true shape target of the key of
    // that code nearest to it (the simulation's ground truth).
    for (const Label& l : tiers["keys_suggested"]->labels) {
      double best = 1e9;
      for (const GestureTruth& g : sim.keys)
        if (g.key.Code() == l.text) best = std::min(best, std::abs(g.timing.shape_target_s - l.start_s));
      ASSERT_LT(best, 1e8) << l.text << " is not a key of " << sim.take.name;
      errors.push_back(best);
      ++compared;
      if (best <= 0.040) ++within;
    }
    // The job's own comparison with the take's label tier agrees in count.
    EXPECT_EQ(r["takes"][i]["labels"]["shape"]["suggested"].get<int64_t>(),
              static_cast<int64_t>(tiers["keys_suggested"]->labels.size()));
  }
  // Measured on these six sentences (2026-12-02): 66 % of the suggestions
  // within 40 ms of the true target, mean error 36 ms; a clean capture with the
  // default phasing laws. Limits just under that, to catch a regression.
  ASSERT_GT(compared, 40);
  double mean = 0;
  for (double e : errors) mean += e;
  mean /= static_cast<double>(errors.size());
  EXPECT_GE(static_cast<double>(within) / static_cast<double>(compared), 0.6) << "mean error " << mean;
  EXPECT_LT(mean, 0.045);
  // At least 90 % of the keys get a shape suggestion.
  EXPECT_GE(r["suggested"].get<double>(), 0.9 * r["keys"].get<double>());
}

TEST(PhasingJob, KinematicTimesFollowTheTruthAndTheCsvHasOneRowPerKey) {
  Fixture fx;
  Progress progress;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s*"};
  t.output = fx.keys;
  KeysTrain(t, progress);
  PhasingOptions o;
  o.corpus = fx.corpus;
  o.keys = fx.keys;
  o.truth = fx.truth;
  o.csv = (fx.dir / "phasing.csv").string();
  const json r = Phasing(o, progress);
  for (const json& take : r["takes"]) {
    EXPECT_EQ(take["truth"], "matched") << take.dump();
    // The simulator's label tiers follow the cued keys: they give the rough targets.
    EXPECT_EQ(take["rough_targets"], "labels") << take.dump();
  }
  // CV keys, kinematic estimates minus the truth, measured on these six
  // sentences (2026-12-02, rough targets from the label tiers, after the
  // phasing fit's standard-error gate): shape onset -0.9 ms, shape target
  // -2.4 ms (36 keys), placement onset +16.8 ms (sd 39), placement target
  // -9.2 ms (17 keys; before the gate +46.2 ms at onset). Six sentences are
  // too few for the 15 ms bar on the placement onset: the 100-sentence
  // acceptance test (tests/phasing_job) holds it. Limits just above.
  const std::map<std::string, double> limit_ms{
      {"shape onset", 10}, {"shape target", 10}, {"placement target", 15}, {"placement onset", 30}};
  for (const char* c : {"placement", "shape"})
    for (const char* l : {"onset", "target"}) {
      const json& e = r["errors_vs_truth"]["kinematic"]["CV"][c][l];
      ASSERT_GT(e["count"].get<int>(), 10) << c << " " << l;
      EXPECT_LT(std::abs(e["mean_ms"].get<double>()), limit_ms.at(std::string(c) + " " + l))
          << c << " " << l << ": " << e.dump();
    }
  // The truth summary is the simulator's laws: CV placement target ~ +37 ms.
  const json& tv = r["truth"]["CV"]["placement"]["target"];
  EXPECT_NEAR(tv["mean_ms"].get<double>(), 37.0, 40.0);
  // One CSV row per measured key, after the header.
  std::ifstream in(o.csv);
  std::string line;
  int64_t lines = 0;
  while (std::getline(in, line))
    if (!line.empty()) ++lines;
  EXPECT_EQ(lines - 1, r["keys_measured"].get<int64_t>());
  EXPECT_FALSE(PhasingText(r).empty());
  EXPECT_NE(PhasingText(r).find("CV placement: onset"), std::string::npos);
  // The placement gate in effect: 8 ms at the simulator's 120 Hz (the
  // reference rate, so not tightened), per take and per rate.
  const json& gate = r["placement_time_sd_gate"];
  EXPECT_DOUBLE_EQ(gate["limit_ms"].get<double>(), 8.0);
  EXPECT_DOUBLE_EQ(gate["reference_rate_hz"].get<double>(), 120.0);
  ASSERT_EQ(gate["by_rate"].size(), 1u);
  EXPECT_DOUBLE_EQ(gate["by_rate"][0]["rate_hz"].get<double>(), 120.0);
  EXPECT_DOUBLE_EQ(gate["by_rate"][0]["limit_ms"].get<double>(), 8.0);
  for (const json& take : r["takes"]) EXPECT_DOUBLE_EQ(take["placement_time_sd_limit_ms"].get<double>(), 8.0);
  EXPECT_NE(PhasingText(r).find("undetermined: placement onset or target standard error over 8.0 ms (× √(120.0 Hz / "
                                "rate) above 120.0 Hz)\n"),
            std::string::npos)
      << PhasingText(r);
}

// The text names the tightened limit of each capture rate above the reference
// (8 ms x sqrt(120 / 240) = 5.66 ms).
TEST(PhasingJob, TextNamesThePlacementGateOfEachRate) {
  json r = {{"keys_measured", 0}, {"takes", json::array()}};
  r["placement_time_sd_gate"] = {
      {"limit_ms", 8.0},
      {"reference_rate_hz", 120.0},
      {"by_rate", {{{"rate_hz", 100.0}, {"limit_ms", 8.0}}, {{"rate_hz", 240.0}, {"limit_ms", 8.0 * std::sqrt(0.5)}}}}};
  const std::string text = PhasingText(r);
  EXPECT_NE(text.find("standard error over 8.0 ms (× √(120.0 Hz / rate) above 120.0 Hz); 5.7 ms at 240.0 Hz\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("at 100.0 Hz"), std::string::npos) << text;  // not tightened there
}

// Without label tiers to start from (--targets aligned), the rough targets
// are the kinematic target times of the aligned decoding
// (analysis/keys/key_timing.h), and the phasing follows the truth as well.
TEST(PhasingJob, AlignedDecodingGivesTheRoughTargetsWithoutLabels) {
  Fixture fx;
  Progress progress;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s*"};
  t.output = fx.keys;
  KeysTrain(t, progress);
  PhasingOptions o;
  o.corpus = fx.corpus;
  o.keys = fx.keys;
  o.truth = fx.truth;
  o.targets = "aligned";
  const json r = Phasing(o, progress);
  for (const json& take : r["takes"]) EXPECT_EQ(take["rough_targets"], "aligned decoding") << take.dump();
  // CV keys, kinematic estimates minus the truth (2026-12-02): shape onset
  // +3.9 ms, shape target +0.9 ms (37 keys), placement onset +4.9 ms,
  // placement target -6.4 ms (16 keys) when this test runs alone; after the
  // test above in the same process the simulated sentences differ slightly
  // (espeak-ng keeps state between runs) and the placement means read +43 /
  // +36 ms (17 keys, sd 157 / 184 ms): one or two placements that the aligned
  // decoding puts on the wrong stretch carry the mean of so few keys. With
  // the plain aligned decoding's segment arrivals as rough targets: -16.0 /
  // -4.7 / +22.3 / -13.5 ms. Limits: the shape tight, the placement loose.
  const std::map<std::string, double> limit_ms{
      {"shape onset", 12}, {"shape target", 10}, {"placement target", 60}, {"placement onset", 60}};
  for (const char* c : {"placement", "shape"})
    for (const char* l : {"onset", "target"}) {
      const json& e = r["errors_vs_truth"]["kinematic"]["CV"][c][l];
      ASSERT_GT(e["count"].get<int>(), 10) << c << " " << l;
      EXPECT_LT(std::abs(e["mean_ms"].get<double>()), limit_ms.at(std::string(c) + " " + l))
          << c << " " << l << ": " << e.dump();
    }
}

// A lab that labels only the shape targets (no placement tier): the shape
// targets seed the placement fits, which stay near their seeds, so the
// placement fits are run again from their first targets.
TEST(PhasingJob, WithoutAPlacementTierThePlacementFitsAreRefittedFromTheirFirstTargets) {
  Fixture fx;
  Progress progress;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s*"};
  t.output = fx.keys;
  KeysTrain(t, progress);
  PhasingOptions o;
  o.corpus = fx.corpus;
  o.keys = fx.keys;
  o.truth = fx.truth;
  o.targets = "labels";
  o.label_placement = "no_such_tier";
  const json r = Phasing(o, progress);
  const json& e = r["errors_vs_truth"]["kinematic"]["CV"]["placement"]["target"];
  std::printf("CV placement target minus the truth, seeded by the shape targets: %s\n", e.dump().c_str());
  ASSERT_GT(e["count"].get<int>(), 10);
  EXPECT_LT(std::abs(e["mean_ms"].get<double>()), 15.0);
  for (const json& take : r["takes"]) {
    ASSERT_TRUE(take["placement_reseeded"].is_object()) << take.dump();
    EXPECT_GE(take["placement_reseeded"]["refitted_from"].get<int>(), 1) << take.dump();
  }
}

TEST(PhasingJob, MissingPhoneTierNamesTheTakeAndItsTiers) {
  Fixture fx;
  Progress progress;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s0"};
  t.output = fx.keys;
  KeysTrain(t, progress);
  PhasingOptions o;
  o.corpus = fx.corpus;
  o.keys = fx.keys;
  o.phones = "phonemes";
  try {
    Phasing(o, progress);
    FAIL() << "no error";
  } catch (const InvalidInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("take 's0'"), std::string::npos) << m;
    EXPECT_NE(m.find("no phone tier 'phonemes'"), std::string::npos) << m;
    EXPECT_NE(m.find("'phones'"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace csw::jobs
