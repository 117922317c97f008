// csw segment (workbench/jobs/segment_job.h): option checks, the exact default
// text, and the job end to end on virtual-signer takes written into a corpus
// with a jittered "manual" tier: the refined tiers written back are compared
// with each hand's true boundaries.
#include "workbench/jobs/segment_job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "datasets/virtual_signer.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/simulate_job.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

SegmentOptions Valid() {
  SegmentOptions o;
  o.corpus = "c.h5";
  o.tier = "manual";
  return o;
}

TEST(SegmentOptionsCheck, AcceptsTheDefaults) {
  EXPECT_EQ(Valid().Check(), "");
  SegmentOptions o = Valid();
  o.hand = "left";
  o.rest_speed_mm_s = 30;
  o.cutoff_hz = 0;
  EXPECT_EQ(o.Check(), "");
}

TEST(SegmentOptionsCheck, RejectsEachBadRequestWithItsReason) {
  auto why = [](auto change) {
    SegmentOptions o = Valid();
    change(o);
    return o.Check();
  };
  EXPECT_EQ(why([](SegmentOptions& o) { o.corpus.clear(); }), "no corpus given");
  EXPECT_EQ(why([](SegmentOptions& o) { o.tier.clear(); }), "--tier must name the manual sign/transition tier");
  EXPECT_EQ(why([](SegmentOptions& o) { o.hand = "dominant"; }), "--hand must be right, left or both, not 'dominant'");
  EXPECT_EQ(why([](SegmentOptions& o) { o.cutoff_hz = -1; }), "--cutoff-hz must be >= 0 (0 = no filter)");
  EXPECT_EQ(why([](SegmentOptions& o) { o.order = 3; }), "--order must be 2, 4, 6 or 8");
  EXPECT_EQ(why([](SegmentOptions& o) { o.threshold_s = 0; }), "--threshold-s must be in (0, 5] seconds");
  EXPECT_EQ(why([](SegmentOptions& o) { o.rest_speed_mm_s = -2; }), "--rest-speed must be in [0, 1000] mm/s");
  EXPECT_EQ(why([](SegmentOptions& o) { o.min_rest_s = 0; }), "--min-rest-s must be in (0, 10] seconds");
  EXPECT_EQ(why([](SegmentOptions& o) { o.right_tier = "manual"; }),
            "the output tier 'manual' would replace the manual tier");
  EXPECT_EQ(why([](SegmentOptions& o) { o.right_tier = o.left_tier = "x"; }),
            "the right and left output tiers must differ");
}

TEST(SegmentText, IsExact) {
  const json r = json::parse(R"({"takes": [{"take": "signs000", "hands": [
      {"hand": "right", "wrist": "RightWrist", "tier": "manual_right", "boundaries": 3, "moved": 2,
       "shift_ms": {"mean": 45.0, "max": 80.0},
       "moves": [{"manual_s": 1.0, "refined_s": 1.05, "moved": true},
                 {"manual_s": 2.0, "refined_s": 2.0, "moved": false, "why": "no minimum within 0.150 s"},
                 {"manual_s": 3.0, "refined_s": 2.92, "moved": true}]},
      {"hand": "left", "wrist": "LeftWrist", "tier": "manual_left", "boundaries": 3, "moved": 0,
       "shift_ms": {"mean": null, "max": null}, "moves": []}]}],
      "boundaries": 6, "moved": 2, "tiers_written": true, "dry_run": false})");
  EXPECT_EQ(SegmentText(r),
            "take signs000, right hand (RightWrist): 2 of 3 boundaries moved (by 45.0 ms on average, 80.0 ms at "
            "most) -> tier 'manual_right'\n"
            "  kept 2.000 s: no minimum within 0.150 s\n"
            "take signs000, left hand (LeftWrist): 0 of 3 boundaries moved -> tier 'manual_left'\n"
            "2 of 6 boundaries moved; refined tiers written\n");
}

struct SignerCorpus {
  testing::TempDir dir;
  std::string corpus;
  std::vector<SignerTake> takes;
  explicit SignerCorpus(int n, const SignerOptions& o = {}) {
    corpus = (dir / "c.h5").string();
    const VirtualSigner signer(o);
    CorpusTransaction tx(corpus);
    for (int i = 0; i < n; ++i) {
      takes.push_back(signer.SimulateTake(i));
      Take t = takes.back().take;
      t.tiers.push_back(JitterBoundaries(t.tiers[0], "manual", 0.1, o.rate_hz, 100 + i));
      tx.WriteTake(t);
    }
    tx.Commit();
  }
};

// Fraction of each hand's true stroke boundaries within 2 frames in the tier.
double Within2Frames(const SignerTake& t, const LabelTier& refined, bool right) {
  std::vector<double> edges;
  for (size_t i = 0; i + 1 < refined.labels.size(); ++i) edges.push_back(refined.labels[i].end_s);
  int n = 0, ok = 0;
  EXPECT_EQ(edges.size(), t.boundaries.size());
  for (size_t b = 0; b < t.boundaries.size() && b < edges.size(); ++b) {
    const double truth = right ? t.boundaries[b].right_s : t.boundaries[b].left_s;
    if (!t.boundaries[b].stroke || !std::isfinite(truth)) continue;
    ++n;
    if (std::abs(edges[b] - truth) <= 0.02 + 1e-9) ++ok;
  }
  return n ? static_cast<double>(ok) / n : 0.0;
}

