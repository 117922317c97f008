// csw clean (workbench/jobs/clean_job.h): option checks, the exact default
// text, and the job end to end on a virtual-cuer take written into a corpus
// (its clean capture is the truth the fills are scored against).
#include "workbench/jobs/clean_job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

CleanOptions Valid() {
  CleanOptions o;
  o.corpus = "c.h5";
  return o;
}

TEST(CleanOptionsCheck, AcceptsTheDefaultsAndEveryMethod) {
  CleanOptions o = Valid();
  EXPECT_EQ(o.Check(), "");
  o.fill = {"spline,rigid", "pattern,dct"};
  EXPECT_EQ(o.Check(), "");
  o.fill.push_back("model");
  o.models = "m.h5";
  EXPECT_EQ(o.Check(), "");
  o.filter = "butterworth";
  o.order = 2;
  EXPECT_EQ(o.Check(), "");
  o.filter = "kalman";
  o.kalman_model = "acceleration";
  EXPECT_EQ(o.Check(), "");
}

TEST(CleanOptionsCheck, RejectsEachBadRequestWithItsReason) {
  auto why = [](auto change) {
    CleanOptions o = Valid();
    change(o);
    return o.Check();
  };
  EXPECT_EQ(why([](CleanOptions& o) { o.corpus.clear(); }), "no corpus given");
  EXPECT_EQ(why([](CleanOptions& o) { o.fill = {"spline,woltring"}; }),
            "--fill: unknown method 'woltring' (spline, rigid, pattern, dct, model)");
  EXPECT_EQ(why([](CleanOptions& o) { o.fill = {"spline", "spline"}; }), "--fill: method 'spline' given twice");
  EXPECT_EQ(why([](CleanOptions& o) { o.fill = {"model"}; }), "--fill model needs --models MODELS.h5 (from csw fit)");
  EXPECT_EQ(why([](CleanOptions& o) { o.models = "m.h5"; }), "--models is only used by --fill model");
  EXPECT_EQ(why([](CleanOptions& o) { o.max_gap_s = -1; }), "--max-gap must be >= 0 seconds");
  EXPECT_EQ(why([](CleanOptions& o) { o.max_gap_s = std::nan(""); }), "--max-gap must be >= 0 seconds");
  EXPECT_EQ(why([](CleanOptions& o) { o.spline = "linear"; }), "--spline must be smoothing, cubic or quintic");
  EXPECT_EQ(why([](CleanOptions& o) { o.side_frames = 0; }), "--side-frames must be >= 1");
  EXPECT_EQ(why([](CleanOptions& o) { o.donors = {"RTIP"}; }), "--donor 'RTIP': expected MARKER=DONOR");
  EXPECT_EQ(why([](CleanOptions& o) { o.donors = {"=RTIP"}; }), "--donor '=RTIP': expected MARKER=DONOR");
  EXPECT_EQ(why([](CleanOptions& o) { o.filter = "median"; }), "--filter must be butterworth or kalman");
  EXPECT_EQ(why([](CleanOptions& o) {
              o.filter = "butterworth";
              o.cutoff_hz = 0;
            }),
            "--cutoff must be > 0 Hz");
  EXPECT_EQ(why([](CleanOptions& o) {
              o.filter = "butterworth";
              o.order = 3;
            }),
            "--order must be 2, 4, 6 or 8");
  EXPECT_EQ(why([](CleanOptions& o) { o.kalman_model = "jerk"; }), "--kalman-model must be velocity or acceleration");
}

