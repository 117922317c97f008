// csw sign-sequence on a corpus of the virtual signer (csw simulate signs):
// the utterance is made of the retrieved signs and the transitions the
// duration model asks for, joins without jumps, reads back as BVH, and bad
// requests are named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "io/formats/bvh.h"
#include "io/formats/textgrid.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/sign_sequence_job.h"
#include "workbench/jobs/simulate_job.h"

namespace csw::jobs {
namespace {

// Largest frame-to-frame move of any joint (mm).
double MaxJump(const Take& t) {
  double worst = 0;
  for (int64_t f = 1; f < t.frames(); ++f) {
    for (int64_t j = 0; j < t.markers.markers(); ++j) {
      const float* a = t.markers.at(f - 1, j);
      const float* b = t.markers.at(f, j);
      worst =
          std::max(worst, std::sqrt(std::pow(a[0] - b[0], 2) + std::pow(a[1] - b[1], 2) + std::pow(a[2] - b[2], 2)));
    }
  }
  return worst;
}

TEST(SignSequenceJob, RetrievesSignsAndJoinsThemWithModelDurations) {
  testing::TempDir dir;
  SimulateJobOptions s;
  s.corpus = "signs";
  s.output = (dir / "sim").string();
  s.count = testing::kSanitized ? 6 : 12;
  s.seed = 4;
  Progress progress;
  Simulate(s, progress);
  const std::string corpus = (dir / "sim" / "signs.h5").string();
  double source_jump = 0;
  {
    const Corpus c = Corpus::Open(corpus);
    for (const TakeSummary& t : c.Takes()) source_jump = std::max(source_jump, MaxJump(c.LoadTake(t.name)));
  }
  for (const std::string method : {"blend", "interpolate"}) {
    SignSequenceOptions o;
    o.corpus = corpus;
    o.glosses = {"HELLO", "MUSEUM", "OPEN"};
    o.method = method;
    o.output = (dir / ("out_" + method) / "seq.bvh").string();
    const nlohmann::json r = SignSequence(o, progress);
    ASSERT_EQ(r["signs"].size(), 3u);
    ASSERT_EQ(r["transitions"].size(), 2u);
    // Frames: every sign's frames (end − start at the takes' rate, both ends
    // included) plus every transition's in-between frames (duration × rate − 1).
    const double rate = r["rate_hz"].get<double>();
    EXPECT_EQ(rate, 120.0);  // SimulateJobOptions' default
    int64_t expected = 0;
    for (const auto& sign : r["signs"]) {
      expected +=
          std::llround(sign["end_s"].get<double>() * rate) - std::llround(sign["start_s"].get<double>() * rate) + 1;
    }
    for (const auto& t : r["transitions"]) {
      expected += std::llround(t["duration_s"].get<double>() * rate) - 1;
      // The seed's SURFACE plane on the measured distances, to the frame.
      const double model = 0.148777 + 0.663958 * t["geodesic"].get<double>() + 0.275229 * t["euclidean"].get<double>();
      EXPECT_NEAR(t["duration_s"].get<double>(), model, 0.5 / 120 + 1e-9) << method;
    }
    EXPECT_EQ(r["frames"].get<int64_t>(), expected) << method;
    const Take back = ReadBvh(o.output, BvhReadOptions{"mm"});
    EXPECT_EQ(back.frames(), expected);
    EXPECT_EQ(back.skeleton.size(), Corpus::Open(corpus).LoadTake("signs000").skeleton.size());
    // No jump at the joins: no joint moves more between two frames than it
    // does anywhere in the captures (with their 0.5 mm noise), plus 20 %.
    EXPECT_LT(MaxJump(back), 1.2 * source_jump) << method;
    const std::vector<LabelTier> tiers = ReadTextGrid((dir / ("out_" + method) / "seq.TextGrid").string());
    ASSERT_EQ(tiers.size(), 2u);
    std::vector<std::string> texts;
    for (const Label& l : tiers[0].labels) texts.push_back(l.text);
    EXPECT_EQ(texts, (std::vector<std::string>{"HELLO", "transition", "MUSEUM", "transition", "OPEN"})) << method;
  }
  SignSequenceOptions bad;
  bad.corpus = corpus;
  bad.glosses = {"HELLO", "BANANA"};
  bad.output = (dir / "bad.bvh").string();
  try {
    SignSequence(bad, progress);
    FAIL() << "an unknown gloss was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("gloss 'BANANA' occurs in no tier 'signs'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("MUSEUM"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.bvh"));
  bad.glosses = {"HELLO"};
  bad.method = "morph";
  EXPECT_NE(bad.Check().find("--method"), std::string::npos);
}

}  // namespace
}  // namespace csw::jobs