TEST(SegmentJob, WritesOneRefinedTierPerHand) {
  SignerCorpus c(4);
  SegmentOptions o = Valid();
  o.corpus = c.corpus;
  Progress progress;
  const json r = Segment(o, progress);
  ASSERT_EQ(r["takes"].size(), 4u);
  EXPECT_TRUE(r["tiers_written"].get<bool>());
  EXPECT_EQ(r["takes"][0]["hands"][0]["wrist"], "RightWrist");
  EXPECT_EQ(r["takes"][0]["hands"][1]["wrist"], "LeftWrist");
  EXPECT_GT(r["moved"].get<int64_t>(), r["boundaries"].get<int64_t>() * 8 / 10);
  const Corpus corpus = Corpus::Open(c.corpus);
  int64_t boundaries = 0;
  for (size_t i = 0; i < c.takes.size(); ++i) {
    const Take t = corpus.LoadTake(c.takes[i].take.name);
    const LabelTier *right = nullptr, *left = nullptr, *manual = nullptr;
    for (const LabelTier& tier : t.tiers) {
      if (tier.name == "manual_right") right = &tier;
      if (tier.name == "manual_left") left = &tier;
      if (tier.name == "manual") manual = &tier;
    }
    ASSERT_TRUE(right != nullptr && left != nullptr && manual != nullptr);
    EXPECT_EQ(right->labels.size(), manual->labels.size());
    EXPECT_GE(Within2Frames(c.takes[i], *right, true), 0.85) << t.name;
    EXPECT_GE(Within2Frames(c.takes[i], *left, false), 0.75) << t.name;
    boundaries += static_cast<int64_t>(manual->labels.size()) - 1;
  }
  EXPECT_EQ(r["boundaries"].get<int64_t>(), 2 * boundaries);
  // Again, one hand, dry run: nothing more written, same numbers for that hand.
  o.hand = "right";
  o.dry_run = true;
  const json d = Segment(o, progress);
  EXPECT_FALSE(d["tiers_written"].get<bool>());
  EXPECT_EQ(d["takes"][0]["hands"].size(), 1u);
  EXPECT_EQ(d["takes"][0]["hands"][0]["moves"], r["takes"][0]["hands"][0]["moves"]);
}

TEST(SegmentJob, OtherNamesAndErrors) {
  SignerOptions so;
  so.naming = "mixamo";
  SignerCorpus c(1, so);
  SegmentOptions o = Valid();
  o.corpus = c.corpus;
  o.dry_run = true;
  Progress progress;
  json r = Segment(o, progress);
  EXPECT_EQ(r["takes"][0]["hands"][0]["wrist"], "mixamorig:RightHand");
  o.right_wrist = "mixamorig:RightForeArm";  // an explicit override is used as given
  r = Segment(o, progress);
  EXPECT_EQ(r["takes"][0]["hands"][0]["wrist"], "mixamorig:RightForeArm");
  o.right_wrist = "Nope";
  EXPECT_THROW(Segment(o, progress), InvalidInput);
  o = Valid();
  o.corpus = c.corpus;
  o.tier = "glosses";
  try {
    Segment(o, progress);
    FAIL() << "no such tier";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("no tier 'glosses' (tiers: 'signs', 'right_hand'"), std::string::npos);
  }
  o.tier = "manual";
  o.hand = "up";
  EXPECT_THROW(Segment(o, progress), UsageError);
}

// csw simulate signs writes a corpus with the truth tiers and a jittered
// "manual" tier, and one truth file per take, that csw segment reads.
TEST(SegmentJob, SimulatedSignsCorpus) {
  testing::TempDir dir;
  SimulateJobOptions s;
  s.corpus = "signs";
  s.output = (dir / "out").string();
  s.count = 3;
  s.rate_hz = 100;
  s.noise_mm = 0.5;
  ASSERT_EQ(s.Check(), "");
  Progress progress;
  const std::vector<std::string> names = Simulate(s, progress);
  EXPECT_EQ(names, (std::vector<std::string>{"signs000", "signs001", "signs002"}));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "signs001.truth.json"));
  const Corpus corpus = Corpus::Open((dir / "out" / "signs.h5").string());
  const Take t = corpus.LoadTake("signs001");
  const SignerTake expected = VirtualSigner(ToSignerOptions(s)).SimulateTake(1);
  EXPECT_EQ(t.markers.data(), expected.take.markers.data());
  std::vector<std::string> tiers;
  for (const LabelTier& tier : t.tiers) tiers.push_back(tier.name);
  EXPECT_EQ(tiers, (std::vector<std::string>{"signs", "right_hand", "left_hand", "sign_types", "manual"}));
  SegmentOptions o = Valid();
  o.corpus = (dir / "out" / "signs.h5").string();
  const json r = Segment(o, progress);
  EXPECT_EQ(r["takes"].size(), 3u);
  s.law = "linear";
  EXPECT_EQ(s.Check(), "simulate: --law must be surface or simple, not 'linear'");
}

}  // namespace
}  // namespace csw::jobs