TEST(CleanText, RendersEveryPartOfATake) {
  const json r = {
      {"corpus", "c.h5"},
      {"dry_run", false},
      {"figures", json::array({"f/t1_gaps.png"})},
      {"takes",
       {{{"take", "t1"},
         {"frames", 1200},
         {"rate_hz", 120.0},
         {"markers", 40},
         {"max_gap_frames", 60},
         {"gaps",
          {{"count", 7},
           {"fraction_missing", 0.0125},
           {"longest", 30},
           {"longest_s", 0.25},
           {"by_length", {{{"frames", "1-5"}, {"gaps", 4}}, {{"frames", "> 60"}, {"gaps", 0}}}},
           {"fillable_by", {{"spline", 6}, {"rigid", 2}}},
           {"fillable_by_none", 1}}},
         {"swaps",
          {{"fixed", true}, {"detected", {{{"a", "ITIP"}, {"b", "MTIP"}, {"first_frame", 100}, {"end_frame", 160}}}}}},
         {"spikes", {{"detected", json::array({json::object(), json::object()})}, {"removed_samples", 2}}},
         {"fills",
          {{"filled_gaps", 6},
           {"filled_samples", 40},
           {"by_method", {{"rigid", 2}, {"spline", 4}}},
           {"unfilled_gaps", 1},
           {"unfilled_samples", 30}}},
         {"filter", {{"method", "butterworth"}}},
         {"cleaned_take", "t1.filled"}}}}};
  EXPECT_EQ(CleanText(r),
            "take t1: 1200 frames at 120.0 Hz, 40 markers\n"
            "  gaps: 7 (1.2 % of samples missing), longest 30 frames (0.2 s); by length: 1-5: 4 > 60: 0\n"
            "  fillable by (max gap 60 frames): rigid 2 spline 6; none 1\n"
            "  label swaps: 1 (fixed); ITIP<->MTIP frames 100-160\n"
            "  spikes: 2 (2 samples removed)\n"
            "  filled: 6 gaps (40 samples): rigid 2 spline 4; left unfilled: 1 gaps (30 samples)\n"
            "  filter: butterworth\n"
            "  written as take t1.filled\n"
            "figure: f/t1_gaps.png\n");
}

// A short virtual-cuer take (hand shapes: head cluster and hand markers only)
// in a new corpus, with or without its marker set.
struct Fixture {
  testing::TempDir dir;
  std::string corpus;
  SimulationResult sim;
  MarkerSet set;
  explicit Fixture(bool with_markerset) {
    corpus = (dir / "c.h5").string();
    SimulateOptions o;
    o.seed = 5;
    o.dropouts_per_s = 0.3;  // many short dropped runs: gaps with a known truth
    const VirtualCuer cuer(o);
    sim = cuer.SimulateShapes("shapes", {1, 5, 2});
    set = cuer.MakeMarkerSet(CorpusKind::kShapes);
    Take t = sim.take;
    if (with_markerset) t.markerset_json = MarkerSetToJson(set);
    CorpusTransaction tx(corpus);
    tx.WriteTake(t);
    tx.Commit();
  }
};

double Distance(const float* a, const float* b) {
  return std::sqrt(std::pow(double(a[0]) - b[0], 2) + std::pow(double(a[1]) - b[1], 2) +
                   std::pow(double(a[2]) - b[2], 2));
}

TEST(CleanJob, FillsGapsIntoANewTakeAndLeavesTheOriginal) {
  Fixture fx(true);
  const MarkerArray& raw = fx.sim.take.markers;
  // The gaps, counted here independently of analysis/cleaning.
  int64_t gaps = 0, missing = 0;
  for (int64_t m = 0; m < raw.markers(); ++m) {
    bool in = false;
    for (int64_t f = 0; f < raw.frames(); ++f) {
      const bool miss = !raw.Visible(f, m);
      missing += miss ? 1 : 0;
      if (miss && !in) ++gaps;
      in = miss;
    }
  }
  ASSERT_GT(gaps, 10) << "the fixture should have gaps to fill";

  CleanOptions o;
  o.corpus = fx.corpus;
  o.fill = {"spline,rigid,pattern,dct"};
  Progress progress;
  const json r = Clean(o, progress);
  ASSERT_EQ(r["takes"].size(), 1u);
  const json& t = r["takes"][0];
  EXPECT_EQ(t["gaps"]["count"].get<int64_t>(), gaps);
  EXPECT_EQ(t["gaps"]["missing_samples"].get<int64_t>(), missing);
  EXPECT_EQ(t["max_gap_frames"].get<int64_t>(), 60);  // 0.5 s at 120 Hz
  const int64_t filled = t["fills"]["filled_gaps"].get<int64_t>();
  EXPECT_EQ(filled + t["fills"]["unfilled_gaps"].get<int64_t>(), gaps);
  EXPECT_GT(filled, 0);
  ASSERT_EQ(t["cleaned_take"].get<std::string>(), "shapes.filled");

  const Corpus c = Corpus::Open(fx.corpus);
  const Take original = c.LoadTake("shapes");
  ASSERT_EQ(original.markers.data().size(), raw.data().size());
  for (size_t i = 0; i < raw.data().size(); ++i) {
    const float a = original.markers.data()[i], b = raw.data()[i];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << "the original take changed at value " << i;
  }
  const Take cleaned = c.LoadTake("shapes.filled");
  // Every filled sample against the clean capture; measured samples untouched.
  double sum = 0, worst = 0;
  int64_t n = 0;
  for (int64_t f = 0; f < raw.frames(); ++f) {
    for (int64_t m = 0; m < raw.markers(); ++m) {
      if (raw.Visible(f, m)) {
        ASSERT_EQ(cleaned.markers.at(f, m)[0], raw.at(f, m)[0]);
        continue;
      }
      if (!cleaned.markers.Visible(f, m)) continue;
      const double d = Distance(cleaned.markers.at(f, m), fx.sim.clean.at(f, m));
      sum += d;
      worst = std::max(worst, d);
      ++n;
    }
  }
  EXPECT_EQ(n, t["fills"]["filled_samples"].get<int64_t>());
  ASSERT_GT(n, 0);
  // Limits: gaps up to 0.5 s of the virtual cuer's fast finger movements, each
  // filled by the first method that can: measured 2.47 mm mean, 19.6 mm max over
  // 502 samples (docs/cleaning.md has the tables by method and gap length).
  EXPECT_LT(sum / n, 3.0) << "mean error of the filled samples (mm)";
  EXPECT_LT(worst, 25.0) << "largest error of a filled sample (mm)";
  // One point per filled gap in the fill log tier.
  const LabelTier* log = nullptr;
  for (const LabelTier& tier : cleaned.tiers)
    if (tier.name == "csw-fills") log = &tier;
  ASSERT_NE(log, nullptr);
  EXPECT_EQ(static_cast<int64_t>(log->labels.size()), filled);
  EXPECT_NE(cleaned.provenance.warnings.back().find("cleaned by csw clean from take 'shapes'"), std::string::npos);

  // A second run makes the next version; a dry run writes nothing.
  Clean(o, progress);
  EXPECT_TRUE(Corpus::Open(fx.corpus).HasTake("shapes.filled-2"));
  o.dry_run = true;
  const json dry = Clean(o, progress);
  EXPECT_FALSE(dry["takes"][0].contains("cleaned_take"));
  EXPECT_FALSE(Corpus::Open(fx.corpus).HasTake("shapes.filled-3"));
}

TEST(CleanJob, ButterworthFilterNeverCrossesAGap) {
  Fixture fx(false);
  CleanOptions o;
  o.corpus = fx.corpus;
  o.filter = "butterworth";
  o.cutoff_hz = 8;
  Progress progress;
  const json r = Clean(o, progress);
  const Take cleaned = Corpus::Open(fx.corpus).LoadTake(r["takes"][0]["cleaned_take"].get<std::string>());
  const MarkerArray& raw = fx.sim.take.markers;
  int64_t changed = 0;
  for (int64_t f = 0; f < raw.frames(); ++f) {
    for (int64_t m = 0; m < raw.markers(); ++m) {
      ASSERT_EQ(raw.Visible(f, m), cleaned.markers.Visible(f, m)) << "frame " << f << " marker " << m;
      if (raw.Visible(f, m) && raw.at(f, m)[0] != cleaned.markers.at(f, m)[0]) ++changed;
    }
  }
  EXPECT_GT(changed, raw.CountVisible() / 2) << "the filter should change most samples";
}

TEST(CleanJob, RigidFillWithoutAMarkerSetIsAUsageErrorNamingTheTake) {
  Fixture fx(false);
  CleanOptions o;
  o.corpus = fx.corpus;
  o.fill = {"spline,rigid"};
  Progress progress;
  try {
    Clean(o, progress);
    FAIL() << "expected a usage error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("take 'shapes'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--markerset"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(Corpus::Open(fx.corpus).HasTake("shapes.filled"));
}

}  // namespace
}  // namespace csw::jobs
